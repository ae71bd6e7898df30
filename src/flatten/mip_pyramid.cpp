// mip_pyramid.cpp — box-filtered mip levels for trilinear image textures (see mip_pyramid.h); read by
// flatten_textures.cpp (ImageAtlas::useMipChain) and tests/test_textures.cpp.
#include "flatten/mip_pyramid.h"

#include <algorithm>
#include <cmath>

namespace clrt {
namespace {

struct Tap {
    int index;
    float weight;
};

// For each of the `m` output texels along an axis of `n` input texels: the input texels its box
// [o·n/m, (o+1)·n/m) covers, each weighted by its overlap / the box's length (weights sum to 1).
std::vector<std::vector<Tap>> boxTaps(int n, int m) {
    std::vector<std::vector<Tap>> taps;
    taps.resize(size_t(m));
    const double scale = double(n) / double(m);
    for (int o = 0; o < m; ++o) {
        const double lo = o * scale, hi = (o + 1) * scale;
        for (int i = int(std::floor(lo)); i < int(std::ceil(hi)) && i < n; ++i) {
            const double overlap = std::min(hi, double(i + 1)) - std::max(lo, double(i));
            if (overlap > 0) taps[size_t(o)].push_back({i, float(overlap / scale)});
        }
    }
    return taps;
}

}  // namespace

MipLevel mipDownsample(const MipLevel& src) {
    MipLevel dst;
    dst.width = std::max(1, src.width / 2);
    dst.height = std::max(1, src.height / 2);
    dst.texels.assign(size_t(dst.width) * dst.height, dev::float4{0, 0, 0, 0});
    const auto tx = boxTaps(src.width, dst.width), ty = boxTaps(src.height, dst.height);
    for (int y = 0; y < dst.height; ++y)
        for (int x = 0; x < dst.width; ++x) {
            double acc[4] = {0, 0, 0, 0};
            for (const Tap& b : ty[size_t(y)])
                for (const Tap& a : tx[size_t(x)]) {
                    const dev::float4& c = src.texels[size_t(b.index) * src.width + size_t(a.index)];
                    const double w = double(a.weight) * b.weight;
                    acc[0] += w * c.x;
                    acc[1] += w * c.y;
                    acc[2] += w * c.z;
                    acc[3] += w * c.w;
                }
            dst.texels[size_t(y) * dst.width + x] = {float(acc[0]), float(acc[1]), float(acc[2]), float(acc[3])};
        }
    return dst;
}

std::vector<MipLevel> mipPyramid(const MipLevel& level0) {
    std::vector<MipLevel> levels;
    const MipLevel* prev = &level0;
    while (prev->width > 1 || prev->height > 1) {
        levels.push_back(mipDownsample(*prev));
        prev = &levels.back();
    }
    return levels;
}

}  // namespace clrt
