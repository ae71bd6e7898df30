/* lanes.cl — the path tracer with four paths per work-item in float4 lanes (render_lanes; CPU devices,
 * compiled under CLRT_HAS_LANES: FeatureSet::lanes). A work-item takes its pixel's samples four at a
 * time (lane k: sample s0 + k) and steps their paths together, one depth per round:
 *   per lane, scalar: the closest hit (Ray_Closest), the surface and the emission the ray sees
 *     (Lanes_Surface: the path branch of Shade_Hit and the start of Path_ShadeHit), the light triangle
 *     picked (MeshLight_PickTriangle), the shadow rays' occlusion (Shadow_Occluded), the specular pick
 *     and a mirror's, conductor's or dielectric's child (Path_SpecularBounce), roulette;
 *   in lanes: the sampler (Lanes_Stratified2D), the light samples (MeshLight_Sample, Shadow_Make,
 *     Path_LightSampleWeight, ObjectLight_AimShadow) and the bounce (Path_SampleBounce, Path_Child).
 * It computes what render_fused computes for the same random streams, up to rounding (tests/test_lanes.cpp):
 * one lane is one path of the fused kernel. Scenes of its family only (src/flatten/device_scene.h
 * lanesFamily, src/render/fused_renderer.h lanesUnsupported): materials without a specular lobe (ks = 0:
 * the non-specular f is kd/π or kd, direction-free; mirrors, conductors, dielectrics in), LightMesh and
 * point lights, the stratified sampler, no textures, motion blur or instances. Why lanes: a path's
 * shading is a chain of dependent sqrt, division, sin/cos and loads; four paths go through it as one
 * chain of vector instructions (docs/studies/2026-12-05-simd-lanes-prototype.md).
 * Reads: the scene's geometry, materials and lights; writes: image, and rayCounts[0] += the bounce rays. */
#ifndef CLRT_LANES_CL
#define CLRT_LANES_CL

#include "fused.cl"

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
inline void Lanes_Basis(LaneV3 n, LaneV3* t, LaneV3* b) { /* makeBasis */
    const LaneF sign = select((LaneF)(-1.0f), (LaneF)(1.0f), n.z >= 0.0f);
    const LaneF a = -1.0f / (sign + n.z);
    const LaneF c = n.x * n.y * a;
    *t = LaneV3_Make(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = LaneV3_Make(c, sign + n.y * n.y * a, -n.y);
}
/* Path_MisWeight for lanes. */
inline LaneF Lanes_MisWeight(int mode, LaneF pa, LaneF pb) {
    if (mode & CLRT_PATH_MIS_MAXIMUM)
        return select(select((LaneF)(0.0f), (LaneF)(0.5f), (pa == pb) & (pa > 0.0f)), (LaneF)(1.0f), pa > pb);
    const int balance = (mode & CLRT_PATH_MIS_BALANCE) != 0;
    const LaneF a = balance ? pa : pa * pa, b = balance ? pb : pb * pb;
    const LaneF fallback = select((LaneF)(0.0f), (LaneF)(1.0f), pa > 0.0f);
    return select(fallback, a / (a + b), (a + b > 0.0f) & isfinite(a + b));
}

/* ---- one depth of the lanes' paths ----------------------------------------------------------- */

/* What a lane's hit gives the lane code: the point and normals (facing the ray, as Shade_Hit's path
 * branch orients them), f (the BRDF's value: direction-free in this family), the radiance that needs no
 * shadow ray, whether the hit samples the lights and bounces, and what a specular child needs
 * (Path_SpecularBounce: the material, wo, the distance the ray travelled, inside a dielectric). */
typedef struct {
    float3 p, ng, ns, f, wo;
    float3 radiance;
    float t;
    int material, nee, bounce, specular, diffuse, inside, lastVertex;
} LaneHit;

/* Lane path `path` along ray: the closest hit and Shade_Hit's path branch up to Path_ShadeHit's
 * light-sample and bounce decisions (a miss: the background, Shade_Miss). */
inline LaneHit Lanes_Surface(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) PathState path, Ray ray) {
    LaneHit lh;
    lh.p = lh.ng = lh.ns = lh.f = lh.wo = lh.radiance = (float3)(0.0f);
    lh.t = 0.0f;
    lh.material = lh.nee = lh.bounce = lh.specular = lh.diffuse = lh.inside = lh.lastVertex = 0;
    int instance;
    const Hit h = Ray_Closest(ray, scene, nodes, leaves, tris, spheres, planes, instances, &instance);
    if (h.prim == CLRT_INVALID) {
        ShadeResult res;
        Shade_Miss(scene, cam, path, ray, textures, images, texels, lights, envDist, &res);
        lh.radiance = res.radiance.xyz;
        return lh;
    }
    HitTriangle ht;
    if (h.prim < scene.numTriangles) HitTriangle_Load(h, instance, tris, triShading, triAttributes, instances, &ht);
    SurfaceHit s = Surface_FromHit(h, ray, &ht, spheres, planes, scene.numTriangles, scene.numSpheres);
    const __global Material* m = &materials[s.material];
    if (dot(s.ns, s.ng) < 0.0f) s.ns = -s.ns; /* Shade_OrientsNormalToRay: every material when path traced */
    const float3 ng = s.frontFacing ? s.ng : -s.ng, ns = s.frontFacing ? s.ns : -s.ns;
    float lightPdf = -1.0f;
    float3 emitted = (float3)(0.0f);
#ifdef CLRT_HAS_LIGHT_MESH
    emitted = Path_HitEmission(h.prim, s.frontFacing, scene, triShading, spheres, lights, s.p, s.dir, s.t, s.ng,
                               path.throughput.w, &lightPdf);
#endif
    const int kind = m->kind;
    lh.inside = kind == MATERIAL_DIELECTRIC && !s.frontFacing; /* Shade_Hit's insideDielectric: no ShadingPoint */
    lh.specular = kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR || kind == MATERIAL_DIELECTRIC;
    ShadingPoint sp;
    sp.position = (float4)(s.p, 1.0f);
    sp.normal = (float4)(ns, 0.0f);
    sp.geomNormal = (float4)(ng, 0.0f);
    sp.wo = (float4)(-s.dir, 0.0f);
    sp.kd = (float4)(m->diffuse.xyz, 0.0f);
    sp.ks = (float4)(m->specular.xyz, m->phongExponent);
    sp.material = s.material;
    sp.pad0 = sp.pad1 = sp.pad2 = 0; /* as ShadingPoint_Make */
    const int mode = scene.pathMode;
    lh.radiance = finiteOrZero(path.throughput.xyz * emitted * Path_EmissionWeight(mode, path.throughput.w, lightPdf));
    const int diffuse = !lh.inside && (maxComponent(sp.kd.xyz) > 0.0f || maxComponent(sp.ks.xyz) > 0.0f);
    const int emissionOnly = path.depth > scene.maxDepth, lastVertex = path.depth >= scene.maxDepth;
    /* Path_ShadeHit's decisions: light samples, and whether a child may follow */
    lh.nee = Path_UsesNee(mode) && diffuse && !emissionOnly;
    lh.bounce = !emissionOnly && !(lastVertex && !(mode & CLRT_PATH_MIS)) && (lh.specular || diffuse);
    lh.diffuse = diffuse;
    lh.lastVertex = lastVertex;
    lh.p = s.p;
    lh.ng = ng;
    lh.ns = ns;
    lh.wo = -s.dir;
    lh.t = s.t;
    lh.material = s.material;
    if (diffuse && (lh.nee || lh.bounce)) lh.f = Material_EvalDirect(sp, materials, ns, 1.0f); /* f: the same for every wi (ks = 0) */
    return lh;
}

/* Which of the lanes in okBits see the shadow ray from org along unit dir unblocked up to tMax
 * (Shadow_Occluded, per lane). */
inline int Lanes_Unoccluded(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int okBits, LaneV3 org, LaneV3 dir, LaneF tMax) {
    if (!okBits) return 0;
    float tm[CLRT_LANES];
    float3 o[CLRT_LANES], d[CLRT_LANES];
    vstore4(tMax, 0, tm);
    LaneV3_Store(org, o);
    LaneV3_Store(dir, d);
    int open = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!(okBits & (1 << k))) continue;
        ShadowRay sr;
        sr.origin = (float4)(o[k], tm[k]);
        sr.direction = (float4)(d[k], 0.0f);
        sr.contribution = (float4)(0.0f);
        if (!Shadow_Occluded(sr, scene, nodes, leaves, tris, spheres, planes, instances)) open |= 1 << k;
    }
    return open;
}

#ifdef CLRT_HAS_LIGHT_MESH
/* MeshLight_Sample for the lanes at p: *wi, *dist (MeshLight_ShadowLength's), the radiance estimate *e
 * (0 where the sample fails), and the light's point's offset distance; u: the lanes' 2D sample. */
inline void Lanes_MeshLightSample(const __global Light* light, const __global float4* lightData, LaneV3 p, LaneF u1,
                                  LaneF u2, LaneV3* wi, LaneF* dist, LaneV3* e) {
    const __global float4* tri = lightData + light->objFirst;
    float ux[CLRT_LANES], ulx[CLRT_LANES];
    float3 v0[CLRT_LANES], v1[CLRT_LANES], v2[CLRT_LANES];
    vstore4(u1, 0, ulx);
    for (int k = 0; k < CLRT_LANES; ++k) { /* MeshLight_PickTriangle, per lane */
        const int t = MeshLight_PickTriangle(tri, light->objCount, ulx[k], &ux[k]);
        v0[k] = tri[3 * t].xyz; v1[k] = tri[3 * t + 1].xyz; v2[k] = tri[3 * t + 2].xyz;
    }
    const LaneV3 a = LaneV3_Load(v0), b = LaneV3_Load(v1), c = LaneV3_Load(v2);
    const LaneF su = sqrt(vload4(0, ux));
    const LaneF b0 = 1.0f - su, b1 = u2 * su;
    const LaneV3 q = LaneV3_Add(LaneV3_Add(LaneV3_Scale(a, b0), LaneV3_Scale(b, b1)), LaneV3_Scale(c, 1.0f - b0 - b1));
    const LaneV3 d = LaneV3_Sub(q, p);
    const LaneF d2 = LaneV3_Dot(d, d);
    const LaneF len = sqrt(d2);
    *wi = LaneV3_Scale(d, 1.0f / len);
    const LaneF cosLight = fabs(LaneV3_Dot(LaneV3_Normalize(LaneV3_Cross(LaneV3_Sub(b, a), LaneV3_Sub(c, a))), *wi));
    *dist = fmax(len - Lanes_OffsetDistance(q) / cosLight, 0.5f * len); /* MeshLight_ShadowLength */
    const LaneF scale = select((LaneF)(0.0f), light->area * cosLight / d2, (d2 > 0.0f) & (cosLight > 0.0f));
    *e = LaneV3_Scale(LaneV3_Splat(light->radiance.xyz), scale);
}
#endif

/* The lanes' light samples of light `light` (LightMesh or PointLight) at their shading points: as
 * Light_ShadowRays and Fused_Shadow, the unoccluded contributions (MIS-weighted, times the throughput). */
inline LaneV3 Lanes_LightSample(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) const __global Light* light, int neeBits,
                                LaneV3 p, LaneV3 ng, LaneV3 ns, LaneV3 f, LaneV3 throughput, uint strat, LaneU sample,
                                uint dim) {
    const LaneV3 zero = LaneV3_Splat((float3)(0.0f));
    LaneV3 wi, e;
    LaneF dist;
    const int mesh = light->kind == LIGHT_MESH;
    if (mesh) {
#ifdef CLRT_HAS_LIGHT_MESH
        if (light->objCount <= 0 || !(light->area > 0.0f)) return zero;
        LaneF u1, u2;
        Lanes_Stratified2D(strat, sample, dim, &u1, &u2);
        Lanes_MeshLightSample(light, lightData, p, u1, u2, &wi, &dist, &e);
#else
        return zero;
#endif
    } else { /* PointLight_Sample */
        const LaneV3 d = LaneV3_Sub(LaneV3_Splat(light->position.xyz), p);
        const LaneF d2 = LaneV3_Dot(d, d);
        dist = sqrt(d2);
        wi = LaneV3_Scale(d, 1.0f / dist);
        e = LaneV3_Scale(LaneV3_Splat(light->radiance.xyz), select((LaneF)(0.0f), 1.0f / d2, d2 > 0.0f));
    }
    /* Shadow_Make */
    const LaneF cosTheta = LaneV3_Dot(ns, wi);
    LaneI ok = Lane_FromBits(neeBits) & (cosTheta > 0.0f) & (LaneV3_Max(e) > 0.0f);
    LaneV3 contrib = LaneV3_FiniteOrZero(LaneV3_Mul(LaneV3_Mul(throughput, LaneV3_Scale(f, cosTheta)), e));
    const int mode = scene.pathMode;
    if (mesh && (mode & CLRT_PATH_MIS)) { /* Path_LightSampleWeight: a point light's weight is 1 */
        const LaneF lightPdf = maxComponent(light->radiance.xyz) / LaneV3_Max(e);
        const LaneF bouncePdf = Path_UsesImportance(mode) ? cosTheta * CLRT_INV_PI : (LaneF)(0.5f * CLRT_INV_PI);
        contrib = LaneV3_Scale(contrib, Lanes_MisWeight(mode, lightPdf, select((LaneF)(0.0f), bouncePdf, cosTheta > 0.0f)));
    }
    /* The ray: from Ray_EpsilonOrigin aimed at the light's point, as long as from p (a mesh light's:
     * ObjectLight_AimShadow, short of its point) */
    const LaneV3 org = LaneV3_Add(p, LaneV3_Scale(ng, fmax(Lanes_OffsetDistance(p), scene.shadowEpsilon)));
    const LaneV3 toLight = LaneV3_Sub(LaneV3_Add(p, LaneV3_Scale(wi, dist)), org);
    const LaneF len = sqrt(LaneV3_Dot(toLight, toLight));
    const LaneV3 dir = LaneV3_Scale(toLight, 1.0f / len);
    ok &= LaneV3_Max(contrib) > 0.0f; /* Fused_Shadow traces no ray of zero contribution */
    LaneF tMax = dist;
    if (mesh) {
        ok &= (len > 0.0f) & isfinite(len);
        tMax = len * (1.0f - 1e-5f);
    }
    const int open = Lanes_Unoccluded(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) Lane_Bits(ok), org, dir, tMax);
    return LaneV3_Select(zero, contrib, Lane_FromBits(open));
}

/* The lanes' non-specular bounces (Path_SampleBounce, no BRDF lobe), picked with probability 1 − pSpecular:
 * *dir, *pdf and the new throughput; the lanes in the returned bits carry a child. */
inline int Lanes_Bounce(int mode, int bounceBits, LaneV3 ng, LaneV3 ns, LaneV3 f, LaneF pSpecular, LaneF u1, LaneF u2,
                        LaneV3* throughput, LaneV3* dir, LaneF* pdf) {
    const int cosine = Path_UsesImportance(mode);
    LaneF c2, s2;
    Lanes_SinCos2Pi(u2, &c2, &s2);
    LaneF lx, ly, lz;
    if (cosine) { /* Warp_CosineHemisphere (also Brdf_Sample's diffuse lobe when ks = 0) */
        const LaneF r = sqrt(u1);
        lx = r * c2; ly = r * s2; lz = sqrt(fmax(0.0f, 1.0f - u1));
    } else { /* Warp_UniformHemisphere */
        const LaneF r = sqrt(fmax(0.0f, 1.0f - u1 * u1));
        lx = r * c2; ly = r * s2; lz = u1;
    }
    LaneV3 t, bt;
    Lanes_Basis(ns, &t, &bt);
    *dir = LaneV3_Normalize(LaneV3_Add(LaneV3_Add(LaneV3_Scale(t, lx), LaneV3_Scale(bt, ly)), LaneV3_Scale(ns, lz)));
    *pdf = cosine ? lz * CLRT_INV_PI : (LaneF)(0.5f * CLRT_INV_PI);
    const LaneF c = LaneV3_Dot(ns, *dir);
    const LaneI ok = Lane_FromBits(bounceBits) & (c > 0.0f) & (LaneV3_Dot(ng, *dir) > 0.0f) & (*pdf > 0.0f) &
                     LaneV3_Finite(*dir);
    const LaneV3 fCos = LaneV3_Scale(f, c);
    const LaneF q = *pdf * (1.0f - pSpecular);
    const LaneV3 weight = LaneV3_Make(fCos.x / q, fCos.y / q, fCos.z / q); /* f·cosθ / (pdf·(1 − pSpecular)) */
    *throughput = LaneV3_Mul(*throughput, weight);
    return Lane_Bits(ok & (LaneV3_Max(weight) > 0.0f));
}

/* Path_ShadeHit's pick at the live lanes' hits: a specular child with probability pSpecular (½ beside a
 * diffuse part, else 1; *pSpec per lane, 0 where no specular material); returns the lanes that take it.
 * A pick at the last vertex ends the lane's path (its only child there is the BSDF sample). */
inline int Lanes_PickSpecular(SceneParams scene, int pixel, const PathState* path, const LaneHit* hit, uint dim, int* live,
                              float* pSpec) {
    int specBits = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        pSpec[k] = 0.0f;
        if (!(*live & (1 << k)) || !hit[k].specular) continue;
        pSpec[k] = hit[k].diffuse ? 0.5f : 1.0f;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        if (!(Rng_Uniform(key, dim + 3u) < pSpec[k])) continue;
        if (hit[k].lastVertex) *live &= ~(1 << k);
        else specBits |= 1 << k;
    }
    return specBits;
}

/* Path_Child (child 0) of each live lane, after Path_RussianRoulette: the specular lanes' child from
 * Path_SpecularBounce, the others' from the lanes' bounce (org, dirs, next3, pdfs). Every lane's path id
 * moves on (they share it). Returns the children made; *live keeps the lanes that have one. */
inline uint Lanes_Children(SceneParams scene, const __global Material* materials, int pixel, int depth, int specBits,
                           const LaneHit* hit, const float* pSpec, float3* org, float3* dirs, const float3* next3,
                           const float* pdfs, PathState* path, Ray* ray, int* live) {
    const int mode = scene.pathMode;
    const uint dim = 4u + 32u * (uint)depth;
    uint children = 0;
    for (int k = 0; k < CLRT_LANES; ++k) { /* Path_Child (child 0), after Path_RussianRoulette */
        const uint id = path[k].pathId;
        path[k].pathId = id < 0x80000000u ? id * 2u : id; /* every lane: they share it */
        if (!(*live & (1 << k))) continue;
        const int spec = (specBits >> k) & 1, roulette = (mode & CLRT_PATH_RR) && depth >= scene.rrMinDepth;
        RngKey key;
        if (spec || roulette) key = Rng_Key(scene.seed, pixel, path[k].sample, id); /* only where a number is drawn */
        float3 next = next3[k];
        float childW = pdfs[k];
        if (spec) { /* Path_SpecularBounce, per lane */
            float3 weight;
            const float2 uGlossy = (float2)(Rng_Uniform(key, dim), Rng_Uniform(key, dim + 1u));
            if (!Path_SpecularBounce(materials[hit[k].material], hit[k].wo, hit[k].ns, hit[k].ng, hit[k].p, hit[k].t,
                                     hit[k].inside, Rng_Uniform(key, dim + 2u), uGlossy, &weight, &org[k], &dirs[k])) {
                *live &= ~(1 << k);
                continue;
            }
            next = path[k].throughput.xyz * (weight / pSpec[k]);
            childW = 0.0f;
        }
        if (roulette && !Path_RussianRoulette(&next, Rng_Uniform(key, dim + 4u))) {
            *live &= ~(1 << k);
            continue;
        }
        if (!(maxComponent(next) > 0.0f) || !allFinite3(next) || !allFinite3(dirs[k])) { *live &= ~(1 << k); continue; }
        path[k].throughput = (float4)(next, childW);
        path[k].depth = depth + 1;
        ray[k].origin = (float4)(org[k], 0.0f);
        ray[k].direction = (float4)(dirs[k], INFINITY);
        ++children;
    }
    return children;
}

/* Samples s0 .. s0 + n - 1 (n <= 4) of pixel `pixel`: their radiance summed in sample order per depth
 * into levelSum (as render_fused's per-depth sums). Returns the bounce rays traced. */
inline uint Lanes_Paths(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int pixel, int px, int py, int s0, int n, int levels,
                        float3* levelSum) {
    PathState path[CLRT_LANES];
    Ray ray[CLRT_LANES];
    int sampleIdx[CLRT_LANES];
    int live = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        sampleIdx[k] = s0 + min(k, n - 1);
        Camera_GenerateAt(cam, scene, pixel, px, py, sampleIdx[k], &path[k], &ray[k]);
        if (k < n) live |= 1 << k;
    }
    const LaneU sample = as_uint4(vload4(0, sampleIdx));
    const int mode = scene.pathMode;
    uint secondary = 0;
    for (int depth = 0; live; ++depth) {
        float3 p[CLRT_LANES], ng[CLRT_LANES], ns[CLRT_LANES], f[CLRT_LANES], rad[CLRT_LANES], thr[CLRT_LANES];
        LaneHit hit[CLRT_LANES];
        int neeBits = 0, bounceBits = 0;
        for (int k = 0; k < CLRT_LANES; ++k) {
            p[k] = ng[k] = f[k] = rad[k] = thr[k] = (float3)(0.0f);
            ns[k] = (float3)(0.0f, 0.0f, 1.0f);
            if (!(live & (1 << k))) continue;
            hit[k] = Lanes_Surface(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) path[k], ray[k]);
            p[k] = hit[k].p; ng[k] = hit[k].ng; ns[k] = hit[k].ns; f[k] = hit[k].f; rad[k] = hit[k].radiance;
            thr[k] = path[k].throughput.xyz;
            neeBits |= hit[k].nee << k;
            bounceBits |= hit[k].bounce << k;
        }
        const LaneV3 P = LaneV3_Load(p), Ng = LaneV3_Load(ng), Ns = LaneV3_Load(ns), F = LaneV3_Load(f);
        LaneV3 throughput = LaneV3_Load(thr);
        const uint strat = Rng_Key(scene.seed, pixel, 0, path[0].pathId).strat; /* the lanes' shared path id */
        const uint dim = 4u + 32u * (uint)depth;
        LaneV3 sum = LaneV3_Load(rad);
        if (neeBits)
            for (int l = 0; l < scene.numLights; ++l)
                sum = LaneV3_Add(sum, Lanes_LightSample(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) & lights[l], neeBits, P, Ng, Ns,
                                                        F, throughput, strat, sample, dim + 8u + 2u * (uint)l));
        float3 out[CLRT_LANES];
        LaneV3_Store(sum, out);
        for (int k = 0; k < CLRT_LANES; ++k) /* as render_fused: per depth, in sample order */
            if (live & (1 << k)) levelSum[min(depth, levels - 1)] += finiteOrZero(out[k]);
        live &= bounceBits;
        if (!live) break;
        float pSpec[CLRT_LANES];
        const int specBits = Lanes_PickSpecular(scene, pixel, path, hit, dim, &live, pSpec);
        LaneF u1, u2, pdf;
        Lanes_Stratified2D(strat, sample, dim + 5u, &u1, &u2);
        LaneV3 dir;
        const int diffuseBits = Lanes_Bounce(mode, live & ~specBits, Ng, Ns, F, vload4(0, pSpec), u1, u2, &throughput, &dir, &pdf);
        float3 org[CLRT_LANES], dirs[CLRT_LANES], next3[CLRT_LANES];
        float pdfs[CLRT_LANES];
        LaneV3_Store(LaneV3_Add(P, LaneV3_Scale(Ng, Lanes_OffsetDistance(P))), org); /* Ray_OffsetOrigin */
        LaneV3_Store(dir, dirs);
        LaneV3_Store(throughput, next3);
        vstore4(pdf, 0, pdfs);
        live &= diffuseBits | specBits;
        secondary += Lanes_Children(scene, materials, pixel, depth, specBits, hit, pSpec, org, dirs, next3, pdfs, path, ray, &live);
    }
    return secondary;
}

/* Parameters: src/shared/kernel_params.h (CLRT_KERNEL_render_lanes: render_fused's). A work-item: its
 * pixel's passes × samples samples of the launch, four at a time (the host gives a launch at least four
 * where the render has them), summed per depth in sample order, then added to the image. */
__kernel CLRT_KERNEL_VEC_HINT void render_lanes(CLRT_KERNEL_PARAMS(render_lanes)) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const int pixel = firstPixel + i;
    const int levels = min(CLRT_LAST_DEPTH(scene.maxDepth, scene.pathMode) + 1, CLRT_FUSED_MAX_LEVELS);
    float3 levelSum[CLRT_FUSED_MAX_LEVELS];
    for (int d = 0; d < levels; ++d) levelSum[d] = (float3)(0.0f);
    float4 acc = image[pixel];
    uint secondary = 0;
    const int px = pixel % cam.width, py = pixel / cam.width;
    const int total = passes * samples;
    for (int s = 0; s < total; s += CLRT_LANES)
        secondary += Lanes_Paths(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) pixel, px, py, firstSample + s,
                                 min(CLRT_LANES, total - s), levels, levelSum);
    for (int d = 0; d < levels; ++d) acc.xyz += levelSum[d];
    image[pixel] = acc;
    if (secondary > 0) atomic_add(&rayCounts[0], secondary);
}

#endif /* CLRT_HAS_LANES */
#endif /* CLRT_LANES_CL */
