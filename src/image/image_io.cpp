// Image files (see image.h): readImage picks a decoder from the magic bytes (PNG/JPEG via stb_image,
// EXR via OpenEXR's generic InputFile so any R,G,B / Y layout, half or float, scanline or tiled,
// reads; an EXR with a `chromaticities` attribute is converted to linear Rec.709/D65, chromaticities.h).
// Every writer (PNG and EXR) and the temporary-file helpers are in image_write.cpp, so the
// fuzz targets, which compile this file (and chromaticities.cpp) alone, need neither zlib nor the writers.
#include "image/image.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>
#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <Imath/half.h>
#include <stb/stb_image.h>

#include "image/chromaticities.h"
#include "image/image_size.h"
#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

namespace {

std::string readAll(const std::string& path) {
    std::error_code ec;
    // Directories, FIFOs and devices would throw from the stream or never end.
    if (!fs::is_regular_file(path, ec))
        throw Error(path + (fs::exists(path, ec) ? ": cannot open image file: not a regular file"
                                                 : ": cannot open image file: no such file"));
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path + ": cannot open image file");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error(path + ": cannot read image file");
    return bytes;
}

bool startsWith(const std::string& s, const char* magic, size_t n) {
    return s.size() >= n && std::memcmp(s.data(), magic, n) == 0;
}

// stb_image 2.27 (the system libstb) writes past its Huffman size table when a DHT segment declares
// more than 256 codes (fixed upstream in 2.28): memory corruption from a corrupt or hostile JPEG, found
// by fuzz/fuzz_image. Walk the marker segments (and skip entropy-coded data the way a decoder does)
// and refuse such a file before stb sees it.
void checkJpegHuffmanTables(const std::string& path, const std::string& b) {
    auto at = [&](size_t i) { return static_cast<unsigned char>(b[i]); };
    const size_t n = b.size();
    size_t p = 2;  // after SOI
    while (p + 1 < n) {
        if (at(p) != 0xFF) { ++p; continue; }  // out of sync: look for the next marker
        unsigned m = at(p + 1);
        if (m == 0xFF) { ++p; continue; }      // fill byte
        if (m == 0x00 || m == 0x01 || (m >= 0xD0 && m <= 0xD8)) { p += 2; continue; }  // no length
        if (m == 0xD9) break;                  // EOI
        if (p + 3 >= n) break;
        const size_t segEnd = std::min(n, p + 2 + (size_t(at(p + 2)) << 8 | at(p + 3)));
        if (m == 0xC4) {
            // Like stb: a table is read whenever any declared byte is left (reads past the end give 0).
            for (size_t q = p + 4; q < segEnd;) {
                size_t codes = 0;
                for (size_t i = 0; i < 16; ++i) codes += q + 1 + i < n ? at(q + 1 + i) : 0;
                if (codes > 256)
                    throw Error(path + ": cannot decode JPEG: corrupt Huffman table (" + std::to_string(codes) +
                                " codes, at most 256)");
                q += 17 + codes;
            }
        }
        p = std::max(segEnd, p + 4);
        if (m == 0xDA)  // start of scan: entropy-coded data runs to the next marker other than RSTn
            while (p + 1 < n && !(at(p) == 0xFF && at(p + 1) != 0x00 && at(p + 1) != 0xFF &&
                                  !(at(p + 1) >= 0xD0 && at(p + 1) <= 0xD7)))
                ++p;
    }
}

// Images larger than kMaxImageTexels are refused before any pixel is decoded (memory stays bounded).
void checkImageSize(const std::string& path, int64_t w, int64_t h) {
    if (w > 0 && h > 0 && w * h <= kMaxImageTexels) return;
    throw Error(path + ": image is " + std::to_string(w) + "x" + std::to_string(h) + ", more than the limit of " +
                std::to_string(kMaxImageTexels) + " texels (16384x8192)");
}

ImageRGB readStb(const std::string& path, const std::string& bytes, bool png) {
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
    if (bytes.size() > size_t(INT32_MAX)) throw Error(path + ": image file too large");
    int len = int(bytes.size());
    int w = 0, h = 0, comp = 0;
    // stb_image 2.27 overflows on JPEGs with more than 256 Huffman codes, in stbi_info too: refused first.
    if (!png) checkJpegHuffmanTables(path, bytes);
    // The header's size is checked before decoding: a few KB of PNG can declare gigabytes of pixels.
    if (stbi_info_from_memory(data, len, &w, &h, &comp)) checkImageSize(path, w, h);
    ImageRGB img;
    if (png && stbi_is_16_bit_from_memory(data, len)) {
        stbi_us* px = stbi_load_16_from_memory(data, len, &w, &h, &comp, 3);
        if (!px) throw Error(path + ": cannot decode PNG: " + stbi_failure_reason());
        img.pixels.assign(px, px + size_t(w) * h * 3);
        stbi_image_free(px);
    } else {
        stbi_uc* px = stbi_load_from_memory(data, len, &w, &h, &comp, 3);
        if (!px) throw Error(path + ": cannot decode " + (png ? "PNG" : "JPEG") + ": " + stbi_failure_reason());
        img.pixels.assign(px, px + size_t(w) * h * 3);
        stbi_image_free(px);
    }
    img.width = w;
    img.height = h;
    return img;
}

// Replaces NaN, Inf and negative values by 0; one warning for the whole image.
void sanitize(const std::string& path, ImageRGB& img) {
    size_t bad = 0;
    for (float& v : img.pixels)
        if (!(v >= 0.0f) || std::isinf(v)) {
            v = 0.0f;
            ++bad;
        }
    if (bad > 0)
        warn(path + ": " + std::to_string(bad) + " NaN, infinite or negative texel values replaced by 0");
}

// Finds the RGB channel names: "R","G","B", or one layer's "<layer>.R" etc. Returns false if none.
bool findRgbChannels(const Imf::ChannelList& ch, std::string names[3]) {
    if (ch.findChannel("R") || ch.findChannel("G") || ch.findChannel("B")) {
        names[0] = "R"; names[1] = "G"; names[2] = "B";
        return true;
    }
    for (auto it = ch.begin(); it != ch.end(); ++it) {
        std::string n = it.name();
        if (n.size() > 2 && n.compare(n.size() - 2, 2, ".R") == 0) {
            std::string layer = n.substr(0, n.size() - 1);
            names[0] = layer + "R"; names[1] = layer + "G"; names[2] = layer + "B";
            return true;
        }
    }
    return false;
}

// Luminance/chroma files (Y, RY, BY): the RGBA interface converts them to RGB.
void readExrLuminanceChroma(const std::string& path, ImageRGB& img) {
    Imf::RgbaInputFile file(path.c_str());
    const Imath::Box2i dw = file.dataWindow();
    std::vector<Imf::Rgba> buf(size_t(img.width) * img.height);
    file.setFrameBuffer(buf.data() - dw.min.x - ptrdiff_t(dw.min.y) * img.width, 1, size_t(img.width));
    file.readPixels(dw.min.y, dw.max.y);
    if (!file.isComplete()) throw Error(path + ": EXR file is incomplete (truncated?)");
    for (size_t i = 0; i < buf.size(); ++i) {
        img.pixels[i * 3 + 0] = buf[i].r;
        img.pixels[i * 3 + 1] = buf[i].g;
        img.pixels[i * 3 + 2] = buf[i].b;
    }
}

// The file's `chromaticities` attribute as Primaries (Rec.709/D65, OpenEXR's default, without one).
Primaries filePrimaries(const Imf::Header& hdr) {
    if (!Imf::hasChromaticities(hdr)) return kRec709Primaries;
    const Imf::Chromaticities& c = Imf::chromaticities(hdr);
    return {{c.red.x, c.red.y}, {c.green.x, c.green.y}, {c.blue.x, c.blue.y}, {c.white.x, c.white.y}};
}

// RGB texels in the file's primaries -> linear Rec.709/D65 (unchanged, bit for bit, when they are
// those already). Grey (Y-only) files stay grey: adapted white maps to white.
void toWorkingPrimaries(const std::string& path, ImageRGB& img, const Primaries& from) {
    if (!convertToRec709(img.pixels.data(), (long long)img.width * img.height, from))
        warn(path + ": its EXR chromaticities are degenerate; texels are used as Rec.709 RGB");
}

ImageRGB readExr(const std::string& path) {
    initExrThreads();
    ImageRGB img;
    img.isHdr = true;
    try {
        bool lumaChroma = false, grey = false;
        Primaries primaries = kRec709Primaries;
        {
            Imf::InputFile file(path.c_str());  // reads scanline and tiled files alike
            const Imf::Header& hdr = file.header();
            primaries = filePrimaries(hdr);
            const Imath::Box2i dw = hdr.dataWindow();
            const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, h = int64_t(dw.max.y) - dw.min.y + 1;
            if (w <= 0 || h <= 0) throw Error(path + ": EXR data window has a bad size");
            checkImageSize(path, w, h);
            img.width = int(w);
            img.height = int(h);
            img.pixels.assign(size_t(w) * size_t(h) * 3, 0.0f);
            const Imf::ChannelList& ch = hdr.channels();
            lumaChroma = ch.findChannel("RY") || ch.findChannel("BY");
            if (!lumaChroma) {
                std::string names[3];
                const bool rgb = findRgbChannels(ch, names);
                if (!rgb && !ch.findChannel("Y")) throw Error(path + ": EXR file has no R, G, B or Y channel");
                if (!rgb) names[0] = "Y";  // grey: read Y into R, copy to G and B below
                Imf::FrameBuffer fb;
                const size_t xs = 3 * sizeof(float), ys = xs * size_t(w);
                for (int c = 0; c < (rgb ? 3 : 1); ++c) {
                    const Imf::Channel* info = ch.findChannel(names[c]);
                    if (info && (info->xSampling != 1 || info->ySampling != 1))
                        throw Error(path + ": EXR channel " + names[c] + " is subsampled, which is not supported");
                    // A channel the file lacks (e.g. only R and G) is filled with 0 by OpenEXR.
                    fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.pixels.data() + c, dw, xs, ys));
                }
                file.setFrameBuffer(fb);
                file.readPixels(dw.min.y, dw.max.y);
                if (!file.isComplete()) throw Error(path + ": EXR file is incomplete (truncated?)");
                grey = !rgb;
                if (grey)
                    for (size_t i = 0; i < img.pixels.size(); i += 3)
                        img.pixels[i + 1] = img.pixels[i + 2] = img.pixels[i];
            }
        }
        if (lumaChroma) readExrLuminanceChroma(path, img);  // RGB in the file's primaries
        if (!grey) toWorkingPrimaries(path, img, primaries);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        std::string what = e.what();
        std::replace(what.begin(), what.end(), '\n', ' ');
        throw Error(path + ": cannot read EXR: " + what);
    }
    sanitize(path, img);
    return img;
}

}  // namespace

// OpenEXR decodes and compresses on a thread pool of one thread per core. CLRT_EXR_THREADS fixes the
// count at build time (the fuzz build uses 0, the calling thread only, so a run does not depend on
// the machine's core count or on thread timing).
void initExrThreads() {
    static bool done = [] {
#ifdef CLRT_EXR_THREADS
        unsigned n = CLRT_EXR_THREADS;
#else
        unsigned n = std::thread::hardware_concurrency();
#endif
        Imf::setGlobalThreadCount(n > 1 ? int(n) : 0);
        return true;
    }();
    (void)done;
}

bool readImageSize(const std::string& path, int& width, int& height) {
    width = height = 0;
    char magic[4] = {0, 0, 0, 0};
    {
        std::ifstream f(path, std::ios::binary);
        if (!f.read(magic, 4)) return false;
    }
    try {
        if (std::memcmp(magic, "\x76\x2F\x31\x01", 4) == 0) {
            Imf::InputFile file(path.c_str());  // reads the header only
            const Imath::Box2i dw = file.header().dataWindow();
            width = dw.max.x - dw.min.x + 1;
            height = dw.max.y - dw.min.y + 1;
            return width > 0 && height > 0;
        }
    } catch (const std::exception&) {
        return false;
    }
    std::ifstream f(path, std::ios::binary);
    auto be16 = [](const unsigned char* b) { return int(b[0]) << 8 | int(b[1]); };
    unsigned char b[24];
    if (std::memcmp(magic, "\x89PNG", 4) == 0) {  // the IHDR chunk comes first: width, height at 16
        if (!f.read(reinterpret_cast<char*>(b), 24) || std::memcmp(b + 12, "IHDR", 4) != 0) return false;
        const uint32_t w = uint32_t(b[16]) << 24 | uint32_t(b[17]) << 16 | uint32_t(b[18]) << 8 | b[19];
        const uint32_t h = uint32_t(b[20]) << 24 | uint32_t(b[21]) << 16 | uint32_t(b[22]) << 8 | b[23];
        if (w == 0 || h == 0 || w > INT32_MAX || h > INT32_MAX) return false;
        width = int(w);
        height = int(h);
        return true;
    }
    if (std::memcmp(magic, "\xFF\xD8\xFF", 3) != 0) return false;
    // JPEG: walk the segments to the first start of frame (SOF0..SOF15 but DHT, JPG, DAC).
    f.seekg(2);
    while (f.read(reinterpret_cast<char*>(b), 4)) {
        if (b[0] != 0xFF) return false;
        const int marker = b[1], len = be16(b + 2);
        if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
            if (!f.read(reinterpret_cast<char*>(b), 5)) return false;
            height = be16(b + 1);
            width = be16(b + 3);
            return width > 0 && height > 0;
        }
        if (len < 2) return false;
        f.seekg(len - 2, std::ios::cur);
    }
    return false;
}

ImageRGB readImage(const std::string& path) {
    std::string bytes = readAll(path);
    if (startsWith(bytes, "\x89PNG", 4)) return readStb(path, bytes, true);
    if (startsWith(bytes, "\xFF\xD8\xFF", 3)) return readStb(path, bytes, false);
    if (startsWith(bytes, "\x76\x2F\x31\x01", 4)) {
        bytes.clear();
        bytes.shrink_to_fit();
        return readExr(path);
    }
    throw Error(path + ": unknown image format (not PNG, JPEG or EXR)");
}

}  // namespace clrt
