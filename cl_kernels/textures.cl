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

/* Perlin gradient noise in [-1, 1] (Perlin 2002 permutation-free hash variant). */
inline float Perlin_Grad(int3 c, float3 f) {
    uint h = Rng_Hash((uint)c.x * 73856093u ^ (uint)c.y * 19349663u ^ (uint)c.z * 83492791u) & 15u;
    float u = h < 8u ? f.x : f.y;
    float v = h < 4u ? f.y : (h == 12u || h == 14u ? f.x : f.z);
    return ((h & 1u) ? -u : u) + ((h & 2u) ? -v : v);
}
inline float Perlin_Fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float Perlin_Noise(float3 p) {
    float3 fl = floor(p);
    int3 c = convert_int3(fl);
    float3 f = p - fl;
    float3 w = (float3)(Perlin_Fade(f.x), Perlin_Fade(f.y), Perlin_Fade(f.z));
    float n000 = Perlin_Grad(c, f), n100 = Perlin_Grad(c + (int3)(1, 0, 0), f - (float3)(1, 0, 0));
    float n010 = Perlin_Grad(c + (int3)(0, 1, 0), f - (float3)(0, 1, 0)), n110 = Perlin_Grad(c + (int3)(1, 1, 0), f - (float3)(1, 1, 0));
    float n001 = Perlin_Grad(c + (int3)(0, 0, 1), f - (float3)(0, 0, 1)), n101 = Perlin_Grad(c + (int3)(1, 0, 1), f - (float3)(1, 0, 1));
    float n011 = Perlin_Grad(c + (int3)(0, 1, 1), f - (float3)(0, 1, 1)), n111 = Perlin_Grad(c + (int3)(1, 1, 1), f - (float3)(1, 1, 1));
    float x00 = mix(n000, n100, w.x), x10 = mix(n010, n110, w.x), x01 = mix(n001, n101, w.x), x11 = mix(n011, n111, w.x);
    return mix(mix(x00, x10, w.y), mix(x01, x11, w.y), w.z);
}

/* The value of texture `tex` at (uv, world position p), in reflectance units (0..1 for images after
 * the normalizer). */
inline float3 Texture_Eval(const __global TextureMap* tex, const __global ImageInfo* images,
                           const __global float4* texels, float2 uv, float3 p) {
    switch (tex->kind) {
    case TEXTURE_IMAGE:
        return Image_Lookup(texels, images[tex->image], uv.x, uv.y, tex->interpolation) / tex->normalizer;
    case TEXTURE_CHECKERBOARD: {
        float3 q = (p + tex->offset) * tex->scale;
        int s = (int)floor(q.x) + (int)floor(q.y) + (int)floor(q.z);
        return (s & 1) ? tex->blackColor.xyz : tex->whiteColor.xyz;
    }
    case TEXTURE_PERLIN: {
        float n = Perlin_Noise(p * tex->noiseScale);
        float t = tex->noiseAbs ? fabs(n) : 0.5f * (n + 1.0f);
        return (float3)(clamp(t, 0.0f, 1.0f));
    }
    }
    return (float3)(0.0f);
}

#endif /* CLRT_TEXTURES_CL */
