// flatten_textures.cpp — the texel atlas (with the half4 copies of environment maps whose values are all
// halves, and the mip levels of trilinear textures), texture maps and per-shape texture sets (see
// flatten.h). Reads the TextureMaps' Interpolation, NumOctaves, degamma and the procedural parameters.
#include <cmath>
#include <cstdint>
#include <cstring>

#include <Imath/half.h>

#include "flatten/flatten.h"
#include "flatten/mip_pyramid.h"
#include "image/image.h"
#include "util/error.h"

namespace clrt {

int ImageAtlas::use(int sceneImage) {
    auto it = slot_.find(sceneImage);
    if (it != slot_.end()) return it->second;
    auto ti = std::chrono::steady_clock::now();
    ImageRGB img = readImage(scene_.imagePaths.at(sceneImage));
    ds_.imageSeconds += secondsSince(ti);
    dev::ImageInfo info{};
    info.offset = int(ds_.texels.size());
    info.width = img.width;
    info.height = img.height;
    if (ds_.texels.size() + size_t(img.width) * img.height > size_t(INT32_MAX))
        throw Error(scene_.path + ": textures exceed 2^31 texels");
    const size_t n = size_t(img.width) * img.height;
    ds_.texels.resize(size_t(info.offset) + n);
    dev::float4* dst = ds_.texels.data() + info.offset;
    const float* src = img.pixels.data();
    for (size_t p = 0; p < n; ++p) dst[p] = {src[p * 3], src[p * 3 + 1], src[p * 3 + 2], 0};
    int slot = int(ds_.images.size());
    ds_.images.push_back(info);
    setHdr(slot, img.isHdr);
    slot_[sceneImage] = slot;
    return slot;
}

bool packHalf4Exact(const dev::float4* src, size_t n, std::vector<dev::float4>& packed) {
    std::vector<uint16_t> bits(((n + 1) / 2) * 8, 0);
    for (size_t p = 0; p < n; ++p) {
        const float c[4] = {src[p].x, src[p].y, src[p].z, src[p].w};
        for (int k = 0; k < 4; ++k) {
            if (!std::isfinite(c[k])) return false;
            const half h(c[k]);
            const float back = float(h);
            if (std::memcmp(&c[k], &back, sizeof(float)) != 0) return false;  // -0 stays -0
            bits[p * 4 + k] = h.bits();
        }
    }
    packed.resize(bits.size() / 8);
    std::memcpy(packed.data(), bits.data(), bits.size() * sizeof(uint16_t));
    return true;
}

std::vector<dev::float4> imageTexels(const DeviceScene& ds, int image) {
    const dev::ImageInfo& info = ds.images.at(size_t(image));
    const size_t n = size_t(info.width) * info.height;
    if (info.format != dev::TEXELS_HALF4)
        return std::vector<dev::float4>(ds.texels.begin() + info.offset, ds.texels.begin() + info.offset + n);
    std::vector<uint16_t> bits(n * 4);
    std::memcpy(bits.data(), ds.texels.data() + info.offset, bits.size() * sizeof(uint16_t));
    std::vector<dev::float4> out(n);
    for (size_t p = 0; p < n; ++p) {
        half c[4];
        for (int k = 0; k < 4; ++k) c[k].setBits(bits[p * 4 + k]);
        out[p] = {float(c[0]), float(c[1]), float(c[2]), float(c[3])};
    }
    return out;
}

int ImageAtlas::useEnvironment(int sceneImage) {
    auto it = envSlot_.find(sceneImage);
    if (it != envSlot_.end()) return it->second;
    const int full = use(sceneImage);
    const dev::ImageInfo info = ds_.images[size_t(full)];
    std::vector<dev::float4> packed;
    int slot = full;
    if (packHalf4Exact(ds_.texels.data() + info.offset, size_t(info.width) * info.height, packed) &&
        ds_.texels.size() + packed.size() <= size_t(INT32_MAX)) {
        dev::ImageInfo h = info;
        h.offset = int(ds_.texels.size());
        h.format = dev::TEXELS_HALF4;
        ds_.texels.insert(ds_.texels.end(), packed.begin(), packed.end());
        slot = int(ds_.images.size());
        ds_.images.push_back(h);
        setHdr(slot, isHdr(full));
    }
    envSlot_[sceneImage] = slot;
    return slot;
}

int ImageAtlas::useDegamma(int sceneImage) {
    auto it = degammaSlot_.find(sceneImage);
    if (it != degammaSlot_.end()) return it->second;
    const int plain = use(sceneImage);
    const dev::ImageInfo info = ds_.images[size_t(plain)];
    const size_t n = size_t(info.width) * info.height;
    if (ds_.texels.size() + n > size_t(INT32_MAX)) throw Error(scene_.path + ": textures exceed 2^31 texels");
    const float range = isHdr(plain) ? 1.0f : 255.0f;
    auto decode = [range](float c) { return c > 0.0f ? range * std::pow(c / range, 2.2f) : 0.0f; };
    dev::ImageInfo d = info;
    d.offset = int(ds_.texels.size());
    ds_.texels.resize(size_t(d.offset) + n);
    for (size_t p = 0; p < n; ++p) {
        const dev::float4 c = ds_.texels[size_t(info.offset) + p];
        ds_.texels[size_t(d.offset) + p] = {decode(c.x), decode(c.y), decode(c.z), c.w};
    }
    const int slot = int(ds_.images.size());
    ds_.images.push_back(d);
    setHdr(slot, isHdr(plain));
    degammaSlot_[sceneImage] = slot;
    return slot;
}

int ImageAtlas::useMipChain(int sceneImage, int* levels, bool degamma) {
    auto it = mipSlot_.find({sceneImage, degamma});
    if (it != mipSlot_.end()) {
        *levels = it->second.second;
        return it->second.first;
    }
    const int full = degamma ? useDegamma(sceneImage) : use(sceneImage);
    const dev::ImageInfo info = ds_.images[size_t(full)];
    MipLevel level0;
    level0.width = info.width;
    level0.height = info.height;
    level0.texels = imageTexels(ds_, full);
    const std::vector<MipLevel> pyramid = mipPyramid(level0);
    size_t total = 0;
    for (const MipLevel& l : pyramid) total += l.texels.size();
    if (ds_.texels.size() + total > size_t(INT32_MAX)) throw Error(scene_.path + ": textures exceed 2^31 texels");
    const int first = int(ds_.images.size());
    ds_.images.push_back(info);  // level 0: the same texels
    setHdr(first, isHdr(full));
    for (const MipLevel& l : pyramid) {
        dev::ImageInfo li{};
        li.offset = int(ds_.texels.size());
        li.width = l.width;
        li.height = l.height;
        li.format = dev::TEXELS_FLOAT4;
        ds_.texels.insert(ds_.texels.end(), l.texels.begin(), l.texels.end());
        setHdr(int(ds_.images.size()), isHdr(full));
        ds_.images.push_back(li);
    }
    *levels = 1 + int(pyramid.size());
    mipSlot_[{sceneImage, degamma}] = {first, *levels};
    return first;
}

namespace {

dev::TextureMap textureMap(const Texture& t) {
    dev::TextureMap d{};
    d.image = CLRT_INVALID;
    d.kind = t.type;
    d.decal = t.decalMode;
    // Trilinear: mip-mapped where Texture_Eval has a footprint (shapes), bilinear elsewhere (Image_Lookup).
    d.interpolation = t.interpolation;
    d.mipLevels = 1;
    d.octaves = t.numOctaves;
    d.normalizer = t.normalizer;
    d.bumpFactor = t.bumpFactor;
    d.scale = t.scale;
    d.offset = t.offset;
    d.noiseScale = t.noiseScale;
    d.noiseAbs = t.noiseConversion == "absval";
    d.blackColor = toFloat4(t.blackColor);
    d.whiteColor = toFloat4(t.whiteColor);
    return d;
}

// An image texture's image is loaded only when a shape uses it or it is the background.
bool imageUsed(const Scene& scene, const Texture& t, int index) {
    bool used = t.decalMode == dev::DECAL_REPLACE_BACKGROUND;
    for (const Shape& s : scene.shapes)
        for (int x : s.textureIndices) used |= (x == index);
    return used;
}

}  // namespace

void flattenTextures(const Scene& scene, DeviceScene& ds, ImageAtlas& atlas) {
    ds.params.backgroundTexture = CLRT_INVALID;
    for (size_t ti = 0; ti < scene.textures.size(); ++ti) {
        const Texture& t = scene.textures[ti];
        dev::TextureMap d = textureMap(t);
        if (t.type == dev::TEXTURE_IMAGE && t.imageIndex >= 0 && imageUsed(scene, t, int(ti))) {
            if (t.interpolation == dev::INTERP_TRILINEAR && t.decalMode != dev::DECAL_REPLACE_BACKGROUND) {
                d.image = atlas.useMipChain(t.imageIndex, &d.mipLevels, t.degamma);
                ds.features.mipMaps |= d.mipLevels > 1;
            } else {
                d.image = t.degamma ? atlas.useDegamma(t.imageIndex) : atlas.use(t.imageIndex);
            }
            if (!t.normalizerGiven) d.normalizer = atlas.isHdr(d.image) ? 1.0f : 255.0f;
            // replace_all pastes texel / Normalizer as radiance (the course); without a Normalizer
            // the texel itself (0..255), as before.
            if (!t.normalizerGiven && t.decalMode == dev::DECAL_REPLACE_ALL) d.normalizer = 1.0f;
        }
        if (t.decalMode == dev::DECAL_REPLACE_BACKGROUND && d.image != CLRT_INVALID) ds.params.backgroundTexture = int(ti);
        ds.textures.push_back(d);
    }
    // Never an empty buffer. (The dummy image comes before any environment map's.)
    if (ds.textures.empty()) ds.textures.push_back(dev::TextureMap{});
    if (ds.images.empty()) ds.images.push_back(dev::ImageInfo{0, 1, 1, 0});
    if (ds.texels.empty()) ds.texels.push_back({0, 0, 0, 0});
}

int flattenTextureSet(const Scene& scene, const Shape& s, DeviceScene& ds) {
    if (s.textureIndices.empty()) return CLRT_INVALID;
    dev::TextureSet set;
    for (int k = 0; k < CLRT_MAX_TEXTURES_PER_SHAPE; ++k) set.texture[k] = CLRT_INVALID;
    int k = 0;
    for (int x : s.textureIndices) {
        if (scene.textures[x].decalMode == dev::DECAL_REPLACE_BACKGROUND) continue;
        if (k == CLRT_MAX_TEXTURES_PER_SHAPE) {
            warnOnce(s.source + ": more than 4 textures; the rest are ignored");
            break;
        }
        set.texture[k++] = x;
        ds.features.normalMaps |= scene.textures[x].decalMode == dev::DECAL_REPLACE_NORMAL;
        ds.features.bumpMaps |= scene.textures[x].decalMode == dev::DECAL_BUMP_NORMAL;
    }
    if (k == 0) return CLRT_INVALID;
    // The object-space point of a hit (checkerboard): a singular transform keeps world space.
    Mat4 inv;
    if (!s.transform.inverse(inv)) inv = Mat4::identity();
    for (int r = 0; r < 3; ++r)
        set.worldToObject[r] = {float(inv.m[r][0]), float(inv.m[r][1]), float(inv.m[r][2]), float(inv.m[r][3])};
    ds.features.textures = true;
    ds.textureSets.push_back(set);
    return int(ds.textureSets.size()) - 1;
}

}  // namespace clrt
