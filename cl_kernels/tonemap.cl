/* tonemap.cl — tone mapping of a float RGB image (3 floats per pixel, row-major) to 8-bit RGB.
 * Three kernels, driven by src/render/tonemap_device.cpp:
 *   Tonemap_Luminance: Y per pixel, and per work-item compensated (Neumaier) partial sums of
 *                      log(δ + Y) that the host adds up in double;
 *   Tonemap_Histogram: one radix-select pass (256 bins of 8 bits of the float bit pattern, among the
 *                      values whose higher bits equal a prefix); four passes find the k-th smallest Y
 *                      exactly (non-negative floats order like their bit patterns);
 *   Tonemap_Map:       the operator (one switch, Tmo_Apply), saturation, clamp, gamma, quantisation;
 *   Tonemap_MapFloat:  the same without the quantisation (float display values, for inspection).
 * Same formulas, in the same float operation order, as the host reference src/image/tonemap.cpp. */
#pragma OPENCL FP_CONTRACT OFF

#define TONEMAP_BINS 256
#define TONEMAP_FLT_MAX 3.402823466e+38f

/* NaN, ±Inf and negative channels count as 0. */
inline float Tonemap_Sanitize(float c) { return (isfinite(c) && c > 0.0f) ? c : 0.0f; }

inline float Tonemap_Luma(float r, float g, float b) {
    float y = 0.2126f * Tonemap_Sanitize(r);
    y = y + 0.7152f * Tonemap_Sanitize(g);
    y = y + 0.0722f * Tonemap_Sanitize(b);
    return fmin(y, TONEMAP_FLT_MAX);
}

/* Reinhard et al. 2002 (global): L/(1+L), or L(1 + L/Lw²)/(1+L) with a white point. */
inline float Tmo_Photographic(float L, int hasWhite, float whiteL) {
    if (!(L > 0.0f)) return 0.0f;
    float a = L / (1.0f + L);
    if (!hasWhite) return a;
    if (!(whiteL > 0.0f)) return TONEMAP_FLT_MAX;
    float b = 1.0f + L / (whiteL * whiteL);
    return a * b;
}

/* Narkowicz 2015 ACES fit; divided through by L² above 1 so huge inputs cannot overflow. */
inline float Tmo_Aces(float L) {
    if (!(L > 0.0f)) return 0.0f;
    if (L <= 1.0f) return (L * (2.51f * L + 0.03f)) / (L * (2.43f * L + 0.59f) + 0.14f);
    float t = 1.0f / L;
    return (2.51f + 0.03f * t) / (2.43f + 0.59f * t + 0.14f * t * t);
}

/* Hable's Uncharted 2 curve (A..F as published), exposure bias 2, white point W = 11.2. */
inline float Tmo_HableCurve(float x) {
    const float A = 0.15f, B = 0.50f, C = 0.10f, D = 0.20f, E = 0.02f, F = 0.30f;
    if (x <= 1.0f) return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
    float t = 1.0f / x;
    return (A + C * B * t + D * E * t * t) / (A + B * t + D * F * t * t) - E / F;
}

inline float Tmo_Filmic(float L) {
    if (!(L > 0.0f)) return 0.0f;
    return Tmo_HableCurve(2.0f * L) / Tmo_HableCurve(11.2f);
}

/* The one dispatcher over operators. */
inline float Tmo_Apply(const TonemapParams* p, float L) {
    switch (p->op) {
        case 0: return Tmo_Photographic(L, p->hasWhite, p->whiteL);
        case 1: return Tmo_Aces(L);
        case 2: return Tmo_Filmic(L);
        default: return 0.0f;
    }
}

inline uchar Tonemap_Encode(float v, const TonemapParams* p) {
    float x = 255.0f * pow(v, p->invGamma);
    x = p->truncate ? floor(x) : floor(x + 0.5f);
    return (uchar)(x > 0.0f ? fmin(x, 255.0f) : 0.0f);
}

__kernel void Tonemap_Luminance(__global const float* rgb, uint n, float delta,
                                __global float* lum, __global float2* partials) {
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
__kernel void Tonemap_Histogram(__global const float* lum, uint n, uint prefix, uint mask, uint shift,
                                __global uint* hist) {
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

/* The display value of one pixel in [0,1] before gamma (operator, saturation, clamp). */
inline float3 Tonemap_Display(__global const float* rgb, size_t base, const TonemapParams* p) {
    float c[3];
    for (int k = 0; k < 3; ++k) c[k] = Tonemap_Sanitize(rgb[base + k]);
    const float Y = Tonemap_Luma(c[0], c[1], c[2]);
    if (!(Y > 0.0f)) return (float3)(0.0f);
    const float L = fmin(Y * p->scale, TONEMAP_FLT_MAX);
    float Yo = Tmo_Apply(p, L);
    Yo = Yo >= 0.0f ? fmin(Yo, TONEMAP_FLT_MAX) : 0.0f;
    float v[3];
    for (int k = 0; k < 3; ++k) {
        v[k] = Yo * pow(c[k] / Y, p->saturation);
        v[k] = v[k] > 0.0f ? fmin(v[k], 1.0f) : 0.0f;
    }
    return (float3)(v[0], v[1], v[2]);
}

/* 8-bit output. */
__kernel void Tonemap_Map(__global const float* rgb, TonemapParams p, __global uchar* out) {
    const uint i = get_global_id(0);
    if (i >= p.numPixels) return;
    const size_t base = 3 * (size_t)i;
    const float3 v = Tonemap_Display(rgb, base, &p);
    out[base + 0] = Tonemap_Encode(v.x, &p);
    out[base + 1] = Tonemap_Encode(v.y, &p);
    out[base + 2] = Tonemap_Encode(v.z, &p);
}

/* Float output: the gamma-encoded display values in [0,1], not quantised. */
__kernel void Tonemap_MapFloat(__global const float* rgb, TonemapParams p, __global float* out) {
    const uint i = get_global_id(0);
    if (i >= p.numPixels) return;
    const size_t base = 3 * (size_t)i;
    const float3 v = Tonemap_Display(rgb, base, &p);
    out[base + 0] = pow(v.x, p.invGamma);
    out[base + 1] = pow(v.y, p.invGamma);
    out[base + 2] = pow(v.z, p.invGamma);
}
