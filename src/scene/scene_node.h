// SceneNode: the small read-only tree interface that the scene walker (scene_walker.h) reads. The
// XML reader (xml_node.cpp, pugixml) and the JSON reader (json_node.cpp, nlohmann::json) each expose
// their document through it, so every scene element is interpreted in exactly one place (the walker's
// element readers, read_*.cpp).
// Reads no elements itself. Locations are "file.xml:12:5" (XML, 1-based line:col of the element's
// '<') or "file.json: Scene.Objects.Mesh[3].Faces" (JSON key path).
#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace clrt {

class SceneNode;
using SceneNodePtr = std::shared_ptr<const SceneNode>;

class SceneNode {
public:
    virtual ~SceneNode() = default;
    // Element name, e.g. "Mesh".
    virtual std::string name() const = 0;
    // The element's text (XML: concatenated PCDATA/CDATA; JSON: the string value or "_data").
    virtual std::string text() const = 0;
    // An attribute by name (XML: id="3"; JSON: "_id": "3"); nullopt when absent.
    virtual std::optional<std::string> attribute(const std::string& name) const = 0;
    // All element children in document order.
    virtual std::vector<SceneNodePtr> children() const = 0;
    // Where this node is, for messages: "file.xml:12:5" or "file.json: Scene.Cameras.Camera[1]".
    virtual std::string location() const = 0;
    // The scene file this node came from (as given to the loader).
    virtual std::string file() const = 0;

    // Children with the given name, in document order.
    std::vector<SceneNodePtr> children(const std::string& childName) const {
        std::vector<SceneNodePtr> out;
        for (auto& c : children())
            if (c->name() == childName) out.push_back(c);
        return out;
    }
    // The first child with the given name, or null.
    SceneNodePtr child(const std::string& childName) const {
        for (auto& c : children())
            if (c->name() == childName) return c;
        return nullptr;
    }
};

// Readers (xml_node.cpp, json_node.cpp): parse `path` whose contents are `data` and return the root
// element (which the caller checks is <Scene>). Throw clrt::Error on a syntax error, with location.
SceneNodePtr parseXmlScene(const std::string& path, std::string data);
SceneNodePtr parseJsonScene(const std::string& path, const std::string& data);

// The walker (scene_walker.h): interprets a <Scene> node tree into the scene model.
struct Scene;
Scene walkScene(const SceneNode& root, const std::string& path);

}  // namespace clrt
