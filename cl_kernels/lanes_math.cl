/* lanes_math.cl — what the lanes kernel (lanes.cl) computes on its four lanes at once: float4 lanes and
 * their three-vectors (LaneV3: structure of arrays), masks and their bits, the stratified sampler for the
 * four samples of a pixel (Lanes_Stratified2D, bit for bit Rng_Stratified2D), and the lane forms of
 * common.cl's and path.cl's small helpers (the same operations). Compiled under CLRT_HAS_LANES only. */
#ifndef CLRT_LANES_MATH_CL
#define CLRT_LANES_MATH_CL

#include "common.cl"
#include "path.cl"

#ifdef CLRT_HAS_LANES

#define CLRT_LANES 4
typedef float4 LaneF;
typedef int4 LaneI;  /* masks: -1 true, 0 false, as vector comparisons give them */
typedef uint4 LaneU;
typedef struct { LaneF x, y, z; } LaneV3;

inline LaneV3 LaneV3_Make(LaneF x, LaneF y, LaneF z) { LaneV3 r; r.x = x; r.y = y; r.z = z; return r; }
inline LaneV3 LaneV3_Splat(float3 v) { return LaneV3_Make((LaneF)(v.x), (LaneF)(v.y), (LaneF)(v.z)); }
inline LaneV3 LaneV3_Add(LaneV3 a, LaneV3 b) { return LaneV3_Make(a.x + b.x, a.y + b.y, a.z + b.z); }
inline LaneV3 LaneV3_Sub(LaneV3 a, LaneV3 b) { return LaneV3_Make(a.x - b.x, a.y - b.y, a.z - b.z); }
inline LaneV3 LaneV3_Scale(LaneV3 a, LaneF s) { return LaneV3_Make(a.x * s, a.y * s, a.z * s); }
inline LaneV3 LaneV3_Mul(LaneV3 a, LaneV3 b) { return LaneV3_Make(a.x * b.x, a.y * b.y, a.z * b.z); }
inline LaneF LaneV3_Dot(LaneV3 a, LaneV3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline LaneV3 LaneV3_Cross(LaneV3 a, LaneV3 b) {
    return LaneV3_Make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
inline LaneV3 LaneV3_Normalize(LaneV3 a) { return LaneV3_Scale(a, rsqrt(LaneV3_Dot(a, a))); }
inline LaneF LaneV3_Max(LaneV3 a) { return fmax(fmax(a.x, a.y), a.z); }
inline LaneI LaneV3_Finite(LaneV3 a) { return isfinite(a.x) & isfinite(a.y) & isfinite(a.z); }
inline LaneV3 LaneV3_Select(LaneV3 a, LaneV3 b, LaneI m) {
    return LaneV3_Make(select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m));
}
inline LaneV3 LaneV3_FiniteOrZero(LaneV3 a) {
    return LaneV3_Make(select((LaneF)(0.0f), a.x, isfinite(a.x)), select((LaneF)(0.0f), a.y, isfinite(a.y)),
                       select((LaneF)(0.0f), a.z, isfinite(a.z)));
}
/* Lanes to and from per-lane values (private arrays: OpenCL C has no variable component index). */
inline LaneV3 LaneV3_Load(const float3* v) {
    return LaneV3_Make((LaneF)(v[0].x, v[1].x, v[2].x, v[3].x), (LaneF)(v[0].y, v[1].y, v[2].y, v[3].y),
                       (LaneF)(v[0].z, v[1].z, v[2].z, v[3].z));
}
inline void LaneV3_Store(LaneV3 a, float3* out) {
    float x[CLRT_LANES], y[CLRT_LANES], z[CLRT_LANES];
    vstore4(a.x, 0, x); vstore4(a.y, 0, y); vstore4(a.z, 0, z);
    for (int k = 0; k < CLRT_LANES; ++k) out[k] = (float3)(x[k], y[k], z[k]);
}
inline int Lane_Bits(LaneI m) { return (m.s0 ? 1 : 0) | (m.s1 ? 2 : 0) | (m.s2 ? 4 : 0) | (m.s3 ? 8 : 0); }
inline LaneI Lane_FromBits(int bits) { return -((LaneI)(bits, bits >> 1, bits >> 2, bits >> 3) & 1); }

/* ---- the sampler: Rng_Stratified2D (common.cl) for the lanes' samples at once -------------------
 * The lanes share the pixel and the path id (each lane's path is its sample's child 0 at every depth),
 * so the dimension's hashes are one; only the sample index differs. Bit for bit Rng_Stratified2D's. */
inline LaneU LaneBits_Reverse(LaneU v) {
#ifdef CLRT_BITS_REVERSE_BY_TABLE /* quirk BIT_REVERSE_TABLE (Oclgrind lacks llvm.bitreverse): per lane, by table */
    return (LaneU)(Bits_Reverse(v.s0), Bits_Reverse(v.s1), Bits_Reverse(v.s2), Bits_Reverse(v.s3));
#else
    CLRT_BITS_REVERSE_NETWORK(v);
    return v;
#endif
}
inline LaneU LaneBits_LaineKarras(LaneU x, uint seed) {
    CLRT_LAINE_KARRAS(x, seed);
    return x;
}
inline LaneU LaneSobol_Dim1Reversed(LaneU i) {
    CLRT_SOBOL_DIM1_REVERSED(i);
    return i;
}
inline void Lanes_Stratified2D(uint strat, LaneU sample, uint dim, LaneF* u1, LaneF* u2) {
    const uint sIdx = Rng_Hash(strat ^ dim * 0x9e3779b1u);
    const uint sX = Rng_Hash(sIdx ^ 0xa54ff53au), sY = Rng_Hash(sIdx ^ 0x510e527fu);
    const LaneU idx = LaneBits_Reverse(LaneBits_LaineKarras(LaneBits_Reverse(sample), sIdx));
    const LaneU x = LaneBits_Reverse(LaneBits_LaineKarras(idx, sX));
    const LaneU y = LaneBits_Reverse(LaneBits_LaineKarras(LaneSobol_Dim1Reversed(idx), sY));
    *u1 = convert_float4(x >> 8) * (1.0f / 16777216.0f);
    *u2 = convert_float4(y >> 8) * (1.0f / 16777216.0f);
}

/* ---- lane forms of common.cl's helpers (same operations) ------------------------------------------ */
inline void Lanes_SinCos2Pi(LaneF t, LaneF* c, LaneF* s) { /* Math_SinCos2Pi */
    const LaneF r0 = t - rint(t);
    const LaneF q = rint(4.0f * r0);
    const LaneF r = r0 - 0.25f * q, r2 = r * r;
    const LaneF sn = r * (6.2831854820e+00f + r2 * (-4.1341659546e+01f + r2 * (8.1592155457e+01f + r2 * -7.5395851135e+01f)));
    const LaneF cs = 1.0f + r2 * (-1.9739208221e+01f + r2 * (6.4939331055e+01f + r2 * (-8.5444244385e+01f + r2 * 5.9263893127e+01f)));
    const LaneI k = convert_int4(q) & 3;
    const LaneI odd = (k & 1) != 0, flip = (k & 2) != 0;
    const LaneF cq = select(cs, -sn, odd), sq = select(sn, cs, odd);
    *c = select(cq, -cq, flip);
    *s = select(sq, -sq, flip);
}
inline LaneF Lanes_OffsetDistance(LaneV3 p) { /* Ray_OffsetDistance */
    const LaneF m = fmax(fmax(fabs(p.x), fabs(p.y)), fabs(p.z));
    return fmax(CLRT_OFFSET_ULPS * FLT_EPSILON * m, 1.0f / 65536.0f);
}
inline LaneF Lanes_Atan2(LaneF y, LaneF x) { /* Math_Atan2 */
    const LaneF ax = fabs(x), ay = fabs(y), mx = fmax(ax, ay), mn = fmin(ax, ay);
    const LaneF a = select((LaneF)(0.0f), mn / mx, mx > 0.0f), s = a * a;
    LaneF p;
    CLRT_ATAN_POLY(p, s);
    LaneF r = a * p;
    r = select(r, 0.5f * CLRT_PI - r, ay > ax);
    r = select(r, CLRT_PI - r, x < 0.0f);
    return select(r, -r, y < 0.0f);
}
inline void Lanes_Basis(LaneV3 n, LaneV3* t, LaneV3* b) { /* makeBasis */
    const LaneF sign = select((LaneF)(-1.0f), (LaneF)(1.0f), n.z >= 0.0f);
    const LaneF a = -1.0f / (sign + n.z);
    const LaneF c = n.x * n.y * a;
    *t = LaneV3_Make(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = LaneV3_Make(c, sign + n.y * n.y * a, -n.y);
}
#ifdef CLRT_HAS_PATH_TRACING
/* Path_MisWeight for lanes. */
inline LaneF Lanes_MisWeight(int mode, LaneF pa, LaneF pb) {
    if (mode & CLRT_PATH_MIS_MAXIMUM)
        return select(select((LaneF)(0.0f), (LaneF)(0.5f), (pa == pb) & (pa > 0.0f)), (LaneF)(1.0f), pa > pb);
    const int balance = (mode & CLRT_PATH_MIS_BALANCE) != 0;
    const LaneF a = balance ? pa : pa * pa, b = balance ? pb : pb * pb;
    const LaneF fallback = select((LaneF)(0.0f), (LaneF)(1.0f), pa > 0.0f);
    return select(fallback, a / (a + b), (a + b > 0.0f) & isfinite(a + b));
}

/* Path_EmissionWeight for lanes. */
inline LaneF Lanes_EmissionWeight(int mode, LaneF bsdfPdf, LaneF lightPdf) {
    if (!Path_UsesNee(mode)) return (LaneF)(1.0f);
    const LaneF w = (mode & CLRT_PATH_MIS) ? select(Lanes_MisWeight(mode, bsdfPdf, lightPdf), (LaneF)(0.0f), lightPdf < 0.0f)
                                           : (LaneF)(0.0f);
    return select(w, (LaneF)(1.0f), !(bsdfPdf > 0.0f));
}
#endif /* CLRT_HAS_PATH_TRACING */

#endif /* CLRT_HAS_LANES */
#endif /* CLRT_LANES_MATH_CL */
