// SceneNode over nlohmann::ordered_json: the 2025 JSON form of the CENG795 scene format. Reads no
// element semantics (the walker does: scene_walker.h). Mapping: {"Scene": {...}} is the root; keys
// starting with '_' are attributes ("_id", "_type", "_plyFile", ...); an element's text is its string
// value, or its "_data" key when it also has attributes; an array value means the element repeats.
// Numbers may be strings or JSON numbers. Locations are key paths: "scene.json: Scene.Objects.Mesh[3].Faces".
// Syntax errors, and numbers beyond double range (1e400), become clrt::Error "scene.json:line:col:
// <description>".
#include <nlohmann/json.hpp>

#include "scene/scene_node.h"
#include "util/error.h"

namespace clrt {
namespace {

using Json = nlohmann::ordered_json;

struct JsonDoc {
    std::string path;
    Json root;
};

std::string scalarText(const Json& j) {
    if (j.is_string()) return j.get<std::string>();
    if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
    if (j.is_number_integer()) return std::to_string(j.get<long long>());
    if (j.is_number_unsigned()) return std::to_string(j.get<unsigned long long>());
    if (j.is_number_float()) return j.dump();
    if (j.is_array()) {
        std::string s;
        for (auto& e : j) {
            if (!s.empty()) s += ' ';
            s += scalarText(e);
        }
        return s;
    }
    return "";
}

class JsonNode : public SceneNode {
public:
    JsonNode(std::shared_ptr<const JsonDoc> doc, const Json* value, std::string name, std::string keyPath)
        : doc_(std::move(doc)), value_(value), name_(std::move(name)), path_(std::move(keyPath)) {}

    std::string name() const override { return name_; }
    std::string text() const override {
        if (value_->is_object()) {
            auto it = value_->find("_data");
            return it == value_->end() ? std::string() : scalarText(*it);
        }
        return scalarText(*value_);
    }
    std::optional<std::string> attribute(const std::string& n) const override {
        if (!value_->is_object()) return std::nullopt;
        auto it = value_->find("_" + n);
        if (it == value_->end()) return std::nullopt;
        return scalarText(*it);
    }
    std::vector<SceneNodePtr> children() const override {
        std::vector<SceneNodePtr> out;
        if (!value_->is_object()) return out;
        for (auto it = value_->begin(); it != value_->end(); ++it) {
            const std::string& key = it.key();
            if (key.empty() || key[0] == '_') continue;
            const Json& v = it.value();
            if (v.is_array() && !v.empty() && (v[0].is_object() || v[0].is_string())) {
                for (size_t i = 0; i < v.size(); ++i)
                    out.push_back(std::make_shared<JsonNode>(doc_, &v[i], key,
                                                             path_ + "." + key + "[" + std::to_string(i) + "]"));
            } else {
                out.push_back(std::make_shared<JsonNode>(doc_, &v, key, path_ + "." + key));
            }
        }
        return out;
    }
    std::string location() const override { return doc_->path + ": " + path_; }
    std::string file() const override { return doc_->path; }

private:
    std::shared_ptr<const JsonDoc> doc_;
    const Json* value_;
    std::string name_, path_;
};

// What Json::parse does (the DOM-building SAX parser), but an error also records where it happened:
// nlohmann's number-overflow error (out_of_range.406, "1e400") carries no position of its own.
struct LocatingParser : nlohmann::detail::json_sax_dom_parser<Json> {
    using json_sax_dom_parser::json_sax_dom_parser;
    size_t errorEnd = 0;     // characters read when the error was found (just past the bad token)
    std::string errorToken;  // the token nlohmann was looking at
    template <class Exception> bool parse_error(size_t position, const std::string& token, const Exception& ex) {
        errorEnd = position;
        errorToken = token;
        throw ex;
    }
};

// "path:line:col" of 0-based byte offset `off` in data.
std::string lineCol(const std::string& path, const std::string& data, size_t off) {
    size_t line = 1, col = 1;
    for (size_t i = 0; i < off && i < data.size(); ++i) {
        if (data[i] == '\n') { ++line; col = 1; } else ++col;
    }
    return path + ":" + std::to_string(line) + ":" + std::to_string(col);
}

// nlohmann's message without its "[json.exception.parse_error.101] parse error at line 1, column 2: "
// prefix (the location is given separately).
std::string plainMessage(const std::exception& e) {
    std::string msg = e.what();
    size_t colon = msg.find(": ");
    if (colon != std::string::npos) return msg.substr(colon + 2);
    size_t bracket = msg.find("] ");
    return bracket != std::string::npos ? msg.substr(bracket + 2) : msg;
}

}  // namespace

SceneNodePtr parseJsonScene(const std::string& path, const std::string& data) {
    auto doc = std::make_shared<JsonDoc>();
    doc->path = path;
    LocatingParser parser(doc->root);
    try {
        Json::sax_parse(data, &parser);
    } catch (const Json::parse_error& e) {
        // e.byte is 1-based (the offending character).
        throw Error(lineCol(path, data, e.byte > 0 ? e.byte - 1 : 0) + ": " + plainMessage(e));
    } catch (const Json::exception& e) {
        // Number overflow: the token ends where the parser stopped.
        size_t end = std::min(parser.errorEnd, data.size());
        size_t start = end >= parser.errorToken.size() ? end - parser.errorToken.size() : 0;
        throw Error(lineCol(path, data, start) + ": " + plainMessage(e) + " (beyond the range of a double)");
    }
    if (!doc->root.is_object() || !doc->root.contains("Scene") || !doc->root["Scene"].is_object())
        throw Error(path + ": the top-level object has no \"Scene\" object");
    if (doc->root.size() != 1) throw Error(path + ": the top-level object has keys besides \"Scene\"");
    const Json* scene = &doc->root["Scene"];
    return std::make_shared<JsonNode>(doc, scene, "Scene", "Scene");
}

}  // namespace clrt
