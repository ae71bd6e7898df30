/* lanes_surface.cl — the lanes' hits (render_lanes, lanes.cl): their closest hits and what was hit
 * (Lanes_Closest), a plain world-space triangle's surface in lanes and any other hit's per lane as
 * Shade_Hit makes it (Lanes_ScalarSurface: instances, textures, bump and normal maps, spheres, planes), the
 * facing, the emission a ray sees and the material's f (Lanes_Surfaces), up to Path_ShadeHit's decisions.
 * Reads the scene's geometry, materials, textures and lights. Compiled under CLRT_HAS_LANES and
 * CLRT_HAS_PATH_TRACING only (a classic camera's lanes use Shade_Hit: lanes.cl, Lanes_Direct). */
#ifndef CLRT_LANES_SURFACE_CL
#define CLRT_LANES_SURFACE_CL

#include "fused.cl"
#include "lanes_math.cl"

#if defined(CLRT_HAS_LANES) && defined(CLRT_HAS_PATH_TRACING) /* path-traced cameras' */

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
    g->emitted[k] = Path_HitEmission(h.prim, s.frontFacing, scene, tris, triShading, spheres, lights, lightData, s.p, s.dir, s.t, s.ng,
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
        Ray r = ray[k];
        if (!Path_BoundEmissionOnly(scene, path[k], lights, lightData, &r)) continue; /* it can bring nothing: a miss's 0 */
        int instance;
        const Hit h = Ray_Closest(r, scene, nodes, leaves, tris, spheres, planes, instances, &instance);
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
    const Material m = materials[material];
    const float3 z = (float3)(0.0f, 0.0f, 1.0f);
    const ShadingPoint sp = ShadingPoint_Make((float3)(0.0f), z, z, z, m.diffuse.xyz, m.specular.xyz, m, material);
    return Material_EvalDirect(sp, materials, z, 1.0f);
}

#ifdef CLRT_HAS_LIGHT_MESH
/* For the lanes whose ray, after a non-specular bounce (bsdfPdf > 0), hit a plain triangle of a LightMesh: area[k]
 * becomes MeshLight_InvAreaPdf from the ray's origin p − t·dir (Path_ObjectLightPdf's; cosLight: the hit's
 * |cosθ_L|), for the hit's MIS density (no other lane's emission weight reads it: Lanes_EmissionWeight). */
inline void Lanes_MeshLightInvAreaPdf(const __global Light* lights, const __global float4* lightData, const LanesGather* g,
                                      LaneV3 pHit, const float3* dirs, LaneF cosLight, const float* bsdfPdf, float* area) {
    float3 p[CLRT_LANES];
    float cosL[CLRT_LANES];
    LaneV3_Store(pHit, p);
    vstore4(cosLight, 0, cosL);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((g->triBits >> k) & 1) || g->light[k] == CLRT_INVALID || !(bsdfPdf[k] > 0.0f)) continue;
        const __global Light* light = &lights[g->light[k]];
        area[k] = MeshLight_InvAreaPdf(light, lightData, g->v0[k], g->v1[k], g->v2[k], p[k] - g->t[k] * dirs[k], g->t[k], cosL[k]);
    }
}
#endif

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
                           const __global float4* lightData, int scalarLights, const LanesGather* g, int depth, const PathState* path, const Ray* ray, LanesHit* lh) {
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
    const LaneF cosL = fabs(LaneV3_Dot(ngRaw, dir));
#ifdef CLRT_HAS_LIGHT_MESH
    if (scene.pathMode & CLRT_PATH_MIS) Lanes_MeshLightInvAreaPdf(lights, lightData, g, lh->p, dirs, cosL, bsdfPdf, area);
#endif
    const LaneI front = LaneV3_Dot(dir, ngRaw) < 0.0f;
    lh->ng = LaneV3_Select(LaneV3_Scale(ngRaw, -1.0f), ngRaw, front);
    lh->ns = LaneV3_Select(LaneV3_Scale(ns, -1.0f), ns, front);
    const int mode = scene.pathMode;
    const LaneF t = vload4(0, g->t), A = vload4(0, area);
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

#endif /* CLRT_HAS_LANES && CLRT_HAS_PATH_TRACING */
#endif /* CLRT_LANES_SURFACE_CL */
