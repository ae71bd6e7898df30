// Tests for the JSON form of the scene format (json_node.cpp feeding the one walker, scene_walker.cpp):
//  - the XML and JSON readers agree: every shared classic/hw5 XML scene is transliterated mechanically
//    to JSON here (attributes -> "_keys", text -> string or "_data", repeated children -> arrays) and
//    both forms load to the same model; for the classic scenes with a json2025 twin, both forms also
//    render bit-identical images;
//  - each json2025 twin differs from its classic XML twin in exactly the values listed below (the
//    course changed light intensities and materials when it converted them), so a new difference,
//    e.g. from a reader bug, fails; the twins render too;
//  - the JSON-only spellings of later course scenes, content-based format detection, error messages
//    with file and key path, and every json2025 scene rendering through the clrt binary.
#include <catch.hpp>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <pugixml.hpp>
#include <set>
#include <sstream>
#include <unistd.h>

#include "flatten/device_scene.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"
#include "util/error.h"

namespace fs = std::filesystem;
using namespace clrt;
using namespace clrt::test;

namespace {

using OJson = nlohmann::ordered_json;

// ---- mechanical XML -> JSON transliteration (the course's 2025 rules) ----------------------------
std::string xmlText(pugi::xml_node n) {
    std::string s;
    for (pugi::xml_node c = n.first_child(); c; c = c.next_sibling())
        if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) {
            if (!s.empty()) s += ' ';
            s += c.value();
        }
    return s;
}

// An element with neither attributes nor child elements becomes its text; otherwise an object with
// "_name" for each attribute, one key per child element name (in order of first appearance: an
// object for one child, an array in document order for several) and "_data" for non-empty text.
OJson transliterate(pugi::xml_node e) {
    OJson obj = OJson::object();
    for (pugi::xml_attribute a = e.first_attribute(); a; a = a.next_attribute())
        obj[std::string("_") + a.name()] = a.value();
    std::vector<std::string> order;
    std::map<std::string, std::vector<OJson>> groups;
    for (pugi::xml_node c = e.first_child(); c; c = c.next_sibling()) {
        if (c.type() != pugi::node_element) continue;
        if (!groups.count(c.name())) order.push_back(c.name());
        groups[c.name()].push_back(transliterate(c));
    }
    std::string text = xmlText(e);
    if (!e.first_attribute() && order.empty()) return text;
    for (auto& name : order) {
        auto& g = groups[name];
        obj[name] = g.size() == 1 ? g[0] : OJson(g);
    }
    if (!text.empty()) obj["_data"] = text;
    return obj;
}

// Writes the JSON form of `xmlPath` to `dir`/<stem>.json; the XML's sibling folders (ply, textures,
// ...) are linked into `dir` so that relative paths in the scene resolve the same way.
std::string transliterateFile(const fs::path& xmlPath, const fs::path& dir) {
    pugi::xml_document doc;
    pugi::xml_parse_result r = doc.load_file(xmlPath.c_str());
    REQUIRE(r);
    OJson root = OJson::object();
    root[doc.document_element().name()] = transliterate(doc.document_element());
    for (auto& e : fs::directory_iterator(xmlPath.parent_path())) {
        fs::path link = dir / e.path().filename();
        if (e.is_directory() && !fs::exists(fs::symlink_status(link))) fs::create_directory_symlink(e.path(), link);
    }
    fs::path out = dir / (xmlPath.stem().string() + ".json");
    // Never write through a link: the output must stay inside the test's own temp folder.
    REQUIRE(fs::weakly_canonical(out).parent_path() == fs::weakly_canonical(dir));
    REQUIRE(fs::weakly_canonical(dir).string().rfind(fs::weakly_canonical(fs::temp_directory_path()).string(), 0) == 0);
    std::ofstream(out, std::ios::binary) << root.dump(2);
    return out.string();
}

// ---- comparing two scene models, field by field ---------------------------------------------------
std::string fmt(float v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", double(v));
    return b;
}
std::string fmt(const Vec3& v) { return fmt(v.x) + " " + fmt(v.y) + " " + fmt(v.z); }
std::string fmt(int v) { return std::to_string(v); }
std::string fmt(bool v) { return v ? "true" : "false"; }
std::string fmt(const std::string& v) { return "'" + v + "'"; }

struct Differ {
    std::vector<std::string> out;
    void f(const std::string& what, float a, float b) { if (!(a == b)) add(what, fmt(a), fmt(b)); }
    void v(const std::string& what, const Vec3& a, const Vec3& b) { if (a != b) add(what, fmt(a), fmt(b)); }
    void i(const std::string& what, int a, int b) { if (a != b) add(what, fmt(a), fmt(b)); }
    void b(const std::string& what, bool a, bool c) { if (a != c) add(what, fmt(a), fmt(c)); }
    void s(const std::string& what, const std::string& a, const std::string& c) { if (a != c) add(what, fmt(a), fmt(c)); }
    void add(const std::string& what, const std::string& a, const std::string& c) { out.push_back(what + ": " + a + " -> " + c); }
};

// Every field of the model except Scene::path, Shape::source and the directory of image paths (which
// name the file the model came from). Returns "field: A -> B" lines.
std::vector<std::string> modelDiffs(const Scene& A, const Scene& B) {
    Differ d;
    d.v("backgroundColor", A.backgroundColor, B.backgroundColor);
    d.i("maxRecursionDepth", A.maxRecursionDepth, B.maxRecursionDepth);
    d.v("ambientLight", A.ambientLight, B.ambientLight);
    d.i("cameras.size", int(A.cameras.size()), int(B.cameras.size()));
    for (size_t k = 0; k < std::min(A.cameras.size(), B.cameras.size()); ++k) {
        const Camera &x = A.cameras[k], &y = B.cameras[k];
        std::string p = "cameras[" + std::to_string(k) + "].";
        d.i(p + "id", x.id, y.id);
        d.v(p + "position", x.position, y.position);
        d.v(p + "u", x.u, y.u);
        d.v(p + "v", x.v, y.v);
        d.v(p + "w", x.w, y.w);
        d.f(p + "left", x.left, y.left);
        d.f(p + "right", x.right, y.right);
        d.f(p + "bottom", x.bottom, y.bottom);
        d.f(p + "top", x.top, y.top);
        d.f(p + "nearDistance", x.nearDistance, y.nearDistance);
        d.f(p + "focusDistance", x.focusDistance, y.focusDistance);
        d.f(p + "apertureSize", x.apertureSize, y.apertureSize);
        d.i(p + "width", x.width, y.width);
        d.i(p + "height", x.height, y.height);
        d.i(p + "numSamples", x.numSamples, y.numSamples);
        d.s(p + "imageName", x.imageName, y.imageName);
        d.i(p + "tonemaps.size", int(x.tonemaps.size()), int(y.tonemaps.size()));
        for (size_t t = 0; t < std::min(x.tonemaps.size(), y.tonemaps.size()); ++t) {
            const TonemapSettings &s = x.tonemaps[t], &r = y.tonemaps[t];
            std::string q = p + "tonemaps[" + std::to_string(t) + "].";
            d.i(q + "op", int(s.op), int(r.op));
            d.f(q + "key", s.key, r.key);
            d.f(q + "burnPercent", s.burnPercent, r.burnPercent);
            d.f(q + "saturation", s.saturation, r.saturation);
            d.f(q + "gamma", s.gamma, r.gamma);
            d.s(q + "extension", s.extension, r.extension);
        }
    }
    d.i("lights.size", int(A.lights.size()), int(B.lights.size()));
    for (size_t k = 0; k < std::min(A.lights.size(), B.lights.size()); ++k) {
        const Light &x = A.lights[k], &y = B.lights[k];
        std::string p = "lights[" + std::to_string(k) + "].";
        d.i(p + "id", x.id, y.id);
        d.i(p + "type", int(x.type), int(y.type));
        d.v(p + "position", x.position, y.position);
        d.v(p + "intensity", x.intensity, y.intensity);
        d.v(p + "direction", x.direction, y.direction);
        d.f(p + "size", x.size, y.size);
        d.f(p + "coverageAngle", x.coverageAngle, y.coverageAngle);
        d.f(p + "falloffAngle", x.falloffAngle, y.falloffAngle);
        d.i(p + "imageIndex", x.imageIndex, y.imageIndex);
        d.i(p + "mapping", int(x.mapping), int(y.mapping));
        d.i(p + "envStrategy", int(x.envStrategy), int(y.envStrategy));
    }
    d.i("materials.size", int(A.materials.size()), int(B.materials.size()));
    for (size_t k = 0; k < std::min(A.materials.size(), B.materials.size()); ++k) {
        const Material &x = A.materials[k], &y = B.materials[k];
        std::string p = "materials[" + std::to_string(k) + "].";
        d.i(p + "id", x.id, y.id);
        d.i(p + "type", int(x.type), int(y.type));
        d.v(p + "ambient", x.ambient, y.ambient);
        d.v(p + "diffuse", x.diffuse, y.diffuse);
        d.v(p + "specular", x.specular, y.specular);
        d.v(p + "mirror", x.mirror, y.mirror);
        d.f(p + "phongExponent", x.phongExponent, y.phongExponent);
        d.f(p + "refractionIndex", x.refractionIndex, y.refractionIndex);
        d.f(p + "absorptionIndex", x.absorptionIndex, y.absorptionIndex);
        d.v(p + "absorptionCoefficient", x.absorptionCoefficient, y.absorptionCoefficient);
        d.f(p + "roughness", x.roughness, y.roughness);
    }
    auto rel = [](const Scene& s, const std::string& img) {
        return fs::path(img).lexically_normal().lexically_relative(fs::path(s.path).parent_path().lexically_normal()).string();
    };
    d.i("imagePaths.size", int(A.imagePaths.size()), int(B.imagePaths.size()));
    for (size_t k = 0; k < std::min(A.imagePaths.size(), B.imagePaths.size()); ++k)
        d.s("imagePaths[" + std::to_string(k) + "]", rel(A, A.imagePaths[k]), rel(B, B.imagePaths[k]));
    d.i("textures.size", int(A.textures.size()), int(B.textures.size()));
    for (size_t k = 0; k < std::min(A.textures.size(), B.textures.size()); ++k) {
        const Texture &x = A.textures[k], &y = B.textures[k];
        std::string p = "textures[" + std::to_string(k) + "].";
        d.i(p + "id", x.id, y.id);
        d.i(p + "type", int(x.type), int(y.type));
        d.i(p + "imageIndex", x.imageIndex, y.imageIndex);
        d.i(p + "decalMode", int(x.decalMode), int(y.decalMode));
        d.i(p + "interpolation", int(x.interpolation), int(y.interpolation));
        d.f(p + "normalizer", x.normalizer, y.normalizer);
        d.b(p + "normalizerGiven", x.normalizerGiven, y.normalizerGiven);
        d.f(p + "bumpFactor", x.bumpFactor, y.bumpFactor);
        d.b(p + "degamma", x.degamma, y.degamma);
        d.s(p + "noiseConversion", x.noiseConversion, y.noiseConversion);
        d.f(p + "noiseScale", x.noiseScale, y.noiseScale);
        d.v(p + "blackColor", x.blackColor, y.blackColor);
        d.v(p + "whiteColor", x.whiteColor, y.whiteColor);
        d.f(p + "scale", x.scale, y.scale);
        d.f(p + "offset", x.offset, y.offset);
    }
    d.i("meshes.size", int(A.meshes.size()), int(B.meshes.size()));
    for (size_t k = 0; k < std::min(A.meshes.size(), B.meshes.size()); ++k) {
        const MeshData &x = A.meshes[k], &y = B.meshes[k];
        std::string p = "meshes[" + std::to_string(k) + "].";
        if (x.positions != y.positions) d.add(p + "positions", "...", "...");
        if (x.normals != y.normals) d.add(p + "normals", "...", "...");
        if (x.indices != y.indices) d.add(p + "indices", "...", "...");
        bool uvSame = x.uvs.size() == y.uvs.size();
        for (size_t u = 0; uvSame && u < x.uvs.size(); ++u)
            uvSame = x.uvs[u].x == y.uvs[u].x && x.uvs[u].y == y.uvs[u].y;
        if (!uvSame) d.add(p + "uvs", "...", "...");
    }
    d.i("shapes.size", int(A.shapes.size()), int(B.shapes.size()));
    for (size_t k = 0; k < std::min(A.shapes.size(), B.shapes.size()); ++k) {
        const Shape &x = A.shapes[k], &y = B.shapes[k];
        std::string p = "shapes[" + std::to_string(k) + "].";
        d.i(p + "id", x.id, y.id);
        d.i(p + "type", int(x.type), int(y.type));
        d.i(p + "meshIndex", x.meshIndex, y.meshIndex);
        d.v(p + "center", x.center, y.center);
        d.f(p + "radius", x.radius, y.radius);
        d.i(p + "materialIndex", x.materialIndex, y.materialIndex);
        if (x.textureIndices != y.textureIndices) d.add(p + "textureIndices", "...", "...");
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c)
                d.f(p + "transform[" + std::to_string(r) + "][" + std::to_string(c) + "]", x.transform.m[r][c],
                    y.transform.m[r][c]);
        d.b(p + "smooth", x.smooth, y.smooth);
        std::string kx = x.source.substr(0, x.source.find(' ')), ky = y.source.substr(0, y.source.find(' '));
        d.s(p + "kind", kx, ky);
    }
    return d.out;
}

// The JSON form groups children by name, so <Objects> children of different kinds that interleave in
// the XML (metal_glass_plates, veachAjar) come out grouped by kind, in order of the kinds' first
// appearance. This puts the XML model's shapes in that order.
void groupShapesByKind(Scene& s) {
    std::vector<std::string> kinds;
    for (auto& sh : s.shapes) {
        std::string k = sh.source.substr(0, sh.source.find(' '));
        if (std::find(kinds.begin(), kinds.end(), k) == kinds.end()) kinds.push_back(k);
    }
    std::stable_sort(s.shapes.begin(), s.shapes.end(), [&](const Shape& a, const Shape& b) {
        auto rank = [&](const Shape& sh) {
            return std::find(kinds.begin(), kinds.end(), sh.source.substr(0, sh.source.find(' '))) - kinds.begin();
        };
        return rank(a) < rank(b);
    });
}

std::string joinLines(const std::vector<std::string>& v) {
    std::string s;
    for (auto& l : v) s += l + "\n";
    return s;
}

// Renders camera 0 at 1 spp, seed 0, shrunk so that its longer side is at most `maxSide` pixels.
ImageRGB renderSmall(Scene scene, int maxSide = 48) {
    for (Camera& c : scene.cameras) {
        int longSide = std::max(c.width, c.height);
        if (longSide > maxSide) {
            c.width = std::max(1, c.width * maxSide / longSide);
            c.height = std::max(1, c.height * maxSide / longSide);
        }
    }
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = 1;
    rs.seed = 0;
    RenderCounters counters;
    return r.render(scene.cameras.at(0), rs, counters);
}

bool sameBits(const ImageRGB& a, const ImageRGB& b) {
    return a.width == b.width && a.height == b.height && a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}
bool allFinite(const ImageRGB& img) {
    for (float v : img.pixels)
        if (!std::isfinite(v)) return false;
    return true;
}

fs::path scenesDir() { return fs::path(sharedDir()) / "scenes"; }

// The classic scenes with a json2025 file of the same name, and every value in which the json2025
// file differs from the XML (found by diffing both trees; "-" is a default the file leaves unset).
// Not model differences, so not listed: bunny.json and two_spheres.json omit MaxRecursionDepth
// (the XML's 6 is the default); scienceTree.json, cornellbox*.json, simple.json, bunny.json add
// _type attributes ("xyz", "triangle") to VertexData/Faces.
const std::map<std::string, std::vector<std::string>>& twinDifferences() {
    static const std::map<std::string, std::vector<std::string>> diffs = {
        {"bunny",
         {"lights[0].intensity: 5000 5000 5000 -> 3000 3000 3000",
          "materials[0].diffuse: 0.200000003 0.200000003 0.200000003 -> 0.800000012 0.800000012 0.800000012",
          "materials[0].specular: 0.5 0.5 0.5 -> 0.200000003 0.200000003 0.200000003",
          "shapes[0].smooth: true -> false"}},  // shadingMode="smooth" is dropped in the JSON
        {"cornellbox", {"lights[0].intensity: 1550 1550 1550 -> 350000 350000 350000"}},
        {"cornellbox_recursive",
         {"lights[0].intensity: 1250 1250 1250 -> 350000 350000 350000",
          "materials[5].mirror: 0 0 0 -> 1 1 1"}},  // dielectric material 6 gains a MirrorReflectance
        {"scienceTree",
         {"backgroundColor: 0 50 50 -> 0 0 0", "lights[0].intensity: 5000 5000 5000 -> 10000 10000 10000"}},
        {"simple", {"shapes.size: 3 -> 4"}},  // the JSON adds a <Plane> (rendered since planes landed)
        {"spheres",
         {"lights[0].intensity: 45 45 45 -> 8550 8550 8550", "lights[1].intensity: 55 55 55 -> 8550 8550 8550"}},
        {"two_spheres",  // material 2: dielectric glass in the XML, a blue Blinn-Phong in the JSON
         {"lights[0].intensity: 55 55 55 -> 25550 25550 25550",
          "materials[1].type: 2 -> 0",
          "materials[1].ambient: 0.200000003 0.200000003 0.200000003 -> 1 1 1",
          "materials[1].diffuse: 0.200000003 0.200000003 0.200000003 -> 0.200000003 0.200000003 1",
          "materials[1].specular: 0.5 0.5 0.5 -> 1 1 1",
          "materials[1].phongExponent: 3 -> 30",
          "materials[1].refractionIndex: 1.5 -> 1",
          "materials[1].absorptionCoefficient: 0.00999999978 0.00999999978 0.00999999978 -> 0 0 0"}},
    };
    return diffs;
}

// Everything these tests write lies under one per-process folder, removed at exit (symlinks are
// removed, not followed).
fs::path jsonTempDir(const std::string& sub) {
    struct Root {
        fs::path path = fs::temp_directory_path() / ("clrt_test_json_" + std::to_string(getpid()));
        ~Root() {
            std::error_code ec;
            fs::remove_all(path, ec);
        }
    };
    static Root root;
    fs::path d = root.path / sub;
    fs::create_directories(d);
    return d;
}
std::string writeText(const std::string& name, const std::string& text) {
    fs::path p = jsonTempDir("inline") / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
}

// The message of the clrt::Error that loading `path` throws ("" when it loads).
std::string loadError(const std::string& path) {
    try {
        loadScene(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// A minimal JSON scene: one simple camera, material 1, two vertices, one sphere; `extra` is spliced
// into the Scene object (it must start with a comma), `cameraExtra` into the Camera object.
std::string jsonScene(const std::string& extra, const std::string& cameraExtra = "",
                      const std::string& lights = R"({"PointLight": {"_id": "1", "Position": "0 5 0", "Intensity": "10 10 10"}})",
                      const std::string& sphere = R"({"_id": "1", "Material": "1", "Center": "1", "Radius": "0.5"})") {
    return R"({
  "Scene": {
    "Cameras": {
      "Camera": {
        "_id": "1",
        "Position": "0 0 3", "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -1 1",
        "NearDistance": "1", "ImageResolution": "8 8", "ImageName": "out.png")" +
           cameraExtra + R"(
      }
    },
    "Lights": )" + lights + R"(,
    "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}},
    "VertexData": {"_data": "0 0 0 1 1 1", "_type": "xyz"},
    "Objects": {"Sphere": )" + sphere + R"(})" + extra + R"(
  }
})";
}

}  // namespace

TEST_CASE("json: every shared XML scene and its mechanical JSON transliteration load to the same model",
          "[json][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    int n = 0;
    for (const char* sub : {"classic", "hw5", "hw5/tt"}) {
        fs::path dir = scenesDir() / sub;
        if (!fs::is_directory(dir)) continue;
        std::vector<fs::path> xmls;
        for (auto& e : fs::directory_iterator(dir))
            if (e.path().extension() == ".xml") xmls.push_back(e.path());
        std::sort(xmls.begin(), xmls.end());
        // One flat folder per scene folder ("hw5/tt" -> "hw5_tt"): the sibling-folder links that
        // transliterateFile makes in "hw5" include one named "tt", and a folder "hw5/tt" under it
        // would resolve through that link into the shared scenes themselves.
        std::string flat = sub;
        std::replace(flat.begin(), flat.end(), '/', '_');
        fs::path tmp = jsonTempDir("translit_" + flat);
        for (auto& x : xmls) {
            INFO(x.string());
            std::string j = transliterateFile(x, tmp);
            Scene a = loadScene(x.string());
            Scene b = loadScene(j);
            groupShapesByKind(a);
            CHECK(joinLines(modelDiffs(a, b)) == "");
            ++n;
        }
    }
    CHECK(n >= 40);
}

TEST_CASE("json: classic scenes with a json2025 twin: XML and transliterated JSON render identically; "
          "the shared twin differs only in the listed values and renders",
          "[json][shared][render][one-implementation]") {
    if (!haveShared() || !fs::is_directory(scenesDir() / "json2025")) {
        WARN("../shared/scenes/json2025 is not present: skipped");
        return;
    }
    // Every classic scene with a same-named json2025 file is listed in twinDifferences().
    std::set<std::string> twins;
    for (auto& e : fs::directory_iterator(scenesDir() / "json2025"))
        if (e.path().extension() == ".json" && fs::exists(scenesDir() / "classic" / (e.path().stem().string() + ".xml")))
            twins.insert(e.path().stem().string());
    std::set<std::string> listed;
    for (auto& kv : twinDifferences()) listed.insert(kv.first);
    CHECK(twins == listed);

    fs::path tmp = jsonTempDir("twins");
    for (const std::string& name : twins) {
        INFO(name);
        fs::path xmlPath = scenesDir() / "classic" / (name + ".xml");
        Scene fromXml = loadScene(xmlPath.string());
        Scene fromTranslit = loadScene(transliterateFile(xmlPath, tmp));
        Scene fromShared = loadScene((scenesDir() / "json2025" / (name + ".json")).string());
        REQUIRE(joinLines(modelDiffs(fromXml, fromTranslit)) == "");
        // The convention the form decides (back-face culling, docs/scene-format.md) aside: the readers are
        // compared, so the JSON scenes take the XML one's.
        for (Scene* j : {&fromTranslit, &fromShared}) j->backfaceCulling = fromXml.backfaceCulling;

        // The readers agree: the same scene as XML and as JSON gives the same bits.
        ImageRGB a = renderSmall(fromXml);
        ImageRGB b = renderSmall(fromTranslit);
        CHECK(allFinite(a));
        CHECK(sameBits(a, b));

        // The shared JSON twin: exactly the listed differences.
        auto it = twinDifferences().find(name);
        if (it != twinDifferences().end()) CHECK(joinLines(modelDiffs(fromXml, fromShared)) == joinLines(it->second));
        ImageRGB c = renderSmall(fromShared);
        CHECK(allFinite(c));
        if (it != twinDifferences().end() && it->second.empty()) CHECK(sameBits(a, c));
    }
}

TEST_CASE("json: JSON-only spellings of the later course scenes", "[json]") {
    SECTION("Tonemap as an array with Extension") {
        std::string cam = R"(,
        "Tonemap": [
          {"TMO": "Photographic", "TMOOptions": "0.18 1", "Saturation": "1.0", "Gamma": "2.2", "Extension": "_phot"},
          {"TMO": "ACES", "TMOOptions": "0.5", "Saturation": "0.8", "Gamma": "2.4", "Extension": "_aces"},
          {"TMO": "Filmic", "TMOOptions": "1.5 2", "Saturation": "1", "Gamma": "2.2", "Extension": "_filmic"}
        ])";
        Scene s = loadScene(writeText("tonemaps.json", jsonScene("", cam)));
        const auto& t = s.cameras.at(0).tonemaps;
        REQUIRE(t.size() == 3);
        CHECK(t[0].op == dev::TMO_PHOTOGRAPHIC);
        CHECK(t[0].extension == "_phot");
        CHECK(t[0].key == Approx(0.18f));
        CHECK(t[1].op == dev::TMO_ACES);
        CHECK(t[1].extension == "_aces");
        CHECK(t[1].saturation == Approx(0.8f));
        CHECK(t[1].gamma == Approx(2.4f));
        CHECK(t[2].op == dev::TMO_FILMIC);
        CHECK(t[2].burnPercent == Approx(2.0f));
        CHECK(t[2].extension == "_filmic");
        // One Tonemap object (not an array) is one tone map.
        Scene one = loadScene(writeText("tonemap1.json",
                                        jsonScene("", R"(, "Tonemap": {"TMO": "ACES", "TMOOptions": "0.3", "Extension": "_a"})")));
        REQUIRE(one.cameras.at(0).tonemaps.size() == 1);
        CHECK(one.cameras.at(0).tonemaps[0].extension == "_a");
    }
    SECTION("SphericalDirectionalLight _type and Sampler") {
        auto envScene = [](const std::string& light) {
            return jsonScene(R"(,
    "Textures": {"Images": {"Image": {"_id": "1", "_data": "env.exr"}}})",
                             "", "{\"SphericalDirectionalLight\": " + light + "}");
        };
        Scene a = loadScene(writeText("env_probe.json", envScene(R"({"_id": "1", "_type": "probe", "ImageId": "1", "Sampler": "cosine"})")));
        REQUIRE(a.lights.size() == 1);
        CHECK(a.lights[0].type == dev::LIGHT_ENVIRONMENT);
        CHECK(a.lights[0].mapping == dev::ENV_PROBE);
        CHECK(a.lights[0].envStrategy == dev::ENV_STRATEGY_COSINE);
        CHECK(a.imagePaths.at(size_t(a.lights[0].imageIndex)).find("env.exr") != std::string::npos);
        Scene b = loadScene(writeText("env_latlong.json", envScene(R"({"_id": "1", "_type": "latlong", "ImageId": "1", "Sampler": "uniform"})")));
        REQUIRE(b.lights.size() == 1);
        CHECK(b.lights[0].mapping == dev::ENV_LATLONG);
        CHECK(b.lights[0].envStrategy == dev::ENV_STRATEGY_UNIFORM);
        Scene c = loadScene(writeText("env_default.json", envScene(R"({"_id": "1", "ImageId": "1"})")));
        CHECK(c.lights.at(0).mapping == dev::ENV_LATLONG);
        CHECK(c.lights.at(0).envStrategy == dev::ENV_STRATEGY_MIS);  // the default
        std::string bad = writeText("env_bad.json", envScene(R"({"_id": "1", "_type": "cube", "ImageId": "1"})"));
        CHECK_THAT(loadError(bad), Catch::StartsWith(bad + ": Scene.Lights.SphericalDirectionalLight: ") &&
                                       Catch::Contains("cube"));
        std::string badS = writeText("env_bad_sampler.json", envScene(R"({"_id": "1", "ImageId": "1", "Sampler": "stratified"})"));
        CHECK_THAT(loadError(badS), Catch::Contains(badS + ": Scene.Lights.SphericalDirectionalLight") &&
                                        Catch::Contains("stratified"));
    }
    SECTION("FallOffAngle as well as FalloffAngle") {
        for (const char* key : {"FallOffAngle", "FalloffAngle"}) {
            INFO(key);
            std::string light = std::string(R"({"SpotLight": {"_id": "1", "Position": "0 5 0", "Direction": "0 -1 0",
                "Intensity": "100 100 100", "CoverageAngle": "40", ")") + key + R"(": "25"}})";
            Scene s = loadScene(writeText(std::string("spot_") + key + ".json", jsonScene("", "", light)));
            REQUIRE(s.lights.size() == 1);
            CHECK(s.lights[0].type == dev::LIGHT_SPOT);
            CHECK(s.lights[0].coverageAngle == 40.0f);
            CHECK(s.lights[0].falloffAngle == 25.0f);
        }
        std::string none = writeText("spot_none.json", jsonScene("", "", R"({"SpotLight": {"_id": "1", "Position": "0 5 0",
            "Direction": "0 -1 0", "Intensity": "100 100 100", "CoverageAngle": "40"}})"));
        CHECK_THAT(loadError(none), Catch::StartsWith(none + ": Scene.Lights.SpotLight: ") && Catch::Contains("FalloffAngle"));
    }
    SECTION("numbers as JSON numbers, booleans, arrays of numbers, null") {
        std::string s = jsonScene(R"(, "MaxRecursionDepth": 3, "ZeroBasedIndexing": false, "BackgroundColor": [1, 2.5, 3],
            "TexCoordData": null)", R"(, "NumSamples": 4)", R"({"PointLight": {"_id": 1, "Position": [0, 5, 0], "Intensity": "10 10 10"}})",
                                  R"({"_id": 1, "Material": 1, "Center": 2, "Radius": 0.25})");
        Scene m = loadScene(writeText("numbers.json", s));
        CHECK(m.maxRecursionDepth == 3);
        CHECK(m.backgroundColor == Vec3(1, 2.5f, 3));
        CHECK(m.cameras.at(0).numSamples == 4);
        CHECK(m.lights.at(0).position == Vec3(0, 5, 0));
        CHECK(m.shapes.at(0).center == Vec3(1, 1, 1));
        CHECK(m.shapes.at(0).radius == 0.25f);
    }
}

TEST_CASE("json: the format is chosen by content, not by the file extension", "[json]") {
    Scene j = loadScene(writeText("really_json.xml", jsonScene("")));
    CHECK(j.shapes.size() == 1);
    CHECK(j.shapes[0].source.find("really_json.xml: Scene.Objects.Sphere") != std::string::npos);
    // A UTF-8 byte-order mark and leading white space before the '{'.
    Scene bom = loadScene(writeText("bom.json", "\xEF\xBB\xBF \n\t" + jsonScene("")));
    CHECK(bom.shapes.size() == 1);
    std::string xml = R"(<?xml version="1.0"?>
<!-- an XML scene in a .json file -->
<Scene>
  <Cameras><Camera id="1"><Position>0 0 3</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
    <ImageName>out.png</ImageName></Camera></Cameras>
  <Lights><PointLight id="1"><Position>0 5 0</Position><Intensity>10 10 10</Intensity></PointLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0 1 1 1</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>0.5</Radius></Sphere></Objects>
</Scene>
)";
    std::string xmlPath = writeText("really_xml.json", xml);
    Scene x = loadScene(xmlPath);
    CHECK(x.shapes.size() == 1);
    CHECK(x.shapes[0].source.find("really_xml.json:10:") != std::string::npos);
    // The same scene either way.
    CHECK(joinLines(modelDiffs(x, j)) == "");
    std::string neither = writeText("neither.json", "  Scene = {}");
    CHECK_THAT(loadError(neither), Catch::StartsWith(neither + ": ") && Catch::Contains("neither XML"));
}

TEST_CASE("json: errors name the file and the key path", "[json]") {
    SECTION("a missing required key") {
        std::string s = jsonScene("");
        size_t at = s.find(R"("ImageResolution": "8 8", )");
        REQUIRE(at != std::string::npos);
        s.erase(at, std::strlen(R"("ImageResolution": "8 8", )"));
        std::string p = writeText("missing.json", s);
        std::string msg = loadError(p);
        CHECK_THAT(msg, Catch::StartsWith(p + ": Scene.Cameras.Camera: ") && Catch::Contains("ImageResolution"));
        CHECK(msg.find('\n') == std::string::npos);
    }
    SECTION("a bad number string, in an array element") {
        std::string p = writeText("badnum.json", jsonScene(R"(, "ShadowRayEpsilon": "1e-3")", "", R"({"PointLight": {"_id": "1", "Position": "0 5 0", "Intensity": "10 10 10"}})",
                                                           R"([{"_id": "1", "Material": "1", "Center": "1", "Radius": "0.5"},
                      {"_id": "2", "Material": "1", "Center": "2", "Radius": "0,25"}])"));
        std::string msg = loadError(p);
        CHECK_THAT(msg, Catch::StartsWith(p + ": Scene.Objects.Sphere[1].Radius: ") && Catch::Contains("'0,25' is not a number"));
        std::string q = writeText("badvec.json", jsonScene(R"(, "BackgroundColor": "0 0 x")"));
        CHECK_THAT(loadError(q), Catch::StartsWith(q + ": Scene.BackgroundColor: ") && Catch::Contains("'x'"));
        std::string r = writeText("badattr.json", jsonScene("", "", R"({"PointLight": {"_id": "one", "Position": "0 5 0", "Intensity": "1 1 1"}})"));
        CHECK_THAT(loadError(r), Catch::StartsWith(r + ": Scene.Lights.PointLight: ") && Catch::Contains("'one'"));
    }
    SECTION("an undefined material id") {
        std::string p = writeText("badmat.json", jsonScene("", "", R"({"PointLight": {"_id": "1", "Position": "0 5 0", "Intensity": "10 10 10"}})",
                                                           R"([{"_id": "1", "Material": "1", "Center": "1", "Radius": "0.5"},
                      {"_id": "7", "Material": "3", "Center": "2", "Radius": "0.5"}])"));
        CHECK_THAT(loadError(p), Catch::StartsWith(p + ": Scene.Objects.Sphere[1].Material: ") &&
                                     Catch::Contains("Sphere id=7") && Catch::Contains("undefined Material 3"));
    }
    SECTION("malformed JSON: file:line:col") {
        std::string text = "{\n  \"Scene\": {\n    \"BackgroundColor\": \"0 0 0\",\n    \"Cameras\": ]\n  }\n}\n";
        std::string p = writeText("malformed.json", text);
        std::string msg = loadError(p);
        CHECK_THAT(msg, Catch::StartsWith(p + ":4:16: ") && Catch::Contains("unexpected ']'"));
        CHECK(msg.find('\n') == std::string::npos);
        std::string q = writeText("truncated.json", "{\n  \"Scene\": {\n    \"A\": \"1\"\n");
        CHECK_THAT(loadError(q), Catch::StartsWith(q + ":4:"));
        std::string r = writeText("noscene.json", "{\"Scene\": {}, \"Other\": 1}");
        CHECK_THAT(loadError(r), Catch::StartsWith(r + ": ") && Catch::Contains("besides \"Scene\""));
        std::string t = writeText("arrayscene.json", "{\"Scene\": [1]}");
        CHECK_THAT(loadError(t), Catch::StartsWith(t + ": ") && Catch::Contains("\"Scene\""));
    }
}

TEST_CASE("json: every json2025 scene renders through the clrt binary", "[json][shared][cli]") {
    if (!haveShared() || !fs::is_directory(scenesDir() / "json2025")) {
        WARN("../shared/scenes/json2025 is not present: skipped");
        return;
    }
    std::vector<fs::path> scenes;
    for (auto& e : fs::recursive_directory_iterator(scenesDir() / "json2025"))
        if (e.path().extension() == ".json") scenes.push_back(e.path());
    std::sort(scenes.begin(), scenes.end());
    CHECK(scenes.size() >= 19);
    TempDir out;
    for (auto& p : scenes) {
        INFO(p.string());
        std::string log = out.file(p.stem().string() + ".log");
        int rc = runClrt("render '" + p.string() + "' -o '" + out.path.string() + "' --spp 1", log);
        std::ifstream lf(log);
        std::string text((std::istreambuf_iterator<char>(lf)), std::istreambuf_iterator<char>());
        INFO(text);
        CHECK(rc == 0);
        if (rc != 0) continue;
        Scene s = loadScene(p.string());
        for (auto& cam : s.cameras) {
            INFO(cam.imageName);
            CHECK(fs::exists(out.path / cam.imageName));
        }
    }
}
