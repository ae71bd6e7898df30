/* path.cl — path tracing in the wavefront (<Renderer>PathTracing, <RendererParams>: SceneParams.pathMode,
 * CLRT_PATH_* bits, set per camera; compiled under CLRT_HAS_PATH_TRACING only). shade_hits hands every
 * hit of a path-traced camera to Path_ShadeHit, which
 *   - adds the emission the ray sees (Path_EmissionWeight: whole for camera rays and specular
 *     bounces; with NextEventEstimation discarded when the previous vertex sampled the lights, as
 *     the course asks; with MultipleImportanceSampling weighted by the power heuristic),
 *   - leaves a ShadingPoint for sample_lights (next-event estimation) when the surface has a
 *     non-specular part (kd or ks), and no ambient term,
 *   - plays Russian roulette (Path_RussianRoulette: q = the throughput's largest component, at most
 *     1, and C = 0; with RussianRoulette there is no depth cap, as the course's references show) at
 *     hits of depth SceneParams.rrMinDepth or deeper (the camera's MinRecursionDepth; 0: all), or
 *     under clrt render --rr-rule course (CLRT_PATH_RR_COURSE) the course references' biased rule
 *     (Path_CourseRoulette, played at every hit before its radiance is counted),
 *   - makes ONE child (ShadeResult child 0; the wavefront's slot 2i): the sampled direction with
 *     throughput · f·cosθ / pdf.
 *     At the depth cap it makes none, except under MIS: there the non-specular BSDF sample still goes
 *     out, as an emission-only segment (depth maxDepth + 1: MIS-weighted emission of an object or
 *     environment light, no light samples, no child), so the last vertex's light samples keep their
 *     power-heuristic weight (as Mitsuba's path; docs/studies/2026-12-04-mitsuba-path.md, addendum). Every
 *     pipeline tests that segment against a few object lights alone first (Path_BoundEmissionOnly: render_fused,
 *     the lanes, the wavefront's shade_hits for the child it queues).
 * PathState.throughput.w: the solid-angle pdf of the BSDF sample that made the path (0: a camera ray
 * or a specular bounce); under CLRT_PATH_RR_COURSE instead ±sigma (Path_CourseSigma): + after a BSDF
 * bounce, − after a specular one, 0 for a camera ray (sigma 1).
 * Sampling (Path_SampleBounce): uniform over the hemisphere (pdf 1/2π) by default; with
 * ImportanceSampling (or MIS) the BRDF's own sampler (Brdf_Sample) for BRDF materials and cosine
 * (pdf cosθ/π) for classic ones. Classic materials (no BRDF) are path traced with the reflectance
 * their direct light implies, f·cosθ = kd·cosθ + ks·cos^p αh (Material_EvalDirect: the course's
 * un-normalized Blinn-Phong), so NEE and BSDF sampling estimate the same integral.
 * Mirror, conductor, dielectric: their specular child (a dielectric picks reflection or refraction by
 * its Fresnel weight, never splits), chosen with probability 1/2 against the non-specular part when
 * the material has kd or ks, else always. Under the course rule instead every child is traced
 * (Path_CourseSpecularChildren: a dielectric's reflection and refraction, and the lobe as child 2). */
#ifndef CLRT_PATH_CL
#define CLRT_PATH_CL

#include "../src/shared/device_types.h"
#include "common.cl"
#include "envmap.cl"
#include "brdf.cl"
#include "material.cl"
#include "object_lights.cl"
#include "intersect.cl"

#ifdef CLRT_HAS_PATH_TRACING

/* Does the path's previous vertex sample the lights? */
inline int Path_UsesNee(int mode) { return (mode & (CLRT_PATH_NEE | CLRT_PATH_MIS)) != 0; }
inline int Path_UsesImportance(int mode) { return (mode & (CLRT_PATH_IMPORTANCE | CLRT_PATH_MIS)) != 0; }

/* The MIS weight of a sample drawn with density pa where the other strategy has density pb, one sample of
 * each: the power heuristic, or under CLRT_PATH_MIS_BALANCE the balance heuristic, under
 * CLRT_PATH_MIS_MAXIMUM the maximum heuristic (1 to the larger density, ½ each on a tie). Every one sums
 * to 1 over the two strategies, so the image's expectation is the same; the noise differs. */
inline float Path_MisWeight(int mode, float pa, float pb) {
    if (mode & CLRT_PATH_MIS_MAXIMUM) return pa > pb ? 1.0f : (pa == pb && pa > 0.0f ? 0.5f : 0.0f);
    const int balance = (mode & CLRT_PATH_MIS_BALANCE) != 0;
    const float a = balance ? pa : pa * pa, b = balance ? pb : pb * pb;
    return a + b > 0.0f && isfinite(a + b) ? a / (a + b) : (pa > 0.0f ? 1.0f : 0.0f);
}

/* The weight of emission reached by a BSDF ray whose pdf was bsdfPdf (0: camera or specular) where
 * light sampling would have drawn the same direction with solid-angle pdf lightPdf. */
inline float Path_EmissionWeight(int mode, float bsdfPdf, float lightPdf) {
    if (!(bsdfPdf > 0.0f) || !Path_UsesNee(mode)) return 1.0f;
    /* course NEE, or a light whose sampling density is not known here: it was sampled there already */
    if (!(mode & CLRT_PATH_MIS) || lightPdf < 0.0f) return 0.0f;
    return Path_MisWeight(mode, bsdfPdf, lightPdf);
}

/* The solid-angle density with which sample_lights draws direction dirWorld from an environment light,
 * or -1 where it depends on the shading normal (the cosine and mis env strategies: such a light keeps the
 * course's NEE rule under MIS). */
inline float Path_EnvLightPdf(const __global Light* light, const __global float* envDist, float3 dirWorld) {
#ifdef CLRT_HAS_ENV_LIGHT
    if (light->envStrategy == ENV_STRATEGY_UNIFORM) return 0.5f * CLRT_INV_PI;
    if (light->envStrategy == ENV_STRATEGY_IMPORTANCE && light->distribution != CLRT_INVALID)
        return EnvDist_PdfUv(envDist + light->distribution, EnvMap_DirToUv(light->mapping, EnvLight_ToMap(light, dirWorld)));
#endif
    return -1.0f;
}

/* The weight of what a ray that leaves the scene brings back from environment light `envLight` (weighted
 * against that light's own samples), or from the background colour (envLight 0: the scene has no
 * environment light). */
inline float Path_MissWeight(SceneParams scene, PathState path, const __global Light* envLight,
                             const __global float* envDist, float3 dirWorld) {
    /* a background colour is no light: never sampled; beyond the depth cap (MIS's emission-only segment) unseen */
    if (!envLight) return path.depth > scene.maxDepth ? 0.0f : 1.0f;
    float l = length(dirWorld);
    if (!(l > 0.0f)) return 0.0f;
    float lightPdf = (scene.pathMode & CLRT_PATH_MIS) ? Path_EnvLightPdf(envLight, envDist, dirWorld / l) : -1.0f;
    return Path_EmissionWeight(scene.pathMode, path.throughput.w, lightPdf);
}

/* ---- the emission-only segment against the object lights alone ---------------------------------------
 * The segment (depth maxDepth + 1, MIS) brings back only the emission of an object light it hits first; a miss
 * or any other hit brings nothing when the scene has no environment light (Path_MissWeight: the background is
 * unseen there). Where the lights a ray can hit are a few primitives (SceneParams.emitterTest), the ray is first
 * tested against them alone: one that meets none is not traced; one that does is traced only up to the nearest
 * (the closest hit is the same: a box entered beyond it holds nothing closer). */
#define CLRT_EMITTER_DISTANCE_WIDEN 1.0001f /* the bound over that distance (the BVH's own test rounds as it will) */

/* The distance from org along dir to the nearest object-light primitive (their lightData copies, flatten_lights.cpp:
 * a LightMesh's world-space triangles, a LightSphere's dev::Sphere rows) before tMax, INFINITY if none. */
inline float Path_EmitterDistance(SceneParams scene, const __global Light* lights, const __global float4* lightData,
                                  float3 org, float3 dir, float tMax) {
    if (!(Aabb_Intersect(scene.emitterLo, scene.emitterHi, org, safeInverse(dir), tMax) < INFINITY)) return INFINITY;
    const RayShear shear = RayShear_Make(dir);
    float tNear = tMax;
    int found = 0;
    for (int l = 0; l < scene.numLights; ++l) {
        const __global Light* light = &lights[l];
        const __global float4* d = lightData + light->objFirst;
        float t, b1, b2;
#ifdef CLRT_HAS_LIGHT_MESH
        if (light->kind == LIGHT_MESH)
            for (int i = 0; i < light->objCount; ++i)
                if (Triangle_Intersect(org, shear, d[3 * i].xyz, d[3 * i + 1].xyz, d[3 * i + 2].xyz, tNear, 0, 0.0f, &t, &b1, &b2)) {
                    tNear = t;
                    found = 1;
                }
#endif
#ifdef CLRT_HAS_LIGHT_SPHERE
        if (light->kind == LIGHT_SPHERE && Sphere_Intersect((const __global Sphere*)d, org, dir, tNear, &t)) {
            tNear = t;
            found = 1;
        }
#endif
    }
    return found ? tNear : INFINITY;
}

/* Whether ray r of path needs tracing: 0 for an emission-only segment that meets no object light (under
 * SceneParams.emitterTest); one that does has its tMax (r->direction.w) cut to just past the nearest. */
inline int Path_BoundEmissionOnly(SceneParams scene, PathState path, const __global Light* lights,
                                  const __global float4* lightData, Ray* r) {
    if (!scene.emitterTest || path.depth <= scene.maxDepth || !(r->direction.w > 0.0f)) return 1;
    const float tLight = Path_EmitterDistance(scene, lights, lightData, r->origin.xyz, r->direction.xyz, r->direction.w);
    if (!(tLight < INFINITY)) return 0;
    r->direction.w = fmin(r->direction.w, tLight * CLRT_EMITTER_DISTANCE_WIDEN);
    return 1;
}

#if defined(CLRT_HAS_LIGHT_MESH) || defined(CLRT_HAS_LIGHT_SPHERE)
/* The solid-angle density with which sample_lights draws the point pHit a ray hit on object light
 * `light` (from origin = pHit − t·dirWorld; ngWorld: the geometric normal there; s: a LightSphere's 7
 * float4s, object_lights.cl; tri: a LightMesh's triangle hit): LightMesh: a point of that triangle,
 * t²/(cosθ_L·MeshLight_InvAreaPdf(origin)); LightSphere under a similarity: a direction in its cone,
 * 1/(2π(1 − cosθmax)) (1/4π from inside); any other LightSphere: the object-space cone's, times
 * dω_obj/dω_world. */
inline float Path_ObjectLightPdf(const __global Light* light, const __global float4* s, const __global Triangle* tri,
                                 const __global float4* lightData, float3 pHit, float3 dirWorld, float t, float3 ngWorld) {
    float3 origin = pHit - t * dirWorld;
    if (light->kind == LIGHT_MESH) {
        const float cosL = fabs(dot(ngWorld, dirWorld));
        const float invAreaPdf = MeshLight_InvAreaPdf(light, lightData, tri->v0.xyz, tri->v1.xyz, tri->v2.xyz, origin, t, cosL);
        return cosL > 0.0f && invAreaPdf > 0.0f ? t * t / (invAreaPdf * cosL) : 0.0f;
    }
    float3 axis = light->position.xyz - origin;
    float R = light->objRadius, scale = 1.0f;
    if (light->objCount != 0) { /* the cone in object space, times dω_obj/dω_world */
        axis = s[0].xyz - (float3)(dot(s[1].xyz, origin) + s[1].w, dot(s[2].xyz, origin) + s[2].w,
                                   dot(s[3].xyz, origin) + s[3].w);
        R = s[0].w;
        scale = SphereLight_DirectionScale(light, s, dirWorld);
    }
    float d2 = dot(axis, axis);
    if (!(d2 > R * R)) return light->objCount != 0 ? 0.0f : 0.25f * CLRT_INV_PI;
    float sin2Max = R * R / d2, cosMax = sqrt(fmax(0.0f, 1.0f - sin2Max));
    return scale / (2.0f * CLRT_PI * (sin2Max / (1.0f + cosMax)));
}

/* What a ray sees emitted where it hit primitive `prim` (the emitting side of an object light, as
 * object_lights.cl's ObjectLight_Emission: LightMesh either face, LightSphere outside), and the
 * density light sampling draws that point with (*lightPdf). bsdfPdf: the pdf of the bounce that made
 * the ray (0: a camera ray or a specular bounce, which see the Radiance itself); after a non-specular
 * bounce a LightSphere gives Radiance·dω_obj/dω_world, as its light samples do. */
inline float3 Path_HitEmission(int prim, int frontFacing, SceneParams scene, const __global Triangle* tris,
                               const __global TriangleShading* shading, const __global Sphere* spheres,
                               const __global Light* lights, const __global float4* lightData, float3 pHit,
                               float3 dirWorld, float t, float3 ngWorld, float bsdfPdf, float* lightPdf) {
    int light = CLRT_INVALID;
    const __global float4* s = 0;
    if (prim < scene.numTriangles) light = shading[prim].light;
    else if (prim < scene.numTriangles + scene.numSpheres) {
        light = spheres[prim - scene.numTriangles].light;
        s = (const __global float4*)&spheres[prim - scene.numTriangles]; /* centre/radius, worldToObject, objectToWorld */
    }
    if (light == CLRT_INVALID || (!frontFacing && s != 0)) return (float3)(0.0f); /* a LightSphere's inside */
    /* only MIS weighs a BSDF ray's emission by the light's density (Path_EmissionWeight); *lightPdf stays -1 */
    if ((scene.pathMode & CLRT_PATH_MIS) && bsdfPdf > 0.0f)
        *lightPdf = Path_ObjectLightPdf(&lights[light], s, prim < scene.numTriangles ? &tris[prim] : tris, lightData, pHit,
                                        dirWorld, t, ngWorld);
    float scale = s != 0 && bsdfPdf > 0.0f ? SphereLight_DirectionScale(&lights[light], s, dirWorld) : 1.0f;
    return lights[light].radiance.xyz * scale;
}
#endif

/* The density Path_SampleBounce draws wi with, for MIS (solid angle; 0 below the surface). */
inline float Path_BouncePdf(ShadingPoint sp, const __global Material* materials, int mode, float3 wi) {
    float c = dot(sp.normal.xyz, wi);
    if (!(c > 0.0f)) return 0.0f;
    if (!Path_UsesImportance(mode)) return 0.5f * CLRT_INV_PI;
#ifdef CLRT_HAS_BRDFS
    const __global Material* m = &materials[sp.material];
    if (m->brdf != CLRT_INVALID) {
        BrdfParams b;
        Brdf_FromMaterial(&b, m, sp.kd.xyz, sp.ks.xyz);
        return Brdf_Pdf(&b, sp.normal.xyz, sp.wo.xyz, wi);
    }
#endif
    return c * CLRT_INV_PI;
}

/* The MIS weight of a light sample (sample_lights) in direction wi: Path_MisWeight against the
 * BSDF sampling of the same direction for lights a BSDF ray can reach (environment lights with a
 * normal-independent env strategy, object lights); 1 for every other light and without
 * MultipleImportanceSampling. e: what Light_Sample returned. */
inline float Path_LightSampleWeight(int mode, const __global Light* light, ShadingPoint sp,
                                    const __global Material* materials, const __global float* envDist,
                                    const __global float4* lightData, float3 wi, float3 e) {
    if (!(mode & CLRT_PATH_MIS)) return 1.0f;
    float lightPdf = -1.0f;
    if (light->kind == LIGHT_ENVIRONMENT) lightPdf = Path_EnvLightPdf(light, envDist, wi);
#if defined(CLRT_HAS_LIGHT_MESH) || defined(CLRT_HAS_LIGHT_SPHERE)
    /* object lights return radiance · dω_obj/dω_world / pdf(wi) (object_lights.cl) */
    if ((light->kind == LIGHT_MESH || light->kind == LIGHT_SPHERE) && maxComponent(e) > 0.0f) {
        float scale = light->kind == LIGHT_SPHERE ? SphereLight_DirectionScale(light, lightData + light->objFirst, wi) : 1.0f;
        lightPdf = maxComponent(light->radiance.xyz) * scale / maxComponent(e);
    }
#endif
    if (lightPdf < 0.0f) return 1.0f;
    return Path_MisWeight(mode, lightPdf, Path_BouncePdf(sp, materials, mode, wi));
}

/* Draws the non-specular bounce at sp: *wi, *pdf, and returns f·cosθ (0 when the sample carries nothing). */
inline float3 Path_SampleBounce(ShadingPoint sp, const __global Material* materials, int mode, float2 u, float3* wi,
                                float* pdf) {
    float3 n = sp.normal.xyz;
    *pdf = 0.0f;
    *wi = n;
    int sampled = 0;
#ifdef CLRT_HAS_BRDFS
    const __global Material* m = &materials[sp.material];
    if (Path_UsesImportance(mode) && m->brdf != CLRT_INVALID) {
        BrdfParams b;
        Brdf_FromMaterial(&b, m, sp.kd.xyz, sp.ks.xyz);
        if (!Brdf_Sample(&b, n, sp.wo.xyz, u, wi, pdf)) return (float3)(0.0f);
        sampled = 1;
    }
#endif
    if (!sampled) {
        float3 t, bt;
        makeBasis(n, &t, &bt);
        int cosine = Path_UsesImportance(mode);
        float3 l = cosine ? Warp_CosineHemisphere(u.x, u.y) : Warp_UniformHemisphere(u.x, u.y);
        *wi = normalize(l.x * t + l.y * bt + l.z * n);
        *pdf = cosine ? l.z * CLRT_INV_PI : 0.5f * CLRT_INV_PI;
    }
    float c = dot(n, *wi);
    if (!(c > 0.0f) || !(dot(sp.geomNormal.xyz, *wi) > 0.0f) || !(*pdf > 0.0f)) return (float3)(0.0f);
    return Material_EvalDirect(sp, materials, *wi, c);
}

/* Russian roulette (course): survive with q = min(1, max throughput component); a survivor's
 * throughput is divided by q (C = 0). Returns 0 when the path ends. */
inline int Path_RussianRoulette(float3* throughput, float u) {
    float q = fmin(1.0f, maxComponent(*throughput));
    if (!(q > 0.0f) || u >= q) return 0;
    *throughput /= q;
    return 1;
}

/* The course's Russian roulette (clrt render --rr-rule course; docs/studies/2026-12-03-russian-roulette-
 * references.md). q = min(1, largest component of T), T = the product of the BRDF values f along the
 * path (not f·cosθ/pdf; 1 for the camera ray, so the first hit always survives). It is played at every
 * hit, after the hit's own radiance (emission, next-event estimation) is gathered: a survivor divides
 * that radiance and everything after it by q, a killed path keeps that radiance undivided and ends.
 * Each hit's radiance therefore counts (2 − q) times in expectation: biased (brighter), as the course's
 * references are. The path carries T as throughput / sigma, sigma a positive scalar kept in
 * PathState.throughput.w (sign: BSDF bounce or not; 0 = camera ray, sigma 1). */
inline float Path_CourseSigma(float w) { return w == 0.0f ? 1.0f : fabs(w); }

/* *scale: what the hit's radiance and the path after it are multiplied by (1/q, or 1 when killed);
 * returns 0 when the path ends after this hit. */
inline int Path_CourseRoulette(float3 throughput, float w, float u, float* scale) {
    float q = fmin(1.0f, maxComponent(throughput) / Path_CourseSigma(w));
    *scale = 1.0f;
    if (!(q > 0.0f) || !(u < q)) return 0;
    *scale = 1.0f / q;
    return 1;
}

/* The child's throughput.w under the course rule: ±sigma with T' = T·f (f: the BRDF values of the
 * bounce, fVec), so that the child's throughput / sigma' = T'. T' = 0 (a lobe of a material without a
 * diffuse part, Path_CourseDiffuseF) gives sigma' = +inf: q = 0 at the child's hit, which ends it there
 * after its radiance. 0 (no child) when the child carries nothing. */
inline float Path_CourseChildW(float3 throughput, float w, float3 next, float3 fVec, int specularBounce) {
    float tNext = maxComponent(throughput / Path_CourseSigma(w) * fVec);
    if (!(maxComponent(next) > 0.0f) || !isfinite(tNext)) return 0.0f;
    float sigma = tNext > 0.0f ? maxComponent(next) / tNext : INFINITY;
    return specularBounce ? -sigma : sigma;
}

/* What the course rule's T takes from a non-specular bounce towards dirWorld: the BRDF's diffuse part
 * (the BRDF with ks = 0: kd/π for the course's BRDFs, kd for a classic material). The hw6 diffuse box
 * (ks = 0 everywhere) cannot tell it from the whole f; the glass box can: its dielectric's lobe (kd = 0)
 * takes T to 0 (docs/studies/2026-12-03-russian-roulette-references.md, addendum of 2026-12-05, session 25). */
inline float3 Path_CourseDiffuseF(ShadingPoint sp, const __global Material* materials, float3 dirWorld) {
    float c = dot(sp.normal.xyz, dirWorld);
    if (!(c > 0.0f)) return (float3)(0.0f);
    sp.ks = (float4)(0.0f, 0.0f, 0.0f, sp.ks.w);
    return Material_EvalDirect(sp, materials, dirWorld, c) / c;
}

/* A dielectric's two specular directions at a hit (wo, ns facing wo): reflection and, unless the ray is
 * totally reflected, refraction; *fresnel: the reflected share (1 under total reflection); *att: Beer's
 * law over the distance t the ray travelled inside. */
inline void Path_DielectricSplit(Material m, float3 wo, float3 ns, float t, int inside, float3* dirR, float3* dirT,
                                 float* fresnel, float3* att) {
    float cosI = dot(wo, ns);
    *att = inside ? exp(-m.absorption.xyz * t) : (float3)(1.0f);
    float n1 = inside ? m.refractionIndex : 1.0f, n2 = inside ? 1.0f : m.refractionIndex;
    float eta = n1 / n2, c = clamp(cosI, 0.0f, 1.0f);
    float sin2T = eta * eta * fmax(0.0f, 1.0f - c * c);
    *dirR = normalize(2.0f * cosI * ns - wo);
    *dirT = (float3)(0.0f);
    *fresnel = 1.0f;
    if (sin2T < 1.0f) {
        float cosT = sqrt(1.0f - sin2T);
        *fresnel = Fresnel_Dielectric(c, cosT, n1, n2);
        *dirT = normalize(-eta * wo + (eta * c - cosT) * ns);
    }
}

/* The specular child of a mirror, conductor or dielectric (weight w), the same directions as
 * shade_hits' classic children (a rough material's perturbed by Glossy_Perturb with uGlossy); insideDielectric: the ray travelled t inside (Beer's law). */
inline int Path_SpecularBounce(Material m, float3 wo, float3 ns, float3 ng, float3 p, float t, int inside, float u,
                               float2 uGlossy, float3* weight, float3* org, float3* dir) {
    float cosI = dot(wo, ns);
    *dir = normalize(2.0f * cosI * ns - wo);
    *org = Ray_OffsetOrigin(p, ng);
    *weight = m.mirror.xyz;
    if (m.kind == MATERIAL_CONDUCTOR) {
        *weight = m.mirror.xyz * Fresnel_Conductor(clamp(cosI, 0.0f, 1.0f), m.refractionIndex, m.absorptionIndex);
    } else if (m.kind == MATERIAL_DIELECTRIC) {
        float3 dirT;
        float fr;
        Path_DielectricSplit(m, wo, ns, t, inside, dir, &dirT, &fr, weight);
        if (u >= fr) { /* refraction, picked by its Fresnel weight (never under total reflection: fr = 1) */
            *dir = dirT;
            *org = Ray_OffsetOrigin(p, -ng);
        }
    } else if (m.kind != MATERIAL_MIRROR) {
        return 0;
    }
    *dir = Glossy_Perturb(*dir, m.roughness, uGlossy.x, uGlossy.y);  /* Roughness: reflected or refracted */
    return allFinite3(*dir);
}

/* Child k of a path-traced hit: the path one bounce deeper with throughput next and throughput.w w, the
 * ray from org along dir. pathId: children 2i (reflection, or the one child), 2i + 1 (refraction); the
 * course rule's lobe child of a specular material (k = 2) 2i with the top bit set (a lineage of its own;
 * saturated ids keep theirs). */
inline void Path_Child(ShadeResult* res, int k, PathState path, float3 next, float w, float3 org, float3 dir) {
    PathState c = path;
    c.throughput = (float4)(next, w);
    c.depth = path.depth + 1;
    uint id = path.pathId;
    c.pathId = k == 2 ? (id < 0x40000000u ? (id * 2u) | 0x80000000u : id) : (id < 0x80000000u ? id * 2u + (uint)(k & 1) : id);
    Ray r;
    r.origin = (float4)(org, 0.0f);
    r.direction = (float4)(dir, INFINITY);
    res->childPath[k] = c;
    res->childRay[k] = r;
    res->childValid[k] = maxComponent(next) > 0.0f && allFinite3(next) && allFinite3(dir) ? 1 : 0;
}

/* Under the course rule a specular material traces all its children, as the course's glass box shows
 * (its RR references' sample values are Le·kd/(1 − F) on the glass: docs/studies/2026-12-03-russian-roulette-
 * references.md, addendum of session 25): the specular ones (a mirror's or conductor's reflection; a
 * dielectric's reflection and refraction, weights F and 1 − F, times Beer's law), each with T times its
 * weight, and, when the material has a BRDF part (kd or ks), a lobe child (k = 2) sampled as any bounce,
 * with T times the BRDF's diffuse part (Path_CourseDiffuseF). */
inline void Path_CourseSpecularChildren(SceneParams scene, PathState path, float3 throughput, Material m, ShadingPoint sp,
                                        const __global Material* materials, float3 wo, float3 ns, float3 ng,
                                        float3 pWorld, float t, int inside, int lobe, RngKey key, uint dim,
                                        ShadeResult* res) {
    const float3 T = path.throughput.xyz;
    if (m.kind == MATERIAL_DIELECTRIC) {
        float3 dirR, dirT, att;
        float fr;
        Path_DielectricSplit(m, wo, ns, t, inside, &dirR, &dirT, &fr, &att);
        float2 uR = Sampler_Other2D(scene, path, key, dim), uT = Sampler_Other2D(scene, path, key, dim + 2u);
        float3 wR = att * fr, wT = att * (1.0f - fr);
        Path_Child(res, 0, path, throughput * wR, Path_CourseChildW(T, path.throughput.w, throughput * wR, wR, 1),
                   Ray_OffsetOrigin(pWorld, ng), Glossy_Perturb(dirR, m.roughness, uR.x, uR.y));
        if (fr < 1.0f)
            Path_Child(res, 1, path, throughput * wT, Path_CourseChildW(T, path.throughput.w, throughput * wT, wT, 1),
                       Ray_OffsetOrigin(pWorld, -ng), Glossy_Perturb(dirT, m.roughness, uT.x, uT.y));
    } else {
        float3 w, org, dir;
        if (Path_SpecularBounce(m, wo, ns, ng, pWorld, t, inside, 0.0f, Sampler_Other2D(scene, path, key, dim), &w, &org, &dir))
            Path_Child(res, 0, path, throughput * w, Path_CourseChildW(T, path.throughput.w, throughput * w, w, 1), org, dir);
    }
    if (!lobe) return;
    float3 dir;
    float pdf = 0.0f;
    float3 fCos = Path_SampleBounce(sp, materials, scene.pathMode, Sampler_2D(scene, path, key, dim + 5u), &dir, &pdf);
    if (!(maxComponent(fCos) > 0.0f) || !(pdf > 0.0f)) return;
    float3 next = throughput * fCos / pdf;
    float w = Path_CourseChildW(T, path.throughput.w, next, Path_CourseDiffuseF(sp, materials, dir), 0);
    if (w != 0.0f) Path_Child(res, 2, path, next, w, Ray_OffsetOrigin(pWorld, ng), dir);
}

/* One path-traced hit (see the file comment) at pWorld, reached over distance t along -wo; ng, ns:
 * the normals facing wo; inside: the ray travelled inside a dielectric. sp arrives as shade_hits
 * fills it (position.w = 1) or zero (inside); emitted: the radiance the surface emits towards wo,
 * lightPdf: the density light sampling would have drawn it with (-1: unknown). res arrives with both
 * children invalid; it receives the ShadingPoint, the radiance and child 0. */
inline void Path_ShadeHit(SceneParams scene, PathState path, Material m, float3 pWorld, float3 ng, float3 ns,
                          float3 wo, float t, int inside, ShadingPoint sp, float3 emitted, float lightPdf,
                          const __global Material* materials, ShadeResult* res) {
    const int mode = scene.pathMode;
    float3 throughput = path.throughput.xyz;
    RngKey key = Rng_Key(scene.seed, path.pixel, path.sample, path.pathId);
    uint dim = 4u + 32u * (uint)path.depth;
    const int course = (mode & CLRT_PATH_RR_COURSE) != 0;
    const int roulette = path.depth >= scene.rrMinDepth; /* the camera's MinRecursionDepth: none before it */
    float courseScale = 1.0f;
    const int courseSurvives = course && (!roulette || Path_CourseRoulette(throughput, path.throughput.w,
                                                                           Sampler_Other1D(scene, path, key, dim + 4u), &courseScale));
    throughput *= courseScale;
    sp.wo.w = courseScale; /* sample_lights scales this hit's light samples by it (course rule only) */
    res->radiance = (float4)(finiteOrZero(throughput * emitted * Path_EmissionWeight(mode, path.throughput.w, lightPdf)), 0.0f);
    int specular = m.kind == MATERIAL_MIRROR || m.kind == MATERIAL_CONDUCTOR || m.kind == MATERIAL_DIELECTRIC;
    int diffuse = !inside && (maxComponent(sp.kd.xyz) > 0.0f || maxComponent(sp.ks.xyz) > 0.0f);
    /* Under MIS the last vertex (depth cap) still draws its BSDF sample, whose hit (depth maxDepth + 1) is
     * emission-only: it adds the MIS-weighted emission of a light it reaches, samples no light, has no child.
     * Only the non-specular sample: it is the other share of the last vertex's light samples. */
    const int emissionOnly = path.depth > scene.maxDepth;
    const int lastVertex = path.depth >= scene.maxDepth;
    if (!Path_UsesNee(mode) || !diffuse || emissionOnly) sp.position.w = 0.0f;
    res->sp = sp;
    if (course && !courseSurvives) return;
    if (emissionOnly || (lastVertex && !(mode & CLRT_PATH_MIS)) || (!specular && !diffuse)) return;
    if (course && specular) {
        Path_CourseSpecularChildren(scene, path, throughput, m, sp, materials, wo, ns, ng, pWorld, t, inside, diffuse, key, dim, res);
        return;
    }
    float pSpecular = specular ? (diffuse ? 0.5f : 1.0f) : 0.0f;
    int pickSpecular = Sampler_Other1D(scene, path, key, dim + 3u) < pSpecular;
    if (pickSpecular && lastVertex) return;
    float3 weight, org, dir;
    float pdf = 0.0f;
    if (pickSpecular) {
        float2 uGlossy = Sampler_Other2D(scene, path, key, dim);
        if (!Path_SpecularBounce(m, wo, ns, ng, pWorld, t, inside, Sampler_Other1D(scene, path, key, dim + 2u), uGlossy, &weight, &org,
                                 &dir))
            return;
        weight /= pSpecular;
    } else {
        float2 u = Sampler_2D(scene, path, key, dim + 5u);
        float3 fCos = Path_SampleBounce(sp, materials, mode, u, &dir, &pdf);
        weight = fCos / (pdf * (1.0f - pSpecular));
        org = Ray_OffsetOrigin(pWorld, ng);
        if (!(maxComponent(fCos) > 0.0f)) return;
    }
    float3 next = throughput * weight;
    float childW = pickSpecular ? 0.0f : pdf;
    if (course) {
        /* the bounce's BRDF diffuse part (a specular material's children are Path_CourseSpecularChildren's) */
        float3 fVec = Path_CourseDiffuseF(sp, materials, dir);
        childW = Path_CourseChildW(path.throughput.xyz, path.throughput.w, next, fVec, pickSpecular);
        if (childW == 0.0f) return;
    } else if ((mode & CLRT_PATH_RR) && roulette && !Path_RussianRoulette(&next, Sampler_Other1D(scene, path, key, dim + 4u))) {
        return;
    }
    Path_Child(res, 0, path, next, childW, org, dir);
}

#endif /* CLRT_HAS_PATH_TRACING */
#endif /* CLRT_PATH_CL */
