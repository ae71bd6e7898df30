// The clrt binary on scenes at the edges of valid input (issue 12), in tests/test_cli.cpp style:
// - valid scenes with nothing for the BVH (only planes, no objects, only degenerate triangles, an
//   empty PLY) render: exit 0, the image is written, and its pixels are the background (and the
//   plane's ambient colour where the plane is seen);
// - numbers beyond float (1e39) or double (1e400) range, NaN/Inf in PLY vertex data, indices and ids
//   beyond int range are bad input: exit 2, ONE "clrt: error:" line naming the file (file:line:col for
//   XML and JSON syntax, the key path for JSON values, the line or byte for PLY), no sanitizer report,
//   no output or temporary file left.
#include <catch.hpp>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "image/image.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;
namespace fs = std::filesystem;

namespace {


// s with the first `from` replaced by `to` (which must be there).
std::string sub(std::string s, const std::string& from, const std::string& to) {
    size_t at = s.find(from);
    REQUIRE(at != std::string::npos);
    return s.replace(at, from.size(), to);
}

using CliRun = CliResult;

// `clrt render SCENE -o DIR [extra]`, output to DIR/clrt.log.
CliRun render(const TempDir& d, const std::string& sceneFile, const std::string& extra = "") {
    std::string log = d.file("clrt.log");
    int rc = runClrt("render " + d.file(sceneFile) + " -o " + d.path.string() + " " + extra, log);
    return cliResult(rc, readFileBytes(log));
}

// No sanitizer report, no temporary file; `image` exists exactly when expected.
void expectClean(const TempDir& d, const CliRun& r, bool imageExpected, const std::string& image = "out.png") {
    INFO("output:\n" << r.log);
    CHECK(r.log.find("runtime error") == std::string::npos);
    CHECK(r.log.find("Sanitizer") == std::string::npos);
    CHECK(fs::exists(d.path / image) == imageExpected);
    for (auto& e : fs::directory_iterator(d.path)) CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);
}

void expectBadInput(const TempDir& d, const CliRun& r, std::initializer_list<std::string> needles) {
    INFO("output:\n" << r.log);
    CHECK(r.rc == 2);
    CHECK(r.errorLines == 1);
    for (const std::string& n : needles) {
        INFO("needle: " << n);
        CHECK(r.errorLine.find(n) != std::string::npos);
    }
    expectClean(d, r, false);
}

// Every pixel of the 8-bit image `file` in rows [y0, y1) has colour (r, g, b).
void expectRows(const std::string& file, int y0, int y1, float r, float g, float b) {
    ImageRGB img = readImage(file);
    REQUIRE(img.width == 4);
    REQUIRE(img.height == 4);
    for (int y = y0; y < y1; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float* p = &img.pixels[(size_t(y) * img.width + x) * 3];
            INFO("pixel " << x << "," << y << " = " << p[0] << " " << p[1] << " " << p[2]);
            CHECK(p[0] == r);
            CHECK(p[1] == g);
            CHECK(p[2] == b);
        }
}

// An XML scene: background 10 20 30, a 4x4 camera at z=5 looking down -z, a point light, one
// material, `vertices`, and `objects` inside <Objects> (no <Objects> at all when objects == "-").
std::string xmlScene(const std::string& vertices, const std::string& objects, const std::string& extra = "") {
    return "<Scene>\n<BackgroundColor>10 20 30</BackgroundColor>\n"
           "<Cameras><Camera id=\"1\"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>"
           "<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution>"
           "<ImageName>out.png</ImageName></Camera></Cameras>\n"
           "<Lights><PointLight id=\"1\"><Position>0 0 5</Position><Intensity>100 100 100</Intensity></PointLight></Lights>\n"
           "<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>\n" +
           extra + (vertices.empty() ? "" : "<VertexData>" + vertices + "</VertexData>\n") +
           (objects == "-" ? "" : "<Objects>" + objects + "</Objects>\n") + "</Scene>\n";
}

// A 2025 JSON scene: camera at y=1 looking along -z (upper half of the image sees the sky, lower
// half the plane y=0), ambient light 100 only, the plane's material ambient 0.5: it shows as 50.
std::string jsonPlanes(const std::string& extraObjects = "", const std::string& background = "\"10 20 30\"",
                       const std::string& vertexData = "0 0 0") {
    return "{\"Scene\": {\n"
           "  \"BackgroundColor\": " + background + ",\n"
           "  \"Cameras\": {\"Camera\": {\"_id\": \"1\", \"Position\": \"0 1 0\", \"Gaze\": \"0 0 -1\", \"Up\": \"0 1 0\",\n"
           "     \"NearPlane\": \"-1 1 -1 1\", \"NearDistance\": \"1\", \"ImageResolution\": \"4 4\", \"ImageName\": \"out.png\"}},\n"
           "  \"Lights\": {\"AmbientLight\": \"100 100 100\"},\n"
           "  \"Materials\": {\"Material\": {\"_id\": \"1\", \"AmbientReflectance\": \"0.5 0.5 0.5\",\n"
           "     \"DiffuseReflectance\": \"0 0 0\", \"SpecularReflectance\": \"0 0 0\"}},\n"
           "  \"VertexData\": {\"_data\": \"" + vertexData + "\", \"_type\": \"xyz\"},\n"
           "  \"Objects\": {\"Plane\": [{\"_id\": \"1\", \"Point\": \"1\", \"Normal\": \"0 1 0\", \"Material\": \"1\"}" +
           extraObjects + "]}\n}}\n";
}

const char* kPlyHead3 = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kPlyMesh = "<Mesh id=\"1\"><Material>1</Material><Faces plyFile=\"m.ply\"/></Mesh>";

}  // namespace

// ==== issue 12: valid scenes with nothing for the BVH =================================================

TEST_CASE("cli input: a JSON scene with only planes renders the background and the planes", "[cli][cli-input]") {
    TempDir d;
    writeFileBytes(d.file("s.json"), jsonPlanes());
    for (const char* extra : {"", "--all-features"}) {
        INFO(extra);
        CliRun r = render(d, "s.json", extra);
        INFO(r.log);
        CHECK(r.rc == 0);
        CHECK(r.errorLines == 0);
        expectClean(d, r, true);
        expectRows(d.file("out.png"), 0, 2, 10, 20, 30);  // sky: the background
        expectRows(d.file("out.png"), 2, 4, 50, 50, 50);  // the plane: ambient 100 * 0.5
        fs::remove(d.path / "out.png");
    }
}

TEST_CASE("cli input: a scene with no objects renders the background", "[cli][cli-input]") {
    TempDir d;
    for (const char* objects : {"-", ""}) {  // no <Objects> element; an empty one
        INFO("objects: '" << objects << "'");
        writeFileBytes(d.file("s.xml"), xmlScene("", objects));
        for (const char* extra : {"", "--all-features"}) {
            INFO(extra);
            CliRun r = render(d, "s.xml", extra);
            INFO(r.log);
            CHECK(r.rc == 0);
            CHECK(r.errorLines == 0);
            expectClean(d, r, true);
            expectRows(d.file("out.png"), 0, 4, 10, 20, 30);
            fs::remove(d.path / "out.png");
        }
    }
}

// The default 8-bit quantisation is the course's (floor: its reference PNGs truncate); round on request.
TEST_CASE("cli input: .png outputs truncate by default, --ldr-quantize round rounds", "[cli][cli-input]") {
    TempDir d;
    std::string xml = xmlScene("", "-");
    xml.replace(xml.find("10 20 30"), 8, "10.6 20.4 30.5");
    writeFileBytes(d.file("s.xml"), xml);
    const std::pair<const char*, std::array<float, 3>> cases[] = {
        {"", {10, 20, 30}}, {"--ldr-quantize floor", {10, 20, 30}}, {"--ldr-quantize round", {11, 20, 31}}};
    for (const auto& [extra, rgb] : cases) {
        INFO("flags: '" << extra << "'");
        CliRun r = render(d, "s.xml", extra);
        INFO(r.log);
        CHECK(r.rc == 0);
        expectRows(d.file("out.png"), 0, 4, rgb[0], rgb[1], rgb[2]);
        fs::remove(d.path / "out.png");
    }
}

TEST_CASE("cli input: a scene whose triangles are all degenerate renders the background", "[cli][cli-input]") {
    TempDir d;
    // Three collinear vertices and a repeated one: a Triangle and a two-triangle Mesh, all zero area.
    writeFileBytes(d.file("s.xml"), xmlScene("0 0 0 1 0 0 2 0 0",
                                   "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle>"
                                   "<Mesh id=\"2\"><Material>1</Material><Faces>1 1 2 2 3 3</Faces></Mesh>"));
    CliRun r = render(d, "s.xml");
    INFO(r.log);
    CHECK(r.rc == 0);
    CHECK(r.errorLines == 0);
    CHECK(r.log.find("skipped 3 degenerate triangles") != std::string::npos);
    expectClean(d, r, true);
    expectRows(d.file("out.png"), 0, 4, 10, 20, 30);
}

TEST_CASE("cli input: a mesh from an empty PLY renders the background", "[cli][cli-input]") {
    TempDir d;
    SECTION("no vertices, no faces") {
        writeFileBytes(d.file("m.ply"), "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
    }
    SECTION("vertices but no faces (binary)") {
        std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
        float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        ply.append(reinterpret_cast<const char*>(v), sizeof v);
        writeFileBytes(d.file("m.ply"), ply);
    }
    SECTION("only a degenerate face") { writeFileBytes(d.file("m.ply"), std::string(kPlyHead3) + "0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n"); }
    writeFileBytes(d.file("s.xml"), xmlScene("", kPlyMesh));
    CliRun r = render(d, "s.xml");
    INFO(r.log);
    CHECK(r.rc == 0);
    CHECK(r.errorLines == 0);
    expectClean(d, r, true);
    expectRows(d.file("out.png"), 0, 4, 10, 20, 30);
}

// ==== issue 12: numbers out of range are bad input (exit 2), never a device failure ==================

TEST_CASE("cli input: a value beyond float range in an XML scene is exit 2 naming file:line:col", "[cli][cli-input]") {
    TempDir d;
    auto run = [&](const std::string& text) {
        writeFileBytes(d.file("s.xml"), text);
        return render(d, "s.xml");
    };
    const std::string tri = "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle>";
    SECTION("vertex 1e39") { expectBadInput(d, run(xmlScene("0 0 0 1 0 0 0 1e39 0", tri)), {"s.xml:", "<VertexData>", "'1e39'", "out of range"}); }
    SECTION("vertex -1e39 in a mesh that is the only object") {
        expectBadInput(d, run(xmlScene("0 0 0 -1e39 0 0 0 1 0", "<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces></Mesh>")),
                       {"s.xml:", "'-1e39'"});
    }
    SECTION("light intensity") {
        std::string s = xmlScene("0 0 0 1 0 0 0 1 0", tri);
        s = sub(s, "100 100 100", "100 1e39 100");
        expectBadInput(d, run(s), {"s.xml:", "<Intensity>", "'1e39'"});
    }
    SECTION("background colour") {
        std::string s = xmlScene("0 0 0 1 0 0 0 1 0", tri);
        s = sub(s, "10 20 30", "10 -4e38 30");
        expectBadInput(d, run(s), {"s.xml:2:1", "<BackgroundColor>", "'-4e38'"});
    }
    SECTION("a transformation") {
        expectBadInput(d, run(xmlScene("0 0 0 1 0 0 0 1 0",
                                       "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material>"
                                       "<Transformations>c1</Transformations></Triangle>",
                                       "<Transformations><Composite id=\"1\">1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1e39"
                                       "</Composite></Transformations>\n")),
                       {"s.xml:", "<Composite>", "'1e39'"});
    }
    SECTION("a degamma'd colour that overflows") {
        std::string s = xmlScene("0 0 0 1 0 0 0 1 0", tri);
        s = sub(s, "<Material id=\"1\">", "<Material id=\"1\" degamma=\"true\">");
        s = sub(s, "<DiffuseReflectance>1 1 1", "<DiffuseReflectance>1 1e30 1");
        expectBadInput(d, run(s), {"s.xml:", "DiffuseReflectance", "overflows"});
    }
    SECTION("camera vectors whose difference overflows") {
        std::string s = xmlScene("0 0 0 1 0 0 0 1 0", tri);
        s = sub(s, "<Camera id=\"1\">", "<Camera id=\"1\" type=\"lookAt\">");
        s = sub(s, "<Position>0 0 5</Position><Gaze>0 0 -1</Gaze>", "<Position>0 0 3e38</Position><GazePoint>0 0 -3e38</GazePoint><FovY>60</FovY>");
        s = sub(s, "<NearPlane>-1 1 -1 1</NearPlane>", "");
        expectBadInput(d, run(s), {"s.xml:", "gaze direction overflows"});
    }
    SECTION("an id beyond int range") {
        std::string s = xmlScene("0 0 0 1 0 0 0 1 0", tri);
        s = sub(s, "<Triangle id=\"1\">", "<Triangle id=\"4294967297\">");
        expectBadInput(d, run(s), {"s.xml:", "id='4294967297' is out of range"});
    }
    SECTION("a transformation reference beyond int range (would wrap onto t1)") {
        expectBadInput(d, run(xmlScene("0 0 0 1 0 0 0 1 0",
                                       "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material>"
                                       "<Transformations>t4294967297</Transformations></Triangle>",
                                       "<Transformations><Translation id=\"1\">0 0 0</Translation></Transformations>\n")),
                       {"s.xml:", "'t4294967297': id out of range"});
    }
}

TEST_CASE("cli input: PLY vertex data that is not a finite float is exit 2 naming the PLY", "[cli][cli-input]") {
    TempDir d;
    writeFileBytes(d.file("s.xml"), xmlScene("", kPlyMesh));
    SECTION("1e39 (ASCII)") {
        writeFileBytes(d.file("m.ply"), std::string(kPlyHead3) + "0 0 0\n1 1e39 0\n0 1 0\n3 0 1 2\n");
        expectBadInput(d, render(d, "s.xml"), {"s.xml:", "m.ply: line 11: vertex 1 has y = 1e+39, not a finite 32-bit float"});
    }
    SECTION("nan (ASCII)") {
        writeFileBytes(d.file("m.ply"), std::string(kPlyHead3) + "nan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        expectBadInput(d, render(d, "s.xml"), {"m.ply: line 10: vertex 0 has x = nan"});
    }
    SECTION("a double beyond float range (binary)") {
        std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                          "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        double v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 1e300};
        ply.append(reinterpret_cast<const char*>(v), sizeof v);
        ply += std::string("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0", 13);
        writeFileBytes(d.file("m.ply"), ply);
        expectBadInput(d, render(d, "s.xml"), {"m.ply: byte ", "vertex 2 has z = 1e+300"});
    }
    SECTION("an infinite normal (binary)") {
        std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
                          "property list uchar int vertex_indices\nend_header\n";
        float v[18] = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
        v[16] = INFINITY;  // vertex 2's ny
        ply.append(reinterpret_cast<const char*>(v), sizeof v);
        ply += std::string("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0", 13);
        writeFileBytes(d.file("m.ply"), ply);
        expectBadInput(d, render(d, "s.xml"), {"m.ply: byte ", "vertex 2 has ny = inf"});
    }
    SECTION("a face index far beyond int range (the fuzz finding)") {
        writeFileBytes(d.file("m.ply"), std::string(kPlyHead3) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 666666666666666666666666666666666\n");
        expectBadInput(d, render(d, "s.xml"), {"m.ply: line 13: face 0 has vertex index 6.66666667e+32, out of range"});
    }
}

TEST_CASE("cli input: JSON numbers out of range are exit 2 naming the file", "[cli][cli-input]") {
    TempDir d;
    SECTION("1e400 (beyond double): file:line:col") {
        std::string s = jsonPlanes("", "\"10 20 30\",\n  \"ShadowRayEpsilon\": 1e400");
        writeFileBytes(d.file("s.json"), s);
        // The number starts on line 3, after `  "ShadowRayEpsilon": `.
        expectBadInput(d, render(d, "s.json"), {"s.json:3:23: number overflow parsing '1e400'"});
    }
    SECTION("-1e400 inside an array") {
        writeFileBytes(d.file("s.json"), jsonPlanes("", "[10, 20, -1e400]"));
        expectBadInput(d, render(d, "s.json"), {"s.json:2:31: number overflow parsing '-1e400'"});
    }
    SECTION("1e39 as a JSON number (beyond float): the key path") {
        writeFileBytes(d.file("s.json"), jsonPlanes("", "[10, 1e39, 30]"));
        expectBadInput(d, render(d, "s.json"), {"s.json: Scene.BackgroundColor", "out of range"});
    }
    SECTION("1e39 in VertexData") {
        writeFileBytes(d.file("s.json"), jsonPlanes("", "\"10 20 30\"", "0 1e39 0"));
        expectBadInput(d, render(d, "s.json"), {"s.json: Scene.VertexData", "'1e39'"});
    }
}

// ==== issue 29: tolerant reading where the course's own reader was =====================================

namespace {
// "line:col" (1-based, col in bytes) of the first `needle` in `text`.
std::string lineColOf(const std::string& text, const std::string& needle) {
    size_t off = text.find(needle);
    REQUIRE(off != std::string::npos);
    size_t line = 1 + size_t(std::count(text.begin(), text.begin() + long(off), '\n'));
    size_t lineStart = text.rfind('\n', off);
    size_t col = lineStart == std::string::npos ? off + 1 : off - lineStart;
    return std::to_string(line) + ":" + std::to_string(col);
}
// The lines of `log` that contain `needle`.
int linesWith(const std::string& log, const std::string& needle) {
    int n = 0;
    std::istringstream in(log);
    for (std::string line; std::getline(in, line);) n += line.find(needle) != std::string::npos;
    return n;
}
}  // namespace

TEST_CASE("cli input: extra numbers in <NearPlane> give one warning naming file:line:col, then render",
          "[cli][cli-input][scene]") {
    TempDir d;
    const std::string tri = "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle>";
    const std::string four = xmlScene("-1 -1 0 1 -1 0 0 1 0", tri);
    writeFileBytes(d.file("four.xml"), four);
    CliRun r4 = render(d, "four.xml");
    REQUIRE(r4.rc == 0);
    const std::string want = readFileBytes(d.file("out.png"));
    fs::remove(d.path / "out.png");

    SECTION("XML: hw1 spheres.xml's five numbers") {
        const std::string five = sub(four, "<NearPlane>-1 1 -1 1</NearPlane>", "<NearPlane> -1 1 -1 1 10</NearPlane>");
        writeFileBytes(d.file("five.xml"), five);
        CliRun r = render(d, "five.xml");
        INFO(r.log);
        CHECK(r.rc == 0);
        CHECK(r.errorLines == 0);
        CHECK(linesWith(r.log, "warning:") == 1);
        CHECK(linesWith(r.log, "five.xml:" + lineColOf(five, "<NearPlane>") + ": <NearPlane> has 5 values") == 1);
        CHECK(linesWith(r.log, "ignoring '10'") == 1);
        CHECK(readFileBytes(d.file("out.png")) == want);  // the first four numbers, as with four
    }
    SECTION("JSON: the key path") {
        std::string json = jsonPlanes();
        writeFileBytes(d.file("four.json"), json);
        REQUIRE(render(d, "four.json").rc == 0);
        const std::string wantJson = readFileBytes(d.file("out.png"));
        fs::remove(d.path / "out.png");
        writeFileBytes(d.file("six.json"), sub(json, "\"NearPlane\": \"-1 1 -1 1\"", "\"NearPlane\": \"-1 1 -1 1 10 20\""));
        CliRun r = render(d, "six.json");
        INFO(r.log);
        CHECK(r.rc == 0);
        CHECK(linesWith(r.log, "warning:") == 1);
        CHECK(linesWith(r.log, "six.json: Scene.Cameras.Camera.NearPlane: <NearPlane> has 6 values") == 1);
        CHECK(linesWith(r.log, "ignoring '10 20'") == 1);
        CHECK(readFileBytes(d.file("out.png")) == wantJson);
    }
    SECTION("fewer than four stays an error") {
        const std::string three = sub(four, "<NearPlane>-1 1 -1 1</NearPlane>", "<NearPlane>-1 1 -1</NearPlane>");
        writeFileBytes(d.file("three.xml"), three);
        expectBadInput(d, render(d, "three.xml"), {"three.xml:" + lineColOf(three, "<NearPlane>"), "has 3 values, expected 4"});
    }
    SECTION("an unknown element still warns once") {
        const std::string odd = sub(four, "<NearDistance>", "<Scissor>1</Scissor><NearDistance>");
        writeFileBytes(d.file("odd.xml"), odd);
        CliRun r = render(d, "odd.xml");
        INFO(r.log);
        CHECK(r.rc == 0);
        CHECK(linesWith(r.log, "warning:") == 1);
        CHECK(linesWith(r.log, "Scissor") == 1);
    }
}

// A path-traced camera with Russian roulette has no depth cap, so a surface that gives back more light
// than it receives makes the image diverge (scenes/lanes_mix.xml's classic walls, kd 0.6: pixels of 1e19
// under RR). clrt render says so once, naming the material and the camera; nothing below 1 warns.
TEST_CASE("cli input: a material that gains energy under uncapped path tracing warns once", "[cli][cli-input][path]") {
    TempDir d;
    const std::string tri = "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle>";
    const std::string base = xmlScene("-1 -1 0 1 -1 0 0 1 0", tri);
    auto variant = [&](const std::string& params, const std::string& material, const std::string& brdfs = "") {
        std::string s = sub(base, "<ImageName>out.png</ImageName>",
                            "<ImageName>out.png</ImageName><NumSamples>1</NumSamples><Renderer>PathTracing</Renderer>"
                            "<RendererParams>" + params + "</RendererParams>");
        return sub(s, "<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>",
                   brdfs + "<Materials>" + material + "</Materials>");
    };
    const std::string classic06 = "<Material id=\"1\"><DiffuseReflectance>0.6 0.6 0.6</DiffuseReflectance></Material>";
    auto warnings = [&](const std::string& xml) {
        writeFileBytes(d.file("s.xml"), xml);
        CliRun r = render(d, "s.xml");
        INFO(r.log);
        CHECK(r.rc == 0);
        return r;
    };
    SECTION("classic kd 0.6 (pi*kd = 1.88) with RussianRoulette") {
        CliRun r = warnings(variant("NextEventEstimation RussianRoulette", classic06));
        CHECK(linesWith(r.log, "warning:") == 1);
        CHECK(linesWith(r.log, "s.xml: material 1 gives back up to 1.88 times") == 1);
        CHECK(linesWith(r.log, "camera 1 plays Russian roulette") == 1);
    }
    SECTION("a mirror with a diffuse part: pi*0.2 + 0.6 = 1.23") {
        CliRun r = warnings(variant("RussianRoulette", "<Material id=\"1\" type=\"mirror\"><DiffuseReflectance>0.2 0.2 0.2"
                                                       "</DiffuseReflectance><MirrorReflectance>0.6 0.6 0.6</MirrorReflectance></Material>"));
        CHECK(linesWith(r.log, "material 1 gives back up to 1.23 times") == 1);
    }
    SECTION("the same material with a depth cap (no roulette): no warning") {
        CHECK(linesWith(warnings(variant("NextEventEstimation", classic06)).log, "warning:") == 0);
    }
    SECTION("classic kd 0.3 (0.94) with RussianRoulette: no warning") {
        CHECK(linesWith(warnings(variant("RussianRoulette", "<Material id=\"1\"><DiffuseReflectance>0.3 0.3 0.3"
                                                           "</DiffuseReflectance></Material>")).log, "warning:") == 0);
    }
    SECTION("a normalized BRDF with kd 0.9 and RussianRoulette: no warning") {
        CHECK(linesWith(warnings(variant("RussianRoulette", "<Material id=\"1\" BRDF=\"1\"><DiffuseReflectance>0.9 0.9 0.9"
                                                           "</DiffuseReflectance></Material>",
                                         "<BRDFs><ModifiedPhong id=\"1\" normalized=\"true\"><Exponent>10</Exponent>"
                                         "</ModifiedPhong></BRDFs>")).log, "warning:") == 0);
    }
}
