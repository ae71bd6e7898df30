// The scene walker: interprets a <Scene> SceneNode tree (from xml_node.cpp or json_node.cpp) into the
// scene model (scene.h). This is the ONE place where scene elements get their meaning. Reads:
//   Scene: BackgroundColor ShadowRayEpsilon IntersectionTestEpsilon MaxRecursionDepth ZeroBasedIndexing
//          Cameras Lights Materials Transformations VertexData TexCoordData Textures Objects
//   Camera (type=lookAt|simple, handedness=left|right): Position Gaze GazePoint Up NearPlane
//          NearDistance FovY ImageResolution ImageName NumSamples FocusDistance ApertureSize Tonemap
//          Renderer (PathTracing, DirectLighting) RendererParams
//          (TMO TMOOptions Saturation Gamma Extension)
//   Lights: AmbientLight PointLight AreaLight DirectionalLight SpotLight SphericalDirectionalLight
//   BRDFs (hw6): OriginalPhong OriginalBlinnPhong ModifiedPhong ModifiedBlinnPhong (normalized)
//          TorranceSparrow (kdfresnel), each with id and Exponent
//   Material (type, degamma, BRDF): Ambient/Diffuse/Specular/MirrorReflectance PhongExponent RefractionIndex
//          AbsorptionCoefficient AbsorptionIndex Roughness Transparency (the older course format's
//          dielectric: see readTransparency)
//   Transformations: Translation Scaling Rotation Composite
//   Textures: Images/Image, TextureMap (type, degamma) ImageId Interpolation DecalMode Normalizer
//          BumpFactor NoiseConversion NoiseScale BlackColor WhiteColor Scale Offset
//   Objects: Mesh (shadingMode) Material Textures Transformations Faces (inline | plyFile |
//          binaryFile; vertexOffset textureOffset), MeshInstance (baseMeshId resetTransform),
//          Triangle (Indices), Sphere (Center Radius), Plane (Point Normal; JSON 2025 scenes), LightMesh (as Mesh
//          + Radiance), LightSphere (as Sphere + Radiance): a shape and a light each.
//          Mesh, MeshInstance, Triangle and Sphere take MotionBlur (a translation over the shutter); object
//          lights do not (their sampling data are the rest position).
// VertexData/TexCoordData/Faces may carry a binaryFile attribute instead of text (course hw6 text): a
// little-endian int32 count (vertices, texture coordinates, faces), then the float32 x y z / u v or
// int32 index triples; the size must match the count (no shared scene uses it).
// Errors: clrt::Error "<location>: <what>", location from SceneNode::location(). Every number must be
// finite and within float range (1e39 is an error, not an infinity), every integer within int range;
// values derived from them (degamma'd colours, camera frame) are checked to stay finite.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <unordered_map>

#include "scene/ply_reader.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "scene/scene_node.h"
#include "scene/transforms.h"
#include "shared/type_tables.h"
#include "util/error.h"

namespace clrt {
namespace {

namespace fs = std::filesystem;
using NodeList = std::vector<SceneNodePtr>;

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
bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

[[noreturn]] void fail(const SceneNode& n, const std::string& msg) { throw Error(n.location() + ": " + msg); }

// "Mesh id=3" or "Camera" — how messages name an element.
std::string describe(const SceneNode& n) {
    auto id = n.attribute("id");
    return id ? n.name() + " id=" + trim(*id) : n.name();
}

// All numbers in a node's text. `what` names the element for messages.
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
        char* e = nullptr;
        double v = std::strtod(p, &e);
        if (e != tokEnd || !std::isfinite(v))
            fail(n, "<" + n.name() + ">: '" + std::string(p, tokEnd) + "' is not a number");
        // Every value ends up a float (or an int, checked by toInteger): converting one beyond float
        // range is undefined and would give an infinity.
        if (std::fabs(v) > double(std::numeric_limits<float>::max()))
            fail(n, "<" + n.name() + ">: '" + std::string(p, tokEnd) + "' is out of range (beyond a 32-bit float)");
        out.push_back(v);
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

// A non-negative integer count above which the renderer would only spend unbounded time: values over
// `limit` (any size, 1e12 included) are capped to it with a warning naming the file.
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
// normalize(v), also when |v|² overflows or underflows a float (components of 1e30 or 1e-30): then
// v is first scaled by its largest component. 0 for a zero vector.
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

std::vector<uint8_t> readBinary(const SceneNode& n, const std::string& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) fail(n, describe(n) + ": cannot open binaryFile '" + path + "': not a regular file");
    std::ifstream f(path, std::ios::binary);
    if (!f) fail(n, describe(n) + ": cannot open binaryFile '" + path + "'");
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

struct MeshProto {
    Shape shape;
    SceneNodePtr node;
};

struct Walker {
    Scene scene;
    std::string dir;  // scene file's directory ("" = working dir)
    bool zeroBased = false;
    TransformTable transforms;
    std::vector<Vec3> vertices;
    std::vector<Vec2> texcoords;
    std::map<int, int> materialIds, imageIds, textureIds, brdfIds;
    std::set<std::string> warnedUnknown;
    std::unordered_map<std::string, int> plyMeshes;  // resolved ply path -> Scene::meshes index

    std::string resolve(const std::string& rel) const {
        fs::path p(trim(rel));
        if (p.is_relative() && !dir.empty()) p = fs::path(dir) / p;
        return p.lexically_normal().string();
    }

    // Warns once per (parent, element) about children that are not in `known`.
    void checkChildren(const SceneNode& n, std::initializer_list<const char*> known) {
        checkChildren(n, std::vector<std::string>(known.begin(), known.end()));
    }
    void checkChildren(const SceneNode& n, const std::vector<std::string>& known) {
        for (auto& c : n.children()) {
            std::string cn = c->name();
            bool ok = false;
            for (const std::string& k : known)
                if (cn == k) { ok = true; break; }
            if (ok) continue;
            std::string key = n.name() + "/" + cn;
            if (warnedUnknown.insert(key).second)
                warnOnce(c->location() + ": unknown element <" + cn + "> in <" + n.name() + "> ignored");
        }
    }

    void run(const SceneNode& root) {
        checkChildren(root, {"BackgroundColor", "ShadowRayEpsilon", "IntersectionTestEpsilon", "MaxRecursionDepth",
                             "ZeroBasedIndexing", "Cameras", "Lights", "Materials", "Transformations",
                             "VertexData", "TexCoordData", "Textures", "Objects", "BRDFs"});
        if (auto c = root.child("BackgroundColor")) scene.backgroundColor = vec3(*c);
        // Read (a malformed value is still an error) but not used: ray origins are offset robustly
        // (cl_kernels/common.cl, Ray_OffsetOrigin) and the intersection tests need no epsilon.
        for (const char* eps : {"ShadowRayEpsilon", "IntersectionTestEpsilon"})
            if (auto c = root.child(eps)) (void)number(*c);
        if (auto c = root.child("MaxRecursionDepth")) {
            scene.maxRecursionDepth = cappedInteger(*c, kMaxRecursionDepth);
            if (scene.maxRecursionDepth < 0) fail(*c, "MaxRecursionDepth must not be negative");
        }
        if (auto c = root.child("ZeroBasedIndexing")) zeroBased = boolean(*c, c->text(), "ZeroBasedIndexing");

        for (auto& t : root.children("Transformations")) readTransformations(*t);
        for (auto& v : root.children("VertexData")) readVertexData(*v);
        for (auto& v : root.children("TexCoordData")) readTexCoordData(*v);
        for (auto& b : root.children("BRDFs")) readBrdfs(*b);
        for (auto& m : root.children("Materials")) readMaterials(*m);
        for (auto& t : root.children("Textures")) readTextures(*t);
        for (auto& c : root.children("Cameras")) readCameras(*c);
        for (auto& l : root.children("Lights")) readLights(*l);
        for (auto& o : root.children("Objects")) readObjects(*o);
    }

    // ---- Transformations ---------------------------------------------------------------------
    void readTransformations(const SceneNode& n) {
        checkChildren(n, {"Translation", "Scaling", "Rotation", "Composite"});
        for (auto& c : n.children()) {
            std::string name = c->name();
            std::map<int, Mat4>* map = nullptr;
            Mat4 m;
            if (name == "Translation") {
                map = &transforms.translations;
                m = Mat4::translation(vec3(*c));
            } else if (name == "Scaling") {
                map = &transforms.scalings;
                m = Mat4::scaling(vec3(*c));
            } else if (name == "Rotation") {
                map = &transforms.rotations;
                auto v = numbers(*c, 4);
                m = makeRotation(v[0], v[1], v[2], v[3]);
                if (v[1] == 0 && v[2] == 0 && v[3] == 0) fail(*c, describe(*c) + ": rotation axis is zero");
            } else if (name == "Composite") {
                map = &transforms.composites;
                auto v = numbers(*c, 16);
                m = makeComposite(v.data());
            } else {
                continue;
            }
            int id = requiredId(*c);
            if (!map->emplace(id, m).second) fail(*c, "duplicate " + name + " id " + std::to_string(id));
        }
    }

    // ---- Vertex data -------------------------------------------------------------------------
    // A binaryFile (course hw6 text): a little-endian int32 count of records (vertices, texture
    // coordinates or faces), then exactly that many records of `perRecord` little-endian 4-byte words.
    // Returns the words after the count; the size must match the count.
    std::vector<uint32_t> binaryWords(const SceneNode& n, const std::string& file, const char* records, size_t perRecord) {
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
    std::vector<double> floatData(const SceneNode& n, const char* records, size_t perRecord) {
        if (auto bf = n.attribute("binaryFile")) {
            auto words = binaryWords(n, *bf, records, perRecord);
            std::vector<double> out(words.size());
            for (size_t i = 0; i < out.size(); ++i) {
                float f;
                std::memcpy(&f, &words[i], 4);
                if (!std::isfinite(f)) fail(n, describe(n) + ": binaryFile '" + *bf + "' holds a non-finite value");
                out[i] = f;
            }
            return out;
        }
        return numbers(n);
    }
    void readVertexData(const SceneNode& n) {
        auto v = floatData(n, "vertices", 3);
        if (v.size() % 3 != 0)
            fail(n, "<VertexData> has " + std::to_string(v.size()) + " values, not a multiple of 3");
        for (size_t i = 0; i < v.size(); i += 3) vertices.emplace_back(float(v[i]), float(v[i + 1]), float(v[i + 2]));
    }
    void readTexCoordData(const SceneNode& n) {
        auto v = floatData(n, "texture coordinates", 2);
        if (v.size() % 2 != 0)
            fail(n, "<TexCoordData> has " + std::to_string(v.size()) + " values, not a multiple of 2");
        for (size_t i = 0; i < v.size(); i += 2) texcoords.push_back(Vec2{float(v[i]), float(v[i + 1])});
    }

    // A vertex index as written (1-based unless ZeroBasedIndexing) plus offset -> 0-based, checked.
    int vertexIndex(const SceneNode& n, const std::string& who, long raw, long offset) const {
        long i = raw + offset - (zeroBased ? 0 : 1);
        if (i < 0 || i >= long(vertices.size()))
            fail(n, who + ": vertex index " + std::to_string(raw) +
                        (offset ? " (+ vertexOffset " + std::to_string(offset) + ")" : std::string()) +
                        " is out of range (VertexData has " + std::to_string(vertices.size()) + " vertices, " +
                        (zeroBased ? "0-based" : "1-based") + ")");
        return int(i);
    }

    // ---- Materials ---------------------------------------------------------------------------
    // ---- BRDFs (course hw6): one element per BRDF, named by the rows of CLRT_BRDF_TABLE ------------
    void readBrdfs(const SceneNode& n) {
        for (auto& c : n.children()) readBrdf(*c);
    }
    void readBrdf(const SceneNode& n) {
        Brdf b;
        if (!lookupType(brdfTypes(), n.name(), b.type))
            fail(n, "unknown BRDF <" + n.name() + "> in <BRDFs> (expected " + typeNames(brdfTypes()) + ")");
        checkChildren(n, {"Exponent"});
        b.id = requiredId(n);
        if (auto c = n.child("Exponent")) {
            b.exponent = number(*c);
            if (!(b.exponent >= 0)) fail(*c, describe(n) + ": <Exponent> must not be negative");
        }
        if (auto a = n.attribute("normalized")) b.normalized = boolean(n, *a, describe(n) + ": normalized");
        if (auto a = n.attribute("kdfresnel")) b.kdFresnel = boolean(n, *a, describe(n) + ": kdfresnel");
        if (!brdfIds.emplace(b.id, int(scene.brdfs.size())).second)
            fail(n, "duplicate BRDF id " + std::to_string(b.id));
        scene.brdfs.push_back(b);
    }

    void readMaterials(const SceneNode& n) {
        checkChildren(n, {"Material"});
        for (auto& c : n.children("Material")) readMaterial(*c);
    }
    void readMaterial(const SceneNode& n) {
        checkChildren(n, {"AmbientReflectance", "DiffuseReflectance", "SpecularReflectance", "MirrorReflectance",
                          "PhongExponent", "RefractionIndex", "AbsorptionCoefficient", "AbsorptionIndex",
                          "Roughness", "Transparency"});
        Material m;
        m.id = requiredId(n);
        std::string type = lower(trim(n.attribute("type").value_or("")));
        if (type.empty() || type == "phong") type = typeRow(materialTypes(), dev::MATERIAL_BLINN_PHONG).name;
        if (!lookupType(materialTypes(), type, m.type))
            fail(n, describe(n) + ": unknown material type '" + *n.attribute("type") + "'");
        bool degamma = false;
        if (auto d = n.attribute("degamma")) degamma = boolean(n, *d, describe(n) + ": degamma");
        auto colour = [&](const char* name, Vec3& out) {
            if (auto c = n.child(name)) {
                out = vec3(*c);
                if (degamma)
                    out = Vec3(std::pow(out.x, 2.2f), std::pow(out.y, 2.2f), std::pow(out.z, 2.2f));
                if (!isFinite(out))  // pow of a negative value, or beyond float range
                    fail(*c, describe(n) + ": <" + name + "> is not finite after degamma (negative, or overflows a 32-bit float)");
            }
        };
        colour("AmbientReflectance", m.ambient);
        colour("DiffuseReflectance", m.diffuse);
        colour("SpecularReflectance", m.specular);
        colour("MirrorReflectance", m.mirror);
        if (auto c = n.child("PhongExponent")) m.phongExponent = number(*c);
        if (auto c = n.child("RefractionIndex")) m.refractionIndex = number(*c);
        if (auto c = n.child("AbsorptionIndex")) m.absorptionIndex = number(*c);
        if (auto c = n.child("Roughness")) m.roughness = number(*c);
        if (auto c = n.child("AbsorptionCoefficient")) {
            auto v = numbers(*c);
            if (v.size() == 1) m.absorptionCoefficient = Vec3(float(v[0]));
            else if (v.size() == 3) m.absorptionCoefficient = Vec3(float(v[0]), float(v[1]), float(v[2]));
            else fail(*c, "<AbsorptionCoefficient> has " + std::to_string(v.size()) + " values, expected 1 or 3");
        }
        if (auto c = n.child("Transparency")) readTransparency(n, *c, m);
        if (n.attribute("BRDF")) {
            int id = intAttribute(n, "BRDF", 0);
            auto it = brdfIds.find(id);
            if (it == brdfIds.end()) fail(n, describe(n) + ": BRDF " + std::to_string(id) + " is not defined in <BRDFs>");
            m.brdf = it->second;
        }
        if (!materialIds.emplace(m.id, int(scene.materials.size())).second)
            fail(n, "duplicate Material id " + std::to_string(m.id));
        scene.materials.push_back(m);
    }

    // <Transparency>T</Transparency> with <RefractionIndex>: the course's older material format (kept in
    // hw6's cornellbox_jaroslav_path_diffuse.xml; the students' parsers of that format make a material
    // refractive when T is non-zero, split reflection and refraction by Fresnel, and weight light that
    // crossed the inside by T^d, d the distance travelled: T is the fraction kept per unit distance).
    // That is this renderer's dielectric with Beer's coefficient -ln T, added to any
    // <AbsorptionCoefficient>; a channel with T = 0 keeps nothing. T = 0 0 0 leaves the material opaque.
    void readTransparency(const SceneNode& n, const SceneNode& c, Material& m) {
        auto v = numbers(c);
        if (v.size() != 1 && v.size() != 3)
            fail(c, describe(n) + ": <Transparency> has " + std::to_string(v.size()) + " values, expected 1 or 3");
        if (v.size() == 1) v.assign(3, v[0]);
        for (double t : v)
            if (!(t >= 0.0 && t <= 1.0))
                fail(c, describe(n) + ": <Transparency> " + trim(c.text()) +
                            ": each value is the fraction of light kept per unit distance, in [0, 1]");
        if (v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0) return;
        if (auto type = n.attribute("type"); type && m.type != dev::MATERIAL_DIELECTRIC)
            fail(c, describe(n) + ": <Transparency> makes a dielectric, but the material has type=\"" + *type + "\"");
        m.type = dev::MATERIAL_DIELECTRIC;
        float* a[3] = {&m.absorptionCoefficient.x, &m.absorptionCoefficient.y, &m.absorptionCoefficient.z};
        for (int k = 0; k < 3; ++k)
            *a[k] = v[k] > 0.0 ? *a[k] - float(std::log(v[k])) : std::numeric_limits<float>::max();
    }

    // ---- Textures ----------------------------------------------------------------------------
    void readTextures(const SceneNode& n) {
        checkChildren(n, {"Images", "TextureMap"});
        for (auto& imgs : n.children("Images")) {
            checkChildren(*imgs, {"Image"});
            for (auto& img : imgs->children("Image")) {
                int id = requiredId(*img);
                std::string p = trim(img->text());
                if (p.empty()) fail(*img, describe(*img) + " has no path");
                if (!imageIds.emplace(id, int(scene.imagePaths.size())).second)
                    fail(*img, "duplicate Image id " + std::to_string(id));
                scene.imagePaths.push_back(resolve(p));
            }
        }
        for (auto& tm : n.children("TextureMap")) readTextureMap(*tm);
    }
    int imageRef(const SceneNode& owner, const SceneNode& idNode) {
        int id = integer(idNode);
        auto it = imageIds.find(id);
        if (it == imageIds.end()) fail(idNode, describe(owner) + " references undefined Image " + std::to_string(id));
        return it->second;
    }
    void readTextureMap(const SceneNode& n) {
        checkChildren(n, {"ImageId", "Interpolation", "DecalMode", "Normalizer", "BumpFactor", "NoiseConversion",
                          "NoiseScale", "BlackColor", "WhiteColor", "Scale", "Offset"});
        Texture t;
        t.id = requiredId(n);
        auto typeAttr = n.attribute("type");
        if (!typeAttr) fail(n, describe(n) + " has no type attribute (image, perlin or checkerboard)");
        std::string type = lower(trim(*typeAttr));
        if (!lookupType(textureTypes(), type, t.type)) fail(n, describe(n) + ": unknown texture type '" + *typeAttr + "'");
        if (auto d = n.attribute("degamma")) t.degamma = boolean(n, *d, describe(n) + ": degamma");
        if (t.type == dev::TEXTURE_IMAGE) t.imageIndex = imageRef(n, *need(n, "ImageId"));
        if (auto c = n.child("Interpolation")) {
            std::string v = lower(trim(c->text()));
            if (!lookupType(interpolations(), v, t.interpolation))
                fail(*c, "<Interpolation>: unknown value '" + trim(c->text()) + "' (nearest, bilinear, trilinear)");
        }
        if (auto c = n.child("DecalMode")) {
            std::string v = lower(trim(c->text()));
            if (!lookupType(decalModes(), v, t.decalMode)) fail(*c, "<DecalMode>: unknown value '" + trim(c->text()) + "'");
        }
        if (auto c = n.child("Normalizer")) {
            t.normalizer = number(*c);
            t.normalizerGiven = true;
            if (t.normalizer <= 0) fail(*c, "<Normalizer> must be positive");
        } else if (t.type == dev::TEXTURE_IMAGE) {
            std::string ext = lower(fs::path(scene.imagePaths[size_t(t.imageIndex)]).extension().string());
            if (ext == ".exr" || ext == ".hdr") t.normalizer = 1;
        }
        if (auto c = n.child("BumpFactor")) t.bumpFactor = number(*c);
        if (auto c = n.child("NoiseConversion")) {
            std::string v = lower(trim(c->text()));
            if (v != "linear" && v != "absval")
                fail(*c, "<NoiseConversion>: unknown value '" + trim(c->text()) + "' (linear or absval)");
            t.noiseConversion = v;
        }
        if (auto c = n.child("NoiseScale")) t.noiseScale = number(*c);
        if (auto c = n.child("BlackColor")) t.blackColor = vec3(*c);
        if (auto c = n.child("WhiteColor")) t.whiteColor = vec3(*c);
        if (auto c = n.child("Scale")) t.scale = number(*c);
        if (auto c = n.child("Offset")) t.offset = number(*c);
        if (!textureIds.emplace(t.id, int(scene.textures.size())).second)
            fail(n, "duplicate TextureMap id " + std::to_string(t.id));
        scene.textures.push_back(t);
    }

    // ---- Cameras -----------------------------------------------------------------------------
    void readCameras(const SceneNode& n) {
        checkChildren(n, {"Camera"});
        for (auto& c : n.children("Camera")) readCamera(*c);
    }
    void readCamera(const SceneNode& n) {
        checkChildren(n, {"Position", "Gaze", "GazePoint", "Up", "NearPlane", "NearDistance", "FovY",
                          "ImageResolution", "ImageName", "NumSamples", "FocusDistance", "ApertureSize",
                          "Tonemap", "Renderer", "RendererParams"});
        Camera cam;
        cam.id = intAttribute(n, "id", 0);
        std::string who = describe(n);
        std::string type = lower(trim(n.attribute("type").value_or("")));
        bool lookAt = type == "lookat";
        if (!lookAt && !type.empty() && type != "simple")
            fail(n, who + ": unknown camera type '" + *n.attribute("type") + "' (lookAt or simple)");
        bool left = false;
        if (auto h = n.attribute("handedness")) {
            std::string v = lower(trim(*h));
            if (v == "left") left = true;
            else if (v != "right") fail(n, who + ": handedness='" + *h + "' is not left or right");
        }
        cam.position = vec3(*need(n, "Position"));
        Vec3 up = vec3(*need(n, "Up"));
        auto resNode = need(n, "ImageResolution");
        auto res = numbers(*resNode, 2);
        cam.width = int(toInteger(*resNode, res[0]));
        cam.height = int(toInteger(*resNode, res[1]));
        if (cam.width <= 0 || cam.height <= 0)
            fail(*resNode, who + ": ImageResolution must be positive, got " + trim(resNode->text()));
        auto nearNode = need(n, "NearDistance");
        cam.nearDistance = number(*nearNode);
        if (!(cam.nearDistance > 0)) fail(*nearNode, who + ": NearDistance must be positive");

        Vec3 gaze;
        if (lookAt) {
            // The course's hw6 lookAt cameras give <Gaze> (a direction) instead of <GazePoint>; their
            // references line up with GazePoint = Position + Gaze.
            auto pointNode = n.child("GazePoint"), dirNode = n.child("Gaze");
            if (pointNode && dirNode) fail(*dirNode, who + ": give <GazePoint> or <Gaze>, not both");
            if (dirNode) gaze = vec3(*dirNode);
            else gaze = vec3(*need(n, "GazePoint")) - cam.position;
            auto fovNode = need(n, "FovY");
            float fovY = number(*fovNode);
            if (!(fovY > 0 && fovY < 180)) fail(*fovNode, who + ": FovY must be in (0, 180) degrees");
            cam.top = cam.nearDistance * float(std::tan(double(fovY) * M_PI / 360.0));
            cam.bottom = -cam.top;
            cam.right = cam.top * float(cam.width) / float(cam.height);
            cam.left = -cam.right;
        } else {
            auto gazeNode = need(n, "Gaze");
            gaze = vec3(*gazeNode);
            auto planeNode = need(n, "NearPlane");
            auto p = numbers(*planeNode, 4);
            cam.left = float(p[0]);
            cam.right = float(p[1]);
            cam.bottom = float(p[2]);
            cam.top = float(p[3]);
            if (!(cam.left < cam.right) || !(cam.bottom < cam.top))
                fail(*planeNode, who + ": NearPlane needs left < right and bottom < top");
        }
        if (!isFinite(gaze)) fail(n, who + ": the gaze direction overflows a 32-bit float");
        if (!(cam.left >= -FLT_MAX && cam.right <= FLT_MAX && cam.bottom >= -FLT_MAX && cam.top <= FLT_MAX))
            fail(n, who + ": the image plane overflows a 32-bit float");
        if (length(unit(gaze)) == 0) fail(n, who + ": gaze direction is zero");
        cam.w = -unit(gaze);
        cam.u = unit(cross(unit(up), cam.w));
        if (length(cam.u) == 0) fail(n, who + ": Up is parallel to the gaze direction");
        if (!isFinite(cam.u) || !isFinite(cam.w)) fail(n, who + ": the camera frame overflows a 32-bit float");
        cam.v = cross(cam.w, cam.u);
        if (left) cam.u = -cam.u;

        auto nameNode = need(n, "ImageName");
        cam.imageName = trim(nameNode->text());
        if (cam.imageName.empty()) fail(*nameNode, who + ": ImageName is empty");
        if (auto c = n.child("NumSamples")) {
            cam.numSamples = cappedInteger(*c, kMaxSamplesPerPixel);
            if (cam.numSamples < 1) fail(*c, who + ": NumSamples must be at least 1");
        }
        if (auto c = n.child("FocusDistance")) cam.focusDistance = number(*c);
        if (auto c = n.child("ApertureSize")) cam.apertureSize = number(*c);
        if (cam.focusDistance < 0 || cam.apertureSize < 0) fail(n, who + ": FocusDistance and ApertureSize must not be negative");
        for (auto& t : n.children("Tonemap")) cam.tonemaps.push_back(readTonemap(*t));
        cam.pathMode = readRenderer(n, who);
        scene.cameras.push_back(cam);
    }
    // <Renderer>PathTracing</Renderer> and its optional <RendererParams> (course hw6): the CLRT_PATH_*
    // bits, or 0 without <Renderer> or with <Renderer>DirectLighting</Renderer> (classic ray tracing). Empty or missing params: uniform sampling.
    // MultipleImportanceSampling is clrt's own option (README "Path tracing").
    int readRenderer(const SceneNode& n, const std::string& who) {
        auto rNode = n.child("Renderer");
        auto pNode = n.child("RendererParams");
        if (!rNode) {
            if (pNode) fail(*pNode, who + ": <RendererParams> needs <Renderer>PathTracing</Renderer>");
            return 0;
        }
        std::string r = trim(rNode->text());
        if (r == "DirectLighting") {  // the course's name (2021 text) for the default, classic ray tracer
            if (pNode && !trim(pNode->text()).empty())
                fail(*pNode, who + ": <RendererParams> needs <Renderer>PathTracing</Renderer> (DirectLighting takes none)");
            return 0;
        }
        if (r != "PathTracing") fail(*rNode, who + ": unknown renderer '" + r + "' (PathTracing, DirectLighting)");
        int mode = CLRT_PATH_ON;
        if (!pNode) return mode;
        std::istringstream in(pNode->text());
        for (std::string tok; in >> tok;) {
            if (tok == "NextEventEstimation") mode |= CLRT_PATH_NEE;
            else if (tok == "ImportanceSampling") mode |= CLRT_PATH_IMPORTANCE;
            else if (tok == "RussianRoulette") mode |= CLRT_PATH_RR;
            else if (tok == "MultipleImportanceSampling") mode |= CLRT_PATH_MIS;
            else
                fail(*pNode, who + ": unknown RendererParams option '" + tok +
                                 "' (NextEventEstimation, ImportanceSampling, RussianRoulette, MultipleImportanceSampling)");
        }
        return mode;
    }
    TonemapSettings readTonemap(const SceneNode& n) {
        checkChildren(n, {"TMO", "TMOOptions", "Saturation", "Gamma", "Extension"});
        TonemapSettings t;
        if (auto c = n.child("TMO")) {
            std::string v = lower(trim(c->text()));
            if (!lookupType(tonemapOperators(), v, t.op))
                fail(*c, "<TMO>: unknown operator '" + trim(c->text()) + "' (Photographic, ACES or Filmic)");
        }
        if (auto c = n.child("TMOOptions")) {
            auto v = numbers(*c);
            if (v.empty() || v.size() > 2)
                fail(*c, "<TMOOptions> has " + std::to_string(v.size()) + " values, expected key [burn_percent]");
            t.key = float(v[0]);
            if (v.size() > 1) t.burnPercent = float(v[1]);
            if (!(t.key > 0)) fail(*c, "<TMOOptions>: key must be positive");
            if (t.burnPercent < 0 || t.burnPercent > 100) fail(*c, "<TMOOptions>: burn_percent must be in [0, 100]");
        }
        if (auto c = n.child("Saturation")) t.saturation = number(*c);
        if (auto c = n.child("Gamma")) {
            if (lower(trim(c->text())) == "srgb") {  // some versions of the course's files
                t.srgb = true;
            } else {
                t.gamma = number(*c);
                if (!(t.gamma > 0)) fail(*c, "<Gamma> must be positive (or sRGB)");
            }
        }
        if (auto c = n.child("Extension")) t.extension = trim(c->text());
        return t;
    }

    // ---- Lights ------------------------------------------------------------------------------
    // The light elements are the names of lightTypes() (src/shared/type_tables.h); readLight() reads
    // the parameters of each type.
    void readLights(const SceneNode& n) {
        std::vector<std::string> known = {"AmbientLight"};
        for (const auto& row : lightTypes()) known.push_back(row.name);
        checkChildren(n, known);
        for (auto& c : n.children()) {
            std::string name = c->name();
            const SceneNode& l = *c;
            Light light;
            light.id = intAttribute(l, "id", 0);
            if (name == "AmbientLight") {
                scene.ambientLight = vec3(l);
                continue;
            }
            const TypeRow<dev::LightKind>* row = findType(lightTypes(), name);
            if (!row) continue;
            light.type = row->kind;
            readLight(l, light);
            scene.lights.push_back(light);
        }
    }
    void readLight(const SceneNode& l, Light& light) {
        switch (light.type) {
        case dev::LIGHT_POINT:
            checkChildren(l, {"Position", "Intensity"});
            light.position = vec3(*need(l, "Position"));
            light.intensity = vec3(*need(l, "Intensity"));
            break;
        case dev::LIGHT_AREA: {
            checkChildren(l, {"Position", "Normal", "Size", "Radiance"});
            light.position = vec3(*need(l, "Position"));
            auto nn = need(l, "Normal");
            light.direction = unit(vec3(*nn));
            if (length(light.direction) == 0) fail(*nn, describe(l) + ": Normal is zero");
            auto sn = need(l, "Size");
            light.size = number(*sn);
            if (!(light.size > 0)) fail(*sn, describe(l) + ": Size must be positive");
            if (!std::isfinite(light.size * light.size)) fail(*sn, describe(l) + ": Size² overflows a 32-bit float");
            light.intensity = vec3(*need(l, "Radiance"));
            break;
        }
        case dev::LIGHT_DIRECTIONAL: {
            checkChildren(l, {"Direction", "Radiance"});
            auto dn = need(l, "Direction");
            light.direction = unit(vec3(*dn));
            if (length(light.direction) == 0) fail(*dn, describe(l) + ": Direction is zero");
            light.intensity = vec3(*need(l, "Radiance"));
            break;
        }
        case dev::LIGHT_SPOT: {
            checkChildren(l, {"Position", "Direction", "Intensity", "CoverageAngle", "FalloffAngle", "FallOffAngle"});
            light.position = vec3(*need(l, "Position"));
            auto dn = need(l, "Direction");
            light.direction = unit(vec3(*dn));
            if (length(light.direction) == 0) fail(*dn, describe(l) + ": Direction is zero");
            light.intensity = vec3(*need(l, "Intensity"));
            light.coverageAngle = number(*need(l, "CoverageAngle"));
            auto fo = l.child("FalloffAngle");
            if (!fo) fo = l.child("FallOffAngle");
            if (!fo) fail(l, describe(l) + " has no <FalloffAngle>");
            light.falloffAngle = number(*fo);
            if (!(light.coverageAngle > 0) || light.falloffAngle < 0 || light.falloffAngle > light.coverageAngle)
                fail(l, describe(l) + ": need 0 <= FalloffAngle <= CoverageAngle and CoverageAngle > 0");
            break;
        }
        case dev::LIGHT_ENVIRONMENT: {
            checkChildren(l, {"ImageId", "Type", "Sampler"});
            light.imageIndex = imageRef(l, *need(l, "ImageId"));
            std::optional<std::string> type = l.attribute("type");
            if (!type)
                if (auto c = l.child("Type")) type = c->text();
            if (type && !lookupType(envMappings(), lower(trim(*type)), light.mapping))
                fail(l, describe(l) + ": unknown type '" + *type + "' (latlong or probe)");
            std::optional<std::string> sampler = l.attribute("sampler");
            if (!sampler)
                if (auto c = l.child("Sampler")) sampler = c->text();
            if (sampler && !lookupType(envStrategies(), lower(trim(*sampler)), light.envStrategy))
                fail(l, describe(l) + ": unknown sampler '" + *sampler + "' (" + typeNames(envStrategies()) + ")");
            break;
        }
        case dev::LIGHT_MESH:
        case dev::LIGHT_SPHERE:  // shapes as well as lights: readObjectLight()
            fail(l, "<" + l.name() + "> is an object: it belongs in <Objects>, not in <Lights>");
        }
    }

    // ---- Objects -----------------------------------------------------------------------------
    static std::string sourceOf(const SceneNode& n) { return describe(n) + " (" + n.location() + ")"; }

    int materialRef(const SceneNode& owner, const SceneNode& matNode) {
        int id = integer(matNode);
        auto it = materialIds.find(id);
        if (it == materialIds.end())
            fail(matNode, describe(owner) + " references undefined Material " + std::to_string(id));
        return it->second;
    }
    std::vector<int> textureRefs(const SceneNode& owner, const SceneNode& texNode) {
        std::vector<int> out;
        for (int id : integers(texNode)) {
            auto it = textureIds.find(id);
            if (it == textureIds.end())
                fail(texNode, describe(owner) + " references undefined TextureMap " + std::to_string(id));
            out.push_back(it->second);
        }
        return out;
    }
    Mat4 transformOf(const SceneNode& owner) {
        auto t = owner.child("Transformations");
        if (!t) return Mat4::identity();
        return composeTransforms(t->text(), transforms, t->location() + ": " + describe(owner));
    }
    // <MotionBlur>x y z</MotionBlur>: a world-space translation over the shutter interval [0, 1],
    // applied after the object's transformations (the object sits at transform, then + time·motion).
    Vec3 motionOf(const SceneNode& owner) {
        auto c = owner.child("MotionBlur");
        return c ? vec3(*c) : Vec3(0, 0, 0);
    }
    bool smoothOf(const SceneNode& n, bool dflt) {
        auto a = n.attribute("shadingMode");
        if (!a) return dflt;
        std::string v = lower(trim(*a));
        if (v == "smooth") return true;
        if (v == "flat") return false;
        fail(n, describe(n) + ": shadingMode='" + *a + "' is not smooth or flat");
    }
    bool hasImageTexture(const std::vector<int>& tex) const {
        for (int t : tex)
            if (scene.textures[size_t(t)].type == dev::TEXTURE_IMAGE) return true;
        return false;
    }

    // Compact per-object MeshData from global-vertex triangles. uvIdx: per corner TexCoordData index.
    MeshData compactMesh(const SceneNode& n, const std::string& who, const std::vector<int>& corners,
                         const std::vector<long>& uvIdx, bool needUv) {
        MeshData md;
        std::unordered_map<int, int> local;
        md.indices.reserve(corners.size());
        std::vector<long> vertUv;
        for (size_t k = 0; k < corners.size(); ++k) {
            auto [it, inserted] = local.emplace(corners[k], int(md.positions.size()));
            if (inserted) {
                md.positions.push_back(vertices[size_t(corners[k])]);
                vertUv.push_back(uvIdx[k]);
            }
            md.indices.push_back(it->second);
        }
        if (!texcoords.empty()) {
            bool allIn = true;
            for (long u : vertUv)
                if (u < 0 || u >= long(texcoords.size())) { allIn = false; break; }
            if (allIn) {
                for (long u : vertUv) md.uvs.push_back(texcoords[size_t(u)]);
            } else if (needUv) {
                warnOnce(n.location() + ": " + who + ": texture coordinate index out of range (TexCoordData has " +
                         std::to_string(texcoords.size()) + " pairs); the mesh gets no texture coordinates");
            }
        } else if (needUv) {
            warnOnce(n.location() + ": " + who + " has an image texture but the scene has no TexCoordData");
        }
        return md;
    }

    std::vector<int32_t> faceData(const SceneNode& faces) {
        if (auto bf = faces.attribute("binaryFile")) {
            auto words = binaryWords(faces, *bf, "faces", 3);
            return std::vector<int32_t>(words.begin(), words.end());
        }
        auto v = integers(faces);
        return std::vector<int32_t>(v.begin(), v.end());
    }

    // Mesh and LightMesh (isLight: <Radiance> is read by readObjectLight; no MotionBlur).
    Shape readMesh(const SceneNode& n, bool isLight = false) {
        if (isLight) checkChildren(n, {"Material", "Textures", "Transformations", "Faces", "Radiance"});
        else checkChildren(n, {"Material", "Textures", "Transformations", "Faces", "MotionBlur"});
        Shape s;
        std::string who = describe(n);
        s.id = intAttribute(n, "id", 0);
        s.type = ShapeType::Mesh;
        s.source = sourceOf(n);
        s.smooth = smoothOf(n, false);
        s.materialIndex = materialRef(n, *need(n, "Material"));
        if (auto t = n.child("Textures")) s.textureIndices = textureRefs(n, *t);
        s.transform = transformOf(n);
        s.motion = motionOf(n);
        auto faces = need(n, "Faces");
        if (auto ply = faces->attribute("plyFile")) {
            std::string p = resolve(*ply);
            auto it = plyMeshes.find(p);
            if (it != plyMeshes.end()) {
                s.meshIndex = it->second;
            } else {
                MeshData md;
                try {
                    md = readPly(p);
                } catch (const Error& e) {
                    throw Error(faces->location() + ": " + who + ": " + e.what(), e.code());
                }
                s.meshIndex = int(scene.meshes.size());
                plyMeshes.emplace(p, s.meshIndex);
                scene.plyPaths.push_back(p);
                scene.meshes.push_back(std::move(md));
            }
            if (hasImageTexture(s.textureIndices) && scene.meshes[size_t(s.meshIndex)].uvs.empty())
                warnOnce(faces->location() + ": " + who + " has an image texture but PLY '" + *ply +
                         "' has no texture coordinates");
            return s;
        }
        long vOff = intAttribute(*faces, "vertexOffset", 0);
        long tOff = intAttribute(*faces, "textureOffset", 0);
        auto idx = faceData(*faces);
        if (idx.size() % 3 != 0)
            fail(*faces, who + ": <Faces> has " + std::to_string(idx.size()) + " indices, not a multiple of 3");
        if (idx.empty()) fail(*faces, who + ": <Faces> is empty");
        std::vector<int> corners(idx.size());
        std::vector<long> uv(idx.size());
        long base = zeroBased ? 0 : 1;
        for (size_t k = 0; k < idx.size(); ++k) {
            corners[k] = vertexIndex(*faces, who, idx[k], vOff);
            uv[k] = long(idx[k]) + tOff - base;
        }
        s.meshIndex = int(scene.meshes.size());
        scene.meshes.push_back(compactMesh(*faces, who, corners, uv, hasImageTexture(s.textureIndices)));
        return s;
    }

    Shape readTriangle(const SceneNode& n) {
        checkChildren(n, {"Material", "Textures", "Transformations", "Indices", "MotionBlur"});
        Shape s;
        std::string who = describe(n);
        s.id = intAttribute(n, "id", 0);
        s.type = ShapeType::Mesh;
        s.source = sourceOf(n);
        s.materialIndex = materialRef(n, *need(n, "Material"));
        if (auto t = n.child("Textures")) s.textureIndices = textureRefs(n, *t);
        s.transform = transformOf(n);
        s.motion = motionOf(n);
        auto in = need(n, "Indices");
        auto v = numbers(*in, 3);
        std::vector<int> corners(3);
        std::vector<long> uv(3);
        for (int k = 0; k < 3; ++k) {
            long raw = long(toInteger(*in, v[size_t(k)]));
            corners[size_t(k)] = vertexIndex(*in, who, raw, 0);
            uv[size_t(k)] = raw - (zeroBased ? 0 : 1);
        }
        s.meshIndex = int(scene.meshes.size());
        scene.meshes.push_back(compactMesh(*in, who, corners, uv, hasImageTexture(s.textureIndices)));
        return s;
    }

    // What spheres and planes read alike: id, Material, Textures, Transformations.
    Shape analyticShape(const SceneNode& n, ShapeType type) {
        Shape s;
        s.id = intAttribute(n, "id", 0);
        s.type = type;
        s.source = sourceOf(n);
        s.materialIndex = materialRef(n, *need(n, "Material"));
        if (auto t = n.child("Textures")) s.textureIndices = textureRefs(n, *t);
        s.transform = transformOf(n);
        return s;
    }

    // The VertexData position named by child `child` (a vertex index) of n.
    Vec3 vertexAt(const SceneNode& n, const char* child, const std::string& who) {
        auto c = need(n, child);
        return vertices[size_t(vertexIndex(*c, who, integer(*c), 0))];
    }

    // Sphere and LightSphere (isLight: <Radiance> is read by readObjectLight; no MotionBlur).
    Shape readSphere(const SceneNode& n, bool isLight = false) {
        if (isLight) checkChildren(n, {"Material", "Textures", "Transformations", "Center", "Radius", "Radiance"});
        else checkChildren(n, {"Material", "Textures", "Transformations", "Center", "Radius", "MotionBlur"});
        Shape s = analyticShape(n, ShapeType::Sphere);
        s.motion = motionOf(n);
        std::string who = describe(n);
        s.center = vertexAt(n, "Center", who);
        auto rn = need(n, "Radius");
        s.radius = number(*rn);
        if (!(s.radius > 0)) fail(*rn, who + ": Radius must be positive");
        return s;
    }

    // Plane (2025 JSON scenes): an infinite plane through vertex Point with normal Normal.
    Shape readPlane(const SceneNode& n) {
        checkChildren(n, {"Material", "Textures", "Transformations", "Point", "Normal"});
        Shape s = analyticShape(n, ShapeType::Plane);
        std::string who = describe(n);
        s.center = vertexAt(n, "Point", who);
        auto nn = need(n, "Normal");
        auto v = numbers(*nn, 3);
        s.normal = Vec3(float(v[0]), float(v[1]), float(v[2]));
        if (!(length(s.normal) > 0) || !isFinite(s.normal)) fail(*nn, who + ": Normal must be a non-zero vector");
        return s;
    }

    Shape readInstance(const SceneNode& n, const std::map<int, MeshProto>& meshes) {
        checkChildren(n, {"Material", "Textures", "Transformations", "MotionBlur"});
        std::string who = describe(n);
        if (!n.attribute("baseMeshId")) fail(n, who + " has no baseMeshId attribute");
        int baseId = intAttribute(n, "baseMeshId", 0);
        auto it = meshes.find(baseId);
        if (it == meshes.end()) fail(n, who + " references undefined Mesh " + std::to_string(baseId));
        const Shape& base = it->second.shape;
        bool reset = false;
        if (auto r = n.attribute("resetTransform")) reset = boolean(n, *r, who + ": resetTransform");
        Shape s = base;
        s.id = intAttribute(n, "id", 0);
        s.source = sourceOf(n);
        s.smooth = smoothOf(n, base.smooth);
        if (auto m = n.child("Material")) s.materialIndex = materialRef(n, *m);
        if (auto t = n.child("Textures")) s.textureIndices = textureRefs(n, *t);
        Mat4 own = transformOf(n);
        s.transform = reset ? own : own * base.transform;
        s.motion = motionOf(n);  // its own motion only: an instance of a moving mesh may stand still
        if (hasImageTexture(s.textureIndices) && scene.meshes[size_t(s.meshIndex)].uvs.empty())
            warnOnce(n.location() + ": " + who + " has an image texture but its mesh has no texture coordinates");
        return s;
    }

    void readObjects(const SceneNode& n) {
        checkChildren(n, {"Mesh", "MeshInstance", "Triangle", "Sphere", "Plane", "LightMesh", "LightSphere"});
        // Meshes first, so that instances may name a mesh defined after them.
        std::map<int, MeshProto> meshes;
        std::set<std::pair<std::string, int>> seen;  // (kind, id)
        NodeList all = n.children();
        std::vector<Shape> meshShapes;
        for (auto& c : all) {
            std::string name = c->name();
            if (name != "Mesh" && name != "MeshInstance" && name != "Triangle" && name != "Sphere") continue;
            if (name == "Mesh") {
                // Mesh ids are what instances refer to: they must be unique. (Shared scenes repeat
                // Sphere ids, so other kinds are not checked.)
                if (c->attribute("id")) {
                    int v = intAttribute(*c, "id", 0);
                    if (!seen.emplace(name, v).second) fail(*c, "duplicate Mesh id " + std::to_string(v));
                }
                Shape s = readMesh(*c);
                meshes.emplace(s.id, MeshProto{s, c});
                meshShapes.push_back(s);
            }
        }
        size_t meshK = 0;
        for (auto& c : all) {
            std::string name = c->name();
            if (name == "Mesh") scene.shapes.push_back(meshShapes[meshK++]);
            else if (name == "MeshInstance") scene.shapes.push_back(readInstance(*c, meshes));
            else if (name == "Triangle") scene.shapes.push_back(readTriangle(*c));
            else if (name == "Sphere") scene.shapes.push_back(readSphere(*c));
            else if (name == "Plane") scene.shapes.push_back(readPlane(*c));
            else if (const TypeRow<dev::LightKind>* row = findType(lightTypes(), name);
                     row && (row->kind == dev::LIGHT_MESH || row->kind == dev::LIGHT_SPHERE))
                readObjectLight(*c, row->kind);
        }
    }

    // An object light (LightMesh, LightSphere: rows of the light table that are also shapes): the
    // shape as a Mesh or Sphere reads it, plus its <Radiance>; the shape and its light point at each other.
    void readObjectLight(const SceneNode& n, dev::LightKind kind) {
        std::string who = describe(n);
        Shape s = kind == dev::LIGHT_MESH ? readMesh(n, true) : readSphere(n, true);
        s.motion = Vec3(0, 0, 0);  // <MotionBlur> is not read for object lights (warned as unknown)
        auto rn = need(n, "Radiance");
        Vec3 radiance = vec3(*rn);
        if (!isFinite(radiance) || radiance.x < 0 || radiance.y < 0 || radiance.z < 0)
            fail(*rn, who + ": Radiance must be three finite non-negative numbers");
        Light light;
        light.id = s.id;
        light.type = kind;
        light.intensity = radiance;
        light.shapeIndex = int(scene.shapes.size());
        s.lightIndex = int(scene.lights.size());
        scene.lights.push_back(light);
        scene.shapes.push_back(s);
    }
};

}  // namespace

Scene walkScene(const SceneNode& root, const std::string& path) {
    Walker w;
    w.scene.path = path;
    w.dir = fs::path(path).parent_path().string();
    if (root.name() != "Scene") fail(root, "root element is <" + root.name() + ">, expected <Scene>");
    w.run(root);
    return std::move(w.scene);
}

}  // namespace clrt

// ---- loadScene (scene_loader.h) ------------------------------------------------------------------

namespace clrt {

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
    if (data[i] == '<') root = parseXmlScene(path, std::move(data));
    else if (data[i] == '{') root = parseJsonScene(path, data);
    else throw Error(path + ": neither XML (starts with '<') nor JSON (starts with '{')");
    return walkScene(*root, path);
}

}  // namespace clrt
