// Replays the committed fuzz inputs through the readers of the normal build: every file of
// fuzz/regressions/<target>/ (past findings, kept so they stay fixed) and fuzz/corpus/<target>/ (the
// seeds of the deterministic fuzz run in scripts/test.sh). Each must load or fail with clrt::Error;
// anything else (another exception type, a crash) fails the test. A loaded result must pass the same
// checks as the fuzz targets (fuzz/fuzz_*.cpp), and the findings listed in kExpected must give the
// outcome written there. The sanitizer builds replay the same files (scripts/fuzz.sh --gate).
#include <catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "image/image.h"
#include "scene/ply_reader.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
namespace fs = std::filesystem;

namespace {

// Files of fuzz/<kind>/<target>/, sorted (deterministic order).
std::vector<fs::path> fuzzFiles(const std::string& kind, const std::string& target) {
    std::vector<fs::path> out;
    fs::path dir = fs::path(CLRT_SOURCE_DIR) / "fuzz" / kind / target;
    if (!fs::is_directory(dir)) return out;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.is_regular_file()) out.push_back(e.path());
    std::sort(out.begin(), out.end());
    return out;
}

// What a past finding must give: "" = loads, anything else = a clrt::Error whose message contains it.
const std::map<std::string, std::string> kExpected = {
    {"face_index_6e32.ply", "face 0 has vertex index 6.66666667e+32, out of range"},
    {"face_index_uint_max_binary.ply", "vertex index 4294967295, out of range"},
    {"vertex_1e39.ply", "vertex 1 has y = 1e+39, not a finite 32-bit float"},
    {"vertex_nan_binary.ply", "vertex 1 has y = nan, not a finite 32-bit float"},
    {"header_lies_count.ply", "the header lies about counts"},
    {"list_count_1e15.ply", "file ends early"},
    {"jpeg_dht_272_codes.jpg", "corrupt Huffman table (272 codes, at most 256)"},
    {"png_zero_length_idat.png", ""},
    {"png_truncated.png", "cannot decode PNG"},
    {"exr_huge_data_window.exr", "cannot read EXR"},
    {"number_overflow_1e400.json", ":3:23: number overflow parsing '1e400'"},
    {"vertex_1e39.xml", ":3:3: <VertexData>: '1e39' is out of range"},
    {"ply_is_directory.xml", "cannot open PLY file: not a regular file"},
    {"ply_dev_zero.xml", "/dev/zero: cannot open PLY file: not a regular file"},
    {"binaryfile_is_directory.xml", "not a regular file"},
    {"id_overflow.xml", "attribute id='99999999999' is out of range"},
    {"transform_id_overflow.xml", "transformation 't4294967297': id out of range"},
    {"camera_huge_gaze.xml", ""},
};

// Runs one input the way fuzz/fuzz_<target>.cpp does (copied to a private folder under the fuzzer's
// file name, so relative paths in scenes resolve the same way). Returns "" if it loaded, else the
// clrt::Error message. Other exceptions propagate and fail the test case.
std::string replay(const std::string& target, const fs::path& input) {
    test::TempDir dir;
    const char* name = target == "scene" ? "scene.xml" : target == "ply" ? "mesh.ply" : "image.bin";
    fs::copy_file(input, dir.path / name);
    const std::string path = dir.file(name);
    try {
        if (target == "scene") {
            Scene s = loadScene(path);
            (void)s;
        } else if (target == "ply") {
            MeshData m = readPly(path);
            CHECK(m.indices.size() % 3 == 0);
            for (int i : m.indices) CHECK((i >= 0 && size_t(i) < m.positions.size()));
            CHECK((m.normals.empty() || m.normals.size() == m.positions.size()));
            CHECK((m.uvs.empty() || m.uvs.size() == m.positions.size()));
            for (const Vec3& p : m.positions) CHECK(isFinite(p));
        } else {
            ImageRGB img = readImage(path);
            CHECK(img.width > 0);
            CHECK(img.height > 0);
            CHECK(img.pixels.size() == size_t(img.width) * size_t(img.height) * 3);
            for (float v : img.pixels) CHECK(std::isfinite(v));
        }
    } catch (const Error& e) {
        std::string msg = e.what();
        CHECK(msg.find('\n') == std::string::npos);  // one line
        CHECK(msg.find(path) != std::string::npos);  // names the file
        return msg;
    }
    return "";
}

}  // namespace

TEST_CASE("fuzz: every past finding in fuzz/regressions gives its expected outcome", "[fuzz]") {
    size_t replayed = 0;
    std::map<std::string, int> seen;
    for (const char* target : {"scene", "ply", "image"}) {
        for (const fs::path& f : fuzzFiles("regressions", target)) {
            const std::string name = f.filename().string();
            INFO(target << " regression " << name);
            std::string outcome = replay(target, f);
            ++replayed;
            auto it = kExpected.find(name);
            if (it == kExpected.end()) continue;  // a new finding: loading or clrt::Error is enough
            ++seen[name];
            INFO("outcome: " << (outcome.empty() ? "loaded" : outcome));
            if (it->second.empty()) CHECK(outcome.empty());
            else CHECK(outcome.find(it->second) != std::string::npos);
        }
    }
    // The findings named above are all still there (none renamed or lost).
    for (const auto& kv : kExpected) {
        INFO(kv.first);
        CHECK(seen[kv.first] == 1);
    }
    CHECK(replayed >= kExpected.size());
}

TEST_CASE("fuzz: every seed of fuzz/corpus loads or fails with clrt::Error", "[fuzz]") {
    for (const char* target : {"scene", "ply", "image"}) {
        std::vector<fs::path> files = fuzzFiles("corpus", target);
        INFO(target);
        CHECK(files.size() >= 4);
        size_t loaded = 0;
        for (const fs::path& f : files) {
            INFO(f.filename().string());
            if (replay(target, f).empty()) ++loaded;
        }
        // The seeds are meant to reach deep into the readers: most of them must load.
        CHECK(loaded * 4 >= files.size() * 3);
    }
}

TEST_CASE("fuzz: a directory or device given as a file is a clrt::Error (fuzz finding)", "[fuzz]") {
    test::TempDir dir;
    for (const std::string& p : {dir.path.string(), std::string("/dev/null")}) {
        INFO(p);
        CHECK_THROWS_AS(readPly(p), Error);
        CHECK_THROWS_AS(readImage(p), Error);
        CHECK_THROWS_AS(loadScene(p), Error);
    }
}
