// Several devices on one image (src/render/multi_device.cpp), through the clrt binary: PoCL exposes
// two CPU devices with POCL_DEVICES="pthread pthread". Checks that a two-device render equals the
// one-device render bit for bit, that dynamic scheduling gives more tiles to the faster device
// (one is throttled by the CLRT_THROTTLE_DEVICE hook), and that a failing device is dropped.
// Only PoCL's devices are used (named by their global indices from `clrt devices`): other
// implementations present (a GPU, Intel's CPU runtime) give images that are not bit-identical.
#include <catch.hpp>

#include <fstream>
#include <regex>
#include <sstream>

#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// A copy of the demo scene that writes EXR (exact floats) at a small size.
std::string writeScene(const TempDir& dir) {
    std::string xml = readFileBytes(std::string(CLRT_SOURCE_DIR) + "/scenes/demo.xml");
    xml = std::regex_replace(xml, std::regex("demo\\.png"), "multi.exr");
    xml = std::regex_replace(xml, std::regex("640 480"), "320 240");
    std::string path = dir.file("multi.xml");
    std::ofstream(path) << xml;
    return path;
}

// Global indices of PoCL's devices ("Portable Computing Language"; PoCL 3 names them pthread-...,
// PoCL 5 cpu-...) as `clrt devices` lists them under the environment prefix `env`.
std::vector<int> poclIndices(const TempDir& dir, const std::string& env) {
    std::string log = dir.file("devices.txt");
    std::system((env + CLRT_BINARY + " devices >" + log + " 2>&1").c_str());
    std::vector<int> out;
    std::istringstream in(readFileBytes(log));
    std::smatch m;
    for (std::string line; std::getline(in, line);)
        if (std::regex_search(line, m, std::regex("^\\[(\\d+)\\].*\\(platform: Portable Computing Language\\)")))
            out.push_back(std::stoi(m[1]));
    return out;
}

int tilesOf(const std::string& log, int device) {
    std::smatch m;
    std::regex re("device \\[" + std::to_string(device) + "\\][^:]*: (\\d+) tiles");
    return std::regex_search(log, m, re) ? std::stoi(m[1]) : -1;
}
}  // namespace

TEST_CASE("two PoCL devices render the same image as one, balanced dynamically", "[multidevice]") {
    TempDir dir;
    std::string scene = writeScene(dir);
    std::string one = dir.file("one"), two = dir.file("two"), three = dir.file("three");
    std::filesystem::create_directories(one);
    std::filesystem::create_directories(two);
    std::filesystem::create_directories(three);
    const std::string env = "POCL_DEVICES='pthread pthread' CLRT_CACHE_DIR=" + dir.file("cache") + " ";
    auto run = [&](const std::string& prefix, const std::string& args) {
        std::string log = dir.file("log.txt");
        int rc = std::system((prefix + env + CLRT_BINARY + " render " + scene + " " + args + " >" + log + " 2>&1").c_str());
        return std::make_pair(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFileBytes(log));
    };
    std::vector<int> pocl = poclIndices(dir, env);
    REQUIRE(pocl.size() == 2);
    const std::string p0 = std::to_string(pocl[0]), p1 = std::to_string(pocl[1]);
    const std::string both01 = " --device " + p0 + "," + p1;
    auto single = run("", "-o " + one + " --device " + p0 + " --spp 2");
    REQUIRE(single.first == 0);
    // Throttle/fail hooks name a device by its position in the --device list (1 = the second).
    auto both = run("CLRT_THROTTLE_DEVICE=1:150 ", "-o " + two + both01 + " --spp 2");
    INFO(both.second);
    REQUIRE(both.first == 0);
    CHECK(readFileBytes(one + "/multi.exr").size() > 1000);
    // EXR headers differ only by attributes we do not write per device; compare the decoded floats.
    ImageRGB a = readImage(one + "/multi.exr"), b = readImage(two + "/multi.exr");
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(a.pixels == b.pixels);
    int t0 = tilesOf(both.second, pocl[0]), t1 = tilesOf(both.second, pocl[1]);
    CHECK(t0 > 0);
    CHECK(t1 > 0);
    CHECK(t0 > t1);  // the throttled device takes fewer tiles

    SECTION("a device that fails mid-render is dropped and its tile re-rendered elsewhere") {
        auto failing = run("CLRT_FAIL_DEVICE=1:2 ", "-o " + three + both01 + " --spp 2");
        INFO(failing.second);
        CHECK(failing.first == 0);
        CHECK(failing.second.find("failed and was dropped") != std::string::npos);
        ImageRGB c = readImage(three + "/multi.exr");
        CHECK(c.pixels == a.pixels);
    }
    SECTION("with no device left the render fails clearly") {
        auto dead = run("CLRT_FAIL_DEVICE=-1:1 ", "-o " + three + both01 + " --spp 2");
        CHECK(dead.first == 3);
        CHECK(dead.second.find("every rendering device failed") != std::string::npos);
    }
}
