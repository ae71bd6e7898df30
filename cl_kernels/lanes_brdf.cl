/* lanes_brdf.cl — a glossy material's light at four shading points at once (render_lanes, lanes.cl): the lane
 * forms of Material_EvalDirect (material.cl), Path_BouncePdf and Path_SampleBounce (path.cl) with brdf.cl's
 * BRDFs and the classic Blinn-Phong lobe of a material without one. Each lane computes what the scalar
 * functions compute for its ShadingPoint, up to rounding (tests/test_lanes.cpp "glossy lobes"): every
 * BRDF's formula runs on all four lanes and each lane keeps its own kind's (select), so the lanes may hold
 * different materials. Reads Material (brdf, brdfExponent, brdfFlags, refractionIndex, absorptionIndex) and
 * the ShadingPoints' normal, geomNormal, wo, kd, ks (ks.w: the classic exponent). */
#ifndef CLRT_LANES_BRDF_CL
#define CLRT_LANES_BRDF_CL

#include "lanes_math.cl"
#include "material.cl"

#if defined(CLRT_HAS_LANES) && defined(CLRT_HAS_PATH_TRACING)

/* The kinds the lane functions below compute: the classic lobe and brdf.cl's five. A BRDF without a case here
 * is shaded per lane by the scalar functions (LaneBrdf.scalar: Lanes_GlossyLightTerms, Lanes_GlossyBounces). */
inline int LaneBrdf_HasLaneForm(int kind) {
    return kind == CLRT_INVALID || kind == BRDF_ORIGINAL_PHONG || kind == BRDF_ORIGINAL_BLINN_PHONG ||
           kind == BRDF_MODIFIED_PHONG || kind == BRDF_MODIFIED_BLINN_PHONG || kind == BRDF_TORRANCE_SPARROW;
}

/* The lanes' ShadingPoints as their BRDFs read them; a lane outside the loaded mask has kd = ks = 0. */
typedef struct {
    int scalar;              /* loaded lanes whose BRDF has no lane form (LaneBrdf_HasLaneForm) */
    LaneI kind;              /* BrdfKind, or CLRT_INVALID: the classic terms (kd·cosθ + ks·cos^p αh) */
    LaneF exponent;          /* the BRDF's, or the classic Phong exponent (ks.w) */
    LaneI normalized, kdFresnel;
    LaneF eta, k;            /* Torrance-Sparrow's Fresnel */
    LaneV3 kd, ks, n, ng, wo;
} LaneBrdf;

inline LaneBrdf LaneBrdf_Load(const __global Material* materials, int lanes, const ShadingPoint* sp) {
    int kind[CLRT_LANES], norm[CLRT_LANES], kdf[CLRT_LANES];
    float e[CLRT_LANES], eta[CLRT_LANES], k[CLRT_LANES];
    float3 kd[CLRT_LANES], ks[CLRT_LANES], n[CLRT_LANES], ng[CLRT_LANES], wo[CLRT_LANES];
    int scalar = 0;
    for (int j = 0; j < CLRT_LANES; ++j) {
        kind[j] = CLRT_INVALID; norm[j] = kdf[j] = 0;
        e[j] = eta[j] = k[j] = 0.0f;
        kd[j] = ks[j] = (float3)(0.0f);
        n[j] = ng[j] = wo[j] = (float3)(0.0f, 0.0f, 1.0f);
        if (!((lanes >> j) & 1)) continue;
        const __global Material* m = &materials[sp[j].material];
#ifdef CLRT_HAS_BRDFS
        kind[j] = m->brdf;
#endif
        scalar |= !LaneBrdf_HasLaneForm(kind[j]) << j;
        e[j] = kind[j] != CLRT_INVALID ? m->brdfExponent : sp[j].ks.w;
        norm[j] = -((m->brdfFlags & CLRT_BRDF_NORMALIZED) != 0);
        kdf[j] = -((m->brdfFlags & CLRT_BRDF_KD_FRESNEL) != 0);
        eta[j] = m->refractionIndex;
        k[j] = m->absorptionIndex;
        kd[j] = sp[j].kd.xyz; ks[j] = sp[j].ks.xyz;
        n[j] = sp[j].normal.xyz; ng[j] = sp[j].geomNormal.xyz; wo[j] = sp[j].wo.xyz;
    }
    LaneBrdf b;
    b.scalar = scalar;
    b.kind = vload4(0, kind); b.normalized = vload4(0, norm); b.kdFresnel = vload4(0, kdf);
    b.exponent = vload4(0, e); b.eta = vload4(0, eta); b.k = vload4(0, k);
    b.kd = LaneV3_Load(kd); b.ks = LaneV3_Load(ks);
    b.n = LaneV3_Load(n); b.ng = LaneV3_Load(ng); b.wo = LaneV3_Load(wo);
    return b;
}

inline LaneF Lanes_PowAtZero(LaneF e) { /* Math_PowNonNegative's 0^e: 0 for e > 0, 1 for e = 0, inf for e < 0 */
    return select(select(select(e, (LaneF)(INFINITY), e < 0.0f), (LaneF)(1.0f), e == 0.0f), (LaneF)(0.0f), e > 0.0f);
}
inline LaneF Lanes_PowNonNegative(LaneF x, LaneF e) { /* Math_PowNonNegative */
    return select(Lanes_PowAtZero(e), exp2(e * log2(x)), x > 0.0f);
}
inline LaneV3 LaneV3_Reflect(LaneV3 w, LaneV3 n) { return LaneV3_Sub(LaneV3_Scale(n, 2.0f * LaneV3_Dot(w, n)), w); }
inline LaneF LaneV3_Sum(LaneV3 a) { return a.x + a.y + a.z; }

/* The lobes drawn about wo mirrored in n (the Phong pair), not about the half vector. */
inline LaneI LaneBrdf_MirrorLobe(const LaneBrdf* b) {
    return (b->kind == BRDF_ORIGINAL_PHONG) | (b->kind == BRDF_MODIFIED_PHONG);
}

/* What f and the glossy lobe's density share at wi, computed once (LaneBrdf_At): the cosines, the half vector's
 * terms and the lobe's power. The lobe's cosine `base` is wo·(wi mirrored in n) for the Phong pair (their
 * Brdf_CosAlphaR before its clamp; Brdf_GlossyPdf's (wo mirrored)·wi, the same up to rounding) and |n·h| for the
 * half-vector lobes (Brdf_CosAlphaH where n·h > 0, the lobe density's cosine of h turned up); one power per lane
 * serves both: f's cos^p of the clamped cosine is the power where the cosine is > 0 and the power at 0 elsewhere. */
typedef struct {
    LaneF cosI, cosO; /* n·wi, n·wo */
    LaneF hl;         /* |wi + wo| */
    LaneF nh, woH;    /* n·h and wo·h, h = (wi + wo)/hl; nh 0 where hl is 0 */
    LaneF cosLobe;    /* the lobe's signed cosine for f: n·h, or wo·(wi mirrored) (Phong pair) */
    LaneF base;       /* the lobe's cosine for the power: |n·h|, or cosLobe (Phong pair) */
    LaneF power;      /* base^exponent (Lanes_PowNonNegative) */
} LaneBrdfAt;

inline LaneBrdfAt LaneBrdf_At(const LaneBrdf* b, LaneV3 wi) {
    LaneBrdfAt a;
    a.cosI = LaneV3_Dot(b->n, wi);
    a.cosO = LaneV3_Dot(b->n, b->wo);
    const LaneV3 hRaw = LaneV3_Add(wi, b->wo);
    a.hl = sqrt(LaneV3_Dot(hRaw, hRaw));
    a.nh = select((LaneF)(0.0f), LaneV3_Dot(b->n, hRaw) / a.hl, a.hl > 0.0f);
    a.woH = LaneV3_Dot(b->wo, hRaw) / a.hl;
    const LaneI mirror = LaneBrdf_MirrorLobe(b);
    a.cosLobe = select(a.nh, LaneV3_Dot(LaneV3_Reflect(wi, b->n), b->wo), mirror);
    a.base = select(fabs(a.nh), a.cosLobe, mirror);
    a.power = Lanes_PowNonNegative(a.base, b->exponent);
    return a;
}

/* Material_EvalDirect: f(wo, wi)·cosθ (cosTheta = n·wi > 0 where it is used), from LaneBrdf_At(b, wi). */
inline LaneV3 LaneBrdf_EvalDirect(const LaneBrdf* b, const LaneBrdfAt* at, LaneF cosTheta) {
    const LaneF cosI = at->cosI, cosO = at->cosO;
    const LaneF cosH = fmax(0.0f, at->nh); /* Brdf_CosAlphaH */
    const LaneI classic = b->kind == CLRT_INVALID, ts = b->kind == BRDF_TORRANCE_SPARROW;
    const LaneI hasSpec = LaneV3_Max(b->ks) > 0.0f;
    /* cos^p of the clamped cosine (Lanes_PowNonNegative(fmax(0, cosLobe), p)): the power at 0 where it is <= 0 */
    const LaneF powAtZero = Lanes_PowAtZero(b->exponent);
    const LaneF spec = select((LaneF)(0.0f), select(powAtZero, at->power, at->cosLobe > 0.0f), hasSpec | ts);
    /* the specular factor s of f = kd' + ks·s, and kd' = kd·dScale */
    LaneF s = spec, dScale = (LaneF)(1.0f);
    const LaneI original = (b->kind == BRDF_ORIGINAL_PHONG) | (b->kind == BRDF_ORIGINAL_BLINN_PHONG);
    s = select(s, spec / cosI, original);
    const LaneI modPhong = (b->kind == BRDF_MODIFIED_PHONG) & b->normalized;
    const LaneI modBlinn = (b->kind == BRDF_MODIFIED_BLINN_PHONG) & b->normalized;
    s = select(s, spec * (b->exponent + 2.0f) * (0.5f * CLRT_INV_PI), modPhong);
    s = select(s, spec * (b->exponent + 8.0f) * (0.125f * CLRT_INV_PI), modBlinn);
    dScale = select(dScale, (LaneF)(CLRT_INV_PI), modPhong | modBlinn | ts);
    if (any(ts)) { /* Torrance-Sparrow: D F G / (4 cosθi cosθo), F at θi; (1 − F) kd with kdfresnel */
        const LaneF woH = at->woH;
        const LaneF d = (b->exponent + 2.0f) * (0.5f * CLRT_INV_PI) * spec;
        const LaneF g = fmin(1.0f, fmin(2.0f * cosH * cosO / woH, 2.0f * cosH * cosI / woH));
        const LaneF c2 = cosI * cosI, nk = b->eta * b->eta + b->k * b->k;
        const LaneF rs = (nk - 2.0f * b->eta * cosI + c2) / (nk + 2.0f * b->eta * cosI + c2);
        const LaneF rp = (nk * c2 - 2.0f * b->eta * cosI + 1.0f) / (nk * c2 + 2.0f * b->eta * cosI + 1.0f);
        const LaneF fres = 0.5f * (rs + rp);
        s = select(s, d * fres * g / (4.0f * cosI * cosO), ts);
        dScale = select(dScale, (1.0f - fres) * CLRT_INV_PI, ts & b->kdFresnel);
    }
    const LaneV3 f = LaneV3_Add(LaneV3_Scale(b->kd, dScale), LaneV3_Scale(b->ks, s));
    const LaneI above = (cosI > 0.0f) & (cosO > 0.0f);
    const LaneV3 brdfTerm = LaneV3_Select(LaneV3_Splat((float3)(0.0f)), LaneV3_Scale(f, cosTheta), above);
    /* classic: kd·cosθ + ks·cos^p αh (h normalized), the lobe skipped when ks = 0 */
    const LaneV3 classicTerm = LaneV3_Add(LaneV3_Scale(b->kd, cosTheta), LaneV3_Scale(b->ks, select((LaneF)(0.0f), spec, hasSpec)));
    return LaneV3_Select(brdfTerm, classicTerm, classic);
}

/* Brdf_LobeExponent: the glossy lobe's q (Torrance-Sparrow: p + 1, D(h) cos αh). */
inline LaneF LaneBrdf_LobeExponent(const LaneBrdf* b) {
    return select(b->exponent, b->exponent + 1.0f, b->kind == BRDF_TORRANCE_SPARROW);
}
inline LaneF LaneBrdf_GlossyWeight(const LaneBrdf* b) { /* Brdf_GlossyWeight */
    const LaneF d = LaneV3_Sum(b->kd), s = LaneV3_Sum(b->ks);
    return select((LaneF)(0.0f), s / (d + s), d + s > 0.0f);
}

/* Brdf_GlossyPdf: the glossy lobe's density at wi, from LaneBrdf_At(b, wi) (its power; Torrance-Sparrow's lobe
 * D(h) cos αh has one cosine more). */
inline LaneF LaneBrdf_GlossyPdf(const LaneBrdf* b, const LaneBrdfAt* at) {
    const LaneF q = LaneBrdf_LobeExponent(b);
    const LaneI mirror = LaneBrdf_MirrorLobe(b);
    const LaneF lobePower = select(at->power, at->power * at->base, b->kind == BRDF_TORRANCE_SPARROW);
    const LaneF lobe = select((LaneF)(0.0f), (q + 1.0f) * (0.5f * CLRT_INV_PI) * lobePower, at->base > 0.0f); /* Brdf_PowerCosinePdf */
    const LaneF woH = fabs(at->woH); /* h turned into the upper hemisphere: the same |wo·h| */
    return select(select((LaneF)(0.0f), lobe / (4.0f * woH), (at->hl > 0.0f) & (woH > 0.0f)), lobe, mirror);
}

/* The mixture's density at wi: (1 − s) cosθ/π + s·Brdf_GlossyPdf (Brdf_Pdf, cosθ clamped at 0). */
inline LaneF LaneBrdf_MixturePdf(const LaneBrdf* b, const LaneBrdfAt* at) {
    const LaneF s = LaneBrdf_GlossyWeight(b);
    return (1.0f - s) * fmax(0.0f, at->cosI) * CLRT_INV_PI + select((LaneF)(0.0f), s * LaneBrdf_GlossyPdf(b, at), s > 0.0f);
}

/* Path_BouncePdf: the density Path_SampleBounce draws wi with (at: LaneBrdf_At(b, wi)). */
inline LaneF LaneBrdf_BouncePdf(const LaneBrdf* b, int mode, const LaneBrdfAt* at) {
    const LaneF c = at->cosI;
    if (!Path_UsesImportance(mode)) return select((LaneF)(0.0f), (LaneF)(0.5f * CLRT_INV_PI), c > 0.0f);
    const LaneF brdfPdf = LaneBrdf_MixturePdf(b, at);
    return select((LaneF)(0.0f), select(brdfPdf, c * CLRT_INV_PI, b->kind == CLRT_INVALID), c > 0.0f);
}

/* Brdf_Sample for the lanes with a BRDF, in importance sampling modes, from u1 and the cosine and sine of 2π·u2
 * (Lanes_SinCos2Pi, which Lanes_Bounce has made): *wi; returns the lanes whose sample can carry something (a
 * finite wi, and for a half-vector draw wo·h != 0; the caller asks for n·wi > 0 and a density > 0 too). Each lane draws from the lobe its u1
 * picks, in one warp: the glossy lobe's power cosine (Brdf_WarpPowerCosine) about wo mirrored in n, or about n
 * for a half vector that wo is then reflected about, or the cosine lobe about n (Warp_CosineHemisphere). Its
 * density is the mixture's at wi (LaneBrdf_MixturePdf), for either lobe: the scalar code takes the glossy
 * lobe's term from the warp's cosine instead, the same value up to rounding. */
inline LaneI LaneBrdf_Sample(const LaneBrdf* b, LaneF u1, LaneF cs, LaneF sn, LaneV3* wi) {
    const LaneF s = LaneBrdf_GlossyWeight(b), q = LaneBrdf_LobeExponent(b);
    const LaneI glossyLobe = u1 < s, mirror = LaneBrdf_MirrorLobe(b);
    const LaneF v1 = fmin((u1 - s) / (1.0f - s), 1.0f);                                 /* the cosine lobe's u1 */
    const LaneF cG = Lanes_PowNonNegative(fmin(u1 / s, 1.0f), 1.0f / (q + 1.0f));       /* the glossy lobe's cosine */
    const LaneF c = select(sqrt(fmax(0.0f, 1.0f - v1)), cG, glossyLobe);
    const LaneF sinT = select(sqrt(v1), sqrt(fmax(0.0f, 1.0f - cG * cG)), glossyLobe);
    const LaneV3 axis = LaneV3_Select(b->n, LaneV3_Reflect(b->wo, b->n), glossyLobe & mirror);
    LaneV3 t, bt;
    Lanes_Basis(axis, &t, &bt);
    const LaneV3 w = LaneV3_Normalize(LaneV3_Add(LaneV3_Add(LaneV3_Scale(t, sinT * cs), LaneV3_Scale(bt, sinT * sn)), LaneV3_Scale(axis, c)));
    const LaneI viaHalf = glossyLobe & ~mirror;
    const LaneF woH = LaneV3_Dot(b->wo, w);
    *wi = LaneV3_Select(w, LaneV3_Normalize(LaneV3_Sub(LaneV3_Scale(w, 2.0f * woH), b->wo)), viaHalf);
    return ~(viaHalf & ~(fabs(woH) > 0.0f)) & LaneV3_Finite(*wi);
}

#endif /* CLRT_HAS_LANES && CLRT_HAS_PATH_TRACING */
#endif /* CLRT_LANES_BRDF_CL */
