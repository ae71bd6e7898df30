/* shade.cl — the shading stages of the wavefront:
 *   shade_hits:      per path, turns a hit into a ShadingPoint (textures applied), adds the terms
 *                    that need no shadow ray (ambient, background on a miss, the emission of an
 *                    object light that is hit), and writes the
 *                    reflection/refraction children to slots 2i and 2i+1 of the next queue
 *                    (path-traced cameras: Path_ShadeHit, cl_kernels/path.cl, one child in 2i);
 *   sample_lights:   per path and light of a chunk, one shadow ray carrying its reflected light
 *                    (Material_EvalDirect: the classic Blinn-Phong terms, or the material's BRDF)
 *                    (environment lights: one sampled direction, the shadow ray going to infinity;
 *                    two, a light and a cosine sample, under multi-sample MIS: see lightSlots);
 *   gather_shadows:  adds the unoccluded shadow contributions of each path in light order;
 *   accumulate:      adds each pixel's paths to the float image (paths of one pixel are adjacent).
 * Each kernel's queue length is the device int *queueCount (launches are sized by a bound); the
 * children are compacted in order on the device by compact.cl.
 * Deterministic by construction: no float atomics, fixed summation order. */
#ifndef CLRT_SHADE_CL
#define CLRT_SHADE_CL

#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"
#include "common.cl"
#include "intersect.cl"
#include "textures.cl"
#include "shading_frame.cl"
#include "lights.cl"
#include "brdf.cl"
#include "material.cl"
#include "path.cl"

typedef struct {
    float3 p, ng, ns, dir;
    float2 uv;
    int material, textureSet;
    float t;
    int frontFacing;
} SurfaceHit;

/* Whether a back-facing hit turns its normals toward the incoming ray (convention in Shade_Hit):
 * dielectrics always, every material in the path tracer, no other material in the classic renderer. */
inline int Shade_OrientsNormalToRay(int materialKind, int pathMode) {
    return materialKind == MATERIAL_DIELECTRIC || pathMode != 0;
}

/* The hit triangle as shading sees it, in world space at rest: a world-space triangle as stored; a
 * triangle of an instanced mesh (instance: Ray_Closest's, beside the Hit) mapped by its Instance: vertices by objectToWorld,
 * normals by the transpose of worldToObject (then unit, as flattening stores them), the material and
 * texture set the instance's, and, for a mirroring instance, the winding reversed (corners 1 and 2 and
 * their barycentrics exchanged), so that it is the triangle flattening would have stored. */
typedef struct {
    float3 v0, v1, v2, n0, n1, n2;
    float2 uv0, uv1, uv2;
    float b1, b2;        /* barycentrics of v1, v2 */
    float3 motion;       /* MotionBlur translation */
    int material, textureSet, light;
} HitTriangle;

inline void HitTriangle_Load(Hit h, int instance, const __global Triangle* tris, const __global TriangleShading* shading,
                             const __global float* triAttributes, const __global Instance* instances, HitTriangle* ht) {
    const __global Triangle* tri = &tris[h.prim];
    const __global TriangleShading* sh = &shading[h.prim];
    ht->v0 = tri->v0.xyz; ht->v1 = tri->v1.xyz; ht->v2 = tri->v2.xyz;
    /* Corner data (TriangleShading.attributes): stored vertex normals, or the face normal thrice, as
     * the flattener stored it before session 16; stored uvs, or (0, 0). */
    const uint attributes = sh->attributes;
    const __global float* corner = triAttributes + (attributes & CLRT_TRI_OFFSET_MASK);
    if (attributes & CLRT_TRI_NORMALS) {
        ht->n0 = vload3(0, corner); ht->n1 = vload3(1, corner); ht->n2 = vload3(2, corner);
        corner += CLRT_TRI_NORMAL_FLOATS;
    } else {
        ht->n0 = ht->n1 = ht->n2 = Triangle_FaceNormal(ht->v0, ht->v1, ht->v2);
    }
    if (attributes & CLRT_TRI_UVS) {
        ht->uv0 = vload2(0, corner); ht->uv1 = vload2(1, corner); ht->uv2 = vload2(2, corner);
    } else {
        ht->uv0 = ht->uv1 = ht->uv2 = (float2)(0.0f);
    }
    ht->b1 = h.u; ht->b2 = h.v;
    ht->motion = Triangle_Motion(tri);
    ht->material = sh->material; ht->textureSet = sh->textureSet; ht->light = sh->light;
#ifdef CLRT_HAS_INSTANCES
    if (instance == CLRT_INVALID) return;
    const __global Instance* in = &instances[instance];
    const __global float4* wo = in->worldToObject;
    ht->v0 = affinePoint(in->objectToWorld, ht->v0);
    ht->v1 = affinePoint(in->objectToWorld, ht->v1);
    ht->v2 = affinePoint(in->objectToWorld, ht->v2);
    ht->n0 = normalize(ht->n0.x * wo[0].xyz + ht->n0.y * wo[1].xyz + ht->n0.z * wo[2].xyz);
    ht->n1 = normalize(ht->n1.x * wo[0].xyz + ht->n1.y * wo[1].xyz + ht->n1.z * wo[2].xyz);
    ht->n2 = normalize(ht->n2.x * wo[0].xyz + ht->n2.y * wo[1].xyz + ht->n2.z * wo[2].xyz);
    ht->motion = in->motion.xyz;
    ht->material = in->material; ht->textureSet = in->textureSet; ht->light = CLRT_INVALID;
    if (in->mirrored) {
        float3 t3 = ht->v1; ht->v1 = ht->v2; ht->v2 = t3;
        t3 = ht->n1; ht->n1 = ht->n2; ht->n2 = t3;
        const float2 t2 = ht->uv1; ht->uv1 = ht->uv2; ht->uv2 = t2;
        const float b = ht->b1; ht->b1 = ht->b2; ht->b2 = b;
    }
#endif
}

/* ht: the hit triangle (HitTriangle_Load) when h.prim is a triangle, else unread. */
inline SurfaceHit Surface_FromHit(Hit h, Ray r, const HitTriangle* ht, const __global Sphere* spheres,
                                  const __global Plane* planes, int numTriangles, int numSpheres) {
    SurfaceHit s;
    s.dir = r.direction.xyz;
    s.t = h.t;
    if (h.prim < numTriangles) {
        float b1 = ht->b1, b2 = ht->b2, b0 = 1.0f - b1 - b2;
        float3 v0 = ht->v0, v1 = ht->v1, v2 = ht->v2;
        s.p = b0 * v0 + b1 * v1 + b2 * v2;
        s.ng = normalize(cross(v1 - v0, v2 - v0));
        float3 ns = b0 * ht->n0 + b1 * ht->n1 + b2 * ht->n2;
        float l = length(ns);
        s.ns = (l > 0.0f && isfinite(l)) ? ns / l : s.ng;
        s.uv = b0 * ht->uv0 + b1 * ht->uv1 + b2 * ht->uv2;
        s.material = ht->material;
        s.textureSet = ht->textureSet;
    } else if (h.prim >= numTriangles + numSpheres) {
        const __global Plane* pl = &planes[h.prim - numTriangles - numSpheres];
        s.p = r.origin.xyz + h.t * r.direction.xyz;
        s.p -= dot(s.p - pl->point.xyz, pl->normal.xyz) * pl->normal.xyz;  /* project onto the plane */
        s.ng = pl->normal.xyz;
        s.ns = s.ng;
        /* Planar uv: the point's coordinates in a frame of the plane (a texture repeats every unit). */
        float3 tu, tv;
        makeBasis(s.ng, &tu, &tv);
        float3 q = s.p - pl->point.xyz;
        s.uv = (float2)(dot(q, tu), dot(q, tv));
        s.material = pl->material;
        s.textureSet = pl->textureSet;
    } else {
        const __global Sphere* sp = &spheres[h.prim - numTriangles];
        float3 o = affinePoint(sp->worldToObject, r.origin.xyz);
        float3 d = affineVector(sp->worldToObject, r.direction.xyz);
        float3 c = sp->centerRadius.xyz;
        float rad = sp->centerRadius.w;
        float3 nObj = normalize(o + h.t * d - c);
        float3 pObj = c + rad * nObj;           /* re-projected onto the surface */
        s.p = affinePoint(sp->objectToWorld, pObj);
        /* inverse transpose of objectToWorld = transpose of worldToObject */
        float3 nW = nObj.x * sp->worldToObject[0].xyz + nObj.y * sp->worldToObject[1].xyz + nObj.z * sp->worldToObject[2].xyz;
        s.ng = normalize(nW);
        s.ns = s.ng;
        float theta = Math_Atan2(sqrt(nObj.x * nObj.x + nObj.z * nObj.z), nObj.y); /* acos(n.y) */
        float phi = Math_Atan2(nObj.z, nObj.x);
        s.uv = (float2)((-phi + CLRT_PI) / (2.0f * CLRT_PI), theta / CLRT_PI);
        s.material = sp->material;
        s.textureSet = sp->textureSet;
    }
    s.frontFacing = dot(s.dir, s.ng) < 0.0f;
    return s;
}

#if defined(CLRT_HAS_NORMAL_MAP) || defined(CLRT_HAS_BUMP_MAP)
/* dp/du and dp/dv at the hit s (world space): per triangle from its positions and uvs, per sphere from
 * its parametrisation, per plane the axes of its planar uv. */
inline TangentFrame Surface_TangentFrame(Hit h, SurfaceHit s, const HitTriangle* ht, const __global Sphere* spheres,
                                         const __global Plane* planes, int numTriangles, int numSpheres) {
    TangentFrame f;
    if (h.prim < numTriangles) return Frame_Triangle(ht->v0, ht->v1, ht->v2, ht->uv0, ht->uv1, ht->uv2);
    if (h.prim >= numTriangles + numSpheres) {
        makeBasis(planes[h.prim - numTriangles - numSpheres].normal.xyz, &f.dpdu, &f.dpdv);
        f.objectSpaceBump = 0;
        return f;
    }
    const __global Sphere* sp = &spheres[h.prim - numTriangles];
    float3 nObj = normalize(affinePoint(sp->worldToObject, s.p) - sp->centerRadius.xyz);
    return Frame_Sphere(nObj, sp->centerRadius.w, sp->objectToWorld);
}
#endif

/* Motion blur: how far the hit primitive has moved at the ray's shutter time (t·motion; planes do not
 * move). Shading takes the ray back by it into the primitive's rest frame and the hit point forward. */
inline float3 MotionBlur_HitShift(Hit h, Ray r, const HitTriangle* ht, const __global Sphere* spheres,
                                  int numTriangles, int numSpheres) {
    if (h.prim < numTriangles) return Ray_Time(r) * ht->motion;
    if (h.prim < numTriangles + numSpheres) return Ray_Time(r) * spheres[h.prim - numTriangles].motion.xyz;
    return (float3)(0.0f);
}

/* Motion blur: the children of a path see the scene at its shutter time. */
inline void MotionBlur_StampChildren(ShadeResult* res, float time) {
    for (int k = 0; k < CLRT_SHADE_CHILDREN; ++k)
        if (res->childValid[k]) res->childRay[k].origin.w = time;
}

/* What environment light `light` (its map img, mapping and radiance scale) brings back to a ray (direction
 * dir) that hits nothing (camera, mirror and refraction rays alike): its map's radiance along -dir, in the
 * path tracer weighted against the light's own samples (Path_MissWeight). */
inline float3 Miss_EnvLight(SceneParams scene, PathState path, const __global Light* light, ImageInfo img, int mapping,
                            float3 scale, const __global float4* texels, const __global float* envDist, float3 dir) {
    float l = length(dir);
    if (!(l > 0.0f) || !isfinite(l)) return (float3)(0.0f);
    float3 radiance = EnvMap_Radiance(texels, img, mapping, scale, EnvLight_ToMap(light, dir / l));
#ifdef CLRT_HAS_PATH_TRACING
    if (scene.pathMode != 0) radiance *= Path_MissWeight(scene, path, light, envDist, dir);
#endif
    return radiance;
}

/* Radiance of a ray that hits nothing in a scene without environment lights. Only camera rays see the
 * background (its texture, else its colour); a reflected, refracted or path ray that hits nothing brings
 * back nothing, as in the course's references (docs/scene-format.md, conventions: hw2 grass_desert's
 * mirror, the 2025 hw3 glass scenes). */
inline float3 Miss_Radiance(SceneParams scene, const __global TextureMap* textures, const __global ImageInfo* images,
                            const __global float4* texels, CameraParams cam, PathState path) {
    if (path.depth > 0) return (float3)(0.0f);
    if (scene.backgroundTexture != CLRT_INVALID) {
        int x = path.pixel % cam.width, y = path.pixel / cam.width;
        /* The course maps pixel i to texel i·texW/W (its corner, not its centre): texel i exactly when
         * the image has the render's size. */
        float2 uv = (float2)((float)x / (float)cam.width, (float)y / (float)cam.height);
        const __global TextureMap* tex = &textures[scene.backgroundTexture];
        return Image_Lookup(texels, images[tex->image], uv.x, uv.y, tex->interpolation) * (255.0f / tex->normalizer);
    }
    return scene.background.xyz;
}

/* Whether a classic child ray that travels in air (not inside a dielectric) skips back faces: in scenes that
 * cull them (SceneParams.cullBackFaces, the course's 2025 renderer); a ray inside a dielectric must meet the
 * inside of its surface to leave. */
inline int Child_Culls(SceneParams scene, int inAir) {
#ifdef CLRT_HAS_BACKFACE_CULLING
    return scene.cullBackFaces && inAir;
#else
    return 0;
#endif
}

/* Child k (0: reflection, 1: refraction) of a classic hit: the parent's path one bounce deeper, weight
 * times its throughput, the ray from org along dir (cull: it skips back faces, Child_Culls). */
inline void Child_Make(ShadeResult* res, int k, PathState parent, float3 weight, uint childBit, float3 org, float3 dir,
                       int cull) {
    PathState c = parent;
    c.throughput = (float4)(parent.throughput.xyz * weight, 0.0f);
    c.depth = parent.depth + 1;
    /* Saturates instead of wrapping: past 31 bounces a path has one child only (the split depth is
     * at most 20), so lineages stay distinct; every RNG dimension has a depth term for the bounces. */
    c.pathId = parent.pathId < 0x80000000u ? parent.pathId * 2u + childBit : parent.pathId;
    Ray r;
    r.origin = (float4)(org, 0.0f);
    r.direction = (float4)(dir, cull ? -INFINITY : INFINITY); /* negative: culls (Ray, device_types.h) */
    res->childPath[k] = c;
    res->childRay[k] = r;
    res->childValid[k] = maxComponent(c.throughput.xyz) > 0.0f && allFinite3(dir) ? 1 : 0;
}

#ifdef CLRT_HAS_MIPMAPS
/* Ray cones (Akenine-Möller et al., "Texture Level of Detail Strategies for Real-Time Ray Tracing", Ray
 * Tracing Gems ch. 20): a path carries the cone's width (PathState.coneWidth, 0 at the camera), which
 * grows by the pixel's spread angle per unit of distance along every segment; surfaces do not change
 * the spread (exact for planar mirrors; docs/scene-format.md, "Trilinear textures"). */
inline float Camera_PixelSpread(CameraParams cam) {
    float pw = fabs(cam.nearPlane.y - cam.nearPlane.x) / (float)cam.width;
    float ph = fabs(cam.nearPlane.w - cam.nearPlane.z) / (float)cam.height;
    return sqrt(pw * ph) / cam.nearDistance;
}
/* |dp/du × dp/dv| at the hit: world area per unit of uv area (triangles from their positions and uvs,
 * spheres from their parametrisation under their transformation, planes 1). */
inline float Surface_UvArea(Hit h, SurfaceHit s, const HitTriangle* ht, const __global Sphere* spheres, int numTriangles,
                            int numSpheres) {
    if (h.prim < numTriangles) {
        float2 d1 = ht->uv1 - ht->uv0, d2 = ht->uv2 - ht->uv0;
        float areaWorld = length(cross(ht->v1 - ht->v0, ht->v2 - ht->v0));
        return areaWorld / fabs(d1.x * d2.y - d2.x * d1.y);  /* uvs all alike: +inf (level 0) */
    }
    if (h.prim >= numTriangles + numSpheres) return 1.0f;
    const __global Sphere* sp = &spheres[h.prim - numTriangles];
    float3 nObj = normalize(affinePoint(sp->worldToObject, s.p) - sp->centerRadius.xyz);
    float r = sp->centerRadius.w;
    float cosT = clamp(nObj.y, -1.0f, 1.0f), sinT = sqrt(fmax(0.0f, 1.0f - cosT * cosT));
    const float2 phi = Sphere_CosSinPhi(nObj);
    const float cosP = phi.x, sinP = phi.y;
    /* u = (π − φ)/2π, v = θ/π (Surface_FromHit) */
    float3 dpdu = affineVector(sp->objectToWorld, (-2.0f * CLRT_PI * r) * (float3)(-sinT * sinP, 0.0f, sinT * cosP));
    float3 dpdv = affineVector(sp->objectToWorld, (CLRT_PI * r) * (float3)(cosT * cosP, -sinT, cosT * sinP));
    return length(cross(dpdu, dpdv));
}
/* The cone's footprint on the surface in uv units: the side of the square of the same area as the
 * ellipse it cuts (axes W and W/|cos|: W/√|cos|), over the world length of one uv unit. Ray Tracing
 * Gems ch. 20 takes the long axis (λ = Δ0 + log2 W − log2 |n·d|), which blurs grazing surfaces more
 * than a pixel's box filter does (scenes/mip_checker_plane.xml: docs/scene-format.md has both). */
inline float Surface_FootprintUv(Hit h, SurfaceHit s, float coneWidth, const HitTriangle* ht,
                                 const __global Sphere* spheres, int numTriangles, int numSpheres) {
    float cosI = fmax(fabs(dot(s.dir, s.ng)), 1e-4f);
    float uvArea = Surface_UvArea(h, s, ht, spheres, numTriangles, numSpheres);
    return coneWidth / sqrt(cosI * uvArea);
}
#endif

#ifdef CLRT_HAS_TEXTURES
/* The textures of the hit's shape: kd, ks, the shading normal (normal and bump maps), or the whole
 * radiance (replace_all: returns 1, *radiance set). */
inline int Shade_Textures(Hit h, SurfaceHit* s, SceneParams scene, const HitTriangle* ht,
                          const __global Sphere* spheres, const __global Plane* planes, const __global TextureSet* textureSets,
                          const __global TextureMap* textures, const __global ImageInfo* images,
                          const __global float4* texels, float coneWidth, float3* kd, float3* ks,
                          float3* radiance) {
    int replaceAll = 0;
    float3 pObj = affinePoint(textureSets[s->textureSet].worldToObject, s->p);  /* procedural textures */
    float footprintUv = 0.0f;  /* trilinear images */
#ifdef CLRT_HAS_MIPMAPS
    footprintUv = Surface_FootprintUv(h, *s, coneWidth, ht, spheres, scene.numTriangles, scene.numSpheres);
#endif
    for (int k = 0; k < CLRT_MAX_TEXTURES_PER_SHAPE; ++k) {
        int ti = textureSets[s->textureSet].texture[k];
        if (ti == CLRT_INVALID) continue;
        const __global TextureMap* tex = &textures[ti];
        float3 c = Texture_Eval(tex, images, texels, s->uv, s->p, pObj, footprintUv);
        switch (tex->decal) {
        case DECAL_REPLACE_KD: *kd = c; break;
        case DECAL_BLEND_KD: *kd = 0.5f * (*kd + c); break;
        case DECAL_REPLACE_KS: *ks = c; break;
        case DECAL_REPLACE_ALL: *radiance = c; replaceAll = 1; break;
#if defined(CLRT_HAS_NORMAL_MAP) || defined(CLRT_HAS_BUMP_MAP)
        case DECAL_REPLACE_NORMAL:
        case DECAL_BUMP_NORMAL: {
            TangentFrame f = Surface_TangentFrame(h, *s, ht, spheres, planes, scene.numTriangles,
                                                  scene.numSpheres);
            s->ns = Texture_PerturbNormal(tex, images, texels, c, s->uv, pObj, f, s->ns,
                                          textureSets[s->textureSet].worldToObject);
            break;
        }
#endif
        default: break;
        }
    }
    return replaceAll;
}
#endif

/* The reflection/refraction children of a classic (not path-traced) hit at p: mirror, conductor
 * (conductor Fresnel), dielectric (Fresnel split below scene.splitDepth, else one child chosen by its
 * Fresnel weight; Beer's law inside). */
inline void Shade_ClassicChildren(SceneParams scene, PathState path, Material m, float3 p, float3 ng, float3 ns,
                                  float3 wo, float t, int insideDielectric, RngKey key, uint dim, ShadeResult* res) {
    float cosI = dot(wo, ns);
    float3 reflDir = normalize(2.0f * cosI * ns - wo);
    const float2 uRefl = Sampler_Other2D(scene, path, key, dim);
    reflDir = Glossy_Perturb(reflDir, m.roughness, uRefl.x, uRefl.y);
    float3 reflOrg = Ray_EpsilonOrigin(p, ng, scene.shadowEpsilon);
    /* the reflected ray stays on the incoming side, the refracted one crosses */
    const int cullRefl = Child_Culls(scene, !insideDielectric), cullRefr = Child_Culls(scene, insideDielectric);
    switch (m.kind) {
#ifdef CLRT_HAS_MIRROR
    case MATERIAL_MIRROR:
        Child_Make(res, 0, path, m.mirror.xyz, 0u, reflOrg, reflDir, cullRefl);
        break;
#endif
#ifdef CLRT_HAS_CONDUCTOR
    case MATERIAL_CONDUCTOR: {
        float fr = Fresnel_Conductor(clamp(cosI, 0.0f, 1.0f), m.refractionIndex, m.absorptionIndex);
        Child_Make(res, 0, path, m.mirror.xyz * fr, 0u, reflOrg, reflDir, cullRefl);
        break;
    }
#endif
#ifdef CLRT_HAS_DIELECTRIC
    case MATERIAL_DIELECTRIC: {
        float3 weight = (float3)(1.0f);
        if (insideDielectric)  /* Beer's law over the distance travelled inside */
            weight = exp(-m.absorption.xyz * t);
        float n1 = insideDielectric ? m.refractionIndex : 1.0f;
        float n2 = insideDielectric ? 1.0f : m.refractionIndex;
        float eta = n1 / n2;
        float c = clamp(cosI, 0.0f, 1.0f);
        float sin2T = eta * eta * fmax(0.0f, 1.0f - c * c);
        float fr = 1.0f, cosT = 0.0f;
        if (sin2T < 1.0f) {
            cosT = sqrt(1.0f - sin2T);
            fr = Fresnel_Dielectric(c, cosT, n1, n2);
        }
        float3 refrDir = normalize(-eta * wo + (eta * c - cosT) * ns);
        const float2 uRefr = Sampler_Other2D(scene, path, key, dim + 3u);
        refrDir = Glossy_Perturb(refrDir, m.roughness, uRefr.x, uRefr.y);
        float3 refrOrg = Ray_EpsilonOrigin(p, -ng, scene.shadowEpsilon);
        if (fr >= 1.0f) {
            Child_Make(res, 0, path, weight, 0u, reflOrg, reflDir, cullRefl);
        } else if (path.depth < scene.splitDepth) {
            Child_Make(res, 0, path, weight * fr, 0u, reflOrg, reflDir, cullRefl);
            Child_Make(res, 1, path, weight * (1.0f - fr), 1u, refrOrg, refrDir, cullRefr);
        } else if (Sampler_Other1D(scene, path, key, dim + 2u) < fr) {
            Child_Make(res, 0, path, weight, 0u, reflOrg, reflDir, cullRefl);
        } else {
            Child_Make(res, 1, path, weight, 1u, refrOrg, refrDir, cullRefr);
        }
        break;
    }
#endif
    default:
        break;
    }
}

/* A ray that hit nothing: what it brings back, no ShadingPoint, no children. With environment lights,
 * the sum of what each brings back (Miss_EnvLight); else the background (Miss_Radiance). */
inline void Shade_Miss(SceneParams scene, CameraParams cam, PathState path, Ray ray, const __global TextureMap* textures,
                       const __global ImageInfo* images, const __global float4* texels, const __global Light* lights,
                       const __global float* envDist, ShadeResult* res) {
    float3 missed = (float3)(0.0f);
#ifdef CLRT_HAS_ENV_LIGHT
    if (scene.envLight != CLRT_INVALID) {
        /* the first one from SceneParams' copy of its fields (no Light load before its texel reads) */
        const float3 dir = ray.direction.xyz;
        missed = Miss_EnvLight(scene, path, &lights[scene.envLight], images[scene.envImage], scene.envMapping,
                               scene.envScale.xyz, texels, envDist, dir);
        for (int l = scene.envLight + 1; l < scene.numLights; ++l) { /* any others */
            const __global Light* light = &lights[l];
            if (light->kind == LIGHT_ENVIRONMENT)
                missed += Miss_EnvLight(scene, path, light, images[light->image], light->mapping, light->radiance.xyz,
                                        texels, envDist, dir);
        }
        res->radiance = (float4)(path.throughput.xyz * missed, 0.0f);
        return;
    }
#endif
    missed = Miss_Radiance(scene, textures, images, texels, cam, path);
#ifdef CLRT_HAS_PATH_TRACING
    if (scene.pathMode != 0) missed *= Path_MissWeight(scene, path, 0, envDist, ray.direction.xyz);
#endif
    res->radiance = (float4)(path.throughput.xyz * missed, 0.0f);
}

/* The ShadingPoint light sampling reads at the surface point p (normals ns, ng facing as shaded, wo
 * towards the viewer), with the reflectances kd, ks after textures. */
inline ShadingPoint ShadingPoint_Make(float3 p, float3 ns, float3 ng, float3 wo, float3 kd, float3 ks, Material m,
                                      int material) {
    ShadingPoint sp;
    sp.position = (float4)(p, 1.0f);
    sp.normal = (float4)(ns, 0.0f);
    sp.geomNormal = (float4)(ng, 0.0f);
    sp.wo = (float4)(wo, 0.0f);
    sp.kd = (float4)(kd, 0.0f);
    sp.ks = (float4)(ks, m.phongExponent);
    sp.material = material;
    sp.pad0 = sp.pad1 = sp.pad2 = 0;
    return sp;
}

/* Shading of one path's hit h along ray (the whole of shade_hits for one path; the fused kernel calls
 * it too): the ShadingPoint for light sampling, the radiance that needs no shadow ray (ambient,
 * background or environment on a miss, object-light emission, replace_all) and the children. */
inline void Shade_Hit(SceneParams scene, CameraParams cam, PathState path, Ray ray, Hit h, int instance,
                      const __global Triangle* tris, const __global TriangleShading* triShading,
                      const __global float* triAttributes, const __global Sphere* spheres, const __global Plane* planes, const __global Instance* instances,
                      const __global Material* materials, const __global TextureSet* textureSets, const __global TextureMap* textures,
                      const __global ImageInfo* images, const __global float4* texels, const __global Light* lights,
                      const __global float* envDist, const __global float4* lightData, ShadeResult* res) {
    float3 throughput = path.throughput.xyz;
    res->childValid[0] = res->childValid[1] = res->childValid[2] = 0;
    ShadingPoint sp;  /* every field set: misses and dielectric interiors store it whole (oclgrind) */
    sp.position = sp.normal = sp.geomNormal = sp.wo = sp.kd = sp.ks = (float4)(0.0f);
    sp.material = 0;
    sp.pad0 = sp.pad1 = sp.pad2 = 0;
    res->sp = sp;
    if (h.prim == CLRT_INVALID) {
        Shade_Miss(scene, cam, path, ray, textures, images, texels, lights, envDist, res);
        return;
    }
    HitTriangle ht;
    if (h.prim < scene.numTriangles) HitTriangle_Load(h, instance, tris, triShading, triAttributes, instances, &ht);
#ifdef CLRT_HAS_MOTION_BLUR
    const float3 motionShift = MotionBlur_HitShift(h, ray, &ht, spheres, scene.numTriangles, scene.numSpheres);
    ray.origin.xyz -= motionShift;  /* the ray in the rest frame of the primitive it hit */
#endif
    SurfaceHit s = Surface_FromHit(h, ray, &ht, spheres, planes, scene.numTriangles, scene.numSpheres);
#ifdef CLRT_HAS_MIPMAPS
    path.coneWidth += Camera_PixelSpread(cam) * s.t;  /* the cone at the hit: its children start from it */
#endif
    Material m = materials[s.material];
    float3 wo = -s.dir;
    /* Course convention (docs/scene-format.md, "Conventions"): the shading normal of an opaque surface
     * is the stored one on both sides; only dielectrics orient it toward the incoming ray (they need
     * the side to tell entering from leaving). So a back-facing hit of an opaque surface is lit by
     * lights on its stored side, through the surface seen from behind (hw2 grass_desert's blades:
     * 29.97 -> 50.80 dB), and the path tracer keeps its two-sided shading (no hw6 path-traced scene
     * shows a back face). */
    /* Smooth shading: an opaque surface of the classic renderer keeps the interpolated vertex normal as it
     * is, even where it faces away from the geometric normal (near edges whose vertex normals average
     * faces that turn sharply), as the course's references do (2025 hw1 windmill_smooth 39.93 -> 41.42 dB,
     * tower_smooth, low_poly_smooth, berserker_smooth +0.9 to +1.2 dB); dielectrics, which tell entering
     * from leaving by it, and the path tracer turn it to the geometric normal's side. */
    if (Shade_OrientsNormalToRay(m.kind, scene.pathMode) && dot(s.ns, s.ng) < 0.0f) s.ns = -s.ns;
    const int orientToRay = !s.frontFacing && Shade_OrientsNormalToRay(m.kind, scene.pathMode);
    float3 ng = orientToRay ? -s.ng : s.ng;
    float3 kd = m.diffuse.xyz, ks = m.specular.xyz;
    float3 radiance = (float3)(0.0f);
    int replaceAll = 0;
#ifdef CLRT_HAS_TEXTURES
    if (s.textureSet != CLRT_INVALID)
        replaceAll = Shade_Textures(h, &s, scene, &ht, spheres, planes, textureSets, textures, images,
                                    texels, path.coneWidth, &kd, &ks, &radiance);
#endif
#ifdef CLRT_HAS_MOTION_BLUR
    s.p += motionShift; /* the textures above saw the rest-frame point: they move with the object */
#endif
    float3 ns = orientToRay ? -s.ns : s.ns;
    RngKey key = Rng_Key(scene.seed, path.pixel, path.sample, path.pathId);
    uint dim = 4u + 32u * (uint)path.depth;
    int insideDielectric = (m.kind == MATERIAL_DIELECTRIC) && !s.frontFacing;

#ifdef CLRT_HAS_OBJECT_LIGHTS
    radiance += ObjectLight_Emission(h.prim, s.frontFacing, scene.numTriangles, scene.numSpheres, triShading, spheres, lights);
#endif
#ifdef CLRT_HAS_PATH_TRACING
    if (scene.pathMode != 0 && path.depth > scene.maxDepth) replaceAll = 0; /* an emission-only segment */
#endif
    if (replaceAll) {
        res->radiance = (float4)(throughput * radiance, 0.0f);
        return;
    }
    if (!insideDielectric) {
        radiance += m.ambient.xyz * scene.ambient.xyz;
        sp = ShadingPoint_Make(s.p, ns, ng, wo, kd, ks, m, s.material);
    }
#ifdef CLRT_HAS_PATH_TRACING
    if (scene.pathMode != 0) {
        float3 emitted = (float3)(0.0f);
        float lightPdf = -1.0f;
#if defined(CLRT_HAS_LIGHT_MESH) || defined(CLRT_HAS_LIGHT_SPHERE)
        emitted = Path_HitEmission(h.prim, s.frontFacing, scene, tris, triShading, spheres, lights, lightData, s.p, s.dir, s.t, s.ng,
                                   path.throughput.w, &lightPdf);
#endif
        Path_ShadeHit(scene, path, m, s.p, ng, ns, wo, s.t, insideDielectric, sp, emitted, lightPdf, materials, res);
#ifdef CLRT_HAS_MOTION_BLUR
        MotionBlur_StampChildren(res, Ray_Time(ray));
#endif
        return;
    }
#endif
    res->sp = sp;
    res->radiance = (float4)(throughput * radiance, 0.0f);
    if (path.depth >= scene.maxDepth) return;
    Shade_ClassicChildren(scene, path, m, s.p, ng, ns, wo, s.t, insideDielectric, key, dim, res);
#ifdef CLRT_HAS_MOTION_BLUR
    MotionBlur_StampChildren(res, Ray_Time(ray));
#endif
}

/* Parameters of every kernel here: src/shared/kernel_params.h.
 * CLRT_KERNEL_VEC_HINT (common.cl; quirk INTEL_VEC_HINT, docs/quirks.md): vec_type_hint(float4) on
 * Intel's OpenCL CPU runtime, nothing elsewhere. A workaround for a miscompile by that runtime (2026.22,
 * its implicit 16-way work-item vectoriser), which the hint turns off for this kernel alone ("Kernel
 * "shade_hits" was not vectorized" in the build log). Vectorised, this kernel hands Child_Write float3
 * values (weight, origin, direction) that hold other work-items' components and, at times, memory never
 * written, so classic/veachAjar's glass teapot went wrong on ~1.5% of pixels, differently from run to
 * run, and only when enough other code (textures, --all-features) was compiled in — even code never
 * executed (the Perlin evaluation). The same source is right with CL_CONFIG_USE_VECTORIZER=False, on PoCL
 * and on Oclgrind (no report); README "Conformance" and issue 17 have the evidence; reproducer:
 * scripts/intel_vectorizer_repro.sh (with tests/intel_repro/shade_hits_alone.cpp). */
__kernel CLRT_KERNEL_VEC_HINT void shade_hits(CLRT_KERNEL_PARAMS(shade_hits)) {
    int i = get_global_id(0);
    if (i >= *queueCount) return;
    ShadeResult res;
#ifdef CLRT_HAS_INSTANCES
    const int instance = hitInstances[i];
#else
    const int instance = CLRT_INVALID;
#endif
    Shade_Hit(scene, cam, paths[i], rays[i], hits[i], instance, tris, triShading, triAttributes, spheres, planes, instances, materials, textureSets,
              textures, images, texels, lights, envDist, lightData, &res);
    /* Whole structs go to global memory from plain locals: oclgrind 21.10's uninitialised-value check
     * (-cl-opt-disable) reports a struct copied straight from a member of res, initialised or not. */
    const ShadingPoint sp = res.sp;
    points[i] = sp;
    pathRadiance[i] = res.radiance;
    const int slots = CLRT_CHILD_SLOTS(scene.pathMode);
    for (int k = 0; k < slots; ++k) {
        childValid[slots * i + k] = res.childValid[k];
        if (res.childValid[k]) {  /* compact_paths reads only the valid children */
            const PathState child = res.childPath[k];
            Ray childRay = res.childRay[k];
#ifdef CLRT_HAS_PATH_TRACING
            /* an emission-only segment that meets no object light: tMax 0, a miss that intersect_closest does not
             * trace (Ray_Closest); one that does: traced up to it, as render_fused and the lanes trace it */
            if (!Path_BoundEmissionOnly(scene, child, lights, lightData, &childRay)) childRay.direction.w = 0.0f;
#endif
            nextPaths[slots * i + k] = child;
            nextRays[slots * i + k] = childRay;
        }
    }
}

/* The shadow ray of one light sample at shading point sp: the reflected light (Material_EvalDirect)
 * times e (Light_Sample's estimate) and the path throughput, or a ray of zero contribution (not traced).
 * The shading normal must face the light; the geometric normal need not: where the two disagree (smooth
 * shading, bump and normal maps) the shadow ray decides, and the own surface occludes it unless it grazes
 * past. The course's references light such points: 2025 hw1 smooth meshes (berserker_smooth 42.4 -> 47.4,
 * tower_smooth 37.9 -> 42.4 dB with the geometric normal no longer required to face the light; every
 * ../shared camera unchanged), hw4 bump_mapping_transformed's sphere (thin lines along the terminators). The
 * ray's geometry is the course's: it starts ShadowRayEpsilon off the surface along ng (Ray_EpsilonOrigin;
 * at such a point ng may face away from the light, and the ray then starts behind its own surface),
 * is aimed from there at the light's point, and is as long as the distance from p, so a surface through
 * the light's point (2025 hw2 mirror_room: a point light on the ceiling plane, dark in the reference)
 * blocks it. Object lights re-aim it short of their surface (ObjectLight_AimShadow). */
inline ShadowRay Shadow_Make(ShadingPoint sp, const __global Material* materials, float3 throughput, float3 wi,
                             float dist, float3 e, float shadowEpsilon) {
    ShadowRay sr;
    sr.contribution = (float4)(0.0f);
    sr.origin = (float4)(0.0f);
    sr.direction = (float4)(0.0f, 0.0f, 1.0f, 0.0f);
    float3 p = sp.position.xyz, n = sp.normal.xyz, ng = sp.geomNormal.xyz;
    float cosTheta = dot(n, wi);
    if (cosTheta > 0.0f && maxComponent(e) > 0.0f) {
        float3 c = throughput * Material_EvalDirect(sp, materials, wi, cosTheta) * e;
        float3 org = Ray_EpsilonOrigin(p, ng, shadowEpsilon);
        float3 dir = wi;
        if (!isinf(dist)) dir = normalize(p + dist * wi - org); /* aimed from org at the light's point */
        sr.origin = (float4)(org, dist); /* as long as from p: a surface through the light's point blocks it */
        sr.direction = (float4)(dir, 0.0f);
        sr.contribution = (float4)(finiteOrZero(c), 0.0f);
    }
    return sr;
}

/* Share of shading points that take multi-sample MIS's cosine sample (1 or ½; see EnvLight_SampleMis).
 * Measured (experiments/env_mis_compare.py, docs/studies/2026-11-29-env-mis.md): ½, every other sample of
 * a pixel, cuts sample_lights by ~25% but doubles the relMSE on sunset.exr and gains nothing on
 * studio.exr; so 1, every shading point takes both samples. */
#ifndef CLRT_ENV_MIS_COSINE_SHARE
#define CLRT_ENV_MIS_COSINE_SHARE 1.0f
#endif

/* Whether light l's multi-sample MIS takes its cosine sample at path's shading point: with a share of ½, at
 * every other sample of a pixel (parity offset per pixel and light), stratified; with 1 (the default): always. */
inline int EnvLight_MisWithCosine(PathState path, RngKey key, int l) {
    return CLRT_ENV_MIS_COSINE_SHARE >= 1.0f || ((path.sample + (int)(Rng_Uniform(key, 0x7ff0u + (uint)l) < 0.5f)) & 1) == 0;
}

/* The shadow rays of light l for a path at shading point sp (sp.position.w > 0): *sr, and under
 * multi-sample MIS of an environment light (lightSlots 2) the cosine sample's *sr2; a slot a light
 * does not use keeps `none` (zero contribution: not traced). */
inline void Light_ShadowRays(SceneParams scene, PathState path, ShadingPoint sp, int l, int lightSlots, RngKey key,
                             const __global Material* materials, const __global Light* lights,
                             const __global ImageInfo* images, const __global float4* texels,
                             const __global float* envDist, const __global float4* lightData, ShadowRay* sr,
                             ShadowRay* sr2) {
    uint dim = 4u + 32u * (uint)path.depth + 8u + 2u * (uint)l;
    float2 u = Sampler_Light2D(scene, path, key, dim);
    float3 wi;
    float dist;
#ifdef CLRT_HAS_ENV_LIGHT
    if (lightSlots == 2 && EnvLight_UsesMis(&lights[l])) {
        /* the cosine sample's uniforms: the same dimensions, offset by 2^15 */
        float2 u2 = Sampler_2D(scene, path, key, dim + 0x8000u);
        float3 wiB, eL, eB;
        EnvLight_SampleMis(&lights[l], sp.normal.xyz, u, u2, CLRT_ENV_MIS_COSINE_SHARE, EnvLight_MisWithCosine(path, key, l),
                           images, texels, envDist, &wi, &eL, &wiB, &eB);
        *sr = Shadow_Make(sp, materials, path.throughput.xyz, wi, INFINITY, eL, scene.shadowEpsilon);
        *sr2 = Shadow_Make(sp, materials, path.throughput.xyz, wiB, INFINITY, eB, scene.shadowEpsilon);
    } else
#endif
    {
        float3 e = Light_Sample(&lights[l], sp.position.xyz, sp.normal.xyz, u, images, texels, envDist, lightData,
                                &wi, &dist);
        *sr = Shadow_Make(sp, materials, path.throughput.xyz, wi, dist, e, scene.shadowEpsilon);
#ifdef CLRT_HAS_PATH_TRACING
        /* at the last vertex (depth cap) too: its BSDF sample is traced for emission only (Path_ShadeHit) */
        sr->contribution *= Path_LightSampleWeight(scene.pathMode, &lights[l], sp, materials, envDist, lightData, wi, e);
#endif
#ifdef CLRT_HAS_OBJECT_LIGHTS
        if (ObjectLight_IsShape(&lights[l])) ObjectLight_AimShadow(sr, sp.position.xyz + dist * wi);
#endif
    }
#ifdef CLRT_HAS_PATH_TRACING
    /* the course's roulette (Path_CourseRoulette) divides this hit's radiance by q when the path survives */
    if (scene.pathMode & CLRT_PATH_RR_COURSE) {
        sr->contribution *= sp.wo.w;
        sr2->contribution *= sp.wo.w;
    }
#endif
#ifdef CLRT_HAS_MOTION_BLUR
    /* the shadow rays of a sample see the scene at its camera sample's time (camera.cl) */
    sr->direction.w = sr2->direction.w = Sampler_Time(scene, path.pixel, path.sample / max(scene.split, 1));
#endif
}

/* Shadow-ray slots: each (path i, light l in [lightBegin, lightEnd)) owns lightSlots consecutive
 * slots from (i·(lightEnd − lightBegin) + l − lightBegin)·lightSlots. lightSlots is 1 unless the scene
 * has an environment light sampled by multi-sample MIS (EnvLight_SampleMis), which fills two (light
 * sample, cosine sample); other lights then leave their second slot at zero contribution (not traced). */
__kernel void sample_lights(CLRT_KERNEL_PARAMS(sample_lights)) {
    int i = get_global_id(0);
    if (i >= *queueCount) return;
    int chunk = lightEnd - lightBegin;
    ShadingPoint sp = points[i];
    PathState path = paths[i];
    RngKey key = Rng_Key(scene.seed, path.pixel, path.sample, path.pathId);
    const ShadowRay none = Shadow_Make(sp, materials, (float3)(0.0f), (float3)(0.0f, 0.0f, 1.0f), 0.0f, (float3)(0.0f), 0.0f);
    for (int l = lightBegin; l < lightEnd; ++l) {
        size_t slot = ((size_t)i * chunk + (l - lightBegin)) * lightSlots;
        ShadowRay sr = none, sr2 = none;
        if (sp.position.w > 0.0f)
            Light_ShadowRays(scene, path, sp, l, lightSlots, key, materials, lights, images, texels, envDist, lightData,
                             &sr, &sr2);
        shadows[slot] = sr;
        if (lightSlots == 2) shadows[slot + 1] = sr2;
    }
}

__kernel void gather_shadows(CLRT_KERNEL_PARAMS(gather_shadows)) {
    int i = get_global_id(0);
    if (i >= *queueCount) return;
    float4 sum = pathRadiance[i];
    for (int l = 0; l < chunk; ++l) sum += shadows[(size_t)i * chunk + l].contribution;
    pathRadiance[i] = sum;
}

/* Paths of one pixel are adjacent; the first of each run adds the whole run (fixed order). */
__kernel void accumulate(CLRT_KERNEL_PARAMS(accumulate)) {
    const int count = *queueCount;
    int i = get_global_id(0);
    if (i >= count) return;
    int pixel = paths[i].pixel;
    if (i > 0 && paths[i - 1].pixel == pixel) return;
    float3 sum = (float3)(0.0f);
    for (int j = i; j < count && paths[j].pixel == pixel; ++j) sum += finiteOrZero(pathRadiance[j].xyz);
    image[pixel] += (float4)(sum, 0.0f);
}

#endif /* CLRT_SHADE_CL */
