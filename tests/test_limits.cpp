// Limits of a render, through the clrt binary (issue 12): memory stays flat however many samples or
// bounces a render takes (peak RSS of the child from wait4), NumSamples and MaxRecursionDepth above
// the documented limits are capped with a warning naming the scene file, progress moves within a
// tile, and a damaged kernel cache entry (truncated, empty, wrong header, flipped payload bytes...)
// is rebuilt and rewritten instead of being handed to the OpenCL driver. No timing assertions.
#include <catch.hpp>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>

#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;
namespace fs = std::filesystem;

extern char** environ;

namespace {


struct Child {
    int rc = -1;          // exit code; -1 when killed by a signal
    int signal = 0;       // the signal that ended it, if any
    long maxRssKb = 0;    // peak resident set of the child (ru_maxrss)
    std::string log;      // stdout + stderr
    int errorLines = 0;   // lines starting "clrt: error:"
};

// Runs clrt with `args` and the extra environment `env` ("NAME=value"), stdout+stderr into a log
// file of `dir`; everything exec needs is prepared before fork (the test process has threads).
Child runChild(const TempDir& dir, const std::vector<std::string>& args, const std::vector<std::string>& env) {
    std::vector<std::string> argStore = {CLRT_BINARY};
    argStore.insert(argStore.end(), args.begin(), args.end());
    std::vector<char*> argv, envp;
    for (std::string& a : argStore) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> envStore(env);
    for (char** e = environ; *e; ++e) {
        std::string s = *e, name = s.substr(0, s.find('='));
        bool overridden = false;
        for (const std::string& x : env) overridden = overridden || x.compare(0, name.size() + 1, name + "=") == 0;
        if (!overridden) envStore.push_back(s);
    }
    for (std::string& e : envStore) envp.push_back(e.data());
    envp.push_back(nullptr);
    const std::string logFile = dir.file("child.log");
    Child c;
    pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        int fd = open(logFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd < 0) _exit(126);
        dup2(fd, 1);
        dup2(fd, 2);
        execve(argv[0], argv.data(), envp.data());
        _exit(127);
    }
    int status = 0;
    struct rusage ru {};
    REQUIRE(wait4(pid, &status, 0, &ru) == pid);
    c.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    c.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    c.maxRssKb = ru.ru_maxrss;
    c.log = readFileBytes(logFile);
    std::istringstream ls(c.log);
    for (std::string line; std::getline(ls, line);) c.errorLines += line.rfind("clrt: error:", 0) == 0;
    return c;
}

std::string testDeviceSpec() {
    const char* spec = std::getenv("CLRT_TEST_DEVICE");
    return spec && *spec ? spec : "cpu";
}

// A 1x1 camera at the origin looking down -z; `body` holds the rest of the scene.
std::string oneByOne(const std::string& top, const std::string& cameraExtra, const std::string& image,
                     const std::string& body) {
    return "<Scene>\n" + top +
           "\n<Cameras><Camera id=\"1\"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>"
           "<NearPlane>-0.1 0.1 -0.1 0.1</NearPlane><NearDistance>1</NearDistance>"
           "<ImageResolution>1 1</ImageResolution><ImageName>" + image + "</ImageName>" + cameraExtra +
           "</Camera></Cameras>\n" + body + "\n</Scene>\n";
}
// A diffuse triangle in front of the camera, lit by a point light.
const char* kDiffuse =
    "<Lights><PointLight id=\"1\"><Position>0 0 0</Position><Intensity>100 100 100</Intensity></PointLight></Lights>\n"
    "<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>\n"
    "<VertexData>-1 -1 -5 1 -1 -5 0 1 -5</VertexData>\n"
    "<Objects><Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle></Objects>";
// Two facing mirrors (z = -1 and z = +1) with the camera and a light between them: the camera ray
// bounces between them forever, each hit adding the same diffuse term (mirror reflectance 1).
const char* kMirrors =
    "<Lights><PointLight id=\"1\"><Position>0 0.5 0</Position><Intensity>1 1 1</Intensity></PointLight></Lights>\n"
    "<Materials><Material id=\"1\" type=\"mirror\"><DiffuseReflectance>0.1 0.1 0.1</DiffuseReflectance>"
    "<MirrorReflectance>1 1 1</MirrorReflectance></Material></Materials>\n"
    "<VertexData>-100 -100 -1 100 -100 -1 0 100 -1 -100 -100 1 100 -100 1 0 100 1</VertexData>\n"
    "<Objects><Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material></Triangle>"
    "<Triangle id=\"2\"><Indices>4 6 5</Indices><Material>1</Material></Triangle></Objects>";

std::string exrAttribute(const std::string& path, const char* name) {
    Imf::InputFile f(path.c_str());
    const auto* a = f.header().findTypedAttribute<Imf::StringAttribute>(name);
    return a ? a->value() : "";
}

void expectClean(const Child& c) {
    INFO(c.log);
    CHECK(c.signal == 0);
    CHECK(c.rc == 0);
    CHECK(c.errorLines == 0);
}

}  // namespace

// ==== issue 12: memory, samples, depth, progress, kernel cache ===================================

TEST_CASE("limits: peak memory of a 1x1 render at 1048576 spp is within 4 MB of one at 1 spp", "[limits][cli]") {
    // Before the fix every kernel launch kept its profiling event until the tile ended (about 2 KB a
    // batch); with 4096 batches of 256 samples that alone is ~9 MB here, and the old one-sample
    // batches grew without bound. The kernel cache is warmed first: a build's peak is much higher.
    TempDir d;
    writeFileBytes(d.file("s.xml"), oneByOne("", "", "one.exr", kDiffuse));
    const std::vector<std::string> env = {"CLRT_CACHE_DIR=" + d.file("cache")};
    auto render = [&](const std::string& spp) {
        return runChild(d, {"render", d.file("s.xml"), "-o", d.path.string(), "--device", testDeviceSpec(), "--spp", spp}, env);
    };
    expectClean(render("1"));  // builds and caches the kernels
    Child one = render("1");
    Child many = render("1048576");
    expectClean(one);
    expectClean(many);
    INFO("max RSS: " << one.maxRssKb << " KB at 1 spp, " << many.maxRssKb << " KB at 1048576 spp");
    CHECK(many.maxRssKb - one.maxRssKb < 4096);
    // Progress moves within the one tile (output is not a terminal: a line every 10%).
    CHECK(many.log.find("1048576 spp) 50%") != std::string::npos);
    CHECK(many.log.find("1048576 spp) done") != std::string::npos);
    CHECK(many.log.find("stats:") != std::string::npos);
    CHECK(many.log.find("spp=1048576") != std::string::npos);
    CHECK(exrAttribute(d.file("one.exr"), "spp") == "1048576");
}

TEST_CASE("limits: progress moves within the one tile of a multi-device render", "[limits][cli][multidevice]") {
    TempDir d;
    writeFileBytes(d.file("s.xml"), oneByOne("", "", "one.exr", kDiffuse));
    Child c = runChild(d, {"render", d.file("s.xml"), "-o", d.path.string(), "--device", "all", "--spp", "65536"},
                       {"POCL_DEVICES=pthread pthread", "CLRT_CACHE_DIR=" + d.file("cache")});
    expectClean(c);
    INFO(c.log);
    CHECK(c.log.find("65536 spp) 10%") != std::string::npos);
    CHECK(c.log.find("65536 spp) 90%") != std::string::npos);
    CHECK(c.log.find("65536 spp) done") != std::string::npos);
}

TEST_CASE("limits: NumSamples above 1048576 is capped with a warning naming the scene file", "[limits][cli]") {
    TempDir d;
    const std::vector<std::string> env = {"CLRT_CACHE_DIR=" + d.file("cache")};
    SECTION("1e9 renders 1048576 samples") {
        writeFileBytes(d.file("big.xml"), oneByOne("", "<NumSamples>1e9</NumSamples>", "big.exr", kDiffuse));
        Child c = runChild(d, {"render", d.file("big.xml"), "-o", d.path.string(), "--device", testDeviceSpec()}, env);
        expectClean(c);
        INFO(c.log);
        CHECK(c.log.find("warning: " + d.file("big.xml") + ":") != std::string::npos);
        CHECK(c.log.find("NumSamples 1000000000 is above the limit 1048576; capped to 1048576") != std::string::npos);
        CHECK(c.log.find("spp=1048576") != std::string::npos);
        CHECK(exrAttribute(d.file("big.exr"), "spp") == "1048576");
    }
    SECTION("a value beyond int (1e12) is capped too, and --spp still overrides it") {
        writeFileBytes(d.file("huge.xml"), oneByOne("", "<NumSamples>1e12</NumSamples>", "huge.exr", kDiffuse));
        Child c = runChild(d, {"render", d.file("huge.xml"), "-o", d.path.string(), "--device", testDeviceSpec(),
                               "--spp", "3"}, env);
        expectClean(c);
        INFO(c.log);
        CHECK(c.log.find("huge.xml:") != std::string::npos);
        CHECK(c.log.find("NumSamples 1000000000000 is above the limit 1048576") != std::string::npos);
        CHECK(exrAttribute(d.file("huge.exr"), "spp") == "3");
    }
    SECTION("the same limit on the command line") {
        writeFileBytes(d.file("s.xml"), oneByOne("", "", "s.exr", kDiffuse));
        Child c = runChild(d, {"render", d.file("s.xml"), "-o", d.path.string(), "--spp", "1048577"}, env);
        INFO(c.log);
        CHECK(c.rc == 1);
        CHECK(c.errorLines == 1);
        CHECK(c.log.find("1048576") != std::string::npos);
        CHECK(!fs::exists(d.file("s.exr")));
    }
}

TEST_CASE("limits: two facing mirrors at MaxRecursionDepth 1e9 finish at depth 256 with a warning", "[limits][cli]") {
    TempDir d;
    const std::vector<std::string> env = {"CLRT_CACHE_DIR=" + d.file("cache")};
    auto render = [&](const std::string& depth, const std::string& name, const std::string& spp = "4") {
        writeFileBytes(d.file(name + ".xml"),
                  oneByOne("<MaxRecursionDepth>" + depth + "</MaxRecursionDepth>", "", name + ".exr", kMirrors));
        return runChild(d, {"render", d.file(name + ".xml"), "-o", d.path.string(), "--device", testDeviceSpec(),
                            "--spp", spp}, env);
    };
    Child capped = render("1e9", "deep");
    expectClean(capped);
    INFO(capped.log);
    CHECK(capped.log.find("warning: " + d.file("deep.xml") + ":") != std::string::npos);
    CHECK(capped.log.find("MaxRecursionDepth 1000000000 is above the limit 256; capped to 256") != std::string::npos);
    Child at256 = render("256", "d256");
    expectClean(at256);
    expectClean(render("255", "d255"));
    ImageRGB a = readImage(d.file("deep.exr")), b = readImage(d.file("d256.exr")), c = readImage(d.file("d255.exr"));
    REQUIRE(a.pixels.size() == 3);
    CHECK(a.pixels == b.pixels);  // rendered at exactly the limit
    CHECK(a.pixels[0] > c.pixels[0]);  // each bounce adds light: the 256th bounce was traced
    CHECK(std::isfinite(a.pixels[0]));
    // 16 batches of 256 samples, 256 bounces each: no more memory than 4 samples (kernels cached).
    Child many = render("256", "many", "4096");
    expectClean(many);
    INFO("max RSS: " << at256.maxRssKb << " KB at 4 spp, " << many.maxRssKb << " KB at 4096 spp");
    CHECK(many.maxRssKb - at256.maxRssKb < 4096);
}

TEST_CASE("limits: samples batched together do not change a pixel whatever the tiling", "[limits][render]") {
    // A small image takes several samples of a pixel per batch; tiles of 7 pixels (as on several
    // devices) and a smaller batch limit must give the same floats as one whole-image render.
    Scene scene = loadScene(std::string(CLRT_SOURCE_DIR) + "/scenes/demo.xml");
    Camera cam = scene.cameras[0];
    cam.width = 24;
    cam.height = 16;
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = 37;
    RenderCounters counters;
    ImageRGB whole = r.render(cam, rs, counters);
    ImageRGB tiled = whole;
    std::fill(tiled.pixels.begin(), tiled.pixels.end(), -1.0f);
    size_t next = 0;
    RenderSettings small = rs;
    small.maxBatchPixels = 100;
    r.renderTiles(cam, small, counters, [&](size_t& first, size_t& count) {
        if (next >= size_t(cam.width) * cam.height) return false;
        first = next;
        count = 7;
        next += 7;
        return true;
    }, tiled);
    CHECK(whole.pixels == tiled.pixels);
    for (float v : whole.pixels) CHECK(std::isfinite(v));
}

TEST_CASE("limits: a damaged kernel cache entry is rebuilt and rewritten, never loaded", "[limits][cli][cache]") {
    TempDir d;
    writeFileBytes(d.file("s.xml"), oneByOne("", "<NumSamples>4</NumSamples>", "c.exr", kDiffuse));
    const std::vector<std::string> env = {"CLRT_CACHE_DIR=" + d.file("cache")};
    const std::vector<std::string> args = {"render", d.file("s.xml"), "-o", d.path.string(), "--device",
                                           testDeviceSpec(), "-v"};
    expectClean(runChild(d, args, env));
    const ImageRGB reference = readImage(d.file("c.exr"));
    std::vector<std::string> entries;
    for (auto& e : fs::directory_iterator(d.file("cache")))
        if (e.path().extension() == ".bin") entries.push_back(e.path().string());
    REQUIRE(!entries.empty());
    for (const std::string& e : entries) REQUIRE(programCacheEntryValid(e));

    using Damage = std::function<void(std::string&)>;
    const std::vector<std::pair<const char*, Damage>> damages = {
        {"truncated to half", [](std::string& b) { b.resize(b.size() / 2); }},
        {"truncated inside the header", [](std::string& b) { b.resize(12); }},
        {"zero length", [](std::string& b) { b.clear(); }},
        {"wrong magic", [](std::string& b) { std::memcpy(&b[0], "NOTCLRT!", 8); }},
        {"not a cache file at all", [](std::string& b) { b = std::string(b.size(), 'x'); }},
        {"payload bytes flipped, header intact", [](std::string& b) {
             for (size_t i = 32 + 101; i < b.size(); i += 997) b[i] = char(b[i] ^ 0x5a);
         }},
        {"one payload bit flipped", [](std::string& b) { b[b.size() / 2] = char(b[b.size() / 2] ^ 1); }},
        {"length field changed", [](std::string& b) { b[16] = char(b[16] + 1); }},
        {"checksum field changed", [](std::string& b) { b[24] = char(b[24] ^ 0xff); }},
        {"trailing bytes", [](std::string& b) { b += "garbage"; }},
    };
    for (const auto& [what, damage] : damages) {
        INFO(what);
        for (const std::string& e : entries) {
            std::string bytes = readFileBytes(e);
            damage(bytes);
            writeFileBytes(e, bytes);
            CHECK(!programCacheEntryValid(e));
        }
        Child c = runChild(d, args, env);
        expectClean(c);
        CHECK(c.log.find("is damaged (length or checksum); rebuilt") != std::string::npos);
        CHECK(readImage(d.file("c.exr")).pixels == reference.pixels);
        for (const std::string& e : entries) CHECK(programCacheEntryValid(e));
        // The rewritten entries load, and nothing but the entries is left in the cache folder.
        Child again = runChild(d, args, env);
        expectClean(again);
        CHECK(again.log.find("loaded from cache") != std::string::npos);
        CHECK(again.log.find("damaged") == std::string::npos);
        CHECK(size_t(std::distance(fs::directory_iterator(d.file("cache")), fs::directory_iterator())) ==
              entries.size());
    }
    // A temporary entry left by a writer killed mid-write goes when an entry is next written, once it
    // is ten minutes old (a younger one may belong to a writer still running).
    const std::string stale = d.file("cache/0000000000000000.bin.tmp.1.0"), fresh = d.file("cache/1.bin.tmp.2.0");
    writeFileBytes(stale, "half an entry");
    writeFileBytes(fresh, "half an entry");
    fs::last_write_time(stale, fs::file_time_type::clock::now() - std::chrono::hours(1));
    for (const std::string& e : entries) writeFileBytes(e, "");
    expectClean(runChild(d, args, env));
    CHECK(!fs::exists(stale));
    CHECK(fs::exists(fresh));
}
