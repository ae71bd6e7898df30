// The scene walker (scene_walker.h): the walk of <Scene> through its table of element readers, the
// shared reading helpers (numbers, vectors, booleans, ids, children, binary files, warnings about
// unknown elements with their file:line:col) and loadScene (scene_loader.h). Reads <Scene> itself; its
// children are read by the family files read_*.cpp, one row of sceneElements() each.
// VertexData/TexCoordData/Faces may carry a binaryFile attribute instead of text (course hw6 text): a
// little-endian int32 count (vertices, texture coordinates, faces), then the float32 x y z / u v or
// int32 index triples; the size must match the count (no shared scene uses it).
#include "scene/scene_walker.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>

#include "scene/scene_loader.h"
#include "util/error.h"

namespace clrt {
namespace walker {

namespace fs = std::filesystem;

// The children of <Scene>, in the order they are read (see scene_walker.h). Adding an element: its
// reader in its family's file (declared in scene_walker.h) and one row here.
static const std::vector<ElementReader>& sceneElements() {
    static const std::vector<ElementReader> table = {
        {"BackgroundColor", readBackgroundColor, true},
        {"ShadowRayEpsilon", readShadowRayEpsilon, true},
        {"IntersectionTestEpsilon", readIntersectionEpsilon, true},
        {"MaxRecursionDepth", readMaxRecursionDepth, true},
        {"ZeroBasedIndexing", readZeroBasedIndexing, true},
        {"Transformations", readTransformations},
        {"VertexData", readVertexData},
        {"TexCoordData", readTexCoordData},
        {"BRDFs", readBrdfs},
        {"Materials", readMaterials},
        {"Textures", readTextures},
        {"Cameras", readCameras},
        {"Lights", readLights},
        {"Objects", readObjects},
    };
    return table;
}

// ---- Text and messages -----------------------------------------------------------------------------

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}
std::string trim(const std::string& s) {
    size_t b = s.find_first_not_of(" \t\r\n\f\v");
    if (b == std::string::npos) return "";
    size_t e = s.find_last_not_of(" \t\r\n\f\v");
    return s.substr(b, e - b + 1);
}
static bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

void fail(const SceneNode& n, const std::string& msg) { throw Error(n.location() + ": " + msg); }

std::string describe(const SceneNode& n) {
    auto id = n.attribute("id");
    return id ? n.name() + " id=" + trim(*id) : n.name();
}

// ---- Values of a node's text -----------------------------------------------------------------------

// One whitespace-separated token [p, tokEnd) of n's text as a finite double within float range.
static double numberToken(const SceneNode& n, const char* p, const char* tokEnd) {
    char* e = nullptr;
    double v = std::strtod(p, &e);
    if (e != tokEnd || !std::isfinite(v))
        fail(n, "<" + n.name() + ">: '" + std::string(p, tokEnd) + "' is not a number");
    // Every value ends up a float (or an int, checked by toInteger): converting one beyond float
    // range is undefined and would give an infinity.
    if (std::fabs(v) > double(std::numeric_limits<float>::max()))
        fail(n, "<" + n.name() + ">: '" + std::string(p, tokEnd) + "' is out of range (beyond a 32-bit float)");
    return v;
}

std::vector<double> numbers(const SceneNode& n) {
    std::vector<double> out;
    std::string t = n.text();
    const char* p = t.c_str();
    const char* end = p + t.size();
    while (p < end) {
        while (p < end && isSpace(*p)) ++p;
        if (p >= end) break;
        const char* tokEnd = p;
        while (tokEnd < end && !isSpace(*tokEnd)) ++tokEnd;
        out.push_back(numberToken(n, p, tokEnd));
        p = tokEnd;
    }
    return out;
}

std::vector<double> numbers(const SceneNode& n, size_t count) {
    auto v = numbers(n);
    if (v.size() != count)
        fail(n, "<" + n.name() + "> has " + std::to_string(v.size()) + " value" + (v.size() == 1 ? "" : "s") +
                    ", expected " + std::to_string(count));
    return v;
}

double toInteger(const SceneNode& n, double v) {
    if (v != std::floor(v) || std::fabs(v) > 2147483647.0) {
        char buf[48];
        std::snprintf(buf, sizeof buf, "%.10g", v);
        fail(n, "<" + n.name() + ">: '" + buf + "' is not an integer in [-2147483647, 2147483647]");
    }
    return v;
}

// A count above which the renderer would only spend unbounded time: values over `limit` (any size,
// 1e12 included) are capped to it with a warning naming the file.
int cappedInteger(const SceneNode& n, int limit) {
    double v = numbers(n, 1)[0];
    if (v != std::floor(v)) fail(n, "<" + n.name() + ">: '" + std::to_string(v) + "' is not an integer");
    if (v <= double(limit)) return int(std::max(v, -1.0));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.15g", v);
    warn(n.location() + ": " + n.name() + " " + buf + " is above the limit " + std::to_string(limit) + "; capped to " +
         std::to_string(limit));
    return limit;
}

float number(const SceneNode& n) { return float(numbers(n, 1)[0]); }
int integer(const SceneNode& n) { return int(toInteger(n, numbers(n, 1)[0])); }
Vec3 vec3(const SceneNode& n) {
    auto v = numbers(n, 3);
    return Vec3(float(v[0]), float(v[1]), float(v[2]));
}
// If |v|² overflows or underflows a float (components of 1e30 or 1e-30), v is first scaled by its
// largest component.
Vec3 unit(const Vec3& v) {
    float l = length(v);
    if (l > 0 && std::isfinite(l)) return v / l;
    float m = std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z)));
    return m > 0 && std::isfinite(m) ? normalize(v / m) : Vec3(0, 0, 0);
}
std::vector<int> integers(const SceneNode& n) {
    auto v = numbers(n);
    std::vector<int> out;
    out.reserve(v.size());
    for (double d : v) out.push_back(int(toInteger(n, d)));
    return out;
}
bool boolean(const SceneNode& n, const std::string& s, const std::string& what) {
    std::string v = lower(trim(s));
    if (v == "true" || v == "1" || v == "yes") return true;
    if (v == "false" || v == "0" || v == "no") return false;
    fail(n, what + ": '" + s + "' is not true or false");
}

// ---- Children, attributes, ids ---------------------------------------------------------------------

SceneNodePtr need(const SceneNode& parent, const std::string& name) {
    auto c = parent.child(name);
    if (!c) fail(parent, describe(parent) + " has no <" + name + ">");
    return c;
}

int intAttribute(const SceneNode& n, const std::string& attr, int dflt) {
    auto a = n.attribute(attr);
    if (!a) return dflt;
    std::string s = trim(*a);
    char* e = nullptr;
    errno = 0;
    long v = std::strtol(s.c_str(), &e, 10);
    if (s.empty() || *e != '\0') fail(n, describe(n) + ": attribute " + attr + "='" + *a + "' is not an integer");
    if (errno == ERANGE || v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
        fail(n, describe(n) + ": attribute " + attr + "='" + *a + "' is out of range");
    return int(v);
}

int requiredId(const SceneNode& n) {
    if (!n.attribute("id")) fail(n, "<" + n.name() + "> has no id attribute");
    return intAttribute(n, "id", 0);
}

// ---- The walk --------------------------------------------------------------------------------------

std::string Walker::resolve(const std::string& rel) const {
    fs::path p(trim(rel));
    if (p.is_relative() && !dir.empty()) p = fs::path(dir) / p;
    return p.lexically_normal().string();
}

void Walker::checkChildren(const SceneNode& n, std::initializer_list<const char*> known) {
    checkChildren(n, std::vector<std::string>(known.begin(), known.end()));
}
void Walker::checkChildren(const SceneNode& n, const std::vector<std::string>& known) {
    for (auto& c : n.children()) {
        std::string cn = c->name();
        if (std::find(known.begin(), known.end(), cn) != known.end()) continue;
        std::string key = n.name() + "/" + cn;
        if (warnedUnknown.insert(key).second)
            warnOnce(c->location() + ": unknown element <" + cn + "> in <" + n.name() + "> ignored");
    }
}

void Walker::readInTableOrder(const SceneNode& n, const std::vector<ElementReader>& table) {
    std::vector<std::string> known;
    for (const ElementReader& row : table) known.push_back(row.name);
    checkChildren(n, known);
    for (const ElementReader& row : table) {
        if (row.firstOnly) {
            if (auto c = n.child(row.name)) row.read(*this, *c);
            continue;
        }
        for (auto& c : n.children(row.name)) row.read(*this, *c);
    }
}

static std::vector<uint8_t> readBinary(const SceneNode& n, const std::string& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) fail(n, describe(n) + ": cannot open binaryFile '" + path + "': not a regular file");
    std::ifstream f(path, std::ios::binary);
    if (!f) fail(n, describe(n) + ": cannot open binaryFile '" + path + "'");
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

std::vector<uint32_t> Walker::binaryWords(const SceneNode& n, const std::string& file, const char* records,
                                          size_t perRecord) const {
    auto bytes = readBinary(n, resolve(file));
    auto word = [&](size_t i) {
        return uint32_t(bytes[4 * i]) | uint32_t(bytes[4 * i + 1]) << 8 | uint32_t(bytes[4 * i + 2]) << 16 |
               uint32_t(bytes[4 * i + 3]) << 24;
    };
    if (bytes.size() < 4) fail(n, describe(n) + ": binaryFile '" + file + "' has no count (it starts with an int32 count of " + records + ")");
    const int32_t count = int32_t(word(0));
    const uint64_t expected = 4 + uint64_t(count < 0 ? 0 : count) * perRecord * 4;
    if (count < 0 || expected != bytes.size())
        fail(n, describe(n) + ": binaryFile '" + file + "' declares " + std::to_string(count) + " " + records + " (" +
                    std::to_string(expected) + " bytes with its count) but has " + std::to_string(bytes.size()) + " bytes");
    std::vector<uint32_t> out(bytes.size() / 4 - 1);
    for (size_t i = 0; i < out.size(); ++i) out[i] = word(i + 1);
    return out;
}

}  // namespace walker

Scene walkScene(const SceneNode& root, const std::string& path) {
    walker::Walker w;
    w.scene.path = path;
    w.dir = std::filesystem::path(path).parent_path().string();
    if (root.name() != "Scene") walker::fail(root, "root element is <" + root.name() + ">, expected <Scene>");
    w.readInTableOrder(root, walker::sceneElements());
    return std::move(w.scene);
}

// ---- loadScene (scene_loader.h) ------------------------------------------------------------------

Scene loadScene(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": not a file or does not exist");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path + ": cannot open for reading");
    std::string data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (f.bad()) throw Error(path + ": read error");
    size_t i = 0;
    if (data.compare(0, 3, "\xEF\xBB\xBF") == 0) i = 3;
    while (i < data.size() && std::isspace(static_cast<unsigned char>(data[i]))) ++i;
    if (i == data.size()) throw Error(path + ": file is empty");
    SceneNodePtr root;
    const bool json = data[i] == '{';  // read before the XML parser takes the text
    if (data[i] == '<') root = parseXmlScene(path, std::move(data));
    else if (json) root = parseJsonScene(path, data);
    else throw Error(path + ": neither XML (starts with '<') nor JSON (starts with '{')");
    Scene scene = walkScene(*root, path);
    // The form decides a convention in which the course's references differ by renderer (docs/scene-format.md):
    scene.backfaceCulling = json;  // the 2025 renderer culls back faces
    return scene;
}

}  // namespace clrt
