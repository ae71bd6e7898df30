// Several OpenCL implementations side by side (issue 17): the platform:NAME device spec, "cpu"
// choosing one implementation, and conformance of PoCL with Intel's OpenCL CPU runtime: the same
// scene and seed rendered on each (through the clrt binary) agree within a measured tolerance, and
// one image rendered on both at once agrees with each. The cross-implementation cases need both
// platforms (scripts/setup_intel_ocl.sh, `source build/opencl-env.sh`); scripts/test.sh checks that
// Intel's platform is present when it was set up, so these cases do not pass by being skipped there.
#include <catch.hpp>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
using namespace clrt::test;
namespace fs = std::filesystem;

namespace {

bool hasPlatform(const std::string& part) {
    for (const DeviceInfo& d : listDevices())
        if (d.platformName.find(part) != std::string::npos) return true;
    return false;
}

// Distance of image a from b: relMSE as clrt-imgdiff computes it, and the fraction of pixels where
// some channel differs by more than `step` (8-bit images: one quantisation step) after scaling.
struct Distance {
    double relMse = 0, differing = 0;
};

Distance distance(const ImageRGB& a, const ImageRGB& b) {
    const double scale = a.isHdr ? 1.0 : 1.0 / 255.0, step = a.isHdr ? 1e-3 : 1.5 / 255.0;
    Distance d;
    size_t n = size_t(a.width) * a.height, diff = 0;
    for (size_t p = 0; p < n; ++p) {
        bool differs = false;
        for (int c = 0; c < 3; ++c) {
            double va = a.pixels[p * 3 + c] * scale, vb = b.pixels[p * 3 + c] * scale, e = va - vb;
            d.relMse += e * e / (vb * vb + 1e-2);
            differs |= std::fabs(e) > step * std::fmax(1.0, std::fabs(vb));
        }
        diff += differs;
    }
    d.relMse /= double(3 * n);
    d.differing = double(diff) / double(n);
    return d;
}

std::string readText(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// The variant list shared with the oclgrind suite: (scene under ../shared/scenes, extra args).
std::vector<std::pair<std::string, std::string>> variantScenes() {
    std::vector<std::pair<std::string, std::string>> out;
    std::ifstream in(std::string(CLRT_SOURCE_DIR) + "/scripts/kernel_variants.txt");
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        size_t sp = line.find(' ');
        out.push_back({line.substr(0, sp), sp == std::string::npos ? "" : line.substr(sp + 1)});
    }
    return out;
}

// Renders `scene` with `args` into a fresh folder `dir`; returns the log, REQUIREs exit 0.
std::string render(const std::string& scene, const std::string& args, const std::string& dir, const TempDir& tmp) {
    fs::create_directories(dir);
    std::string log = tmp.file("log.txt");
    int rc = runClrt("render " + scene + " -o " + dir + " " + args, log);
    std::string text = readText(log);
    INFO(scene << " " << args << "\n" << text);
    REQUIRE(rc == 0);
    return text;
}

// Tolerance of PoCL vs Intel's runtime, measured over the variant list at 64x48, 2 spp, seed 7 (see
// README "OpenCL implementations"): per image relMSE and fraction of pixels differing by more than
// one 8-bit step (HDR: 1e-3 relative). The relMSE allows a sample or two whose path diverged (a shadow
// or hit decision at its threshold flipped by rounding: hw4/bump_mapping_transformed under the
// stratified sampler, one pixel 26.5 vs 30.0, relMSE 2.1e-6 of the 8-bit image); a miscompile shows
// as 1e-3 and more (issue 17: 0.0092).
constexpr double kMaxRelMse = 1e-5, kMaxDiffering = 0.005;
// Issue 17: Intel's implicit vectoriser miscompiled shade_hits (cl_kernels/shade.cl, vec_type_hint) and
// rendered classic/veachAjar's glass teapot wrong whenever texture code was compiled in, also with
// --all-features. The variant list has veachAjar with its own feature set; this adds the other
// configuration that showed it (the variant list's --all-features scenes have no dielectric).
const std::pair<std::string, std::string> kIssue17Variant = {"classic/veachAjar.xml", "--all-features"};

}  // namespace

TEST_CASE("platform:NAME selects the devices of one OpenCL platform; cpu picks one implementation", "[cl][impl]") {
    std::vector<DeviceInfo> all = listDevices();
    REQUIRE(!all.empty());
    const std::string plat = all[0].platformName;
    std::vector<DeviceInfo> sel = selectDevices("platform:" + plat.substr(0, std::min<size_t>(plat.size(), 8)));
    REQUIRE(!sel.empty());
    for (const DeviceInfo& d : sel) CHECK(d.platformName.compare(0, 8, plat.substr(0, 8)) == 0);
    size_t same = 0;
    for (const DeviceInfo& d : all) same += d.platformName.compare(0, 8, plat.substr(0, 8)) == 0;
    CHECK(sel.size() == same);
    try {
        selectDevices("platform:no-such-platform-xyz");
        FAIL("no throw");
    } catch (const Error& e) {
        CHECK(e.code() == ExitCode::Device);
        CHECK(std::string(e.what()).find("platform:no-such-platform-xyz") != std::string::npos);
    }
    // "cpu": the CPU devices of a single platform, PoCL's when present.
    std::vector<DeviceInfo> cpus = selectDevices("cpu");
    REQUIRE(!cpus.empty());
    for (const DeviceInfo& d : cpus) CHECK(d.platformName == cpus[0].platformName);
    if (hasPlatform("Portable Computing Language")) CHECK(cpus[0].platformName == "Portable Computing Language");
    CHECK(selectDevices("")[0].index >= 0);
}

TEST_CASE("PoCL and Intel's OpenCL runtime render every kernel variant alike", "[impl][conformance][shared]") {
    if (!hasPlatform("Portable Computing Language") || !hasPlatform("Intel(R) OpenCL") || !haveShared()) {
        WARN("needs PoCL, Intel's OpenCL runtime (source build/opencl-env.sh) and ../shared: not run");
        return;
    }
    TempDir tmp;
    double worstRel = 0, worstDiff = 0;
    int n = 0, images = 0;
    std::vector<std::pair<std::string, std::string>> variants = variantScenes();
    variants.push_back(kIssue17Variant);
    for (const auto& [scene, extra] : variants) {
        const std::string path = sharedDir() + "/scenes/" + scene, a = tmp.file(std::to_string(n) + "p"),
                          b = tmp.file(std::to_string(n) + "i");
        const std::string args = "--resolution 64x48 --spp 2 --seed 7 " + extra;
        ++n;
        render(path, args + " --device platform:portable", a, tmp);
        render(path, args + " --device platform:intel", b, tmp);
        for (const auto& e : fs::directory_iterator(a)) {
            ImageRGB ip = readImage(e.path().string()), ii = readImage(b + "/" + e.path().filename().string());
            REQUIRE(ip.pixels.size() == ii.pixels.size());
            Distance d = distance(ii, ip);
            INFO(scene << " " << extra << ": " << e.path().filename().string() << " relMSE " << d.relMse
                       << ", differing pixels " << d.differing);
            CHECK(d.relMse <= kMaxRelMse);
            CHECK(d.differing <= kMaxDiffering);
            worstRel = std::max(worstRel, d.relMse);
            worstDiff = std::max(worstDiff, d.differing);
            ++images;
        }
    }
    CHECK(images >= n);
    WARN("PoCL vs Intel over " << n << " variants, " << images << " images: worst relMSE " << worstRel
                               << ", worst differing-pixel fraction " << worstDiff);
}

TEST_CASE("one image rendered on PoCL and Intel's runtime at once agrees with each", "[impl][multidevice]") {
    if (!hasPlatform("Portable Computing Language") || !hasPlatform("Intel(R) OpenCL")) {
        WARN("needs PoCL and Intel's OpenCL runtime (source build/opencl-env.sh): not run");
        return;
    }
    TempDir tmp;
    const std::string scene = std::string(CLRT_SOURCE_DIR) + "/scenes/demo.xml";
    const std::string args = "--resolution 256x192 --spp 2 --seed 3 ";
    render(scene, args + "--device platform:portable", tmp.file("p"), tmp);
    render(scene, args + "--device platform:intel", tmp.file("i"), tmp);
    std::string log = render(scene, args + "--device platform:portable,platform:intel", tmp.file("both"), tmp);
    // The dynamic split is printed per device, one line each, naming both platforms' devices.
    std::regex line("device \\[(\\d+)\\] [^\\n]*: (\\d+) tiles");
    int devices = 0, tiles = 0;
    for (auto it = std::sregex_iterator(log.begin(), log.end(), line); it != std::sregex_iterator(); ++it) {
        ++devices;
        tiles += std::stoi((*it)[2]);
    }
    INFO(log);
    CHECK(devices == 2);
    CHECK(tiles > 0);
    for (const auto& e : fs::directory_iterator(tmp.file("both"))) {
        ImageRGB both = readImage(e.path().string());
        for (const char* single : {"p", "i"}) {
            Distance d = distance(both, readImage(tmp.file(single) + "/" + e.path().filename().string()));
            INFO(e.path().filename().string() << " vs " << single << ": relMSE " << d.relMse << ", differing "
                                              << d.differing);
            CHECK(d.relMse <= kMaxRelMse);
            CHECK(d.differing <= kMaxDiffering);
        }
    }
}
