// Tests for the PLY reader: small files of every format written to a temp dir and read back exactly,
// fanning of polygons, skipped elements/properties, every failure mode (truncation, lying counts,
// bad indices, bad headers), and every PLY file in the shared scenes folder.
#include <catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include <unistd.h>

#include "scene/ply_reader.h"
#include "util/error.h"

namespace fs = std::filesystem;
using clrt::MeshData;
using clrt::readPly;

namespace {

fs::path plyTempDir() {
    fs::path d = fs::temp_directory_path() / ("clrt_test_ply_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d;
}

std::string writeFile(const std::string& name, const std::string& bytes) {
    fs::path p = plyTempDir() / name;
    std::ofstream out(p, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    return p.string();
}

// Appends the bytes of `v` in the requested byte order.
template <class T> void put(std::string& s, T v, bool bigEndian) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    uint16_t one = 1;
    bool hostLittle = *reinterpret_cast<unsigned char*>(&one) == 1;
    if (hostLittle == bigEndian)
        for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    s.append(reinterpret_cast<char*>(b), sizeof(T));
}

// A quad (fanned into two triangles) and a triangle over 5 vertices with normals and uvs, plus an
// extra per-vertex property and list, an extra face property and an edge element to skip.
std::string binaryQuadPly(bool bigEndian) {
    std::string s = std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment made by test\nobj_info whatever\n"
                    "element vertex 5\nproperty float32 x\nproperty double y\nproperty float z\n"
                    "property uchar red\nproperty list uint8 int16 junk\n"
                    "property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n"
                    "element face 2\nproperty ushort flags\nproperty list uint8 uint32 vertex_indices\n"
                    "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    for (int i = 0; i < 5; ++i) {
        put<float>(s, float(i) + 0.5f, bigEndian);
        put<double>(s, -double(i), bigEndian);
        put<float>(s, 2.0f * i, bigEndian);
        put<uint8_t>(s, 200, bigEndian);
        put<uint8_t>(s, uint8_t(i % 3), bigEndian);
        for (int k = 0; k < i % 3; ++k) put<int16_t>(s, int16_t(-7), bigEndian);
        put<float>(s, 0.0f, bigEndian);
        put<float>(s, 1.0f, bigEndian);
        put<float>(s, float(i), bigEndian);
        put<float>(s, 0.25f * i, bigEndian);
        put<float>(s, 1.0f - 0.25f * i, bigEndian);
    }
    put<uint16_t>(s, 7, bigEndian);
    put<uint8_t>(s, 4, bigEndian);
    for (uint32_t v : {0u, 1u, 2u, 3u}) put<uint32_t>(s, v, bigEndian);
    put<uint16_t>(s, 9, bigEndian);
    put<uint8_t>(s, 3, bigEndian);
    for (uint32_t v : {4u, 3u, 2u}) put<uint32_t>(s, v, bigEndian);
    put<int32_t>(s, 0, bigEndian);
    put<int32_t>(s, 1, bigEndian);
    return s;
}

void checkQuadMesh(const MeshData& m) {
    REQUIRE(m.positions.size() == 5);
    REQUIRE(m.normals.size() == 5);
    REQUIRE(m.uvs.size() == 5);
    for (int i = 0; i < 5; ++i) {
        CHECK(m.positions[i].x == float(i) + 0.5f);
        CHECK(m.positions[i].y == -float(i));
        CHECK(m.positions[i].z == 2.0f * i);
        CHECK(m.normals[i].x == 0.0f);
        CHECK(m.normals[i].y == 1.0f);
        CHECK(m.normals[i].z == float(i));
        CHECK(m.uvs[i].x == 0.25f * i);
        CHECK(m.uvs[i].y == 1.0f - 0.25f * i);
    }
    CHECK(m.indices == std::vector<int>{0, 1, 2, 0, 2, 3, 4, 3, 2});
}

void requireErrorContaining(const std::string& path, const std::string& what) {
    try {
        readPly(path);
        FAIL("expected clrt::Error for " << path);
    } catch (const clrt::Error& e) {
        std::string msg = e.what();
        INFO(msg);
        CHECK(msg.rfind(path, 0) == 0);  // starts with the path
        CHECK(msg.find(what) != std::string::npos);
    }
}

const char* kAsciiTri =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_index\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

}  // namespace

TEST_CASE("PLY ascii with quads, uv and CRLF", "[ply]") {
    std::string text =
        "ply\r\nformat ascii 1.0\r\ncomment hello\r\nelement vertex 4\r\nproperty float x\r\nproperty float y\r\n"
        "property float z\r\nproperty float u\r\nproperty float v\r\nelement face 2\r\n"
        "property list uchar int vertex_indices\r\nend_header\r\n"
        "0 0 0 0 0\r\n1 0 0 1 0\r\n1 1 0 1 1\r\n0 1 -2.5e-1 0 1\r\n4 0 1 2 3\r\n2 0 1\r\n";
    MeshData m = readPly(writeFile("ascii_crlf.ply", text));
    REQUIRE(m.positions.size() == 4);
    CHECK(m.normals.empty());
    REQUIRE(m.uvs.size() == 4);
    CHECK(m.positions[3].z == -0.25f);
    CHECK(m.uvs[2].x == 1.0f);
    CHECK(m.uvs[2].y == 1.0f);
    // The quad is fanned (0,1,2)(0,2,3); the 2-vertex face is dropped.
    CHECK(m.indices == std::vector<int>{0, 1, 2, 0, 2, 3});
}

TEST_CASE("PLY ascii triangle, vertex_index name", "[ply]") {
    MeshData m = readPly(writeFile("ascii_tri.ply", kAsciiTri));
    REQUIRE(m.positions.size() == 3);
    CHECK(m.positions[1].x == 1.0f);
    CHECK(m.indices == std::vector<int>{0, 1, 2});
}

TEST_CASE("PLY binary little and big endian read exactly", "[ply]") {
    checkQuadMesh(readPly(writeFile("bin_le.ply", binaryQuadPly(false))));
    checkQuadMesh(readPly(writeFile("bin_be.ply", binaryQuadPly(true))));
}

TEST_CASE("PLY vertex values that are NaN, infinite or beyond float range are errors", "[ply]") {
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (const char* bad : {"nan", "inf", "-inf", "1e39", "-3.5e38"}) {
        INFO(bad);
        std::string p = writeFile("nonfinite.ply", head + "0 0 0\n1 " + bad + " 0\n0 1 0\n3 0 1 2\n");
        try {
            readPly(p);
            FAIL("no error");
        } catch (const clrt::Error& e) {
            std::string msg = e.what();
            CHECK(msg.find(p + ": line 11: vertex 1 has y = ") == 0);
            CHECK(msg.find("not a finite 32-bit float") != std::string::npos);
        }
    }
    // The largest float is fine, and so is a double-typed value within float range.
    MeshData m = readPly(writeFile("big.ply", head + "0 0 0\n1 3.4e38 0\n0 1 0\n3 0 1 2\n"));
    CHECK(m.positions[1].y == 3.4e38f);
}

// Float-only vertices and `list uchar int` faces take the reader's direct binary paths; a quad, a bad
// index or a non-finite value hands the rest to the general reader, so results and messages are those
// of the general path (the big-endian file of the same values never takes the direct path).
TEST_CASE("PLY direct binary paths hand what they do not expect to the general reader", "[ply]") {
    auto file = [](bool bigEndian, float badY, int badIndex) {
        std::string s = std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                        // (the comments make both headers the same length, so byte offsets agree)
                        (bigEndian ? " 1.0\ncomment abc\n" : " 1.0\ncomment \n") + "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                        "property float u\nproperty float v\n"
                        "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
        for (int i = 0; i < 5; ++i)
            for (float f : {float(i), i == 2 ? badY : 1.0f, 0.5f * i, 0.25f * i, 1.0f})
                put<float>(s, f, bigEndian);
        const std::vector<std::vector<int>> faces = {{0, 1, 2}, {0, 2, 3, 4}, {4, 3, 1}, {1, 2, badIndex}};
        for (const auto& f : faces) {
            put<uint8_t>(s, uint8_t(f.size()), bigEndian);
            for (int v : f) put<int32_t>(s, v, bigEndian);
        }
        return s;
    };
    const MeshData le = readPly(writeFile("direct_le.ply", file(false, 1.0f, 3)));
    const MeshData be = readPly(writeFile("direct_be.ply", file(true, 1.0f, 3)));
    CHECK(le.indices == std::vector<int>{0, 1, 2, 0, 2, 3, 0, 3, 4, 4, 3, 1, 1, 2, 3});
    CHECK(le.indices == be.indices);
    REQUIRE(le.uvs.size() == 5);
    for (int i = 0; i < 5; ++i) {
        CHECK(le.positions[i] == be.positions[i]);
        CHECK(le.positions[i] == clrt::Vec3(float(i), 1.0f, 0.5f * i));
        CHECK(le.uvs[i].x == 0.25f * i);
    }
    // The same message, byte offset included, from either byte order (only the big-endian file is read
    // by the general path alone).
    auto message = [&](bool bigEndian, float badY, int badIndex) {
        const std::string p = writeFile("direct_bad.ply", file(bigEndian, badY, badIndex));
        try {
            readPly(p);
        } catch (const clrt::Error& e) {
            return std::string(e.what()).substr(p.size());
        }
        return std::string("no error");
    };
    const std::string badIndex = message(false, 1.0f, -5), badY = message(false, INFINITY, 3);
    CHECK(badIndex == message(true, 1.0f, -5));
    CHECK(badY == message(true, INFINITY, 3));
    CHECK(badIndex.find("face 3 has vertex index -5, out of range") != std::string::npos);
    CHECK(badIndex.find(": byte ") == 0);
    CHECK(badY.find("vertex 2 has y = inf, not a finite 32-bit float") != std::string::npos);
}

TEST_CASE("PLY face index far beyond int range is an error naming it (found by the fuzzer: UB)", "[ply]") {
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    struct Case { const char* index; const char* shown; };
    for (Case c : {Case{"666666666666666666666666666666666", "6.66666667e+32"}, Case{"2147483648", "2147483648"},
                   Case{"-1", "-1"}, Case{"1e300", "1e+300"}}) {
        INFO(c.index);
        std::string p = writeFile("bigindex.ply", head + "3 0 1 " + c.index + "\n");
        try {
            readPly(p);
            FAIL("no error");
        } catch (const clrt::Error& e) {
            CHECK(std::string(e.what()) == p + ": line 13: face 0 has vertex index " + c.shown + ", out of range");
        }
    }
}

TEST_CASE("PLY errors name the file", "[ply]") {
    SECTION("missing file") {
        std::string p = (plyTempDir() / "does_not_exist.ply").string();
        requireErrorContaining(p, "cannot open");
    }
    SECTION("not a PLY") { requireErrorContaining(writeFile("notply.ply", "hello\nworld\n"), "not a PLY"); }
    SECTION("empty file") { requireErrorContaining(writeFile("empty.ply", ""), "not a PLY"); }
    SECTION("no end_header") {
        requireErrorContaining(writeFile("noend.ply", "ply\nformat ascii 1.0\nelement vertex 0\n"), "end_header");
    }
    SECTION("unsupported format") {
        requireErrorContaining(writeFile("fmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n"),
                               "unsupported PLY format");
    }
    SECTION("unknown type") {
        requireErrorContaining(
            writeFile("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n0\n"),
            "unknown type");
    }
    SECTION("property before element") {
        requireErrorContaining(writeFile("prop.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n"),
                               "property before any element");
    }
    SECTION("ascii truncated") {
        std::string t = kAsciiTri;
        requireErrorContaining(writeFile("ascii_trunc.ply", t.substr(0, t.size() - 4)), "ends early");
    }
    SECTION("ascii garbage number") {
        std::string t = kAsciiTri;
        t.replace(t.find("1 0 0\n"), 1, "x");
        requireErrorContaining(writeFile("ascii_garbage.ply", t), "not a number");
    }
    SECTION("binary truncated") {
        std::string b = binaryQuadPly(false);
        requireErrorContaining(writeFile("bin_trunc.ply", b.substr(0, b.size() - 30)), "ends early");
    }
    SECTION("header lies about counts") {
        std::string b = binaryQuadPly(false);
        b.replace(b.find("element vertex 5"), 16, "element vertex 500");
        requireErrorContaining(writeFile("lies.ply", b), "lies about counts");
        b = binaryQuadPly(false);
        b.replace(b.find("element face 2"), 14, "element face 4000000000");
        requireErrorContaining(writeFile("lies2.ply", b), "lies about counts");
    }
    SECTION("count overflow") {
        std::string b = binaryQuadPly(false);
        b.replace(b.find("element vertex 5"), 16, "element vertex 99999999999999999999999");
        requireErrorContaining(writeFile("overflow.ply", b), "too large");
    }
    SECTION("vertex index out of range") {
        std::string t = kAsciiTri;
        t.replace(t.find("3 0 1 2"), 7, "3 0 1 3");
        requireErrorContaining(writeFile("badidx.ply", t), "vertex index 3");
        t = kAsciiTri;
        t.replace(t.find("3 0 1 2"), 7, "3 0 -1 2");
        requireErrorContaining(writeFile("negidx.ply", t), "out of range");
    }
    SECTION("no vertex_indices") {
        std::string t = kAsciiTri;
        t.replace(t.find("vertex_index"), 12, "corners");
        requireErrorContaining(writeFile("nolist.ply", t), "vertex_indices");
    }
}

TEST_CASE("PLY every shared scene file loads", "[ply][shared]") {
    fs::path root = fs::path(CLRT_SHARED_DIR) / "scenes";
    if (!fs::is_directory(root)) {
        WARN("shared scenes not found, skipped: " << root);
        return;
    }
    int files = 0;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file() || entry.path().extension() != ".ply") continue;
        INFO(entry.path().string());
        MeshData m;
        REQUIRE_NOTHROW(m = readPly(entry.path().string()));
        CHECK(!m.positions.empty());
        CHECK(m.indices.size() % 3 == 0);
        CHECK((m.normals.empty() || m.normals.size() == m.positions.size()));
        CHECK((m.uvs.empty() || m.uvs.size() == m.positions.size()));
        ++files;
    }
    CHECK(files > 0);
}
