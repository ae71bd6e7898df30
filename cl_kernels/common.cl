/* common.cl — math helpers, the counter-based random number generator, sampling warps and the
 * robust ray-origin offset shared by every kernel. No kernels here. */
#ifndef CLRT_COMMON_CL
#define CLRT_COMMON_CL

#include "../src/shared/device_types.h"

#define CLRT_PI 3.14159265358979323846f
#define CLRT_INV_PI 0.31830988618379067154f

/* ---- Device quirks ---------------------------------------------------------------------------
 * The one place where the kernels read the CLRT_QUIRK_<NAME> defines that the host gives a device's
 * programs (the table in src/cl/quirks.cpp; docs/quirks.md has each defect and its reproducer). Code
 * elsewhere uses the macros defined here, never a vendor name.
 * CLRT_QUIRK_INTEL_VEC_HINT (Intel's CPU runtime): its implicit work-item vectoriser miscompiles
 * shade_hits (issue 17; scripts/intel_vectorizer_repro.sh, tests/intel_repro/shade_hits_alone.cpp) and
 * slows render_fused 2.1x; vec_type_hint(float4) on those kernels keeps it from vectorising them. Other
 * implementations ignore the hint (it only describes the kernel's data), so it is left out there. */
#ifdef CLRT_QUIRK_INTEL_VEC_HINT
#define CLRT_KERNEL_VEC_HINT __attribute__((vec_type_hint(float4)))
#else
#define CLRT_KERNEL_VEC_HINT
#endif
/* CLRT_QUIRK_BIT_REVERSE_TABLE (Oclgrind): LLVM turns Bits_Reverse's shift-and-mask network into the
 * llvm.bitreverse intrinsic, which Oclgrind cannot run ("Undefined external function"); there the bits
 * are reversed by a table of reversed bytes, the same values. */
#ifdef CLRT_QUIRK_BIT_REVERSE_TABLE
#define CLRT_BITS_REVERSE_BY_TABLE 1
#endif

inline float4 f4(float3 v, float w) { return (float4)(v, w); }
inline float maxComponent(float3 v) { return fmax(v.x, fmax(v.y, v.z)); }
inline int allFinite3(float3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* Orthonormal basis around unit n (Duff et al. 2017, branchless). */
inline void makeBasis(float3 n, float3* t, float3* b) {
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = (float3)(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = (float3)(c, sign + n.y * n.y * a, -n.y);
}

/* The course's (Shirley's) orthonormal basis across unit r: t = r with its smallest-magnitude component set
 * to 1, u = unit(t × r), v = r × u. Unlike makeBasis it is not continuous in r, and a square of offsets
 * spanned by it turns with r: the glossy perturbation's square (Glossy_Perturb) must be this one to match
 * the course's references (2025 hw3 cornellbox_brushed_metal, roughness 5: see docs/scene-format.md). */
inline void courseBasis(float3 r, float3* u, float3* v) {
    float3 t = r;
    const float ax = fabs(r.x), ay = fabs(r.y), az = fabs(r.z);
    if (ax <= ay && ax <= az) t.x = 1.0f;
    else if (ay <= az) t.y = 1.0f;
    else t.z = 1.0f;
    *u = normalize(cross(t, r));
    *v = cross(r, *u);
}

/* ---- Random numbers --------------------------------------------------------------------------
 * Counter-based: every number is a pure function of (seed, pixel, sample, pathId, dimension), so an
 * image does not depend on how work is split over batches or devices. PCG-style 32-bit hash. */
inline uint Rng_Hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

/* key: the stream of (seed, pixel, sample, path id), for Rng_Uniform; strat: of (seed, pixel, path id)
 * alone, shared by the pixel's samples, for Rng_Stratified2D. */
typedef struct { uint key; uint strat; } RngKey;

inline RngKey Rng_Key(uint seed, int pixel, int sample, uint pathId) {
    RngKey k;
    uint h = Rng_Hash(seed ^ 0x9e3779b9u);
    h = Rng_Hash(h ^ (uint)pixel);
    k.strat = Rng_Hash(h ^ pathId * 0x27d4eb2fu);
    h = Rng_Hash(h ^ (uint)sample * 0x85ebca6bu);
    h = Rng_Hash(h ^ pathId * 0xc2b2ae35u);
    k.key = h;
    return k;
}

/* Uniform float in [0,1) for dimension `dim` of the stream. */
inline float Rng_Uniform(RngKey k, uint dim) {
    uint h = Rng_Hash(k.key ^ Rng_Hash(dim + 0x68e31da4u));
    return (float)(h >> 8) * (1.0f / 16777216.0f);
}

/* ---- Stratified 2D samples (CLRT_PIXEL_SAMPLER_STRATIFIED) --------------------------------------------
 * Sample s of a pixel takes point idx of the (0,2)-sequence (radical inverse, Sobol's second
 * dimension), Owen-scrambled, where idx is s shuffled by an Owen scramble of its bits (Burley 2020,
 * "Practical Hash-based Owen Scrambling", JCGT 9(4)). The shuffle and both scrambles are hashed from
 * (seed, pixel, path id, dimension pair) — not from s — so every pixel and every pair of dimensions
 * has its own randomisation ("padding": pairs are independent of each other, the camera jitter included)
 * while the samples of one pixel share it: any 2^m consecutive samples from a multiple of 2^m form a
 * (0,m,2)-net, one point in each elementary interval of area 2^-m. Each point alone is uniform, so
 * every estimate stays unbiased. Host replica: tests/test_sampler.cpp. */

/* Bit reversal: the shift-and-mask network (LLVM makes it llvm.bitreverse: a few instructions on x86, one
 * on GPUs), or under CLRT_BITS_REVERSE_BY_TABLE (quirk BIT_REVERSE_TABLE) a table of reversed bytes. The
 * network was 1.5-3% faster than the table on the CPU (hw6 box, TT; docs/quirks.md). */
#define CLRT_REV2_(n) n, n + 2 * 64, n + 1 * 64, n + 3 * 64
#define CLRT_REV4_(n) CLRT_REV2_(n), CLRT_REV2_(n + 2 * 16), CLRT_REV2_(n + 1 * 16), CLRT_REV2_(n + 3 * 16)
#define CLRT_REV6_(n) CLRT_REV4_(n), CLRT_REV4_(n + 2 * 4), CLRT_REV4_(n + 1 * 4), CLRT_REV4_(n + 3 * 4)
#ifdef CLRT_BITS_REVERSE_BY_TABLE
__constant uchar kBitsReversedByte[256] = {CLRT_REV6_(0), CLRT_REV6_(2), CLRT_REV6_(1), CLRT_REV6_(3)};
#endif

/* The bodies of the three bit functions below, as statements on a variable of type uint or uintN:
 * lanes.cl's lane forms (LaneBits_*) run the same operations on uint4. */
#define CLRT_BITS_REVERSE_NETWORK(v)                                                               \
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);                                      \
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);                                      \
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);                                      \
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);                                      \
    v = (v >> 16) | (v << 16)
#define CLRT_LAINE_KARRAS(x, seed)                                                                 \
    x += seed;                                                                                     \
    x ^= x * 0x6c50b47cu;                                                                          \
    x ^= x * 0xb82f1e52u;                                                                          \
    x ^= x * 0xc7afe638u;                                                                          \
    x ^= x * 0x8d22f6e6u
#define CLRT_SOBOL_DIM1_REVERSED(i)                                                                \
    i ^= (i >> 1) & 0x55555555u;                                                                   \
    i ^= (i >> 2) & 0x33333333u;                                                                   \
    i ^= (i >> 4) & 0x0f0f0f0fu;                                                                   \
    i ^= (i >> 8) & 0x00ff00ffu;                                                                   \
    i ^= (i >> 16) & 0x0000ffffu

inline uint Bits_Reverse(uint v) {
#ifdef CLRT_BITS_REVERSE_BY_TABLE
    return ((uint)kBitsReversedByte[v & 0xffu] << 24) | ((uint)kBitsReversedByte[(v >> 8) & 0xffu] << 16) |
           ((uint)kBitsReversedByte[(v >> 16) & 0xffu] << 8) | (uint)kBitsReversedByte[v >> 24];
#else
    CLRT_BITS_REVERSE_NETWORK(v);
    return v;
#endif
}

/* Laine and Karras' hash: each output bit depends on that bit and the ones below it only, so on
 * bit-reversed digits it is a nested uniform (Owen) scramble. Constants from Burley 2020. */
inline uint Bits_LaineKarras(uint x, uint seed) {
    CLRT_LAINE_KARRAS(x, seed);
    return x;
}

/* Sobol's second dimension of index i, bit-reversed: the XOR of rows k of Pascal's triangle mod 2
 * over the set bits k of i, i.e. bit j is the parity of i's set bits k with j ⊆ k (a superset
 * transform in five steps). */
inline uint Sobol_Dim1Reversed(uint i) {
    CLRT_SOBOL_DIM1_REVERSED(i);
    return i;
}

/* The point of sample `sample` for dimensions (dim, dim + 1) of the path whose key is k
 * (Rng_Key(seed, pixel, sample, pathId): its strat part, hashed once per path). */
inline float2 Rng_Stratified2D(RngKey k, int sample, uint dim) {
    const uint sIdx = Rng_Hash(k.strat ^ dim * 0x9e3779b1u);
    const uint sX = Rng_Hash(sIdx ^ 0xa54ff53au), sY = Rng_Hash(sIdx ^ 0x510e527fu);
    const uint idx = Bits_Reverse(Bits_LaineKarras(Bits_Reverse((uint)sample), sIdx));
    const uint x = Bits_Reverse(Bits_LaineKarras(idx, sX));  /* radical inverse of idx, scrambled */
    const uint y = Bits_Reverse(Bits_LaineKarras(Sobol_Dim1Reversed(idx), sY));
    return (float2)((float)(x >> 8), (float)(y >> 8)) * (1.0f / 16777216.0f);
}

/* ---- Z-ordered Sobol samples (CLRT_PIXEL_SAMPLER_ZSOBOL) ---------------------------------------------
 * One Owen-scrambled (0,2)-sequence (Sobol's first two dimensions) for the whole image, its index laid
 * out as [pixel's Morton code | sample], after Ahmed and Wonka 2020 ("Screen-space blue-noise diffusion of
 * Monte Carlo sampling error via hierarchical ordering of pixels") as pbrt-v4's ZSobolSampler does; own
 * construction. Per dimension pair (dim, pathId, seed — not the pixel) both parts of the index are shuffled
 * by a nested top-down scramble of their bits (each bit flipped by a hash of the bits above it, Laine–
 * Karras on the reversed bits), and the point is Owen-scrambled with one seed for the whole image:
 * - a pixel's 2^L samples (L = scene.samplerLog2Spp) are the points of one aligned index block: a
 *   (0,L,2)-net, any 2^m of them from a multiple of 2^m a (0,m,2)-net, as the stratified sampler's;
 * - an aligned 2x2 (4^k) block of pixels holds an aligned index block too: together their points form
 *   a (0,L+2k,2)-net, so neighbouring pixels' errors are anti-correlated (blue noise in screen space);
 * - pairs of dimensions get independent shuffles of the sample part (padding), as with `stratified`.
 * 1D dimensions take a pair's first coordinate. Index bits above 32 (images × samples beyond 2^32) and
 * samples from 2^L on (progressive passes) select independent scrambles instead (an "epoch" hash).
 * Host replica: tests/test_sampler.cpp. */

/* The 16 low bits of v spread to the even bits. */
inline uint Bits_Spread2(uint v) {
    v &= 0x0000ffffu;
    v = (v | (v << 8)) & 0x00ff00ffu;
    v = (v | (v << 4)) & 0x0f0f0f0fu;
    v = (v | (v << 2)) & 0x33333333u;
    v = (v | (v << 1)) & 0x55555555u;
    return v;
}

/* v with each bit flipped by a hash of (seed, the bits above it): a nested uniform scramble of the
 * index, top-down, so aligned blocks of indices stay aligned blocks. */
inline uint Bits_NestedTopDown(uint v, uint seed) { return Bits_Reverse(Bits_LaineKarras(Bits_Reverse(v), seed)); }

/* The point of sample `sample` of pixel `pixel` for dimensions (dim, dim + 1) of path pathId. */
inline float2 ZSobol_2D(SceneParams scene, int pixel, int sample, uint pathId, uint dim) {
    const uint width = (uint)max(scene.samplerWidth, 1);
    const uint log2Spp = (uint)clamp(scene.samplerLog2Spp, 0, 31);
    const uint x = (uint)pixel % width, y = (uint)pixel / width;
    const uint morton = (Bits_Spread2(y) << 1) | Bits_Spread2(x);
    const uint dimSeed = Rng_Hash(Rng_Hash(scene.seed ^ 0x3c6ef372u) ^ Rng_Hash(pathId * 0x27d4eb2fu ^ Rng_Hash(dim + 0x1b873593u)));
    const uint zPixel = Bits_NestedTopDown(morton, dimSeed);
    const uint zSample = Bits_NestedTopDown((uint)sample, Rng_Hash(dimSeed ^ zPixel));
    const uint mask = (1u << log2Spp) - 1u;
    const uint idx = (log2Spp == 0u ? zPixel : zPixel << log2Spp) | (zSample & mask);
    /* what the index cannot hold: Morton bits shifted out, samples past 2^L */
    const uint epoch = Rng_Hash((log2Spp == 0u ? 0u : zPixel >> (32u - log2Spp)) ^ Rng_Hash(((uint)sample >> log2Spp) + 0x2545f491u));
    const uint sX = Rng_Hash(dimSeed ^ epoch ^ 0xa54ff53au), sY = Rng_Hash(dimSeed ^ epoch ^ 0x510e527fu);
    const uint px = Bits_Reverse(Bits_LaineKarras(idx, sX)); /* radical inverse of idx, Owen-scrambled */
    const uint py = Bits_Reverse(Bits_LaineKarras(Sobol_Dim1Reversed(idx), sY));
    return (float2)((float)(px >> 8), (float)(py >> 8)) * (1.0f / 16777216.0f);
}

/* Whether the render draws from ZSobol_2D: only programs built with CLRT_HAS_ZSOBOL (clrt render --sampler
 * zsobol) carry its branches; in the others the compiler drops them (their dead code cost the env-lit
 * sphere ~6% of its render through the inlining around Rng_Stratified2D; studies/2026-12-04-time-per-sample-s18.md). */
#ifdef CLRT_HAS_ZSOBOL
#define CLRT_SAMPLER_IS_ZSOBOL(scene) ((scene).pixelSampler == CLRT_PIXEL_SAMPLER_ZSOBOL)
#else
#define CLRT_SAMPLER_IS_ZSOBOL(scene) 0
#endif
/* Likewise CLRT_PIXEL_SAMPLER_CORRELATED's branches, only with CLRT_HAS_CORRELATED_SAMPLER (--sampler correlated). */
#ifdef CLRT_HAS_CORRELATED_SAMPLER
#define CLRT_SAMPLER_IS_CORRELATED(scene) ((scene).pixelSampler == CLRT_PIXEL_SAMPLER_CORRELATED)
#else
#define CLRT_SAMPLER_IS_CORRELATED(scene) 0
#endif

/* The 2D sample of dimensions (dim, dim + 1) at a shading point of `path` for light and BSDF samples:
 * stratified over the pixel's samples, Z-ordered Sobol or independent, by scene.pixelSampler.
 * key = Rng_Key(scene.seed, path.pixel, path.sample, path.pathId). */
inline float2 Sampler_2D(SceneParams scene, PathState path, RngKey key, uint dim) {
    if (CLRT_SAMPLER_IS_ZSOBOL(scene)) return ZSobol_2D(scene, path.pixel, path.sample, path.pathId, dim);
    if (scene.pixelSampler != CLRT_PIXEL_SAMPLER_INDEPENDENT) /* stratified, or correlated's other dimensions */
        return Rng_Stratified2D(key, path.sample, dim);
    return (float2)(Rng_Uniform(key, dim), Rng_Uniform(key, dim + 1u));
}

/* The dimensions the stratified sampler leaves independent (glossy perturbations, lobe and Fresnel
 * picks, roulette): Z-ordered Sobol under CLRT_PIXEL_SAMPLER_ZSOBOL, else independent uniforms
 * (Rng_Uniform of dim, and dim + 1 for the second coordinate). */
inline float2 Sampler_Other2D(SceneParams scene, PathState path, RngKey key, uint dim) {
    if (CLRT_SAMPLER_IS_ZSOBOL(scene)) return ZSobol_2D(scene, path.pixel, path.sample, path.pathId, dim);
    return (float2)(Rng_Uniform(key, dim), Rng_Uniform(key, dim + 1u));
}
inline float Sampler_Other1D(SceneParams scene, PathState path, RngKey key, uint dim) {
    if (CLRT_SAMPLER_IS_ZSOBOL(scene)) return ZSobol_2D(scene, path.pixel, path.sample, path.pathId, dim).x;
    return Rng_Uniform(key, dim);
}

/* The camera sample's own 2D point (stratified over the pixel's samples: dimensions 0, 1 of path id 1),
 * key = Rng_Key(seed, pixel, cameraSample, 1u). Its pixel jitter; under CLRT_PIXEL_SAMPLER_CORRELATED also
 * its lens point and the classic renderer's light samples at the camera ray's hit (Sampler_Light2D): the course's
 * renderer until 2022 drew them so, one point for all three (its 2020 and 2022 references show it: an area
 * light's glow on a box's ceiling, out-of-focus silhouettes; docs/scene-format.md).
 * That estimates another integral than the scene's (the blur and the penumbrae change shape), so it is a
 * sampler for reproducing those references, never the default. */
inline float2 Sampler_Camera2D(RngKey key, int cameraSample) { return Rng_Stratified2D(key, cameraSample, 0u); }

/* The 2D sample of the light sample at dimensions (dim, dim + 1) of `path`: Sampler_2D, or under
 * CLRT_PIXEL_SAMPLER_CORRELATED in the classic renderer at the camera ray's hit (depth 0) the camera sample's
 * own point; the light samples of reflected and refracted rays' hits are the path's own, as in the course's
 * references (hw3 cornellbox_area, the ceiling's glow in the mirror sphere; docs/scene-format.md). */
inline float2 Sampler_Light2D(SceneParams scene, PathState path, RngKey key, uint dim) {
    if (CLRT_SAMPLER_IS_CORRELATED(scene) && scene.pathMode == 0 && path.depth == 0)
        return Sampler_Camera2D(Rng_Key(scene.seed, path.pixel, path.sample, 1u), path.sample);
    return Sampler_2D(scene, path, key, dim);
}

/* ---- Motion blur ------------------------------------------------------------------------------
 * The shutter time of a camera sample, uniform in [0, 1) (the course draws one per primary ray):
 * a function of (seed, pixel, sample) alone, in a stream of its own (path id 0, which no path has),
 * so every ray of the sample (reflections, refractions, shadow rays) sees the scene at that time.
 * Rays carry it in Ray.origin.w and ShadowRay.direction.w. */
inline float MotionBlur_Time(uint seed, int pixel, int sample) {
    return Rng_Uniform(Rng_Key(seed, pixel, sample, 0u), 0u);
}
/* The same under the scene's sampler: Z-ordered Sobol (path id 0, dimension 0) or MotionBlur_Time. */
inline float Sampler_Time(SceneParams scene, int pixel, int sample) {
    if (CLRT_SAMPLER_IS_ZSOBOL(scene)) return ZSobol_2D(scene, pixel, sample, 0u, 0u).x;
    return MotionBlur_Time(scene.seed, pixel, sample);
}

/* x^e for x >= 0 (Phong lobes). exp2(e·log2 x) instead of pow(): PoCL's one-value pow() costs about
 * as much as the rest of sample_lights (TT at 1 spp: 0.36 -> 0.30 s for the kernel); the relative
 * error, ~3 ulp of log2 times e·|log2 x|, stays below 1e-5 wherever the lobe is not negligible.
 * The form on every device, not a quirk (docs/quirks.md "Not quirks"). */
inline float Math_PowNonNegative(float x, float e) {
    /* x = 0 as pow(0, e) gives it (1 for e = 0, 0 for e > 0, +inf for e < 0, NaN for a NaN e), without
     * calling pow: the compiler turned the ternary into a select that computes both sides (pow is a pure
     * function), and PoCL's pow took 12% of a Phong box's render (perf, hw6 path box). */
    const float atZero = e > 0.0f ? 0.0f : (e == 0.0f ? 1.0f : (e < 0.0f ? INFINITY : e));
    return x > 0.0f ? exp2(e * log2(x)) : atZero;
}

/* p = atan(a)/a for a in [0, 1], s = a²: Math_Atan2's fitted polynomial P(s), as statements on p (float or floatN:
 * Math_Atan2 and its lane form, lanes_math.cl Lanes_Atan2). */
#define CLRT_ATAN_POLY(p, s)          \
    p = 2.932761940e-03f;             \
    p = p * (s) - 1.641319041e-02f;   \
    p = p * (s) + 4.327824176e-02f;   \
    p = p * (s) - 7.556900204e-02f;   \
    p = p * (s) + 1.066748690e-01f;   \
    p = p * (s) - 1.421110605e-01f;   \
    p = p * (s) + 1.999369432e-01f;   \
    p = p * (s) - 3.333313797e-01f;   \
    p = p * (s) + 9.999999938e-01f

/* atan2(y, x) for finite arguments, within 3e-7 rad (about an ulp of π) of the exact value (the
 * polynomial's error is 8.7e-8 over [0, 1]; the rest is the rounding of the quadrant fix-ups): atan(a) = a·P(a²) on
 * a = min/max in [0, 1], P fitted by us (least squares on Chebyshev nodes, degree 8 in a²). PoCL's
 * atan2 made EnvMap_DirToUv most of shade_hits and much of sample_lights; spheres' (u, v) and frames use it too.
 * atan2(±0, x<0) gives +π (u = 0 or 1: the same lat-long column either way). The form on every device,
 * not a quirk (docs/quirks.md "Not quirks"). */
inline float Math_Atan2(float y, float x) {
    float ax = fabs(x), ay = fabs(y);
    float mx = fmax(ax, ay), mn = fmin(ax, ay);
    float a = mx > 0.0f ? mn / mx : 0.0f;
    float s = a * a;
    float p;
    CLRT_ATAN_POLY(p, s);
    float r = a * p;
    if (ay > ax) r = 0.5f * CLRT_PI - r;
    if (x < 0.0f) r = CLRT_PI - r;
    return y < 0.0f ? -r : r;
}

/* (cos 2πt, sin 2πt) for finite t in turns: every angle on the render path is a fraction of a turn
 * (2π·u of a sample, π·v of a map row), so the reduction is exact and needs no constants of π: r0 = t −
 * rint(t) in [−1/2, 1/2] and r = r0 − q/4 in [−1/8, 1/8] with q = rint(4·r0) are exact (Sterbenz), and the
 * quarter turns q rotate the pair. sin 2πr = r·P(r²) and cos 2πr = 1 + r²·Q(r²), fitted by us (weighted
 * least squares towards minimax relative error on Chebyshev nodes, coefficients rounded to float). Within
 * 1.7 ulp of the exact values wherever |sin|, |cos| > 1e-3 and 9e-8 absolute (tests/test_math.cpp: the
 * device against the host replica sinCos2Pi, both against long double); a non-finite t gives NaNs.
 * PoCL's sin and cos reduce every argument out of line (__pocl_argReductionS, 3-4% of render_fused on
 * the TT and the hw6 box). */
inline float2 Math_SinCos2Pi(float t) {
    const float r0 = t - rint(t);
    const float q = rint(4.0f * r0);
    const float r = r0 - 0.25f * q, r2 = r * r;
    const float s = r * (6.2831854820e+00f + r2 * (-4.1341659546e+01f + r2 * (8.1592155457e+01f + r2 * -7.5395851135e+01f)));
    const float c = 1.0f + r2 * (-1.9739208221e+01f + r2 * (6.4939331055e+01f + r2 * (-8.5444244385e+01f + r2 * 5.9263893127e+01f)));
    const int k = (int)q & 3; /* quarter turns: (c, s) rotated k times by 90 degrees */
    const float cq = (k & 1) ? -s : c, sq = (k & 1) ? c : s;
    return (k & 2) ? (float2)(-cq, -sq) : (float2)(cq, sq);
}

/* ---- Warps ------------------------------------------------------------------------------------ */
inline float3 Warp_CosineHemisphere(float u1, float u2) {
    float r = sqrt(u1);
    float2 cs = Math_SinCos2Pi(u2);
    return (float3)(r * cs.x, r * cs.y, sqrt(fmax(0.0f, 1.0f - u1)));
}

inline float3 Warp_UniformHemisphere(float u1, float u2) {
    float z = u1;
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    float2 cs = Math_SinCos2Pi(u2);
    return (float3)(r * cs.x, r * cs.y, z);
}

/* ---- Robust ray origins -----------------------------------------------------------------------
 * Moves p off the surface along the geometric normal n (unit, pointing to the side the new ray
 * leaves to) by a distance proportional to p's largest coordinate, so no scene-scale epsilon is
 * needed: a hit point (barycentric interpolation, or a sphere point re-projected onto the surface)
 * is off its surface by a few ulps of that magnitude, and the offset is CLRT_OFFSET_ULPS of them.
 * Unlike the per-component integer-ulp offset of Wächter & Binder (Ray Tracing Gems ch. 6, 256
 * ulps per component), this stays small far from the origin: at 1e5 that offset was 2 units and
 * lifted shadow rays over whole objects (light leaks); this one is 0.19 units there, 1.9e-6 at 1.
 * Near the origin an absolute floor of 2^-16 applies (as in Wächter & Binder). */
#ifndef CLRT_OFFSET_ULPS
#define CLRT_OFFSET_ULPS 16.0f
#endif
/* The robust offset distance at p (above). */
inline float Ray_OffsetDistance(float3 p) {
    const float floorOffset = 1.0f / 65536.0f;
    float m = fmax(fmax(fabs(p.x), fabs(p.y)), fabs(p.z));
    return fmax(CLRT_OFFSET_ULPS * FLT_EPSILON * m, floorOffset);
}
inline float3 Ray_OffsetOrigin(float3 p, float3 n) {
    return p + Ray_OffsetDistance(p) * n;
}

/* The origin of a classic renderer's secondary ray from p (shadow, reflection and refraction rays; ng: the
 * geometric normal on the side the ray leaves to): the scene's ShadowRayEpsilon along ng, or the robust
 * offset where that is larger (large coordinates). The course's references show the epsilon on every one
 * of them: at 1e-3, hw1 bunny's shadow terminators (points whose own neighbouring faces block a shadow ray
 * that starts closer) come out lit as in the reference, and the mirror images in 2025 hw1
 * bunny_with_plane and spheres_mirror sit where the reference's do only when reflection rays start there
 * too (34.0 -> 54.1 and 42.2 -> 52.6 dB; docs/scene-format.md, conventions). The path tracer keeps the
 * robust offset (Ray_OffsetOrigin). */
inline float3 Ray_EpsilonOrigin(float3 p, float3 ng, float shadowEpsilon) {
    return p + fmax(Ray_OffsetDistance(p), shadowEpsilon) * ng;
}

/* A ray's shutter time (0 without motion blur: the origin's w is then never read). */
inline float Ray_Time(Ray r) {
#ifdef CLRT_HAS_MOTION_BLUR
    return r.origin.w;
#else
    return 0.0f;
#endif
}

/* Replaces NaN/Inf components by 0 (radiance guard before accumulation). */
inline float3 finiteOrZero(float3 c) {
    return (float3)(isfinite(c.x) ? c.x : 0.0f, isfinite(c.y) ? c.y : 0.0f, isfinite(c.z) ? c.z : 0.0f);
}

#endif /* CLRT_COMMON_CL */
