/* textures.cl — texture lookups: image textures from the texel atlas (nearest or bilinear, repeat
 * wrap, the course's texel convention: (i, j) = (u·w, v·h), row 0 at the top; trilinear: bilinear in
 * the two mip levels around the ray cone's level of detail, CLRT_HAS_MIPMAPS), the checkerboard and
 * Perlin procedurals (NumOctaves: a fractal sum), and the decal modes that change kd / ks / the final
 * colour. */
#ifndef CLRT_TEXTURES_CL
#define CLRT_TEXTURES_CL

#include "../src/shared/device_types.h"
#include "common.cl"

inline float4 Image_Texel(const __global float4* texels, ImageInfo img, int x, int y) {
    x = x % img.width; if (x < 0) x += img.width;
    y = y % img.height; if (y < 0) y += img.height;
    return texels[img.offset + y * img.width + x];
}

/* Bilinear or nearest lookup at texture coordinates (u, v), v growing downwards. */
inline float3 Image_Lookup(const __global float4* texels, ImageInfo img, float u, float v, int interp) {
    float px = u * (float)img.width, py = v * (float)img.height;
    if (interp == INTERP_NEAREST) return Image_Texel(texels, img, (int)floor(px), (int)floor(py)).xyz;
    float fx = floor(px), fy = floor(py);
    float dx = px - fx, dy = py - fy;
    int ix = (int)fx, iy = (int)fy;
    float3 c00 = Image_Texel(texels, img, ix, iy).xyz, c10 = Image_Texel(texels, img, ix + 1, iy).xyz;
    float3 c01 = Image_Texel(texels, img, ix, iy + 1).xyz, c11 = Image_Texel(texels, img, ix + 1, iy + 1).xyz;
    return (1.0f - dx) * (1.0f - dy) * c00 + dx * (1.0f - dy) * c10 + (1.0f - dx) * dy * c01 + dx * dy * c11;
}

/* Perlin noise as the course defines it: 16 gradients (the 12 cube-edge directions and 4 repeated),
 * the course's 16-entry permutation P (src/shared/device_types.h says how it was found), the lattice
 * hash P[|i + P[|j + P[|k| mod 16]| mod 16]| mod 16] (the absolute value, not a wrap: the course's
 * lattice is mirrored about 0, which the references show on negative coordinates), and the weight
 * w(t) = 1 − 6|t|^5 + 15|t|^4 − 10|t|^3 per axis: noise(p) = Σ_corners w·w·w·(g · (p − corner)). */
__constant int CLRT_PERLIN_PERM[16] = {CLRT_PERLIN_PERM_VALUES};
__constant float CLRT_PERLIN_GRAD[16][3] = {CLRT_PERLIN_GRAD_VALUES};
inline int Perlin_Index(int a) { return (int)(abs(a) & 15u); }
inline int Perlin_Hash(int i, int j, int k) {
    int a = CLRT_PERLIN_PERM[Perlin_Index(k)];
    int b = CLRT_PERLIN_PERM[Perlin_Index(j + a)];
    return CLRT_PERLIN_PERM[Perlin_Index(i + b)];
}
inline float Perlin_Weight(float t) {
    t = fabs(t);
    return t >= 1.0f ? 0.0f : 1.0f - t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f);
}
inline float Perlin_Noise(float3 p) {
    float3 fl = floor(p);
    int3 c = convert_int3(fl);
    float sum = 0.0f;
    for (int corner = 0; corner < 8; ++corner) {
        int3 d = (int3)(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        float3 v = p - (fl + convert_float3(d));
        int g = Perlin_Hash(c.x + d.x, c.y + d.y, c.z + d.z);
        float dotGv = CLRT_PERLIN_GRAD[g][0] * v.x + CLRT_PERLIN_GRAD[g][1] * v.y + CLRT_PERLIN_GRAD[g][2] * v.z;
        sum += Perlin_Weight(v.x) * Perlin_Weight(v.y) * Perlin_Weight(v.z) * dotGv;
    }
    return sum;
}
/* NumOctaves (course 2025): n = Σ_{k < octaves} 2^-k · noise(2^k · s·p), s = NoiseScale; the
 * conversion (Perlin_Value) applies to the sum. One octave is the plain noise, bit for bit. */
inline float Perlin_Fractal(const __global TextureMap* tex, float3 p) {
    float3 q = p * tex->noiseScale;
    float n = Perlin_Noise(q);
    float amplitude = 1.0f;
    for (int k = 1; k < tex->octaves; ++k) {
        q *= 2.0f;
        amplitude *= 0.5f;
        n += amplitude * Perlin_Noise(q);
    }
    return n;
}
/* The converted noise (absval: |n|, linear: (n + 1)/2) at the scaled point: the texture's value and
 * the height of a Perlin bump map. */
inline float Perlin_Value(const __global TextureMap* tex, float3 p) {
    float n = Perlin_Fractal(tex, p);
    return tex->noiseAbs ? fabs(n) : 0.5f * (n + 1.0f);
}
/* ∇ of Perlin_Value at p by central differences (step CLRT_PERLIN_GRAD_STEP in the units of the
 * finest octave's lattice). */
inline float3 Perlin_Gradient(const __global TextureMap* tex, float3 p) {
    float e = CLRT_PERLIN_GRAD_STEP / fmax(tex->noiseScale * (float)(1 << (tex->octaves - 1)), 1e-20f);
    float3 g;
    g.x = Perlin_Value(tex, p + (float3)(e, 0.0f, 0.0f)) - Perlin_Value(tex, p - (float3)(e, 0.0f, 0.0f));
    g.y = Perlin_Value(tex, p + (float3)(0.0f, e, 0.0f)) - Perlin_Value(tex, p - (float3)(0.0f, e, 0.0f));
    g.z = Perlin_Value(tex, p + (float3)(0.0f, 0.0f, e)) - Perlin_Value(tex, p - (float3)(0.0f, 0.0f, e));
    return g / (2.0f * e);
}

#ifdef CLRT_HAS_MIPMAPS
/* The level of detail of a footprint of `footprintUv` uv units on an image of w×h texels: log2 of the
 * footprint in texels (an isotropic footprint: the level's texel spacing equals it), 0 when unknown (NaN). */
inline float Mip_Level(float footprintUv, int width, int height) {
    float texelsAcross = footprintUv * sqrt((float)width * (float)height);
    return texelsAcross > 0.0f ? log2(fmin(texelsAcross, 1e30f)) : 0.0f;  /* NaN: 0; +inf: the coarsest */
}
/* Trilinear: the level clamped to the chain, bilinear at the levels below and above it, blended
 * linearly between them (level k at images[tex->image + k]). */
inline float3 Image_Trilinear(const __global float4* texels, const __global ImageInfo* images,
                              const __global TextureMap* tex, float2 uv, float footprintUv) {
    ImageInfo base = images[tex->image];
    float level = clamp(Mip_Level(footprintUv, base.width, base.height), 0.0f, (float)(tex->mipLevels - 1));
    int l0 = (int)floor(level);
    float f = level - (float)l0;
    float3 c0 = Image_Lookup(texels, images[tex->image + l0], uv.x, uv.y, INTERP_BILINEAR);
    if (!(f > 0.0f) || l0 + 1 >= tex->mipLevels) return c0;
    float3 c1 = Image_Lookup(texels, images[tex->image + l0 + 1], uv.x, uv.y, INTERP_BILINEAR);
    return (1.0f - f) * c0 + f * c1;
}
#endif

/* The value of texture `tex` at (uv, world position p, object-space position pObj), in reflectance
 * units (0..1 for images after the normalizer). The procedural textures are evaluated in object space
 * (the checkerboard's tiles and the noise follow the object's scale, as in the course). footprintUv:
 * the ray cone's width on the surface in uv units (Surface_FootprintUv, shade.cl), read by trilinear
 * images only. */
inline float3 Texture_Eval(const __global TextureMap* tex, const __global ImageInfo* images,
                           const __global float4* texels, float2 uv, float3 p, float3 pObj, float footprintUv) {
    switch (tex->kind) {
    case TEXTURE_IMAGE:
#ifdef CLRT_HAS_MIPMAPS
        if (tex->mipLevels > 1) return Image_Trilinear(texels, images, tex, uv, footprintUv) / tex->normalizer;
#endif
        return Image_Lookup(texels, images[tex->image], uv.x, uv.y, tex->interpolation) / tex->normalizer;
    case TEXTURE_CHECKERBOARD: {
        /* Each coordinate's integer part by truncation toward zero, as the course's references have it: the
         * tiles on both sides of a zero plane share a colour (hw5 veach_ajar, 2020 package: 37.47 -> 40.73 dB;
         * floor() shifts the pattern by a tile on the negative side). */
        float3 q = (pObj + tex->offset) * tex->scale;
        int s = (int)q.x + (int)q.y + (int)q.z;
        return (s & 1) ? tex->blackColor.xyz : tex->whiteColor.xyz;
    }
    case TEXTURE_PERLIN:
        return (float3)(clamp(Perlin_Value(tex, pObj), 0.0f, 1.0f));
    }
    return (float3)(0.0f);
}

#endif /* CLRT_TEXTURES_CL */
