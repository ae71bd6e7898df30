/* envmap.cl — environment maps on the device: the lat-long and probe mappings of SCENE_FORMAT.md,
 * their (u,v) -> solid-angle Jacobians, the bilinear radiance lookup, and sampling / pdf of the
 * piecewise-constant importance distribution built by src/flatten/env_distribution.cpp (whose host
 * functions mirror these float-for-float; see the layout and within-cell rules there). No kernels. */
#ifndef CLRT_ENVMAP_CL
#define CLRT_ENVMAP_CL

#include "../src/shared/device_types.h"
#include "common.cl"

#define CLRT_ENV_MAX_REJECTIONS 32
#define CLRT_ONE_MINUS_EPS 0.99999994f

/* Direction (unit, y up) -> (u, v). */
inline float2 EnvMap_DirToUv(int mapping, float3 d) {
    if (mapping == ENV_PROBE) {
        float s = sqrt(d.x * d.x + d.y * d.y);
        float r = Math_Atan2(s, -d.z) / CLRT_PI; /* acos(-dz), accurate near the centre and the rim */
        float x = s > 0.0f ? r * d.x / s : r, y = s > 0.0f ? r * d.y / s : 0.0f;
        return (float2)(0.5f * (x + 1.0f), 0.5f * (1.0f - y));
    }
    return (float2)(0.5f * (1.0f + Math_Atan2(d.x, -d.z) / CLRT_PI), Math_Atan2(sqrt(d.x * d.x + d.z * d.z), d.y) / CLRT_PI);
}

/* (u, v) -> unit direction; returns 0 where (u, v) carries no light (probe: outside the disc). */
inline int EnvMap_UvToDir(int mapping, float u, float v, float3* d) {
    if (mapping == ENV_PROBE) {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        float r = sqrt(x * x + y * y);
        if (!(r <= 1.0f)) return 0;
        if (r <= 0.0f) { *d = (float3)(0.0f, 0.0f, -1.0f); return 1; }
        float2 th = Math_SinCos2Pi(0.5f * r); /* θ = π·r */
        *d = (float3)(th.y * x / r, th.y * y / r, -th.x);
        return 1;
    }
    /* φ = π(2u − 1) = 2πu − π: sin φ = −sin 2πu, cos φ = −cos 2πu; θ = π·v */
    float2 ph = Math_SinCos2Pi(u), th = Math_SinCos2Pi(0.5f * v);
    *d = (float3)(-th.y * ph.y, th.x, th.y * ph.x);
    return 1;
}

/* pdf over solid angle = pdf over (u, v) times this; 0 where degenerate. */
inline float EnvMap_UvToSolidAngle(int mapping, float u, float v) {
    if (mapping == ENV_PROBE) {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        float r = sqrt(x * x + y * y);
        if (!(r <= 1.0f)) return 0.0f;
        if (r < 1e-6f) return 1.0f / (4.0f * CLRT_PI * CLRT_PI);
        float s = Math_SinCos2Pi(0.5f * r).y;
        return s > 0.0f ? r / (4.0f * CLRT_PI * s) : 0.0f;
    }
    float s = Math_SinCos2Pi(0.5f * v).y;
    return s > 0.0f ? 1.0f / (2.0f * CLRT_PI * CLRT_PI * s) : 0.0f;
}

/* The rgb of a half4 texel (bits: r | g << 16, b | a << 16, as the host packs them), exactly: sign, exponent
 * and mantissa moved into a float's, subnormals (and zero) as mantissa · 2^-24 (the packer stores finite
 * halves only). EnvMap_Lookup's fallback where vload_half4 is not declared (clang's OpenCL header for nvptx,
 * scripts/gpu_compile_check.sh); on the CPU vload_half4 (one instruction) is 8% faster on the sphere scene.
 * Tested against vload_half4 on every finite half (tests/test_lights.cpp). */
inline float3 Env_HalfRgb(uint2 bits) {
    const uint3 h = (uint3)(bits.x & 0xffffu, bits.x >> 16, bits.y & 0xffffu);
    const uint3 sign = (h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    const uint3 normal = sign | ((e + 112u) << 23) | (m << 13);
    const uint3 small = sign | as_uint3(convert_float3(m) * 0x1p-24f);
    return as_float3(select(normal, small, e == (uint3)(0u)));
}

/* Bilinear, texel centres at ((i+0.5)/W, (j+0.5)/H); lat-long wraps in u, rows and probe columns clamp.
 * In two halves: the four texels' indices and the weights (EnvMap_Footprint: arithmetic only), then their
 * loads and the blend (EnvMap_Blend), so that callers with several lookups to make (the lanes) can find
 * every footprint before the first load. */
typedef struct {
    int i00, i10, i01, i11; /* texel indices in the image: (x0, y0), (x1, y0), (x0, y1), (x1, y1) */
    float dx, dy;
} EnvTexels;

inline EnvTexels EnvMap_Footprint(ImageInfo img, int mapping, float u, float v) {
    int w = img.width, h = img.height;
    float px = u * (float)w - 0.5f, py = v * (float)h - 0.5f;
    float fx = floor(px), fy = floor(py);
    int x0 = (int)fx, y0 = (int)fy, x1 = x0 + 1, y1 = y0 + 1;
    if (mapping == ENV_LATLONG) {
        if (x0 >= -1 && x0 < w) { /* u in [0, 1]: one wrap step; the integer division (%) was a long stall on the address */
            if (x0 < 0) x0 = w - 1;
            if (x1 >= w) x1 = 0;
        } else {
            x0 %= w; if (x0 < 0) x0 += w;
            x1 %= w; if (x1 < 0) x1 += w;
        }
    } else {
        x0 = clamp(x0, 0, w - 1); x1 = clamp(x1, 0, w - 1);
    }
    y0 = clamp(y0, 0, h - 1); y1 = clamp(y1, 0, h - 1);
    EnvTexels f;
    f.i00 = y0 * w + x0; f.i10 = y0 * w + x1; f.i01 = y1 * w + x0; f.i11 = y1 * w + x1;
    f.dx = px - fx;
    f.dy = py - fy;
    return f;
}

/* Texels float4 or half4 (img.format): a half converts to its float exactly, so the result is the same. */
inline float3 EnvMap_Blend(const __global float4* texels, ImageInfo img, EnvTexels f) {
    const __global float4* t = texels + img.offset;
    float3 c00, c10, c01, c11;
    if (img.format == TEXELS_HALF4) { /* the same values in half the bytes: fewer cache misses */
#ifdef __NVPTX__
        const __global uint2* th = (const __global uint2*)t;
        c00 = Env_HalfRgb(th[f.i00]); c10 = Env_HalfRgb(th[f.i10]);
        c01 = Env_HalfRgb(th[f.i01]); c11 = Env_HalfRgb(th[f.i11]);
#else
        const __global half* th = (const __global half*)t;
        c00 = vload_half4(f.i00, th).xyz; c10 = vload_half4(f.i10, th).xyz;
        c01 = vload_half4(f.i01, th).xyz; c11 = vload_half4(f.i11, th).xyz;
#endif
    } else {
        c00 = t[f.i00].xyz; c10 = t[f.i10].xyz;
        c01 = t[f.i01].xyz; c11 = t[f.i11].xyz;
    }
    const float dx = f.dx, dy = f.dy;
    return c00 * ((1.0f - dx) * (1.0f - dy)) + c10 * (dx * (1.0f - dy)) + c01 * ((1.0f - dx) * dy) + c11 * (dx * dy);
}

inline float3 EnvMap_Lookup(const __global float4* texels, ImageInfo img, int mapping, float u, float v) {
    return EnvMap_Blend(texels, img, EnvMap_Footprint(img, mapping, u, v));
}

/* Radiance of the map in direction d (unit), times `scale`. */
inline float3 EnvMap_Radiance(const __global float4* texels, ImageInfo img, int mapping, float3 scale, float3 d) {
    float2 uv = EnvMap_DirToUv(mapping, d);
    return EnvMap_Lookup(texels, img, mapping, uv.x, uv.y) * scale;
}

/* Extra uniforms for rejection retries: the k-th pair derived from (u1, u2) (host: envRetryUniforms). */
inline float2 Env_RetryUniforms(float u1, float u2, uint k) {
    uint h1 = Rng_Hash(as_uint(u1) ^ Rng_Hash(as_uint(u2) + 0x632be5abu * (k + 1u)));
    uint h2 = Rng_Hash(h1 ^ 0x9e3779b9u);
    return (float2)((float)(h1 >> 8) * (1.0f / 16777216.0f), (float)(h2 >> 8) * (1.0f / 16777216.0f));
}

/* How many of cdf[0 .. n-1] are <= x: eight at a time, one vector comparison each, then one at a time. */
inline int EnvDist_CountAtMost(const __global float* cdf, int n, float x) {
    int8 below = (int8)(0); /* -1 per lane where cdf <= x */
    int k = 0;
    for (; k + 8 <= n; k += 8) below += islessequal(vload8(0, cdf + k), (float8)(x));
    const int4 b4 = below.lo + below.hi;
    int count = -(b4.x + b4.y + b4.z + b4.w);
    for (; k < n; ++k) count += cdf[k] <= x;
    return count;
}

/* Largest k in [0, n-1] with cdf[k] <= x (cdf[0] = 0 <= x < cdf[n] = 1; 0 for a NaN x). Up to 256 entries (the
 * cosine tables' rows, CDFs of at most 129 values, and the texels of a cell up to 16 × 16) by counting the
 * entries <= x (the CDF does not decrease): no branch on the data, every load independent of the others; TT
 * render 0.89× (PoCL) and 0.92–0.94× (Intel) the time of the binary search, images identical
 * (docs/studies/2026-12-06-env-search-scan.md). Longer ones (a map's own distribution) by a binary search of
 * ceil(log2 n) steps. Its `?:` is a select in the source, but on x86 LLVM turns it back into a branch (PoCL
 * 3.1: a jump on the comparison of the loaded cdf); a truly branch-free step (sign bit of x - cdf as a shift)
 * was slower on the TT, the mispredicted branch letting the next probe's load start early
 * (docs/studies/2026-12-04-time-per-sample-candidates.md). */
inline int EnvDist_FindInterval(const __global float* cdf, int n, float x) {
    if (n <= 256) return max(EnvDist_CountAtMost(cdf, n, x) - 1, 0);
    int lo = 0;
    for (int len = n; len > 1;) {
        const int step = len / 2;
        lo = cdf[lo + step] <= x ? lo + step : lo;
        len -= step;
    }
    return lo;
}

/* pdf over solid angle at map coordinates uv in cell (i, j) of `dist`, which was drawn with probability p
 * (lat-long: uniform in solid angle within a cell; probe: uniform in (u, v) over the cell's part inside the
 * disc). */
inline float EnvDist_CellPdf(const __global float* dist, int i, int j, float p, float2 uv) {
    const int W = (int)dist[0], H = (int)dist[1], mapping = (int)dist[2];
    if (mapping == ENV_LATLONG) {
        const __global float* z = dist + 4 + H + 1 + H * (W + 1) + W * H;
        float omega = 2.0f * CLRT_PI / (float)W * (z[j] - z[j + 1]);
        return omega > 0.0f ? p / omega : 0.0f;
    }
    float f = dist[4 + H + 1 + H * (W + 1) + j * W + i];
    return f > 0.0f ? p * (float)W * (float)H / f * EnvMap_UvToSolidAngle(mapping, uv.x, uv.y) : 0.0f;
}

/* pdf over solid angle of the unit direction with map coordinates uv. */
inline float EnvDist_PdfUv(const __global float* dist, float2 uv) {
    int W = (int)dist[0], H = (int)dist[1];
    int i = clamp((int)(uv.x * (float)W), 0, W - 1), j = clamp((int)(uv.y * (float)H), 0, H - 1);
    const __global float* marg = dist + 4;
    const __global float* cond = dist + 4 + H + 1 + j * (W + 1);
    return EnvDist_CellPdf(dist, i, j, (marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]), uv);
}

/* Within cell (i, j) of `dist`, drawn with probability p: the direction from the uniforms du, dv in [0, 1)
 * (lat-long: u uniform, cos θ uniform between the row's bounds; probe: uniform in (u, v), retried inside
 * the disc with uniforms derived from the sample's u1, u2), its solid-angle pdf and map coordinates;
 * returns 0 where none. */
inline int EnvDist_CellSample(const __global float* dist, int i, int j, float du, float dv, float p, float u1, float u2,
                              float3* dir, float* pdf, float2* uvOut) {
    const int W = (int)dist[0], H = (int)dist[1], mapping = (int)dist[2];
    *pdf = 0.0f;
    if (mapping == ENV_LATLONG) { /* cos θ uniform between the row's bounds */
        const __global float* zr = dist + 4 + H + 1 + H * (W + 1) + W * H;
        float z = zr[j] - dv * (zr[j] - zr[j + 1]);
        float st = sqrt(fmax(0.0f, 1.0f - z * z));
        float2 ph = Math_SinCos2Pi(((float)i + du) / (float)W); /* φ = 2πu − π, as in EnvMap_UvToDir */
        *dir = (float3)(-st * ph.y, z, st * ph.x);
        *uvOut = (float2)(((float)i + du) / (float)W, Math_Atan2(st, z) * CLRT_INV_PI); /* acos(z) */
        float omega = 2.0f * CLRT_PI / (float)W * (zr[j] - zr[j + 1]);
        *pdf = omega > 0.0f ? p / omega : 0.0f;
        return *pdf > 0.0f && isfinite(*pdf);
    }
    float u = ((float)i + du) / (float)W, v = ((float)j + dv) / (float)H;
    {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        int inside = x * x + y * y <= 1.0f;
        for (int k = 0; !inside && k < CLRT_ENV_MAX_REJECTIONS; ++k) {
            float2 r = Env_RetryUniforms(u1, u2, (uint)k);
            u = ((float)i + r.x) / (float)W;
            v = ((float)j + r.y) / (float)H;
            x = 2.0f * u - 1.0f;
            y = 1.0f - 2.0f * v;
            inside = x * x + y * y <= 1.0f;
        }
        if (!inside) return 0;
    }
    if (!EnvMap_UvToDir(mapping, u, v, dir)) return 0;
    *uvOut = (float2)(u, v);
    float f = dist[4 + H + 1 + H * (W + 1) + j * W + i];
    float pUv = f > 0.0f ? p * (float)W * (float)H / f : 0.0f;
    *pdf = pUv * EnvMap_UvToSolidAngle(mapping, u, v);
    return *pdf > 0.0f && isfinite(*pdf);
}

/* Importance sample: returns 1 and the direction, its solid-angle pdf and its map coordinates (for
 * the radiance lookup, sparing the direction -> (u, v) round trip), or 0 (no direction). */
inline int EnvDist_SampleUv(const __global float* dist, float u1, float u2, float3* dir, float* pdf, float2* uvOut) {
    const int W = (int)dist[0], H = (int)dist[1];
    const __global float* marg = dist + 4;
    int j = EnvDist_FindInterval(marg, H, u2);
    float dv = fmin((u2 - marg[j]) / (marg[j + 1] - marg[j]), CLRT_ONE_MINUS_EPS);
    const __global float* cond = dist + 4 + H + 1 + j * (W + 1);
    int i = EnvDist_FindInterval(cond, W, u1);
    float du = fmin((u1 - cond[i]) / (cond[i + 1] - cond[i]), CLRT_ONE_MINUS_EPS);
    float p = (marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]);
    return EnvDist_CellSample(dist, i, j, du, dv, p, u1, u2, dir, pdf, uvOut);
}
inline int EnvDist_Sample(const __global float* dist, float u1, float u2, float3* dir, float* pdf) {
    float2 uv;
    return EnvDist_SampleUv(dist, u1, u2, dir, pdf, &uv);
}

/* ---- Cosine-weighted light sampling (the mis env strategy; layout and rules: src/flatten/env_distribution.h,
 * EnvCosineTable, whose sample and pdf mirror these) ---------------------------------------------------
 * The bucket of (world) shading normal n in table `tab`: its cell of the octahedral k × k grid (y up), or
 * -1 where n is 0 or not finite (the map's own distribution is used then). */
inline int EnvCos_Bucket(const __global float* tab, float3 n) {
    const float l1 = fabs(n.x) + fabs(n.y) + fabs(n.z);
    if (!(l1 > 0.0f) || !isfinite(l1)) return -1;
    const int k = (int)tab[0];
    float a = n.x / l1, b = n.z / l1;
    if (n.y < 0.0f) { /* the lower hemisphere, folded out to the square's corners */
        const float a2 = (1.0f - fabs(b)) * (a < 0.0f ? -1.0f : 1.0f);
        b = (1.0f - fabs(a)) * (b < 0.0f ? -1.0f : 1.0f);
        a = a2;
    }
    const int i = clamp((int)((a + 1.0f) * 0.5f * (float)k), 0, k - 1);
    const int j = clamp((int)((b + 1.0f) * 0.5f * (float)k), 0, k - 1);
    return j * k + i;
}

/* The first texel of cell c of `cells` over `texels`, and the cell holding texel t (floor divisions, as the
 * host's). In 32 bits where the products fit (cells <= kEnvCosineCellsU = 128, so any map under 2^23 texels
 * wide: c·texels and (t + 1)·cells < 2^30), else in 64: the lanes' TT 0.983× [0.960–1.000] (PoCL, 7 rounds),
 * 0.989× (Intel), images identical. */
inline int EnvCos_CellStart(int c, int texels, int cells) {
    return texels < (1 << 23) ? (int)(((uint)c * (uint)texels) / (uint)cells) : (int)(((long)c * texels) / cells);
}
inline int EnvCos_CellOf(int t, int texels, int cells) {
    return texels < (1 << 23) ? (int)(((uint)(t + 1) * (uint)cells - 1u) / (uint)texels)
                              : (int)(((long)(t + 1) * cells - 1) / texels);
}

/* A sample of bucket b in three steps, each a few dependent loads (the lanes run each step for four
 * shading points in turn, so that their loads overlap: lights.cl EnvMis_*, lanes.cl): the cell's row J by
 * the bucket's marginal CDF (EnvCos_PickRow), its column I by the row's CDF (EnvCos_PickColumn), then a
 * texel of the cell by its share (EnvCos_PickTexel); the point within the texel is placed as the map's
 * distribution `own` places it (EnvDist_CellSample). du, dv: the uniforms' remainders within the cell; p: the cell's probability. */
typedef struct {
    int I, J;
    float du, dv, p;
} EnvCosCell;

inline void EnvCos_PickRow(const __global float* tab, int b, float u2, EnvCosCell* c) {
    const int Hc = (int)tab[2];
    const __global float* marg = tab + 8 + b * (int)tab[3];
    c->J = EnvDist_FindInterval(marg, Hc, u2);
    c->dv = fmin((u2 - marg[c->J]) / (marg[c->J + 1] - marg[c->J]), CLRT_ONE_MINUS_EPS);
    c->p = marg[c->J + 1] - marg[c->J];
}

inline void EnvCos_PickColumn(const __global float* tab, int b, float u1, EnvCosCell* c) {
    const int Wc = (int)tab[1], Hc = (int)tab[2];
    const __global float* cond = tab + 8 + b * (int)tab[3] + Hc + 1 + c->J * (Wc + 1);
    c->I = EnvDist_FindInterval(cond, Wc, u1);
    c->du = fmin((u1 - cond[c->I]) / (cond[c->I + 1] - cond[c->I]), CLRT_ONE_MINUS_EPS);
    c->p *= cond[c->I + 1] - cond[c->I];
}

/* The texel of cell c (the map's own cell (I, J) = the texel, du its column remainder, p its probability). */
inline EnvCosCell EnvCos_PickTexel(const __global float* own, const __global float* tab, EnvCosCell c) {
    const int W = (int)own[0], H = (int)own[1], Wc = (int)tab[1], Hc = (int)tab[2];
    const int x0 = EnvCos_CellStart(c.I, W, Wc), y0 = EnvCos_CellStart(c.J, H, Hc), y1 = EnvCos_CellStart(c.J + 1, H, Hc);
    const int w = EnvCos_CellStart(c.I + 1, W, Wc) - x0, n = w * (y1 - y0);
    const __global float* fine = tab + (int)tab[4] + y0 * W + x0 * (y1 - y0);
    const int k = EnvDist_FindInterval(fine, n, c.du);
    const float share = (k + 1 < n ? fine[k + 1] : 1.0f) - fine[k];
    EnvCosCell t;
    t.I = x0 + k % w;
    t.J = y0 + k / w;
    t.du = fmin((c.du - fine[k]) / share, CLRT_ONE_MINUS_EPS);
    t.dv = c.dv;
    t.p = c.p * share;
    return t;
}

/* Sample of bucket b (the three steps above, then EnvDist_CellSample in the texel); returns 0 where none. */
inline int EnvCos_SampleUv(const __global float* own, const __global float* tab, int b, float u1, float u2, float3* dir,
                           float* pdf, float2* uvOut) {
    EnvCosCell c;
    EnvCos_PickRow(tab, b, u2, &c);
    EnvCos_PickColumn(tab, b, u1, &c);
    const EnvCosCell t = EnvCos_PickTexel(own, tab, c);
    return EnvDist_CellSample(own, t.I, t.J, t.du, t.dv, t.p, u1, u2, dir, pdf, uvOut);
}

/* pdf over solid angle of bucket b at map coordinates uv. */
inline float EnvCos_PdfUv(const __global float* own, const __global float* tab, int b, float2 uv) {
    const int W = (int)own[0], H = (int)own[1], Wc = (int)tab[1], Hc = (int)tab[2];
    const int x = clamp((int)(uv.x * (float)W), 0, W - 1), y = clamp((int)(uv.y * (float)H), 0, H - 1);
    const int I = EnvCos_CellOf(x, W, Wc), J = EnvCos_CellOf(y, H, Hc);
    const __global float* marg = tab + 8 + b * (int)tab[3];
    const __global float* cond = marg + Hc + 1 + J * (Wc + 1);
    const int x0 = EnvCos_CellStart(I, W, Wc), y0 = EnvCos_CellStart(J, H, Hc), y1 = EnvCos_CellStart(J + 1, H, Hc);
    const int w = EnvCos_CellStart(I + 1, W, Wc) - x0, n = w * (y1 - y0), k = (y - y0) * w + (x - x0);
    const __global float* fine = tab + (int)tab[4] + y0 * W + x0 * (y1 - y0);
    const float share = (k + 1 < n ? fine[k + 1] : 1.0f) - fine[k];
    return EnvDist_CellPdf(own, x, y, (marg[J + 1] - marg[J]) * (cond[I + 1] - cond[I]) * share, uv);
}

#endif /* CLRT_ENVMAP_CL */
