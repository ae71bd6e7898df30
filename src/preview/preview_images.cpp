// preview_images.cpp — tone-mapped views, thumbnails and in-memory EXR files of the preview (see
// preview_images.h). Reads no scene element itself.
#include "preview/preview_images.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include "image/tonemap.h"

namespace clrt {

namespace {

// An OpenEXR output stream into a string.
class MemoryOStream : public Imf::OStream {
public:
    MemoryOStream() : Imf::OStream("preview.exr") {}
    void write(const char c[], int n) override {
        if (pos_ + size_t(n) > data_.size()) data_.resize(pos_ + size_t(n));
        std::memcpy(&data_[pos_], c, size_t(n));
        pos_ += size_t(n);
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = size_t(pos); }
    std::string take() { return std::move(data_); }

private:
    std::string data_;
    size_t pos_ = 0;
};

// Linear view: radiance * 2^exposure / white, clamped; sRGB-encoded unless `ldr` (the course's PNGs
// are the clamped radiance itself).
std::vector<unsigned char> linearView(const ImageRGB& img, bool ldr, double exposure) {
    const float gain = float(std::exp2(exposure) / (ldr ? 255.0 : 1.0));
    std::vector<unsigned char> out(img.pixels.size());
    for (size_t i = 0; i < out.size(); ++i) {
        float v = std::min(1.0f, tonemapSanitize(img.pixels[i]) * gain);
        if (!ldr) v = srgbEncode(v);
        out[i] = (unsigned char)std::lround(std::min(255.0f, std::max(0.0f, v * 255.0f)));
    }
    return out;
}

}  // namespace

bool validViewSettings(const ViewSettings& v) {
    static const char* names[] = {"scene", "photographic", "aces", "filmic", "linear"};
    const bool known = std::any_of(std::begin(names), std::end(names), [&](const char* n) { return v.tmo == n; });
    return known && std::isfinite(v.exposure) && std::fabs(v.exposure) <= 20 && v.maxWidth >= 0;
}

ImageRGB boxDownscale(const ImageRGB& img, int maxWidth) {
    if (maxWidth <= 0 || img.width <= maxWidth) return img;
    const int f = (img.width + maxWidth - 1) / maxWidth;
    ImageRGB out;
    out.width = std::max(1, img.width / f);
    out.height = std::max(1, img.height / f);
    out.pixels.assign(size_t(out.width) * size_t(out.height) * 3, 0.0f);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 3; ++c) {
                double s = 0;
                for (int dy = 0; dy < f; ++dy)
                    for (int dx = 0; dx < f; ++dx) s += tonemapSanitize(img.at(x * f + dx, y * f + dy, c));
                out.at(x, y, c) = float(s / (f * f));
            }
    return out;
}

std::vector<unsigned char> previewView(const ImageRGB& full, bool ldr, bool hasTonemap, const TonemapSettings& scene,
                                       const ViewSettings& v, int& width, int& height) {
    const ImageRGB small = v.maxWidth > 0 && full.width > v.maxWidth ? boxDownscale(full, v.maxWidth) : ImageRGB{};
    const ImageRGB& img = small.width > 0 ? small : full;
    width = img.width;
    height = img.height;
    if (v.tmo == "linear" || (v.tmo == "scene" && !hasTonemap)) return linearView(img, ldr, v.exposure);
    TonemapSettings s = hasTonemap ? scene : TonemapSettings{};
    if (v.tmo != "scene") s.op = parseTmoKind(v.tmo);
    s.key = float(s.key * std::exp2(v.exposure));
    s.truncate = false;
    return tonemapHost(img, s);
}

std::string exrBytes(const ImageRGB& img, const std::vector<std::pair<std::string, std::string>>& attributes) {
    Imf::Header hdr(img.width, img.height);
    hdr.compression() = Imf::ZIP_COMPRESSION;
    const char* names[3] = {"R", "G", "B"};
    for (const char* n : names) hdr.channels().insert(n, Imf::Channel(Imf::FLOAT));
    for (const auto& kv : attributes) hdr.insert(kv.first, Imf::StringAttribute(kv.second));
    Imf::FrameBuffer fb;
    const char* base = reinterpret_cast<const char*>(img.pixels.data());
    for (int c = 0; c < 3; ++c)
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, const_cast<char*>(base + c * sizeof(float)), 3 * sizeof(float),
                                       3 * sizeof(float) * size_t(img.width)));
    MemoryOStream os;
    {
        Imf::OutputFile out(os, hdr, /*numThreads=*/0);  // on this thread: the render keeps the cores
        out.setFrameBuffer(fb);
        out.writePixels(img.height);
    }
    return os.take();
}

}  // namespace clrt
