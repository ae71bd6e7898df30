// The clrt binary on bad input: every case runs `clrt render` (tests/test_helpers.h runClrt) and checks
// the exit code (1 usage, 2 bad input, 3 device, 4 output), that stderr holds exactly ONE
// "clrt: error:" line naming the offending file (file:line:col for XML syntax errors), that nothing
// crashed, and that no output (or temporary file) was left behind. Most cases fail before the kernel
// build; the few that get past it use a 4x4 image.
#include <catch.hpp>

#include <fstream>
#include <iterator>
#include <sstream>

#include <stb/stb_image_write.h>

#include "image/image.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;
namespace fs = std::filesystem;

namespace {


using Run = CliResult;

// Runs `clrt <args>` (arguments already quoted where needed) with an optional environment prefix.
Run runCli(const TempDir& dir, const std::string& args, const std::string& envPrefix = "") {
    std::string logFile = dir.file("clrt.log");
    int rc = -1;
    if (envPrefix.empty()) {
        rc = runClrt(args, logFile);
    } else {
        std::string cmd = envPrefix + " " + std::string(CLRT_BINARY) + " " + args + " >" + logFile + " 2>&1";
        int st = std::system(cmd.c_str());
        rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }
    return cliResult(rc, readFileBytes(logFile));
}

// A scene with one camera (4x4 unless `resolution` says otherwise), one point light, one material,
// 3 vertices and whatever `objects` and `extra` (top-level elements) say.
std::string scene(const std::string& objects, const std::string& extra = "", const std::string& resolution = "4 4",
                  const std::string& cameraBody = "") {
    std::string cam = cameraBody.empty() ? "<Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>"
                                           "<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance>"
                                         : cameraBody;
    return "<Scene>\n<Cameras><Camera id=\"1\">" + cam + "<ImageResolution>" + resolution +
           "</ImageResolution><ImageName>out.png</ImageName></Camera></Cameras>\n"
           "<Lights><PointLight id=\"1\"><Position>0 0 5</Position><Intensity>100 100 100</Intensity></PointLight>"
           "</Lights>\n<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material>"
           "</Materials>\n<VertexData>-1 -1 0 1 -1 0 0 1 0</VertexData>\n<TexCoordData>0 0 1 0 0.5 1</TexCoordData>\n" +
           extra + "\n<Objects>\n" + objects + "\n</Objects>\n</Scene>\n";
}
const char* kTriangle = "<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle>";

std::string texturedScene(const std::string& imageFile) {
    return scene("<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material><Textures>1</Textures></Triangle>",
                 "<Textures><Images><Image id=\"1\">" + imageFile +
                     "</Image></Images><TextureMap id=\"1\" type=\"image\"><ImageId>1</ImageId>"
                     "<DecalMode>replace_kd</DecalMode></TextureMap></Textures>");
}

// Expect exit code `rc` and one error line that contains every needle.
void expectError(const Run& r, int rc, std::initializer_list<std::string> needles) {
    INFO("output:\n" << r.log);
    CHECK(r.rc == rc);
    CHECK(r.errorLines == 1);
    for (const std::string& n : needles) CHECK(r.errorLine.find(n) != std::string::npos);
    CHECK(r.log.find("AddressSanitizer") == std::string::npos);
    CHECK(r.log.find("runtime error") == std::string::npos);
}

// No output image and no temporary sibling was left in `dir`.
void expectNoOutput(const fs::path& dir) {
    for (auto& e : fs::directory_iterator(dir)) {
        std::string n = e.path().filename().string();
        INFO(n);
        CHECK(n.find(".tmp-") == std::string::npos);
        CHECK(n != "out.png");
    }
}

// Small valid image files made here (no dependency on ../shared).
void makePng(const std::string& path) {
    std::vector<unsigned char> px(16 * 16 * 3);
    for (size_t i = 0; i < px.size(); ++i) px[i] = (unsigned char)(i * 7);
    REQUIRE(stbi_write_png(path.c_str(), 16, 16, 3, px.data(), 16 * 3));
}
void makeJpg(const std::string& path) {
    std::vector<unsigned char> px(16 * 16 * 3);
    for (size_t i = 0; i < px.size(); ++i) px[i] = (unsigned char)(i * 13);
    REQUIRE(stbi_write_jpg(path.c_str(), 16, 16, 3, px.data(), 90));
}
void makeExr(const std::string& path) {
    ImageRGB img;
    img.width = img.height = 16;
    img.pixels.assign(16 * 16 * 3, 0.5f);
    writeExr(path, img);
}
void truncateCopy(const std::string& from, const std::string& to, double keep) {
    std::string bytes = readFileBytes(from);
    writeFileBytes(to, bytes.substr(0, size_t(double(bytes.size()) * keep)));
}
void corruptCopy(const std::string& from, const std::string& to, size_t skipHeader) {
    std::string bytes = readFileBytes(from);
    for (size_t i = skipHeader; i < bytes.size(); i += 3) bytes[i] = char(bytes[i] ^ 0x5A);
    writeFileBytes(to, bytes);
}

}  // namespace

TEST_CASE("cli: usage errors exit 1 with one line", "[cli]") {
    TempDir d;
    expectError(runCli(d, "render"), 1, {"expected exactly one scene file"});
    expectError(runCli(d, "render a.xml --spp 0"), 1, {"--spp"});
    expectError(runCli(d, "render a.xml --bogus"), 1, {"--bogus"});
    expectError(runCli(d, "frobnicate"), 1, {"frobnicate"});
}

TEST_CASE("cli: files that are not scenes", "[cli]") {
    TempDir d;
    SECTION("missing file") {
        expectError(runCli(d, "render " + d.file("nope.xml") + " -o " + d.path.string()), 2, {"nope.xml", "does not exist"});
    }
    SECTION("a directory") { expectError(runCli(d, "render " + d.path.string() + " -o " + d.path.string()), 2, {d.path.string()}); }
    SECTION("binary garbage") {
        std::string f = d.file("garbage.xml");
        writeFileBytes(f, std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16));
        expectError(runCli(d, "render " + f + " -o " + d.path.string()), 2, {"garbage.xml", "neither XML"});
    }
    SECTION("empty file") {
        std::string f = d.file("empty.xml");
        writeFileBytes(f, "  \n ");
        expectError(runCli(d, "render " + f + " -o " + d.path.string()), 2, {"empty.xml", "empty"});
    }
    SECTION("XML syntax error has file:line:col") {
        std::string f = d.file("broken.xml");
        writeFileBytes(f, "<Scene>\n  <Cameras>\n    <Camera id=\"1\">\n  </Cameras>\n</Scene>\n");
        Run r = runCli(d, "render " + f + " -o " + d.path.string());
        expectError(r, 2, {"broken.xml:4:"});
    }
    SECTION("JSON syntax error has file:line:col") {
        std::string f = d.file("broken.json");
        writeFileBytes(f, "{\"Scene\": {\n  \"MaxRecursionDepth\": \"2\",\n  ]\n}\n");
        expectError(runCli(d, "render " + f + " -o " + d.path.string()), 2, {"broken.json:3:"});
    }
    SECTION("unknown root") {
        std::string f = d.file("root.xml");
        writeFileBytes(f, "<!-- c -->\n<Scen></Scen>\n");
        expectError(runCli(d, "render " + f + " -o " + d.path.string()), 2, {"root.xml:2:1", "<Scen>"});
    }
}

TEST_CASE("cli: scene content errors name file:line:col", "[cli]") {
    TempDir d;
    std::string f = d.file("s.xml");
    auto run = [&](const std::string& text) {
        writeFileBytes(f, text);
        return runCli(d, "render " + f + " -o " + d.path.string());
    };
    SECTION("missing required element") {
        expectError(run(scene(kTriangle, "", "4 4", "<Gaze>0 0 -1</Gaze><Up>0 1 0</Up><NearPlane>-1 1 -1 1</NearPlane>"
                                                     "<NearDistance>1</NearDistance>")),
                    2, {"s.xml:2:", "Position"});
    }
    SECTION("undefined material") {
        expectError(run(scene("<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>7</Material></Triangle>")), 2,
                    {"s.xml:", "undefined Material 7"});
    }
    SECTION("undefined texture") {
        expectError(run(scene("<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material>"
                              "<Textures>3</Textures></Triangle>")),
                    2, {"s.xml:", "undefined TextureMap 3"});
    }
    SECTION("undefined transformation") {
        expectError(run(scene("<Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material>"
                              "<Transformations>t9</Transformations></Triangle>")),
                    2, {"s.xml:", "t9"});
    }
    SECTION("vertex index out of range") {
        expectError(run(scene("<Triangle id=\"1\"><Indices>1 2 4</Indices><Material>1</Material></Triangle>")), 2,
                    {"s.xml:", "vertex index 4", "out of range"});
        expectError(run(scene("<Mesh id=\"1\"><Material>1</Material><Faces>1 2 0</Faces></Mesh>")), 2,
                    {"s.xml:", "vertex index 0"});
    }
    SECTION("zero and negative resolution") {
        expectError(run(scene(kTriangle, "", "0 4")), 2, {"s.xml:", "ImageResolution must be positive"});
        expectError(run(scene(kTriangle, "", "4 -3")), 2, {"s.xml:", "ImageResolution must be positive"});
        expectError(run(scene(kTriangle, "", "4.5 4")), 2, {"s.xml:", "not an integer"});
        expectError(run(scene(kTriangle, "", "99999999999 4")), 2, {"s.xml:"});
    }
    SECTION("a number that is not a number") {
        expectError(run(scene(kTriangle, "<BackgroundColor>0 nan 0</BackgroundColor>")), 2, {"s.xml:", "'nan'"});
    }
    expectNoOutput(d.path);
}

TEST_CASE("cli: absurd resolution is refused up front with the device limit", "[cli]") {
    TempDir d;
    std::string f = d.file("huge.xml");
    writeFileBytes(f, scene(kTriangle, "", "200000 200000"));
    Run r = runCli(d, "render " + f + " -o " + d.path.string() + " --device cpu");
    expectError(r, 2, {"200000x200000", "MiB"});
    // Refused before the kernel build and before any host allocation of that size.
    CHECK(r.log.find("out of host memory") == std::string::npos);
    expectNoOutput(d.path);
}

TEST_CASE("cli: bad PLY files", "[cli]") {
    TempDir d;
    std::string f = d.file("s.xml");
    writeFileBytes(f, scene("<Mesh id=\"1\"><Material>1</Material><Faces plyFile=\"m.ply\"/></Mesh>"));
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    auto run = [&](const std::string& ply) {
        if (!ply.empty()) writeFileBytes(d.file("m.ply"), ply);
        return runCli(d, "render " + f + " -o " + d.path.string());
    };
    SECTION("missing") { expectError(run(""), 2, {"s.xml:", "m.ply", "cannot open"}); }
    SECTION("not a PLY") { expectError(run("solid cube\nfacet normal 0 0 1\n"), 2, {"m.ply", "not a PLY file"}); }
    SECTION("truncated ASCII") { expectError(run(header + "0 0 0\n1 0 0\n0 1"), 2, {"m.ply"}); }
    SECTION("header lies about counts") {
        std::string lie = header;
        lie.replace(lie.find("vertex 3"), 8, "vertex 3000000000");
        expectError(run(lie + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), 2, {"m.ply", "header"});
    }
    SECTION("binary, truncated") {
        std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        bin += std::string(36, '\0');  // vertices
        bin += std::string("\x03\x00\x00\x00\x00\x01\x00", 7);  // face cut short
        expectError(run(bin), 2, {"m.ply", "ends early"});
    }
    SECTION("face index out of range") { expectError(run(header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), 2, {"m.ply", "vertex index 3"}); }
    SECTION("unreadable (a directory)") {
        fs::create_directory(d.file("m.ply"));
        expectError(run(""), 2, {"m.ply"});
    }
    expectNoOutput(d.path);
}

TEST_CASE("cli: missing, truncated and corrupt texture images", "[cli]") {
    TempDir d;
    makePng(d.file("good.png"));
    makeJpg(d.file("good.jpg"));
    makeExr(d.file("good.exr"));
    std::string f = d.file("s.xml");
    auto run = [&](const std::string& image) {
        writeFileBytes(f, texturedScene(image));
        return runCli(d, "render " + f + " -o " + d.path.string());
    };
    SECTION("missing") { expectError(run("nope.png"), 2, {"nope.png", "cannot open"}); }
    SECTION("empty") {
        writeFileBytes(d.file("empty.png"), "");
        expectError(run("empty.png"), 2, {"empty.png"});
    }
    SECTION("unknown format") {
        writeFileBytes(d.file("text.png"), "this is not an image\n");
        expectError(run("text.png"), 2, {"text.png", "unknown image format"});
    }
    for (const char* ext : {"png", "jpg", "exr"}) {
        DYNAMIC_SECTION("truncated " << ext) {
            std::string bad = std::string("trunc.") + ext;
            truncateCopy(d.file(std::string("good.") + ext), d.file(bad), 0.5);
            expectError(run(bad), 2, {bad});
        }
        DYNAMIC_SECTION("header only " << ext) {
            std::string bad = std::string("head.") + ext;
            truncateCopy(d.file(std::string("good.") + ext), d.file(bad), 0.05);
            expectError(run(bad), 2, {bad});
        }
    }
    SECTION("corrupt PNG (bad CRC/zlib)") {
        corruptCopy(d.file("good.png"), d.file("bad.png"), 8);
        expectError(run("bad.png"), 2, {"bad.png"});
    }
    SECTION("corrupt EXR header") {
        corruptCopy(d.file("good.exr"), d.file("bad.exr"), 4);
        expectError(run("bad.exr"), 2, {"bad.exr"});
    }
    SECTION("JPEG with an oversized Huffman table (stb_image 2.27 overflow)") {
        // SOI, DHT whose 16 code counts sum to 16*255, then garbage: must be refused, not decoded.
        std::string j = "\xFF\xD8\xFF\xC4";
        j += std::string("\x01\x13\x00", 3);  // length 275, class 0 table 0
        j += std::string(16, '\xFF');
        j += std::string(256, '\x01');
        j += "\xFF\xD9";
        writeFileBytes(d.file("evil.jpg"), j);
        expectError(run("evil.jpg"), 2, {"evil.jpg", "Huffman"});
    }
    expectNoOutput(d.path);
}

TEST_CASE("cli: output errors exit 4 and leave no partial file", "[cli]") {
    TempDir d;
    std::string f = d.file("s.xml");
    writeFileBytes(f, scene(kTriangle));
    SECTION("output directory does not exist") {
        expectError(runCli(d, "render " + f + " -o " + d.file("no/such/dir")), 4, {"no/such/dir", "does not exist"});
    }
    SECTION("output directory is a file") {
        writeFileBytes(d.file("afile"), "x");
        expectError(runCli(d, "render " + f + " -o " + d.file("afile")), 4, {"afile"});
    }
    SECTION("output file cannot be written (a directory has its name)") {
        fs::create_directories(d.file("out/out.png"));
        Run r = runCli(d, "render " + f + " -o " + d.file("out"));
        expectError(r, 4, {"out.png"});
        CHECK(fs::is_directory(d.file("out/out.png")));
        for (auto& e : fs::directory_iterator(d.file("out")))
            CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);
    }
}

TEST_CASE("cli: --device naming no device", "[cli]") {
    TempDir d;
    std::string f = d.file("s.xml");
    writeFileBytes(f, scene(kTriangle));
    expectError(runCli(d, "render " + f + " -o " + d.path.string() + " --device no-such-device-xyz"), 3,
                {"no-such-device-xyz", "names no OpenCL device"});
    expectError(runCli(d, "render " + f + " -o " + d.path.string() + " --device 99"), 3, {"99"});
    expectNoOutput(d.path);
}

TEST_CASE("cli: a kernel build failure prints the build log and keeps a good output file", "[cli]") {
    // A copy of cl_kernels/ with a syntax error in shade.cl, used through CLRT_KERNEL_DIR (the kernels'
    // includes of ../src/shared/ are then read from $CLRT_KERNEL_DIR/../src/shared/).
    TempDir d;
    fs::path src = fs::path(CLRT_SOURCE_DIR);
    fs::create_directories(d.path / "k/cl_kernels");
    fs::create_directories(d.path / "k/src/shared");
    for (auto& e : fs::directory_iterator(src / "cl_kernels")) fs::copy_file(e.path(), d.path / "k/cl_kernels" / e.path().filename());
    for (auto& e : fs::directory_iterator(src / "src/shared"))  // what the kernels #include
        fs::copy_file(e.path(), d.path / "k/src/shared" / e.path().filename());
    {
        std::ofstream out(d.path / "k/cl_kernels/shade.cl", std::ios::app);
        out << "\n__kernel void clrt_broken_on_purpose(void) { this is not C; }\n";
    }
    fs::create_directories(d.file("out"));
    const std::string good = "previous good render";
    writeFileBytes(d.file("out/out.png"), good);
    std::string f = d.file("s.xml");
    writeFileBytes(f, scene(kTriangle));
    Run r = runCli(d, "render " + f + " -o " + d.file("out") + " --device cpu",
                 "CLRT_NO_CACHE=1 CLRT_KERNEL_DIR='" + (d.path / "k/cl_kernels").string() + "'");
    INFO(r.log);
    CHECK(r.rc == 3);
    CHECK(r.errorLines == 1);
    CHECK(r.errorLine.find("build failed") != std::string::npos);
    CHECK(r.log.find("build log") != std::string::npos);
    CHECK(r.log.find("shade.cl") != std::string::npos);
    CHECK(readFileBytes(d.file("out/out.png")) == good);
    for (auto& e : fs::directory_iterator(d.file("out")))
        CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);
}

TEST_CASE("cli: a render that fails after loading leaves the existing output untouched", "[cli]") {
    TempDir d;
    fs::create_directories(d.file("out"));
    const std::string good = "previous good render";
    writeFileBytes(d.file("out/out.png"), good);
    // The scene loads (the image path is only a name), then flattening fails to decode the image.
    writeFileBytes(d.file("bad.png"), "\x89PNG\r\n\x1a\n truncated");
    std::string f = d.file("s.xml");
    writeFileBytes(f, texturedScene("bad.png"));
    Run r = runCli(d, "render " + f + " -o " + d.file("out"));
    expectError(r, 2, {"bad.png"});
    CHECK(readFileBytes(d.file("out/out.png")) == good);
    // And the same scene with a good image does replace it (the test can tell the two apart).
    makePng(d.file("bad.png"));
    Run ok = runCli(d, "render " + f + " -o " + d.file("out"));
    INFO(ok.log);
    CHECK(ok.rc == 0);
    CHECK(readFileBytes(d.file("out/out.png")) != good);
    ImageRGB img = readImage(d.file("out/out.png"));
    CHECK(img.width == 4);
}
