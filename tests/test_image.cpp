// Tests for image IO: EXR float/half round trips (bit-exact for float), the EXR writer's file layout
// (header attributes, multi-chunk and incompressible chunks, long attribute names), PNG round trips and
// the PNG encoder's chunks (CRCs, zlib stream, filter types), grey/Y and tiled/RGBA EXR layouts,
// NaN/negative clamping with one warning, the shared env maps and textures, corrupt and truncated
// inputs, and atomic writes (a failed write leaves the old file intact; uncommitted writes).
#include <catch.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <random>
#include <string>
#include <vector>
#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfTiledOutputFile.h>
#include <ImfBoxAttribute.h>
#include <ImfLineOrderAttribute.h>
#include <Imath/half.h>
#include <stb/stb_image_write.h>
#include <zlib.h>

#include "image/image.h"
#include "test_helpers.h"
#include "util/error.h"

namespace fs = std::filesystem;
using clrt::ImageRGB;

namespace {

fs::path imgTempDir() {
    fs::path d = fs::temp_directory_path() / ("clrt_test_image_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d;
}
std::string imgTemp(const std::string& name) { return (imgTempDir() / name).string(); }


uint32_t bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

ImageRGB makeImage(int w, int h) {
    ImageRGB img;
    img.width = w;
    img.height = h;
    img.pixels.assign(size_t(w) * h * 3, 0.0f);
    return img;
}

// Runs f with stderr redirected to a file and returns what was written to it.
template <class F> std::string captureStderr(F f) {
    std::string path = imgTemp("stderr.txt");
    std::fflush(stderr);
    int saved = dup(2);
    FILE* tmp = std::fopen(path.c_str(), "w");
    dup2(fileno(tmp), 2);
    try {
        f();
    } catch (...) {
        std::fflush(stderr);
        dup2(saved, 2);
        close(saved);
        std::fclose(tmp);
        throw;
    }
    std::fflush(stderr);
    dup2(saved, 2);
    close(saved);
    std::fclose(tmp);
    return clrt::test::readFileBytes(path);
}

void requireReadError(const std::string& path) {
    try {
        clrt::readImage(path);
        FAIL("expected clrt::Error reading " << path);
    } catch (const clrt::Error& e) {
        INFO(e.what());
        CHECK(std::string(e.what()).find(path) != std::string::npos);
        CHECK(e.code() == clrt::ExitCode::BadInput);
    }
}

void requireWriteError(const std::function<void()>& f, const std::string& path) {
    try {
        f();
        FAIL("expected clrt::Error writing " << path);
    } catch (const clrt::Error& e) {
        INFO(e.what());
        CHECK(std::string(e.what()).find(path) != std::string::npos);
        CHECK(e.code() == clrt::ExitCode::Output);
    }
}

size_t countOccurrences(const std::string& s, const std::string& what) {
    size_t n = 0;
    for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
    return n;
}

}  // namespace

TEST_CASE("EXR float round trip is bit-exact, with attributes and ZIP", "[image]") {
    ImageRGB img = makeImage(37, 23);
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> uni(0.0f, 10.0f);
    for (float& v : img.pixels) v = uni(rng);
    const float specials[] = {0.0f, 1e-40f, FLT_MIN / 4, FLT_MIN, 65504.0f, 65520.0f, 70000.0f, 1e10f, 3e38f, FLT_MAX};
    for (size_t i = 0; i < sizeof(specials) / sizeof(float); ++i) img.pixels[i * 7] = specials[i];

    std::string path = imgTemp("float.exr");
    clrt::ExrWriteOptions opts;
    opts.attributes["renderer"] = "clrt";
    opts.attributes["spp"] = "16";
    clrt::writeExr(path, img, opts);

    ImageRGB back = clrt::readImage(path);
    CHECK(back.isHdr);
    REQUIRE(back.width == 37);
    REQUIRE(back.height == 23);
    REQUIRE(back.pixels.size() == img.pixels.size());
    size_t mismatches = 0;
    for (size_t i = 0; i < img.pixels.size(); ++i) mismatches += bits(img.pixels[i]) != bits(back.pixels[i]);
    CHECK(mismatches == 0);
    CHECK(back.pixels[7] == 1e-40f);

    Imf::InputFile f(path.c_str());
    CHECK(f.header().compression() == Imf::ZIP_COMPRESSION);
    const auto* r = f.header().channels().findChannel("R");
    REQUIRE(r);
    CHECK(r->type == Imf::FLOAT);
    CHECK(!f.header().channels().findChannel("A"));
    const auto* a = f.header().findTypedAttribute<Imf::StringAttribute>("renderer");
    REQUIRE(a);
    CHECK(a->value() == "clrt");
    const auto* b = f.header().findTypedAttribute<Imf::StringAttribute>("spp");
    REQUIRE(b);
    CHECK(b->value() == "16");
}

TEST_CASE("EXR half round trip within half precision", "[image]") {
    ImageRGB img = makeImage(16, 9);
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> uni(0.001f, 60000.0f);
    for (float& v : img.pixels) v = uni(rng);
    img.pixels[0] = 0.0f;
    img.pixels[1] = 65504.0f;
    std::string path = imgTemp("half.exr");
    clrt::ExrWriteOptions opts;
    opts.half = true;
    clrt::writeExr(path, img, opts);
    {
        Imf::InputFile f(path.c_str());
        const auto* g = f.header().channels().findChannel("G");
        REQUIRE(g);
        CHECK(g->type == Imf::HALF);
    }
    ImageRGB back = clrt::readImage(path);
    REQUIRE(back.pixels.size() == img.pixels.size());
    for (size_t i = 0; i < img.pixels.size(); ++i) {
        INFO(i << ": " << img.pixels[i] << " vs " << back.pixels[i]);
        REQUIRE(std::fabs(back.pixels[i] - img.pixels[i]) <= img.pixels[i] * (1.0f / 2048.0f));
        REQUIRE(back.pixels[i] == float(Imath::half(img.pixels[i])));
    }
    CHECK(back.pixels[1] == 65504.0f);
}

TEST_CASE("EXR NaN, Inf and negatives become 0 with one warning", "[image]") {
    ImageRGB img = makeImage(4, 2);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i) + 1;
    img.pixels[0] = std::nanf("");
    img.pixels[5] = INFINITY;
    img.pixels[10] = -3.0f;
    img.pixels[11] = -INFINITY;
    std::string path = imgTemp("bad_values.exr");
    clrt::writeExr(path, img);
    ImageRGB back;
    std::string err = captureStderr([&] { back = clrt::readImage(path); });
    CHECK(back.pixels[0] == 0.0f);
    CHECK(back.pixels[5] == 0.0f);
    CHECK(back.pixels[10] == 0.0f);
    CHECK(back.pixels[11] == 0.0f);
    CHECK(back.pixels[1] == 2.0f);
    CHECK(countOccurrences(err, "warning") == 1);
    CHECK(err.find(" 4 ") != std::string::npos);
}

TEST_CASE("EXR Y-only file expands to grey; tiled RGBA with offset data window reads", "[image]") {
    const int w = 5, h = 3;
    SECTION("Y channel, half") {
        std::string path = imgTemp("grey.exr");
        std::vector<Imath::half> y(w * h);
        for (int i = 0; i < w * h; ++i) y[i] = float(i) * 0.5f;
        Imf::Header hdr(w, h);
        hdr.channels().insert("Y", Imf::Channel(Imf::HALF));
        Imf::FrameBuffer fb;
        fb.insert("Y", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(y.data()), sizeof(Imath::half),
                                  sizeof(Imath::half) * w));
        {
            Imf::OutputFile out(path.c_str(), hdr);
            out.setFrameBuffer(fb);
            out.writePixels(h);
        }
        ImageRGB img = clrt::readImage(path);
        REQUIRE(img.width == w);
        REQUIRE(img.height == h);
        for (int i = 0; i < w * h; ++i)
            for (int c = 0; c < 3; ++c) CHECK(img.pixels[i * 3 + c] == float(i) * 0.5f);
    }
    SECTION("tiled RGBA float with data window not at the origin") {
        std::string path = imgTemp("tiled.exr");
        Imath::Box2i dw(Imath::V2i(10, 20), Imath::V2i(10 + w - 1, 20 + h - 1));
        Imf::Header hdr(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(63, 63)), dw);
        const char* names[4] = {"R", "G", "B", "A"};
        for (const char* n : names) hdr.channels().insert(n, Imf::Channel(Imf::FLOAT));
        hdr.setTileDescription(Imf::TileDescription(2, 2, Imf::ONE_LEVEL));
        std::vector<float> px(size_t(w) * h * 4);
        for (size_t i = 0; i < px.size(); ++i) px[i] = float(i);
        Imf::FrameBuffer fb;
        for (int c = 0; c < 4; ++c)
            fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, px.data() + c, dw, 4 * sizeof(float),
                                                 4 * sizeof(float) * w));
        {
            Imf::TiledOutputFile out(path.c_str(), hdr);
            out.setFrameBuffer(fb);
            out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
        }
        ImageRGB img = clrt::readImage(path);
        REQUIRE(img.width == w);
        REQUIRE(img.height == h);
        for (int i = 0; i < w * h; ++i)
            for (int c = 0; c < 3; ++c) CHECK(img.pixels[i * 3 + c] == px[i * 4 + c]);
    }
}

TEST_CASE("PNG round trips", "[image]") {
    const int w = 13, h = 7;
    std::vector<unsigned char> rgb(w * h * 3);
    std::mt19937 rng(7);
    for (auto& v : rgb) v = static_cast<unsigned char>(rng() & 0xFF);
    rgb[0] = 0;
    rgb[1] = 255;
    std::string path = imgTemp("rt.png");
    clrt::writePng8(path, w, h, rgb);
    ImageRGB img = clrt::readImage(path);
    CHECK(!img.isHdr);
    REQUIRE(img.width == w);
    REQUIRE(img.height == h);
    REQUIRE(img.pixels.size() == rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) REQUIRE(img.pixels[i] == float(rgb[i]));

    SECTION("clamped writer rounds and clamps") {
        ImageRGB lin = makeImage(2, 1);
        lin.pixels = {-5.0f, 0.4f, 0.5f, 254.6f, 300.0f, std::nanf("")};
        std::string p2 = imgTemp("clamped.png");
        clrt::writePngClamped(p2, lin);
        ImageRGB back = clrt::readImage(p2);
        CHECK(back.pixels == std::vector<float>{0, 0, 1, 255, 255, 0});
    }
    SECTION("grey PNG expands to RGB") {
        unsigned char grey[6] = {0, 10, 20, 30, 40, 250};
        std::string p3 = imgTemp("grey.png");
        REQUIRE(stbi_write_png(p3.c_str(), 3, 2, 1, grey, 3));
        ImageRGB g = clrt::readImage(p3);
        REQUIRE(g.width == 3);
        REQUIRE(g.height == 2);
        for (int i = 0; i < 6; ++i)
            for (int c = 0; c < 3; ++c) CHECK(g.pixels[i * 3 + c] == float(grey[i]));
    }
    SECTION("PNG with a .exr name is read by content") {
        std::string p4 = imgTemp("actually_png.exr");
        fs::copy_file(path, p4, fs::copy_options::overwrite_existing);
        CHECK(clrt::readImage(p4).pixels == img.pixels);
    }
}

TEST_CASE("shared env maps and textures load", "[image][shared]") {
    fs::path shared(CLRT_SHARED_DIR);
    fs::path sunset = shared / "envmaps" / "sunset.exr";
    if (!fs::exists(sunset)) {
        WARN("shared env maps not found, skipped: " << sunset);
        return;
    }
    ImageRGB img;
    std::string err = captureStderr([&] { img = clrt::readImage(sunset.string()); });
    CHECK(img.isHdr);
    CHECK(img.width == 1024);
    CHECK(img.height == 512);
    // The file holds negative values: they were clamped, with one warning.
    CHECK(countOccurrences(err, "warning") == 1);
    float maxV = 0;
    bool allOk = true;
    for (float v : img.pixels) {
        allOk = allOk && std::isfinite(v) && v >= 0.0f;
        maxV = std::max(maxV, v);
    }
    CHECK(allOk);
    CHECK(maxV > 1.0f);  // it is HDR

    int count = 0;
    for (const fs::path& dir : {shared / "envmaps", shared / "scenes"}) {
        for (const auto& e : fs::recursive_directory_iterator(dir)) {
            std::string ext = e.path().extension().string();
            if (!e.is_regular_file() || (ext != ".exr" && ext != ".png" && ext != ".jpg" && ext != ".jpeg")) continue;
            INFO(e.path().string());
            ImageRGB t;
            captureStderr([&] { REQUIRE_NOTHROW(t = clrt::readImage(e.path().string())); });
            CHECK(t.width > 0);
            CHECK(t.pixels.size() == size_t(t.width) * t.height * 3);
            ++count;
        }
    }
    CHECK(count > 20);
}

TEST_CASE("corrupt and truncated images raise clrt::Error", "[image]") {
    ImageRGB img = makeImage(64, 64);
    std::mt19937 rng(5);
    for (float& v : img.pixels) v = float(rng() % 1000) / 7.0f;
    std::string exr = imgTemp("good.exr"), png = imgTemp("good.png");
    clrt::writeExr(exr, img);
    clrt::writePngClamped(png, img);
    std::string exrBytes = clrt::test::readFileBytes(exr), pngBytes = clrt::test::readFileBytes(png);

    SECTION("missing file") { requireReadError(imgTemp("nope.png")); }
    SECTION("empty file") {
        clrt::test::writeFileBytes(imgTemp("empty.png"), "");
        requireReadError(imgTemp("empty.png"));
    }
    SECTION("unknown format") {
        clrt::test::writeFileBytes(imgTemp("text.png"), "this is not an image at all");
        requireReadError(imgTemp("text.png"));
    }
    SECTION("truncated EXR") {
        for (double frac : {0.1, 0.5, 0.9}) {
            std::string p = imgTemp("trunc" + std::to_string(int(frac * 10)) + ".exr");
            clrt::test::writeFileBytes(p, exrBytes.substr(0, size_t(exrBytes.size() * frac)));
            requireReadError(p);
        }
    }
    SECTION("EXR magic then random bytes") {
        std::string b = "\x76\x2f\x31\x01";
        for (int i = 0; i < 500; ++i) b += char(rng() & 0xFF);
        clrt::test::writeFileBytes(imgTemp("random.exr"), b);
        requireReadError(imgTemp("random.exr"));
    }
    SECTION("truncated PNG") {
        for (double frac : {0.05, 0.5, 0.95}) {
            std::string p = imgTemp("trunc" + std::to_string(int(frac * 100)) + ".png");
            clrt::test::writeFileBytes(p, pngBytes.substr(0, size_t(pngBytes.size() * frac)));
            requireReadError(p);
        }
    }
    SECTION("PNG magic then random bytes") {
        std::string b = "\x89PNG\r\n\x1a\n";
        for (int i = 0; i < 500; ++i) b += char(rng() & 0xFF);
        clrt::test::writeFileBytes(imgTemp("random.png"), b);
        requireReadError(imgTemp("random.png"));
    }
    SECTION("truncated and random JPEG") {
        std::vector<unsigned char> rgb(64 * 64 * 3);
        for (auto& v : rgb) v = static_cast<unsigned char>(rng() & 0xFF);
        std::string jpg = imgTemp("good.jpg");
        REQUIRE(stbi_write_jpg(jpg.c_str(), 64, 64, 3, rgb.data(), 90));
        ImageRGB ok = clrt::readImage(jpg);
        CHECK(ok.width == 64);
        std::string jb = clrt::test::readFileBytes(jpg);
        clrt::test::writeFileBytes(imgTemp("trunc.jpg"), jb.substr(0, jb.size() / 2));
        requireReadError(imgTemp("trunc.jpg"));
        std::string b = "\xFF\xD8\xFF";
        for (int i = 0; i < 500; ++i) b += char(rng() & 0xFF);
        clrt::test::writeFileBytes(imgTemp("random.jpg"), b);
        requireReadError(imgTemp("random.jpg"));
    }
}

TEST_CASE("writers fail cleanly and never truncate the target", "[image]") {
    ImageRGB img = makeImage(8, 8);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i % 256);
    std::vector<unsigned char> rgb(8 * 8 * 3, 77);

    SECTION("missing output directory") {
        std::string p = (imgTempDir() / "no_such_dir" / "out.png").string();
        requireWriteError([&] { clrt::writePng8(p, 8, 8, rgb); }, p);
        std::string e = (imgTempDir() / "no_such_dir" / "out.exr").string();
        requireWriteError([&] { clrt::writeExr(e, img); }, e);
        CHECK(!fs::exists(imgTempDir() / "no_such_dir"));
    }
    SECTION("temporary path is a hidden sibling") {
        std::string p = imgTemp("x.png");
        fs::path t = clrt::temporarySiblingPath(p);
        CHECK(t.parent_path() == imgTempDir());
        CHECK(t.filename().string().rfind(".x.png.tmp-", 0) == 0);
    }
    SECTION("failed writes leave the good file intact and no temporary behind") {
        for (const std::string name : {"keep.png", "keep.exr"}) {
            std::string p = imgTemp(name);
            if (name == "keep.png") clrt::writePng8(p, 8, 8, rgb);
            else clrt::writeExr(p, img);
            std::string good = clrt::test::readFileBytes(p);
            REQUIRE(!good.empty());
            // A writer that produces half a file and then fails.
            CHECK_THROWS_AS(clrt::writeAtomically(p,
                                                  [&](const std::string& tmp) {
                                                      clrt::test::writeFileBytes(tmp, good.substr(0, good.size() / 2));
                                                      throw clrt::Error("simulated failure", clrt::ExitCode::Output);
                                                  }),
                            clrt::Error);
            // A real writer given bad input.
            ImageRGB bad = makeImage(8, 8);
            bad.pixels.resize(10);
            requireWriteError([&] { clrt::writeExr(p, bad); }, p);
            requireWriteError([&] { clrt::writePng8(p, 8, 8, std::vector<unsigned char>(5)); }, p);
            CHECK(clrt::test::readFileBytes(p) == good);
            CHECK(!fs::exists(clrt::temporarySiblingPath(p)));
        }
    }
    SECTION("target is a directory: rename fails, temporary removed") {
        fs::path d = imgTempDir() / "a_directory.png";
        fs::create_directories(d / "child");
        requireWriteError([&] { clrt::writePng8(d.string(), 8, 8, rgb); }, d.string());
        CHECK(fs::is_directory(d / "child"));
        CHECK(!fs::exists(clrt::temporarySiblingPath(d.string())));
    }
}

TEST_CASE("a PNG with a zero-length IDAT chunk (valid, found by the fuzzer) reads correctly", "[image]") {
    // 1x1 RGB, red; an empty IDAT precedes the one with the data. stb_image passes a null pointer to
    // memcpy with length 0 for it (UBSan in the fuzz build; see scripts/fuzz.sh).
    static const char kPng[] =
        "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x01\x00\x00\x00\x01"
        "\x08\x02\x00\x00\x00\x90\x77\x53\xde\x00\x00\x00\x00\x49\x44\x41\x54\x35\xaf\x06\x1e\x00\x00\x00"
        "\x0c\x49\x44\x41\x54\x78\x9c\x63\xf8\xcf\xc0\x00\x00\x03\x01\x01\x00\xc9\xfe\x92\xef\x00\x00\x00"
        "\x00\x49\x45\x4e\x44\xae\x42\x60\x82";
    std::string path = imgTemp("zero_idat.png");
    clrt::test::writeFileBytes(path, std::string(kPng, sizeof(kPng) - 1));
    ImageRGB img = clrt::readImage(path);
    REQUIRE(img.width == 1);
    REQUIRE(img.height == 1);
    CHECK(img.at(0, 0, 0) == 255.0f);
    CHECK(img.at(0, 0, 1) == 0.0f);
    CHECK(img.at(0, 0, 2) == 0.0f);
}

TEST_CASE("EXR writer: multi-chunk, incompressible and long-name files read back through OpenEXR", "[image]") {
    SECTION("300x250 (16 chunks, the last of 10 lines): bit-exact, standard header attributes") {
        ImageRGB img = makeImage(300, 250);
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x)
                for (int c = 0; c < 3; ++c) img.at(x, y, c) = float(x * (c + 1)) * 0.01f + std::sin(float(y) * 0.1f) + 1.5f;
        std::string path = imgTemp("chunks.exr");
        clrt::writeExr(path, img);
        ImageRGB back = clrt::readImage(path);
        REQUIRE(back.pixels.size() == img.pixels.size());
        size_t mismatches = 0;
        for (size_t i = 0; i < img.pixels.size(); ++i) mismatches += bits(img.pixels[i]) != bits(back.pixels[i]);
        CHECK(mismatches == 0);
        CHECK(fs::file_size(path) < img.pixels.size() * sizeof(float));  // compressed
        Imf::InputFile f(path.c_str());
        const Imf::Header& h = f.header();
        CHECK(h.dataWindow() == Imath::Box2i({0, 0}, {299, 249}));
        CHECK(h.displayWindow() == Imath::Box2i({0, 0}, {299, 249}));
        CHECK(h.lineOrder() == Imf::INCREASING_Y);
        CHECK(h.pixelAspectRatio() == 1.0f);
        CHECK(h.screenWindowWidth() == 1.0f);
        CHECK(h.compression() == Imf::ZIP_COMPRESSION);
        int channels = 0;
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) ++channels;
        CHECK(channels == 3);
        CHECK(f.isComplete());
    }
    SECTION("random bits do not compress: chunks stored raw, still bit-exact") {
        ImageRGB img = makeImage(64, 20);
        std::mt19937 rng(5);
        for (float& v : img.pixels) {
            uint32_t u = rng() & 0x7F7FFFFFu;  // positive, finite
            std::memcpy(&v, &u, 4);
        }
        for (bool half : {false, true}) {
            std::string path = imgTemp(half ? "random_half.exr" : "random.exr");
            clrt::ExrWriteOptions o;
            o.half = half;
            clrt::writeExr(path, img, o);
            if (!half) CHECK(fs::file_size(path) >= img.pixels.size() * 4);  // (as halves most are 0 or Inf)
            Imf::InputFile f(path.c_str());
            const Imath::Box2i dw = f.header().dataWindow();
            std::vector<float> px(img.pixels.size());
            Imf::FrameBuffer fb;
            const char* names[3] = {"R", "G", "B"};
            for (int c = 0; c < 3; ++c) fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, px.data() + c, dw, 12, 12 * 64));
            f.setFrameBuffer(fb);
            f.readPixels(dw.min.y, dw.max.y);
            size_t mismatches = 0;
            for (size_t i = 0; i < px.size(); ++i)
                mismatches += bits(px[i]) != bits(half ? float(Imath::half(img.pixels[i])) : img.pixels[i]);
            CHECK(mismatches == 0);
        }
    }
    SECTION("flat content (a constant background) compresses") {
        // A constant float repeats with period 4 bytes: ZIP's LZ77 matching leaves about 1% of it.
        ImageRGB img = makeImage(400, 300);
        std::fill(img.pixels.begin(), img.pixels.end(), 0.25f);
        for (int y = 100; y < 140; ++y)
            for (int x = 50; x < 90; ++x) img.at(x, y, 1) = float(x * y) * 1e-3f;
        std::string path = imgTemp("flat.exr");
        clrt::writeExr(path, img);
        CHECK(fs::file_size(path) * 50 < img.pixels.size() * sizeof(float));
        CHECK(clrt::readImage(path).pixels == img.pixels);
    }
    SECTION("attribute names: long ones are written, reserved or empty ones refused") {
        ImageRGB img = makeImage(5, 3);
        const std::string longName = "aHeaderAttributeNameLongerThanThirtyOneCharacters";
        clrt::ExrWriteOptions o;
        o.attributes[longName] = "value";
        o.attributes["empty"] = "";
        std::string path = imgTemp("long_name.exr");
        clrt::writeExr(path, img, o);
        Imf::InputFile f(path.c_str());
        const auto* a = f.header().findTypedAttribute<Imf::StringAttribute>(longName);
        REQUIRE(a);
        CHECK(a->value() == "value");
        const auto* e = f.header().findTypedAttribute<Imf::StringAttribute>("empty");
        REQUIRE(e);
        CHECK(e->value().empty());
        for (const std::string bad : {"channels", "dataWindow", ""}) {
            clrt::ExrWriteOptions ob;
            ob.attributes[bad] = "x";
            std::string p = imgTemp("bad_attr.exr");
            requireWriteError([&] { clrt::writeExr(p, img, ob); }, p);
            CHECK(!fs::exists(p));
            CHECK(!fs::exists(clrt::temporarySiblingPath(p)));
        }
    }
}

TEST_CASE("PNG encoder: valid chunks and zlib stream, every filter type, exact round trips", "[image]") {
    // Smooth gradients, flat areas, noise and sharp edges: rows where each of the five filters wins.
    auto makeRgb = [](int w, int h, unsigned seed) {
        std::vector<unsigned char> rgb(size_t(w) * h * 3);
        std::mt19937 rng(seed);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    unsigned char v;
                    switch ((y / 4) % 5) {
                        case 0: v = static_cast<unsigned char>(x * 3 + c); break;           // horizontal ramp
                        case 1: v = static_cast<unsigned char>(y * 5 + c * 40); break;      // vertical ramp
                        case 2: v = static_cast<unsigned char>(rng() & 0xFF); break;        // noise
                        case 3: v = static_cast<unsigned char>((x + y) * 2); break;         // diagonal
                        default: v = static_cast<unsigned char>(x < w / 2 ? 17 : 230); break;  // flat halves
                    }
                    rgb[(size_t(y) * w + x) * 3 + c] = v;
                }
        return rgb;
    };
    for (auto [w, h] : {std::pair{1, 1}, {1, 9}, {2, 1}, {3, 5}, {129, 60}, {640, 41}}) {
        INFO(w << "x" << h);
        const std::vector<unsigned char> rgb = makeRgb(w, h, unsigned(w * 1000 + h));
        const std::string png = clrt::encodePng8("x.png", w, h, rgb);
        REQUIRE(png.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0);
        // Walk the chunks: lengths, CRCs, IHDR fields, the IDAT zlib stream, IEND last.
        auto be32 = [&](size_t at) {
            return uint32_t(uint8_t(png[at])) << 24 | uint32_t(uint8_t(png[at + 1])) << 16 |
                   uint32_t(uint8_t(png[at + 2])) << 8 | uint32_t(uint8_t(png[at + 3]));
        };
        std::string idat, last;
        size_t at = 8;
        while (at < png.size()) {
            REQUIRE(at + 12 <= png.size());
            const uint32_t len = be32(at);
            REQUIRE(at + 12 + len <= png.size());
            const std::string type = png.substr(at + 4, 4);
            const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(png.data() + at + 4), uInt(len + 4));
            CHECK(be32(at + 8 + len) == uint32_t(crc));
            if (type == "IHDR") {
                REQUIRE(len == 13);
                CHECK(be32(at + 8) == uint32_t(w));
                CHECK(be32(at + 12) == uint32_t(h));
                CHECK(png.substr(at + 16, 5) == std::string("\x08\x02\x00\x00\x00", 5));  // 8-bit RGB
            }
            if (type == "IDAT") idat += png.substr(at + 8, len);
            last = type;
            at += 12 + len;
        }
        CHECK(last == "IEND");
        const size_t stride = size_t(w) * 3 + 1;
        std::vector<unsigned char> raw(stride * h + 1);
        uLongf rawLen = uLongf(raw.size());
        REQUIRE(uncompress(raw.data(), &rawLen, reinterpret_cast<const Bytef*>(idat.data()), uLong(idat.size())) == Z_OK);
        REQUIRE(rawLen == stride * h);
        std::vector<int> used(5, 0);
        for (int y = 0; y < h; ++y) {
            REQUIRE(raw[size_t(y) * stride] <= 4);
            ++used[raw[size_t(y) * stride]];
        }
        if (w == 640)
            for (int f = 0; f < 5; ++f) CHECK(used[f] > 0);
        // Decoded by stb_image: the same pixels.
        const std::string path = imgTemp("enc.png");
        clrt::writePng8(path, w, h, rgb);
        CHECK(clrt::test::readFileBytes(path) == png);
        ImageRGB back = clrt::readImage(path);
        REQUIRE(back.width == w);
        REQUIRE(back.height == h);
        size_t mismatches = 0;
        for (size_t i = 0; i < rgb.size(); ++i) mismatches += back.pixels[i] != float(rgb[i]);
        CHECK(mismatches == 0);
    }
}

TEST_CASE("uncommitted writes leave the target alone until committed", "[image]") {
    ImageRGB img = makeImage(6, 4);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i);
    std::vector<unsigned char> rgb(6 * 4 * 3, 9);
    const std::string exr = imgTemp("pending.exr"), png = imgTemp("pending.png");
    clrt::test::writeFileBytes(exr, "old exr");
    clrt::test::writeFileBytes(png, "old png");
    const std::string exrTmp = clrt::writeExrUncommitted(exr, img);
    const std::string pngTmp = clrt::writePng8Uncommitted(png, 6, 4, rgb);
    CHECK(exrTmp == clrt::temporarySiblingPath(exr));
    CHECK(pngTmp == clrt::temporarySiblingPath(png));
    CHECK(clrt::test::readFileBytes(exr) == "old exr");
    CHECK(clrt::test::readFileBytes(png) == "old png");
    clrt::commitTemporary(exrTmp, exr);
    clrt::commitTemporary(pngTmp, png);
    CHECK(clrt::readImage(exr).pixels == img.pixels);
    CHECK(clrt::readImage(png).pixels == std::vector<float>(6 * 4 * 3, 9.0f));
    CHECK(!fs::exists(exrTmp));
    CHECK(!fs::exists(pngTmp));
}

// A few bytes can declare gigabytes of pixels: the size is refused from the header, before decoding.
TEST_CASE("images above the texel limit are refused from their header", "[image]") {
    char tmpl[] = "/tmp/clrt-bomb-XXXXXX";
    REQUIRE(mkdtemp(tmpl));
    const std::string dir = tmpl;
    auto be32 = [](std::string& s, uint32_t v) {
        for (int i = 3; i >= 0; --i) s.push_back(char((v >> (8 * i)) & 0xFF));
    };
    auto chunk = [&](std::string& png, const char* type, const std::string& data) {
        be32(png, uint32_t(data.size()));
        std::string body = std::string(type, 4) + data;
        png += body;
        be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
    };
    auto pngOf = [&](uint32_t w, uint32_t h) {
        std::string png = "\x89PNG\r\n\x1a\n", ihdr;
        be32(ihdr, w);
        be32(ihdr, h);
        ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit RGB
        chunk(png, "IHDR", ihdr);
        chunk(png, "IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8));
        chunk(png, "IEND", "");
        return png;
    };
    const std::string big = dir + "/big.png", fits = dir + "/fits.png";
    std::ofstream(big, std::ios::binary) << pngOf(16384, 8193);
    std::ofstream(fits, std::ios::binary) << pngOf(16384, 8192);
    try {
        clrt::readImage(big);
        FAIL("a 16384x8193 PNG header was accepted");
    } catch (const clrt::Error& e) {
        CHECK(std::string(e.what()).find("big.png: image is 16384x8193, more than the limit") != std::string::npos);
    }
    // At the limit the header passes and the (empty) pixel data is what fails.
    try {
        clrt::readImage(fits);
        FAIL("a PNG without pixel data was accepted");
    } catch (const clrt::Error& e) {
        CHECK(std::string(e.what()).find("more than the limit") == std::string::npos);
    }
    // An EXR whose data window is 20000x20000: the header is read, no pixel is allocated.
    const std::string exr = dir + "/big.exr";
    {
        Imf::Header hdr(20000, 20000);
        hdr.channels().insert("R", Imf::Channel(Imf::HALF));
        Imf::OutputFile out(exr.c_str(), hdr);
    }
    try {
        clrt::readImage(exr);
        FAIL("a 20000x20000 EXR header was accepted");
    } catch (const clrt::Error& e) {
        CHECK(std::string(e.what()).find("big.exr: image is 20000x20000, more than the limit") != std::string::npos);
    }
    std::filesystem::remove_all(dir);
}
