/* lanes.cl — the path tracer with four paths per work-item in float4 lanes (render_lanes; CPU devices,
 * compiled under CLRT_HAS_LANES: FeatureSet::lanes). A work-item takes its pixel's samples four at a
 * time (lane k: sample s0 + k) and steps their paths together, one depth per round:
 *   per lane, scalar: the closest hit (Ray_Closest) and the loads of what it hit (Lanes_Closest), a
 *     sphere's or plane's surface (Surface_FromHit), the material's f, the shadow rays' occlusion
 *     (Shadow_Occluded), the specular pick and a mirror's, conductor's or dielectric's child
 *     (Path_SpecularBounce), roulette;
 *   in lanes: a triangle's surface, its facing and the emission the ray sees (Lanes_Surfaces: the path
 *     branch of Shade_Hit and the start of Path_ShadeHit), the sampler (Lanes_Stratified2D), the light
 *     samples (MeshLight_PickTriangle, MeshLight_Sample, Shadow_Make, Path_LightSampleWeight,
 *     ObjectLight_AimShadow) and the bounce (Path_SampleBounce, Path_Child).
 * It computes what render_fused computes for the same random streams, up to rounding (tests/test_lanes.cpp):
 * one lane is one path of the fused kernel. Scenes of its family only (src/flatten/device_scene.h
 * lanesFamily, src/render/fused_renderer.h lanesUnsupported): the stratified sampler, one light slot, no
 * motion blur or mip-maps; every surface (a plain world-space triangle's in lanes, the others per lane:
 * Lanes_ScalarSurface, textures and instances included), every material (a direction-free f,
 * CLRT_BRDF_LAMBERTIAN, in lanes; a glossy or textured one per lane: Lanes_GlossyLightTerms,
 * Lanes_GlossyBounces) and every light (LightMesh and point lights in lanes, the others per lane:
 * Lanes_ScalarLightSample). Why lanes: a path's
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

/* The lanes' closest hits as Lanes_Closest gathers them: a plain world-space triangle's corners, corner
 * normals (smooth triangles) and barycentrics (triBits: the lane code makes its surface); any other hit's
 * surface made per lane (Lanes_ScalarSurface: p in v0, ng in n0, ns in n1, facing as Shade_Hit leaves them)
 * and emission; every hit's kd and ks (textureBits: from its textures); the radiance of a miss (Shade_Miss)
 * or of a replace_all texture. hitBits: the lanes with a surface to shade. */
typedef struct {
    float3 v0[CLRT_LANES], v1[CLRT_LANES], v2[CLRT_LANES], n0[CLRT_LANES], n1[CLRT_LANES], n2[CLRT_LANES];
    float3 radiance[CLRT_LANES];
    float3 emitted[CLRT_LANES]; /* a per-lane surface's: Path_HitEmission (a LightSphere), with lightPdf */
    float lightPdf[CLRT_LANES];
    float3 kd[CLRT_LANES], ks[CLRT_LANES]; /* the material's, or its textures' */
    float b1[CLRT_LANES], b2[CLRT_LANES], t[CLRT_LANES];
    int material[CLRT_LANES], light[CLRT_LANES];
    int hitBits, triBits, smoothBits, textureBits;
} LanesGather;

/* What the lanes' hits give the lane code (Lanes_Surfaces): the point and normals (facing the ray, as
 * Shade_Hit's path branch orients them), f (the non-specular part's value where it is direction-free),
 * the radiance that needs no shadow ray; per lane the material and the distance the ray travelled (for
 * Path_SpecularBounce); and the lanes whose hit samples the lights (nee), may have a child (bounce), is
 * specular, has a diffuse part, lies inside a dielectric, is the last vertex, is glossy. */
typedef struct {
    LaneV3 p, ng, ns, f, radiance;
    float t[CLRT_LANES];
    int material[CLRT_LANES];
    int nee, bounce, specular, diffuse, inside, lastVertex;
    int glossy;                   /* diffuse lanes whose f depends on the directions (not CLRT_BRDF_LAMBERTIAN) */
    ShadingPoint sp[CLRT_LANES];  /* ShadingPoint_Make's, for the per-lane code: the glossy lanes' (their f and
                                     pdfs), every nee lane's where a light has no lane form */
} LanesHit;

/* Shade_Hit's surface for lane k's hit h (an instance's triangle, a textured one, a sphere or a plane):
 * Surface_FromHit, the path tracer's facing, the textures (kd, ks, a bump or normal map's ns) and the
 * emission, into g. A replace_all texture (before the depth cap) gives the lane its radiance and ends it. */
inline void Lanes_ScalarSurface(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int k, Hit h, int instance, PathState path,
                                Ray ray, LanesGather* g) {
    HitTriangle ht;
    if (h.prim < scene.numTriangles) HitTriangle_Load(h, instance, tris, triShading, triAttributes, instances, &ht);
    SurfaceHit s = Surface_FromHit(h, ray, &ht, spheres, planes, scene.numTriangles, scene.numSpheres);
    if (dot(s.ns, s.ng) < 0.0f) s.ns = -s.ns; /* Shade_OrientsNormalToRay: every material when path traced */
    const __global Material* m = &materials[s.material];
    float3 kd = m->diffuse.xyz, ks = m->specular.xyz, radiance = (float3)(0.0f);
    int replaceAll = 0;
#ifdef CLRT_HAS_TEXTURES
    if (s.textureSet != CLRT_INVALID) {
        replaceAll = Shade_Textures(h, &s, scene, &ht, spheres, planes, textureSets, textures, images, texels,
                                    path.coneWidth, &kd, &ks, &radiance);
        g->textureBits |= 1 << k;
    }
#endif
    if (replaceAll && !(path.depth > scene.maxDepth)) { /* Shade_Hit's replace_all: no shading, no child */
#ifdef CLRT_HAS_OBJECT_LIGHTS
        radiance += ObjectLight_Emission(h.prim, s.frontFacing, scene.numTriangles, scene.numSpheres, triShading, spheres, lights);
#endif
        g->radiance[k] = path.throughput.xyz * radiance;
        return;
    }
    g->hitBits |= 1 << k;
    g->v0[k] = s.p; g->n0[k] = s.ng; g->n1[k] = s.ns;
    g->kd[k] = kd; g->ks[k] = ks;
    g->material[k] = s.material;
#if defined(CLRT_HAS_LIGHT_MESH) || defined(CLRT_HAS_LIGHT_SPHERE)
    g->emitted[k] = Path_HitEmission(h.prim, s.frontFacing, scene, triShading, spheres, lights, s.p, s.dir, s.t, s.ng,
                                     path.throughput.w, &g->lightPdf[k]);
#endif
}

/* The closest hits of the live lanes' rays (Ray_Closest) and what Lanes_Surfaces reads of them, per lane:
 * loads only for plain triangles; Lanes_ScalarSurface for other hits, Shade_Miss for misses. */
inline void Lanes_Closest(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int live, const PathState* path, const Ray* ray,
                          LanesGather* g) {
    g->hitBits = g->triBits = g->smoothBits = g->textureBits = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        g->v0[k] = g->v1[k] = g->v2[k] = g->n0[k] = g->n1[k] = g->n2[k] = g->radiance[k] = (float3)(0.0f);
        g->emitted[k] = g->kd[k] = g->ks[k] = (float3)(0.0f);
        g->b1[k] = g->b2[k] = g->t[k] = 0.0f;
        g->lightPdf[k] = -1.0f;
        g->material[k] = 0;
        g->light[k] = CLRT_INVALID;
        if (!(live & (1 << k))) continue;
        int instance;
        const Hit h = Ray_Closest(ray[k], scene, nodes, leaves, tris, spheres, planes, instances, &instance);
        if (h.prim == CLRT_INVALID) {
            ShadeResult res;
            Shade_Miss(scene, cam, path[k], ray[k], textures, images, texels, lights, envDist, &res);
            g->radiance[k] = res.radiance.xyz;
            continue;
        }
        g->t[k] = h.t;
        if (h.prim >= scene.numTriangles || instance != CLRT_INVALID || triShading[h.prim].textureSet != CLRT_INVALID) {
            Lanes_ScalarSurface(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) k, h, instance, path[k], ray[k], g);
            continue;
        }
        /* a plain world-space triangle: HitTriangle_Load's fields that the lanes read */
        const __global Triangle* tri = &tris[h.prim];
        const __global TriangleShading* sh = &triShading[h.prim];
        g->v0[k] = tri->v0.xyz; g->v1[k] = tri->v1.xyz; g->v2[k] = tri->v2.xyz;
        const uint attributes = sh->attributes;
        if (attributes & CLRT_TRI_NORMALS) {
            const __global float* corner = triAttributes + (attributes & CLRT_TRI_OFFSET_MASK);
            g->n0[k] = vload3(0, corner); g->n1[k] = vload3(1, corner); g->n2[k] = vload3(2, corner);
            g->smoothBits |= 1 << k;
        }
        g->b1[k] = h.u; g->b2[k] = h.v;
        g->material[k] = sh->material;
        g->kd[k] = materials[sh->material].diffuse.xyz;
        g->ks[k] = materials[sh->material].specular.xyz;
        g->light[k] = sh->light;
        g->hitBits |= 1 << k;
        g->triBits |= 1 << k;
    }
}

/* The lanes' points and normals (Surface_FromHit for triangles, in lanes; the gathered surface for the
 * rest): *ngRaw the geometric normal as stored (not yet facing the ray), *ns agreeing with it. */
inline void Lanes_Geometry(const LanesGather* g, LaneV3* p, LaneV3* ngRaw, LaneV3* ns) {
    const LaneF b1 = vload4(0, g->b1), b2 = vload4(0, g->b2), b0 = 1.0f - b1 - b2;
    const LaneV3 v0 = LaneV3_Load(g->v0), v1 = LaneV3_Load(g->v1), v2 = LaneV3_Load(g->v2);
    const LaneV3 n0 = LaneV3_Load(g->n0), n1 = LaneV3_Load(g->n1);
    const LaneV3 pTri = LaneV3_Add(LaneV3_Add(LaneV3_Scale(v0, b0), LaneV3_Scale(v1, b1)), LaneV3_Scale(v2, b2));
    const LaneV3 ngTri = LaneV3_Normalize(LaneV3_Cross(LaneV3_Sub(v1, v0), LaneV3_Sub(v2, v0)));
    const LaneV3 nsSum = LaneV3_Add(LaneV3_Add(LaneV3_Scale(n0, b0), LaneV3_Scale(n1, b1)), LaneV3_Scale(LaneV3_Load(g->n2), b2));
    const LaneF len = sqrt(LaneV3_Dot(nsSum, nsSum));
    /* a flat triangle's corner normals are its face normal: ns = ng */
    const LaneI smooth = Lane_FromBits(g->smoothBits) & (len > 0.0f) & isfinite(len);
    const LaneV3 nsTri = LaneV3_Select(ngTri, LaneV3_Scale(nsSum, 1.0f / len), smooth);
    const LaneI tri = Lane_FromBits(g->triBits);
    *p = LaneV3_Select(v0, pTri, tri);
    *ngRaw = LaneV3_Select(n0, ngTri, tri);
    /* Shade_OrientsNormalToRay (the per-lane surfaces are oriented already, before their bump maps) */
    const LaneV3 nsFacing = LaneV3_Select(nsTri, LaneV3_Scale(nsTri, -1.0f), LaneV3_Dot(nsTri, ngTri) < 0.0f);
    *ns = LaneV3_Select(n1, nsFacing, tri);
}

/* The non-specular f of material `material` (ks = 0: Material_EvalDirect's value for any pair of
 * directions above the surface; a BRDF's is 0 where wo is below ns, Lanes_Surfaces). */
inline float3 Lanes_MaterialF(const __global Material* materials, int material) {
    const __global Material* m = &materials[material];
    ShadingPoint sp;
    sp.position = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
    sp.normal = sp.geomNormal = sp.wo = (float4)(0.0f, 0.0f, 1.0f, 0.0f);
    sp.kd = (float4)(m->diffuse.xyz, 0.0f);
    sp.ks = (float4)(m->specular.xyz, m->phongExponent);
    sp.material = material;
    sp.pad0 = sp.pad1 = sp.pad2 = 0;
    return Material_EvalDirect(sp, materials, (float3)(0.0f, 0.0f, 1.0f), 1.0f);
}

/* Path_EmissionWeight for lanes. */
inline LaneF Lanes_EmissionWeight(int mode, LaneF bsdfPdf, LaneF lightPdf) {
    if (!Path_UsesNee(mode)) return (LaneF)(1.0f);
    const LaneF w = (mode & CLRT_PATH_MIS) ? select(Lanes_MisWeight(mode, bsdfPdf, lightPdf), (LaneF)(0.0f), lightPdf < 0.0f)
                                           : (LaneF)(0.0f);
    return select(w, (LaneF)(1.0f), !(bsdfPdf > 0.0f));
}

/* The ShadingPoints (ShadingPoint_Make) of the hits of the lanes in `lanes`. */
inline void Lanes_ShadingPoints(const __global Material* materials, int lanes, const LanesGather* g, LanesHit* lh,
                                const float3* dirs) {
    float3 p[CLRT_LANES], ng[CLRT_LANES], ns[CLRT_LANES];
    LaneV3_Store(lh->p, p);
    LaneV3_Store(lh->ng, ng);
    LaneV3_Store(lh->ns, ns);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((lanes >> k) & 1)) continue;
        const Material m = materials[lh->material[k]];
        lh->sp[k] = ShadingPoint_Make(p[k], ns[k], ng[k], -dirs[k], g->kd[k], g->ks[k], m, lh->material[k]);
    }
}

/* The gathered hits (Lanes_Closest) as Shade_Hit's path branch sees them, up to Path_ShadeHit's light-sample
 * and bounce decisions: geometry, facing and emission (Path_HitEmission: LightMesh, weighted by
 * Path_EmissionWeight) in lanes, the materials per lane. depth: the lanes' (they step together);
 * scalarLights: some light has no lane form (the nee lanes get ShadingPoints). */
inline void Lanes_Surfaces(SceneParams scene, const __global Material* materials, const __global Light* lights,
                           int scalarLights, const LanesGather* g, int depth, const PathState* path, const Ray* ray, LanesHit* lh) {
    float3 dirs[CLRT_LANES], thr[CLRT_LANES], fMat[CLRT_LANES], emit[CLRT_LANES];
    float bsdfPdf[CLRT_LANES], area[CLRT_LANES];
    int dielectric = 0, plain = 0, brdf = 0, glossy = 0;
    lh->specular = 0;
    for (int k = 0; k < CLRT_LANES; ++k) { /* per lane: loads */
        dirs[k] = ray[k].direction.xyz;
        thr[k] = path[k].throughput.xyz;
        bsdfPdf[k] = path[k].throughput.w;
        fMat[k] = emit[k] = (float3)(0.0f);
        area[k] = 0.0f;
        lh->t[k] = g->t[k];
        lh->material[k] = g->material[k];
        if (!(g->hitBits & (1 << k))) continue;
        const __global Material* m = &materials[g->material[k]];
        const int kind = m->kind;
        lh->specular |= (kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR || kind == MATERIAL_DIELECTRIC) << k;
        dielectric |= (kind == MATERIAL_DIELECTRIC) << k;
        brdf |= (m->brdf != CLRT_INVALID) << k;
        if (maxComponent(g->kd[k]) > 0.0f || maxComponent(g->ks[k]) > 0.0f) {
            plain |= 1 << k;
            if (!(m->brdfFlags & CLRT_BRDF_LAMBERTIAN) || ((g->textureBits >> k) & 1)) { /* textures: kd, ks per hit */
                glossy |= 1 << k;
            } else {
                int j = 0; /* a lane before with the same material has its f (the pixel's lanes often do) */
                while (j < k && !((plain & ~glossy) >> j & 1 && g->material[j] == g->material[k])) ++j;
                fMat[k] = j < k ? fMat[j] : Lanes_MaterialF(materials, g->material[k]);
            }
        }
#ifdef CLRT_HAS_LIGHT_MESH
        if (g->light[k] != CLRT_INVALID) { emit[k] = lights[g->light[k]].radiance.xyz; area[k] = lights[g->light[k]].area; }
#endif
    }
    LaneV3 ngRaw, ns;
    Lanes_Geometry(g, &lh->p, &ngRaw, &ns);
    const LaneV3 dir = LaneV3_Load(dirs);
    const LaneI front = LaneV3_Dot(dir, ngRaw) < 0.0f;
    lh->ng = LaneV3_Select(LaneV3_Scale(ngRaw, -1.0f), ngRaw, front);
    lh->ns = LaneV3_Select(LaneV3_Scale(ns, -1.0f), ns, front);
    const int mode = scene.pathMode;
    const LaneF t = vload4(0, g->t), A = vload4(0, area), cosL = fabs(LaneV3_Dot(ngRaw, dir));
    const LaneI tri = Lane_FromBits(g->triBits);
    LaneF lightPdf = select((LaneF)(0.0f), t * t / (A * cosL), (cosL > 0.0f) & (A > 0.0f));
    lightPdf = select(vload4(0, g->lightPdf), lightPdf, tri);
    const LaneF weight = Lanes_EmissionWeight(mode, vload4(0, bsdfPdf), lightPdf); /* emit 0 where no light */
    const LaneV3 emitted = LaneV3_Select(LaneV3_Load(g->emitted), LaneV3_Load(emit), tri);
    const LaneV3 radiance = LaneV3_FiniteOrZero(LaneV3_Scale(LaneV3_Mul(LaneV3_Load(thr), emitted), weight));
    lh->radiance = LaneV3_Select(LaneV3_Load(g->radiance), radiance, Lane_FromBits(g->hitBits));
    /* a BRDF is 0 where wo lies below ns (Brdf_Eval) */
    const LaneI fZero = Lane_FromBits(brdf) & !(LaneV3_Dot(lh->ns, dir) < 0.0f);
    lh->f = LaneV3_Select(LaneV3_Load(fMat), LaneV3_Splat((float3)(0.0f)), fZero);
    lh->inside = dielectric & ~Lane_Bits(front); /* Shade_Hit's insideDielectric */
    lh->diffuse = plain & ~lh->inside;
    const int emissionOnly = depth > scene.maxDepth, lastVertex = depth >= scene.maxDepth;
    lh->nee = Path_UsesNee(mode) && !emissionOnly ? lh->diffuse : 0;
    lh->bounce = !emissionOnly && !(lastVertex && !(mode & CLRT_PATH_MIS)) ? (lh->specular | lh->diffuse) : 0;
    lh->lastVertex = lastVertex ? g->hitBits : 0;
    lh->glossy = glossy & lh->diffuse & (lh->nee | lh->bounce);
    const int points = lh->glossy | (scalarLights ? lh->nee : 0);
    if (points) Lanes_ShadingPoints(materials, points, g, lh, dirs);
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
/* MeshLight_PickTriangle for the lanes: the first of the light's n triangles whose cumulative area
 * fraction (the w of its first vertex) exceeds u (the last if none), by a binary search of fixed steps
 * (the count of those at or below u: the same triangle for a non-decreasing table); *uRest as there. */
inline LaneI Lanes_PickTriangle(const __global float4* tri, int n, LaneF u, LaneF* uRest) {
    LaneI pos = (LaneI)(0);
    int step = 1;
    while (step * 2 <= n - 1) step *= 2;
    for (; step > 0 && n > 1; step >>= 1) {
        const LaneI next = pos + step;
        int idx[CLRT_LANES];
        float c[CLRT_LANES];
        vstore4(min(next, n - 1) - 1, 0, idx);
        for (int k = 0; k < CLRT_LANES; ++k) c[k] = tri[3 * idx[k]].w;
        pos = select(pos, next, (next <= n - 1) & (vload4(0, c) <= u));
    }
    int at[CLRT_LANES];
    float c0[CLRT_LANES], c1[CLRT_LANES];
    vstore4(pos, 0, at);
    for (int k = 0; k < CLRT_LANES; ++k) {
        const int i = at[k];
        c0[k] = i > 0 ? tri[3 * (i - 1)].w : 0.0f;
        c1[k] = tri[3 * i].w;
    }
    const LaneF lo = vload4(0, c0), hi = vload4(0, c1);
    *uRest = select((LaneF)(0.5f), clamp((u - lo) / (hi - lo), 0.0f, 0.99999994f), hi > lo);
    return pos;
}

/* MeshLight_Sample for the lanes at p: *wi, *dist (MeshLight_ShadowLength's), the radiance estimate *e
 * (0 where the sample fails), and the light's point's offset distance; u: the lanes' 2D sample. */
inline void Lanes_MeshLightSample(const __global Light* light, const __global float4* lightData, LaneV3 p, LaneF u1,
                                  LaneF u2, LaneV3* wi, LaneF* dist, LaneV3* e) {
    const __global float4* tri = lightData + light->objFirst;
    LaneF ux;
    const LaneI pick = Lanes_PickTriangle(tri, light->objCount, u1, &ux);
    int at[CLRT_LANES];
    float3 v0[CLRT_LANES], v1[CLRT_LANES], v2[CLRT_LANES];
    vstore4(pick, 0, at);
    for (int k = 0; k < CLRT_LANES; ++k) {
        const int t = at[k];
        v0[k] = tri[3 * t].xyz; v1[k] = tri[3 * t + 1].xyz; v2[k] = tri[3 * t + 2].xyz;
    }
    const LaneV3 a = LaneV3_Load(v0), b = LaneV3_Load(v1), c = LaneV3_Load(v2);
    const LaneF su = sqrt(ux);
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

/* f·cosθ towards wi and Path_BouncePdf's density of wi at the glossy lanes' hits, per lane (Shadow_Make's
 * Material_EvalDirect, Path_LightSampleWeight's pdf); the other lanes keep *fCos and *bouncePdf. */
inline void Lanes_GlossyLightTerms(const __global Material* materials, int mode, int glossy, const ShadingPoint* sp,
                                   LaneV3 wi, LaneF cosTheta, LaneV3* fCos, LaneF* bouncePdf) {
    float3 w[CLRT_LANES], fc[CLRT_LANES];
    float c[CLRT_LANES], pdf[CLRT_LANES];
    LaneV3_Store(wi, w);
    LaneV3_Store(*fCos, fc);
    vstore4(cosTheta, 0, c);
    vstore4(*bouncePdf, 0, pdf);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((glossy >> k) & 1)) continue;
        fc[k] = c[k] > 0.0f ? Material_EvalDirect(sp[k], materials, w[k], c[k]) : (float3)(0.0f);
        pdf[k] = Path_BouncePdf(sp[k], materials, mode, w[k]);
    }
    *fCos = LaneV3_Load(fc);
    *bouncePdf = vload4(0, pdf);
}

/* The lanes' light samples of light `light` (LightMesh or PointLight) at their hits (those in hit->nee):
 * as Light_ShadowRays and Fused_Shadow, the unoccluded contributions (MIS-weighted, times the throughput). */
inline LaneV3 Lanes_LightSample(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) const __global Light* light, const LanesHit* hit,
                                LaneV3 throughput, uint strat, LaneU sample, uint dim) {
    const LaneV3 zero = LaneV3_Splat((float3)(0.0f)), p = hit->p, ng = hit->ng, ns = hit->ns;
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
    const int mode = scene.pathMode;
    const LaneF cosTheta = LaneV3_Dot(ns, wi);
    LaneI ok = Lane_FromBits(hit->nee) & (cosTheta > 0.0f) & (LaneV3_Max(e) > 0.0f);
    LaneV3 fCos = LaneV3_Scale(hit->f, cosTheta);
    LaneF bouncePdf = Path_UsesImportance(mode) ? cosTheta * CLRT_INV_PI : (LaneF)(0.5f * CLRT_INV_PI);
    if (hit->glossy & hit->nee)
        Lanes_GlossyLightTerms(materials, mode, hit->glossy & hit->nee, hit->sp, wi, cosTheta, &fCos, &bouncePdf);
    LaneV3 contrib = LaneV3_FiniteOrZero(LaneV3_Mul(LaneV3_Mul(throughput, fCos), e));
    if (mesh && (mode & CLRT_PATH_MIS)) { /* Path_LightSampleWeight: a point light's weight is 1 */
        const LaneF lightPdf = maxComponent(light->radiance.xyz) / LaneV3_Max(e);
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

/* Whether light l's samples have a lane form (Lanes_LightSample): LightMesh and point lights. */
inline int Lanes_HasLaneForm(const __global Light* light) { return light->kind == LIGHT_MESH || light->kind == LIGHT_POINT; }

/* Light l's samples at the lanes in hit->nee through clrt's scalar Light_ShadowRays and Fused_Shadow, per lane
 * (the light kinds without a lane form: area, sphere, spot and directional lights, environment maps with
 * one light slot): each lane's path, ShadingPoint and random stream as render_fused's. */
inline LaneV3 Lanes_ScalarLightSample(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int l, const LanesHit* hit,
                                      const PathState* path, int pixel) {
    float3 out[CLRT_LANES];
    for (int k = 0; k < CLRT_LANES; ++k) {
        out[k] = (float3)(0.0f);
        if (!((hit->nee >> k) & 1)) continue;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        ShadowRay sr, unused;
        Light_ShadowRays(scene, path[k], hit->sp[k], l, 1, key, materials, lights, images, texels, envDist, lightData, &sr,
                         &unused);
        out[k] = Fused_Shadow(sr, scene, nodes, leaves, tris, spheres, planes, instances).xyz;
    }
    return LaneV3_Load(out);
}

/* Path_SampleBounce at the glossy lanes' hits, per lane, with the lanes' sample u: their *dir, *pdf and
 * *fCos (0 where the sample carries nothing); the other lanes keep theirs. */
inline void Lanes_GlossyBounces(const __global Material* materials, int mode, int glossy, const ShadingPoint* sp, LaneF u1,
                                LaneF u2, LaneV3* dir, LaneF* pdf, LaneV3* fCos) {
    float3 d[CLRT_LANES], fc[CLRT_LANES];
    float a[CLRT_LANES], b[CLRT_LANES], pd[CLRT_LANES];
    LaneV3_Store(*dir, d);
    LaneV3_Store(*fCos, fc);
    vstore4(u1, 0, a);
    vstore4(u2, 0, b);
    vstore4(*pdf, 0, pd);
    for (int k = 0; k < CLRT_LANES; ++k)
        if ((glossy >> k) & 1) fc[k] = Path_SampleBounce(sp[k], materials, mode, (float2)(a[k], b[k]), &d[k], &pd[k]);
    *dir = LaneV3_Load(d);
    *fCos = LaneV3_Load(fc);
    *pdf = vload4(0, pd);
}

/* The lanes' non-specular bounces (Path_SampleBounce; the glossy lanes' per lane) for the lanes in
 * bounceBits, picked with probability 1 − pSpecular: *dir, *pdf and the new throughput; the lanes in the
 * returned bits carry a child. */
inline int Lanes_Bounce(const __global Material* materials, int mode, int bounceBits, const LanesHit* hit, LaneF pSpecular,
                        LaneF u1, LaneF u2, LaneV3* throughput, LaneV3* dir, LaneF* pdf) {
    const int cosine = Path_UsesImportance(mode);
    const LaneV3 ng = hit->ng, ns = hit->ns;
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
    LaneV3 fCos = LaneV3_Scale(hit->f, LaneV3_Dot(ns, *dir));
    if (hit->glossy & bounceBits)
        Lanes_GlossyBounces(materials, mode, hit->glossy & bounceBits, hit->sp, u1, u2, dir, pdf, &fCos);
    const LaneI ok = Lane_FromBits(bounceBits) & (LaneV3_Dot(ns, *dir) > 0.0f) & (LaneV3_Dot(ng, *dir) > 0.0f) &
                     (*pdf > 0.0f) & LaneV3_Finite(*dir);
    const LaneF q = *pdf * (1.0f - pSpecular);
    const LaneV3 weight = LaneV3_Make(fCos.x / q, fCos.y / q, fCos.z / q); /* f·cosθ / (pdf·(1 − pSpecular)) */
    *throughput = LaneV3_Mul(*throughput, weight);
    return Lane_Bits(ok & (LaneV3_Max(weight) > 0.0f));
}

/* Path_ShadeHit's pick at the live lanes' hits: a specular child with probability pSpecular (½ beside a
 * diffuse part, else 1; *pSpec per lane, 0 where no specular material); returns the lanes that take it.
 * A pick at the last vertex ends the lane's path (its only child there is the BSDF sample). */
inline int Lanes_PickSpecular(SceneParams scene, int pixel, const PathState* path, const LanesHit* hit, uint dim, int* live,
                              float* pSpec) {
    int specBits = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        pSpec[k] = 0.0f;
        if (!(*live & hit->specular & (1 << k))) continue;
        pSpec[k] = (hit->diffuse >> k) & 1 ? 0.5f : 1.0f;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        if (!(Rng_Uniform(key, dim + 3u) < pSpec[k])) continue;
        if ((hit->lastVertex >> k) & 1) *live &= ~(1 << k);
        else specBits |= 1 << k;
    }
    return specBits;
}

/* Path_SpecularBounce for the lanes in specBits (their hits: hit, p, ns, ng per lane): *org, dirs and
 * *weight per lane; a lane whose bounce fails leaves specBits (returned). */
inline int Lanes_SpecularBounces(SceneParams scene, const __global Material* materials, int pixel, uint dim, int specBits,
                                 const LanesHit* hit, const PathState* path, const Ray* ray, float3* org, float3* dirs,
                                 float3* weight) {
    float3 p[CLRT_LANES], ns[CLRT_LANES], ng[CLRT_LANES];
    LaneV3_Store(hit->p, p);
    LaneV3_Store(hit->ns, ns);
    LaneV3_Store(hit->ng, ng);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((specBits >> k) & 1)) continue;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        const float2 uGlossy = (float2)(Rng_Uniform(key, dim), Rng_Uniform(key, dim + 1u));
        if (!Path_SpecularBounce(materials[hit->material[k]], -ray[k].direction.xyz, ns[k], ng[k], p[k], hit->t[k],
                                 (hit->inside >> k) & 1, Rng_Uniform(key, dim + 2u), uGlossy, &weight[k], &org[k], &dirs[k]))
            specBits &= ~(1 << k);
    }
    return specBits;
}

/* Path_Child (child 0) of each live lane, after Path_RussianRoulette: the specular lanes' child from
 * Path_SpecularBounce (specWeight), the others' from the lanes' bounce (org, dirs, next3, pdfs). Every
 * lane's path id moves on (they share it). Returns the children made; *live keeps the lanes that have one. */
inline uint Lanes_Children(SceneParams scene, int pixel, int depth, int specBits, const float* pSpec, const float3* org,
                           const float3* dirs, const float3* next3, const float3* specWeight, const float* pdfs,
                           PathState* path, Ray* ray, int* live) {
    const int mode = scene.pathMode;
    const uint dim = 4u + 32u * (uint)depth;
    uint children = 0;
    for (int k = 0; k < CLRT_LANES; ++k) { /* Path_Child (child 0), after Path_RussianRoulette */
        const uint id = path[k].pathId;
        path[k].pathId = id < 0x80000000u ? id * 2u : id; /* every lane: they share it */
        if (!(*live & (1 << k))) continue;
        const int spec = (specBits >> k) & 1, roulette = (mode & CLRT_PATH_RR) && depth >= scene.rrMinDepth;
        float3 next = spec ? path[k].throughput.xyz * (specWeight[k] / pSpec[k]) : next3[k];
        if (roulette && !Path_RussianRoulette(&next, Rng_Uniform(Rng_Key(scene.seed, pixel, path[k].sample, id), dim + 4u))) {
            *live &= ~(1 << k);
            continue;
        }
        if (!(maxComponent(next) > 0.0f) || !allFinite3(next) || !allFinite3(dirs[k])) { *live &= ~(1 << k); continue; }
        path[k].throughput = (float4)(next, spec ? 0.0f : pdfs[k]);
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
    int scalarLights = 0;
    for (int l = 0; l < scene.numLights; ++l) scalarLights |= !Lanes_HasLaneForm(&lights[l]);
    uint secondary = 0;
    for (int depth = 0; live; ++depth) {
        LanesGather g;
        Lanes_Closest(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) live, path, ray, &g);
        LanesHit hit;
        Lanes_Surfaces(scene, materials, lights, scalarLights, &g, depth, path, ray, &hit);
        float3 thr[CLRT_LANES];
        for (int k = 0; k < CLRT_LANES; ++k) thr[k] = path[k].throughput.xyz;
        LaneV3 throughput = LaneV3_Load(thr);
        const uint strat = Rng_Key(scene.seed, pixel, 0, path[0].pathId).strat; /* the lanes' shared path id */
        const uint dim = 4u + 32u * (uint)depth;
        LaneV3 sum = hit.radiance;
        for (int l = 0; l < scene.numLights && hit.nee; ++l)
            sum = LaneV3_Add(sum, Lanes_HasLaneForm(&lights[l])
                                      ? Lanes_LightSample(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) & lights[l], &hit,
                                                          throughput, strat, sample, dim + 8u + 2u * (uint)l)
                                      : Lanes_ScalarLightSample(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) l, &hit, path, pixel));
        float3 out[CLRT_LANES];
        LaneV3_Store(sum, out);
        for (int k = 0; k < CLRT_LANES; ++k) /* as render_fused: per depth, in sample order */
            if (live & (1 << k)) levelSum[min(depth, levels - 1)] += finiteOrZero(out[k]);
        live &= hit.bounce;
        if (!live) break;
        float pSpec[CLRT_LANES];
        float3 org[CLRT_LANES], dirs[CLRT_LANES], next3[CLRT_LANES], specWeight[CLRT_LANES];
        int specBits = Lanes_PickSpecular(scene, pixel, path, &hit, dim, &live, pSpec);
        LaneF u1, u2, pdf;
        Lanes_Stratified2D(strat, sample, dim + 5u, &u1, &u2);
        LaneV3 dir;
        const int diffuseBits = Lanes_Bounce(materials, mode, live & ~specBits, &hit, vload4(0, pSpec), u1, u2, &throughput,
                                             &dir, &pdf);
        float pdfs[CLRT_LANES];
        LaneV3_Store(LaneV3_Add(hit.p, LaneV3_Scale(hit.ng, Lanes_OffsetDistance(hit.p))), org); /* Ray_OffsetOrigin */
        LaneV3_Store(dir, dirs);
        LaneV3_Store(throughput, next3);
        vstore4(pdf, 0, pdfs);
        if (specBits) {
            const int ok = Lanes_SpecularBounces(scene, materials, pixel, dim, specBits, &hit, path, ray, org, dirs, specWeight);
            live &= ~(specBits & ~ok);
            specBits = ok;
        }
        live &= diffuseBits | specBits;
        secondary += Lanes_Children(scene, pixel, depth, specBits, pSpec, org, dirs, next3, specWeight, pdfs, path, ray, &live);
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
