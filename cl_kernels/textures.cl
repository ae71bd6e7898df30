/* textures.cl — texture lookups: image textures from the texel atlas (nearest or bilinear, repeat
 * wrap, the course's texel convention: (i, j) = (u·w, v·h), row 0 at the top), the checkerboard and
 * Perlin procedurals, and the decal modes that change kd / ks / the final colour. */
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
/* The converted noise (absval: |n|, linear: (n + 1)/2) at the scaled point: the texture's value and
 * the height of a Perlin bump map. */
inline float Perlin_Value(const __global TextureMap* tex, float3 p) {
    float n = Perlin_Noise(p * tex->noiseScale);
    return tex->noiseAbs ? fabs(n) : 0.5f * (n + 1.0f);
}
/* ∇ of Perlin_Value at p by central differences (step CLRT_PERLIN_GRAD_STEP in scaled units). */
inline float3 Perlin_Gradient(const __global TextureMap* tex, float3 p) {
    float e = CLRT_PERLIN_GRAD_STEP / fmax(tex->noiseScale, 1e-20f);
    float3 g;
    g.x = Perlin_Value(tex, p + (float3)(e, 0.0f, 0.0f)) - Perlin_Value(tex, p - (float3)(e, 0.0f, 0.0f));
    g.y = Perlin_Value(tex, p + (float3)(0.0f, e, 0.0f)) - Perlin_Value(tex, p - (float3)(0.0f, e, 0.0f));
    g.z = Perlin_Value(tex, p + (float3)(0.0f, 0.0f, e)) - Perlin_Value(tex, p - (float3)(0.0f, 0.0f, e));
    return g / (2.0f * e);
}

/* The value of texture `tex` at (uv, world position p, object-space position pObj), in reflectance
 * units (0..1 for images after the normalizer). The procedural textures are evaluated in object space
 * (the checkerboard's tiles and the noise follow the object's scale, as in the course). */
inline float3 Texture_Eval(const __global TextureMap* tex, const __global ImageInfo* images,
                           const __global float4* texels, float2 uv, float3 p, float3 pObj) {
    switch (tex->kind) {
    case TEXTURE_IMAGE:
        return Image_Lookup(texels, images[tex->image], uv.x, uv.y, tex->interpolation) / tex->normalizer;
    case TEXTURE_CHECKERBOARD: {
        float3 q = (pObj + tex->offset) * tex->scale;
        int s = (int)floor(q.x) + (int)floor(q.y) + (int)floor(q.z);
        return (s & 1) ? tex->blackColor.xyz : tex->whiteColor.xyz;
    }
    case TEXTURE_PERLIN:
        return (float3)(clamp(Perlin_Value(tex, pObj), 0.0f, 1.0f));
    }
    return (float3)(0.0f);
}

#endif /* CLRT_TEXTURES_CL */
