/* tonemap.cl — tone mapping of a float RGB image (3 floats per pixel, row-major) to 8-bit RGB.
 * Three kernels, driven by src/output/tonemap_device.cpp:
 *   Tonemap_Luminance: Y per pixel, and per work-item compensated (Neumaier) partial sums of
 *                      log(δ + Y) that the host adds up in double;
 *   Tonemap_Histogram: one radix-select pass (256 bins of 8 bits of the float bit pattern, among the
 *                      values whose higher bits equal a prefix); four passes find the k-th smallest Y
 *                      exactly (non-negative floats order like their bit patterns);
 *   Tonemap_Map:       the operator (one switch, Tmo_Apply), saturation, clamp, gamma, quantisation;
 *   Tonemap_MapFloat:  the same without the quantisation (float display values, for inspection).
 * Same formulas, in the same float operation order, as the host reference src/image/tonemap.cpp.
 * The two map kernels take TONEMAP_VEC (16) pixels per work-item and work on float16 vectors (lanes =
 * pixels): PoCL's CPU device runs its vector pow about 15 times faster per value than its scalar pow,
 * and the two are the same code instantiated per vector width, so the bytes equal those of the scalar
 * one-pixel-per-work-item form (pow checked exhaustively for the exponents 1/2.2 and 1 on PoCL;
 * tests/test_tonemap.cpp compares the kernels with that form, kept there, byte for byte). Branches
 * become select() over both sides; every other operation is IEEE-exact, so lanes equal scalars.
 * The form on every device, not a quirk (docs/quirks.md "Not quirks"). */
#ifndef CLRT_TONEMAP_CL
#define CLRT_TONEMAP_CL

#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"
/* FP_CONTRACT OFF from here to the end of this file: the same float operations as the host. */
#pragma OPENCL FP_CONTRACT OFF

#define TONEMAP_BINS 256
#define TONEMAP_FLT_MAX 3.402823466e+38f
#define TONEMAP_VEC 16 /* pixels per work-item of the map kernels (the host's kPixelsPerMapItem) */

/* NaN, ±Inf and negative channels count as 0. */
inline float Tonemap_Sanitize(float c) { return (isfinite(c) && c > 0.0f) ? c : 0.0f; }

inline float Tonemap_Luma(float r, float g, float b) {
    float y = 0.2126f * Tonemap_Sanitize(r);
    y = y + 0.7152f * Tonemap_Sanitize(g);
    y = y + 0.0722f * Tonemap_Sanitize(b);
    return fmin(y, TONEMAP_FLT_MAX);
}

/* The operators on TONEMAP_VEC luminances at once (both sides of every branch computed, then
 * select): the same float operations, in the same order, as the scalar host reference. */

/* Reinhard et al. 2002 (global): L/(1+L), or L(1 + L/Lw²)/(1+L) with a white point. */
inline float16 Tmo_Photographic(float16 L, int hasWhite, float whiteL) {
    float16 y = L / (1.0f + L);
    if (hasWhite) y = whiteL > 0.0f ? y * (1.0f + L / (whiteL * whiteL)) : (float16)(TONEMAP_FLT_MAX);
    return select((float16)(0.0f), y, L > 0.0f);
}

/* Narkowicz 2015 ACES fit; divided through by L² above 1 so huge inputs cannot overflow. */
inline float16 Tmo_Aces(float16 L) {
    const float16 low = (L * (2.51f * L + 0.03f)) / (L * (2.43f * L + 0.59f) + 0.14f);
    const float16 t = 1.0f / L;
    const float16 high = (2.51f + 0.03f * t) / (2.43f + 0.59f * t + 0.14f * t * t);
    return select((float16)(0.0f), select(high, low, L <= 1.0f), L > 0.0f);
}

/* Hable's Uncharted 2 curve (A..F as published), exposure bias 2, white point W = 11.2. */
inline float16 Tmo_HableCurve(float16 x) {
    const float A = 0.15f, B = 0.50f, C = 0.10f, D = 0.20f, E = 0.02f, F = 0.30f;
    const float16 low = (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
    const float16 t = 1.0f / x;
    const float16 high = (A + C * B * t + D * E * t * t) / (A + B * t + D * F * t * t) - E / F;
    return select(high, low, x <= 1.0f);
}

inline float16 Tmo_Filmic(float16 L) {
    const float16 y = Tmo_HableCurve(2.0f * L) / Tmo_HableCurve((float16)(11.2f));
    return select((float16)(0.0f), y, L > 0.0f);
}

/* The one dispatcher over operators. */
inline float16 Tmo_Apply(const TonemapParams* p, float16 L) {
    switch (p->op) {
        case TMO_PHOTOGRAPHIC: return Tmo_Photographic(L, p->hasWhite, p->whiteL);
        case TMO_ACES: return Tmo_Aces(L);
        case TMO_FILMIC: return Tmo_Filmic(L);
        default: return (float16)(0.0f);
    }
}

/* The sRGB transfer curve (<Gamma>sRGB</Gamma>) of 16 display values in [0,1]. */
inline float16 Tonemap_Srgb16(float16 v) {
    const float16 curve = select(1.055f * pow(v, (float16)(1.0f / 2.4f)) - 0.055f, 12.92f * v, v <= 0.0031308f);
    return select(curve, (float16)(1.0f), v >= 1.0f); /* 1.055 − 0.055 is one ulp short of 1 in float */
}

/* Gamma-encoded display values: the sRGB curve, or v^(1/gamma). */
inline float16 Tonemap_GammaEncode16(float16 v, const TonemapParams* p) {
    if (p->srgb) return Tonemap_Srgb16(v);
    return pow(v, (float16)(p->invGamma));
}

/* 8-bit value of 16 display values: 255·v^(1/gamma) (or 255·sRGB(v)), floored or rounded, clamped to [0,255]. */
inline uchar16 Tonemap_Encode16(float16 v, const TonemapParams* p) {
    float16 x = 255.0f * Tonemap_GammaEncode16(v, p);
    x = p->truncate ? floor(x) : floor(x + 0.5f);
    return convert_uchar16(select((float16)(0.0f), fmin(x, 255.0f), x > 0.0f));
}

/* Parameters of every kernel here: src/shared/kernel_params.h. */
__kernel void Tonemap_Luminance(CLRT_KERNEL_PARAMS(Tonemap_Luminance)) {
    const uint gid = get_global_id(0), stride = get_global_size(0);
    float sum = 0.0f, comp = 0.0f;  /* Neumaier: sum + comp is the exact running total */
    for (uint i = gid; i < n; i += stride) {
        float y = Tonemap_Luma(rgb[3 * (size_t)i], rgb[3 * (size_t)i + 1], rgb[3 * (size_t)i + 2]);
        lum[i] = y;
        float term = log(delta + y);
        float t = sum + term;
        comp += fabs(sum) >= fabs(term) ? (sum - t) + term : (term - t) + sum;
        sum = t;
    }
    partials[gid] = (float2)(sum, comp);
}

/* Counts, among the Y whose bits under `mask` equal `prefix`, the 8-bit digit at `shift`.
 * hist (256 uints) must be zero before the launch; any local size works. */
__kernel void Tonemap_Histogram(CLRT_KERNEL_PARAMS(Tonemap_Histogram)) {
    __local uint local_hist[TONEMAP_BINS];
    const uint lid = get_local_id(0), lsize = get_local_size(0);
    for (uint b = lid; b < TONEMAP_BINS; b += lsize) local_hist[b] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    const uint stride = get_global_size(0);
    for (uint i = get_global_id(0); i < n; i += stride) {
        uint bits = as_uint(lum[i]);
        if ((bits & mask) == prefix) atomic_inc(&local_hist[(bits >> shift) & 255u]);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint b = lid; b < TONEMAP_BINS; b += lsize)
        if (local_hist[b] != 0) atomic_add(&hist[b], local_hist[b]);
}

/* The display values in [0,1] before gamma (operator, saturation, clamp) of the pixels first ..
 * first + count - 1 (count <= TONEMAP_VEC), one float16 per channel; black pixels (Y not > 0) and
 * the lanes >= count are 0. */
inline void Tonemap_Display16(__global const float* rgb, uint first, uint count, const TonemapParams* p,
                              float16 v[3]) {
    __global const float* src = rgb + 3 * (size_t)first;
    float px[3 * TONEMAP_VEC], ch[3][TONEMAP_VEC];
    if (count == TONEMAP_VEC) {
        for (int k = 0; k < 3; ++k) vstore16(vload16(k, src), k, px);
    } else {
        for (uint j = 0; j < 3 * TONEMAP_VEC; ++j) px[j] = j < 3 * count ? src[j] : 0.0f;
    }
    for (int j = 0; j < TONEMAP_VEC; ++j)
        for (int k = 0; k < 3; ++k) ch[k][j] = px[3 * j + k];
    float16 c[3];
    for (int k = 0; k < 3; ++k) { /* NaN, ±Inf and negative channels count as 0 */
        const float16 x = vload16(0, ch[k]);
        c[k] = select((float16)(0.0f), x, isfinite(x) & (x > 0.0f));
    }
    float16 Y = 0.2126f * c[0]; /* Tonemap_Luma */
    Y = Y + 0.7152f * c[1];
    Y = Y + 0.0722f * c[2];
    Y = fmin(Y, TONEMAP_FLT_MAX);
    const float16 L = fmin(Y * p->scale, TONEMAP_FLT_MAX);
    float16 Yo = Tmo_Apply(p, L);
    Yo = select((float16)(0.0f), fmin(Yo, TONEMAP_FLT_MAX), Yo >= 0.0f); /* NaN -> 0 */
    for (int k = 0; k < 3; ++k) {
        float16 x = Yo * pow(c[k] / Y, (float16)(p->saturation));
        x = select((float16)(0.0f), fmin(x, 1.0f), x > 0.0f); /* NaN -> 0 */
        v[k] = select((float16)(0.0f), x, Y > 0.0f);
    }
}

/* 8-bit output: TONEMAP_VEC pixels per work-item. */
__kernel void Tonemap_Map(CLRT_KERNEL_PARAMS(Tonemap_Map)) {
    const uint first = get_global_id(0) * TONEMAP_VEC;
    if (first >= p.numPixels) return;
    const uint count = min(p.numPixels - first, (uint)TONEMAP_VEC);
    float16 v[3];
    Tonemap_Display16(rgb, first, count, &p, v);
    uchar q[3][TONEMAP_VEC];
    for (int k = 0; k < 3; ++k) vstore16(Tonemap_Encode16(v[k], &p), 0, q[k]);
    __global uchar* o = out + 3 * (size_t)first;
    for (uint j = 0; j < count; ++j)
        for (int k = 0; k < 3; ++k) o[3 * j + k] = q[k][j];
}

/* Float output: the gamma-encoded display values in [0,1], not quantised; TONEMAP_VEC pixels per
 * work-item. */
__kernel void Tonemap_MapFloat(CLRT_KERNEL_PARAMS(Tonemap_MapFloat)) {
    const uint first = get_global_id(0) * TONEMAP_VEC;
    if (first >= p.numPixels) return;
    const uint count = min(p.numPixels - first, (uint)TONEMAP_VEC);
    float16 v[3];
    Tonemap_Display16(rgb, first, count, &p, v);
    float q[3][TONEMAP_VEC];
    for (int k = 0; k < 3; ++k) vstore16(Tonemap_GammaEncode16(v[k], &p), 0, q[k]);
    __global float* o = out + 3 * (size_t)first;
    for (uint j = 0; j < count; ++j)
        for (int k = 0; k < 3; ++k) o[3 * j + k] = q[k][j];
}

/* End of the FP_CONTRACT OFF scope (back to the OpenCL default). */
#pragma OPENCL FP_CONTRACT ON

#endif /* CLRT_TONEMAP_CL */
