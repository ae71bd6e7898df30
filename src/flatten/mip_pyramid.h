// mip_pyramid.h — the mip-map pyramid of an image texture with Interpolation trilinear (2025): each level
// half the size of the one before (rounded down, at least 1), box-filtered over the exact footprint of
// each texel in the level before (fractional edge weights when a size is odd, so non-power-of-two
// images keep their mean), per channel, in the texels' stored space (as the atlas holds them).
#pragma once

#include <vector>

#include "shared/device_types.h"

namespace clrt {

struct MipLevel {
    int width = 0, height = 0;
    std::vector<dev::float4> texels;  // row-major, row 0 at the top
};

// Level `src` halved: width max(1, w/2), height max(1, h/2).
MipLevel mipDownsample(const MipLevel& src);
// Levels 1, 2, ... down to 1×1 (level 0, the image itself, is not repeated).
std::vector<MipLevel> mipPyramid(const MipLevel& level0);

}  // namespace clrt
