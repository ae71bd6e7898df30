// SceneNode over a pugixml document: the XML form of the CENG795 scene format. Reads no element
// semantics (the walker does: scene_walker.h); it exposes names, text, attributes and children, and turns
// pugixml's byte offsets into "file.xml:line:col" locations (1-based; col counts bytes and points at
// the element's '<'). Parse errors become clrt::Error "file.xml:line:col: <pugixml description>".
#include <algorithm>
#include <pugixml.hpp>

#include "scene/scene_node.h"
#include "util/error.h"

namespace clrt {
namespace {

struct XmlDoc {
    std::string path;
    std::string data;
    std::vector<size_t> lineStarts;  // byte offset of the first character of each line
    pugi::xml_document doc;

    void indexLines() {
        lineStarts.push_back(0);
        for (size_t i = 0; i < data.size(); ++i)
            if (data[i] == '\n') lineStarts.push_back(i + 1);
    }
    std::string where(ptrdiff_t offset) const {
        if (offset < 0) return path;
        auto it = std::upper_bound(lineStarts.begin(), lineStarts.end(), size_t(offset));
        size_t line = size_t(it - lineStarts.begin());  // 1-based
        size_t col = size_t(offset) - lineStarts[line - 1] + 1;
        return path + ":" + std::to_string(line) + ":" + std::to_string(col);
    }
};

class XmlNode : public SceneNode {
public:
    XmlNode(std::shared_ptr<const XmlDoc> doc, pugi::xml_node node) : doc_(std::move(doc)), node_(node) {}

    std::string name() const override { return node_.name(); }
    std::string text() const override {
        std::string s;
        for (pugi::xml_node c = node_.first_child(); c; c = c.next_sibling())
            if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) {
                if (!s.empty()) s += ' ';
                s += c.value();
            }
        return s;
    }
    std::optional<std::string> attribute(const std::string& n) const override {
        pugi::xml_attribute a = node_.attribute(n.c_str());
        if (!a) return std::nullopt;
        return std::string(a.value());
    }
    std::vector<SceneNodePtr> children() const override {
        std::vector<SceneNodePtr> out;
        for (pugi::xml_node c = node_.first_child(); c; c = c.next_sibling())
            if (c.type() == pugi::node_element) out.push_back(std::make_shared<XmlNode>(doc_, c));
        return out;
    }
    std::string location() const override {
        ptrdiff_t off = node_.offset_debug();
        return doc_->where(off > 0 ? off - 1 : off);  // offset_debug points at the name, after '<'
    }
    std::string file() const override { return doc_->path; }

private:
    std::shared_ptr<const XmlDoc> doc_;
    pugi::xml_node node_;
};

}  // namespace

SceneNodePtr parseXmlScene(const std::string& path, std::string data) {
    auto doc = std::make_shared<XmlDoc>();
    doc->path = path;
    doc->data = std::move(data);
    doc->indexLines();
    pugi::xml_parse_result r =
        doc->doc.load_buffer(doc->data.data(), doc->data.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!r) throw Error(doc->where(r.offset) + ": " + r.description());
    pugi::xml_node root = doc->doc.document_element();
    if (!root) throw Error(path + ": no root element");
    // Only one element may be at the top level; pugixml accepts several, the format does not.
    int elements = 0;
    for (pugi::xml_node c = doc->doc.first_child(); c; c = c.next_sibling())
        if (c.type() == pugi::node_element) ++elements;
    auto node = std::make_shared<XmlNode>(doc, root);
    if (std::string(root.name()) != "Scene")
        throw Error(node->location() + ": root element is <" + root.name() + ">, expected <Scene>");
    if (elements > 1) throw Error(node->location() + ": more than one top-level element");
    return node;
}

}  // namespace clrt
