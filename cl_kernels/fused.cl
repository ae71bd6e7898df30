/* fused.cl — the fused render kernel for CPU devices (src/render/fused_renderer.cpp): one work-item per
 * pixel takes `passes` groups of `samples` samples of it and, for each, generates the camera ray,
 * traces it, shades the hit, samples every light and traces the shadow rays, follows the children
 * (mirror, conductor, dielectric, the path tracer's bounce) depth first with a small explicit stack,
 * and adds the result to the image: no queues, one launch per batch of pixels and passes.
 * Every physics function is the wavefront's (Camera_Generate, Ray_Closest, Shade_Hit,
 * Light_ShadowRays, Shadow_Occluded), with the same random streams (keyed by pixel, sample, path id
 * and dimension), and the sums are made in the wavefront's order, so the image is the same, bit for
 * bit: a path's radiance is its shading term plus its shadow contributions in light and slot order
 * (gather_shadows), and a pixel adds, per group of samples, the sum over the group's paths of each
 * depth in turn (accumulate). Depth first visits the paths of one depth in the wavefront's queue
 * order (sample, then left child before right); with one sample per group and no split there is one
 * path per depth and each is added at once, else per-depth sums are kept (CLRT_FUSED_MAX_LEVELS; the
 * host uses the wavefront when a render needs more, or more stack than CLRT_FUSED_STACK_SIZE).
 * Reads: the scene's geometry, surfaces, materials, textures, lights and environment (as the
 * wavefront); writes: image, and rayCounts[0] += the secondary rays traced. */
#ifndef CLRT_FUSED_CL
#define CLRT_FUSED_CL

#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"
#include "common.cl"
#include "intersect.cl"
#include "camera.cl"
#include "shade.cl"

#if defined(CLRT_HAS_MIRROR) || defined(CLRT_HAS_DIELECTRIC) || defined(CLRT_HAS_CONDUCTOR) || \
    defined(CLRT_HAS_PATH_TRACING)
#define CLRT_FUSED_BOUNCES 1 /* some path can have children */
#endif

/* A shadow ray's contribution as gather_shadows adds it: zero (untraced) or occluded: zero. */
inline float4 Fused_Shadow(ShadowRay sr, SceneParams scene, const __global Bvh8Node* nodes,
                           const __global LeafBlock* leaves, const __global Triangle* tris,
                           const __global Sphere* spheres, const __global Plane* planes,
                           const __global Instance* instances) {
    float4 c = sr.contribution;
    if (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f) return c;
    return Shadow_Occluded(sr, scene, nodes, leaves, tris, spheres, planes, instances) ? (float4)(0.0f) : c;
}

/* One path: its closest hit, shading (children into *res) and direct light; returns its radiance as
 * accumulate adds it (finite). */
inline float3 Fused_Path(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int lightSlots, PathState path, Ray ray, ShadeResult* res) {
    int instance = CLRT_INVALID;
    Hit h;
    h.t = -1.0f; h.prim = CLRT_INVALID; h.u = 0.0f; h.v = 0.0f; /* Ray_Closest's miss */
#ifdef CLRT_HAS_PATH_TRACING
    Ray bounded = ray; /* an emission-only segment: traced only if it meets an object light, up to it */
    if (Path_BoundEmissionOnly(scene, path, lights, lightData, &bounded))
        h = Ray_Closest(bounded, scene, nodes, leaves, tris, spheres, planes, instances, &instance);
#else
    h = Ray_Closest(ray, scene, nodes, leaves, tris, spheres, planes, instances, &instance);
#endif
    Shade_Hit(scene, cam, path, ray, h, instance, tris, triShading, triAttributes, spheres, planes, instances, materials, textureSets, textures, images,
              texels, lights, envDist, lightData, res);
    float4 sum = res->radiance;
    const ShadingPoint sp = res->sp;
    if (!(sp.position.w > 0.0f)) {
        if (scene.numLights > 0) sum += (float4)(0.0f); /* the wavefront adds the empty slots (-0 + 0 = +0) */
        return finiteOrZero(sum.xyz);
    }
    RngKey key = Rng_Key(scene.seed, path.pixel, path.sample, path.pathId);
    const ShadowRay none = Shadow_Make(sp, materials, (float3)(0.0f), (float3)(0.0f, 0.0f, 1.0f), 0.0f, (float3)(0.0f), 0.0f);
    for (int l = 0; l < scene.numLights; ++l) {
        ShadowRay sr = none, sr2 = none;
        Light_ShadowRays(scene, path, sp, l, lightSlots, key, materials, lights, images, texels, envDist, lightData,
                         &sr, &sr2);
        sum += Fused_Shadow(sr, scene, nodes, leaves, tris, spheres, planes, instances);
        if (lightSlots == 2) sum += Fused_Shadow(sr2, scene, nodes, leaves, tris, spheres, planes, instances);
    }
    return finiteOrZero(sum.xyz);
}

typedef struct {
    PathState path;
    Ray ray;
} FusedEntry;

#ifdef CLRT_FUSED_BOUNCES
/* A shaded path's children into the walk of its tree, depth first: the left (reflection) child next, the
 * right ones onto the stack, so each depth comes in queue order. Returns 1 with *path, *ray the path to
 * trace next (that child, or the stack's top), 0 when the tree is done; *secondary counts the children. */
inline int Fused_NextPath(const ShadeResult* res, FusedEntry* stack, int* top, PathState* path, Ray* ray, uint* secondary) {
    for (int k = 2; k >= 1; --k)
        if (res->childValid[k] && *top < CLRT_FUSED_STACK_SIZE) {
            stack[*top].path = res->childPath[k];
            stack[*top].ray = res->childRay[k];
            ++*top;
            ++*secondary;
        }
    if (res->childValid[0]) {
        *path = res->childPath[0];
        *ray = res->childRay[0];
        ++*secondary;
        return 1;
    }
    if (*top == 0) return 0;
    --*top;
    *path = stack[*top].path;
    *ray = stack[*top].ray;
    return 1;
}
#endif

/* Parameters: src/shared/kernel_params.h (CLRT_KERNEL_render_fused).
 * CLRT_KERNEL_VEC_HINT (common.cl; quirk INTEL_VEC_HINT, docs/quirks.md): vec_type_hint(float4) on
 * Intel's OpenCL CPU runtime, which keeps it from vectorising this kernel across work-items (a speed
 * defect, not a wrong result); nothing elsewhere. Vectorised 16 wide (its default choice;
 * CL_CONFIG_DUMP_ASM shows zmm code with ~700 gathers, calling 16-wide variants of Shade_Hit and
 * Light_ShadowRays) the divergent kernel took 2.1x the scalar time: sphere 64 spp 0.35 against 0.18 s, TT 3.1 against 1.4 s; forced to 8 wide with every
 * function inlined, 0.22 s (README "Intel's runtime and render_fused"). */
__kernel CLRT_KERNEL_VEC_HINT void render_fused(CLRT_KERNEL_PARAMS(render_fused)) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const int pixel = firstPixel + i;
    /* One path per depth: add each as it comes; else per-depth sums (levels <= CLRT_FUSED_MAX_LEVELS). */
    /* A path is a tree (a dielectric split, or the course rule's children of a specular material,
     * Path_CourseSpecularChildren): per-depth sums, in the wavefront's order (FusedPlan::tree). */
#if defined(CLRT_HAS_MIRROR) || defined(CLRT_HAS_DIELECTRIC) || defined(CLRT_HAS_CONDUCTOR)
    const int tree = scene.splitDepth > 0 || (scene.pathMode & CLRT_PATH_RR_COURSE) != 0;
#else
    const int tree = scene.splitDepth > 0;
#endif
    const int direct = samples == 1 && !tree;
#ifdef CLRT_FUSED_BOUNCES
    const int levels = min(CLRT_LAST_DEPTH(scene.maxDepth, scene.pathMode) + 1, CLRT_FUSED_MAX_LEVELS);
#else
    const int levels = 1;
#endif
    float3 levelSum[CLRT_FUSED_MAX_LEVELS];
    float4 acc = image[pixel];
    uint secondary = 0;
    const int px = pixel % cam.width, py = pixel / cam.width;
    for (int pass = 0; pass < passes; ++pass) {
        for (int d = 0; d < levels; ++d) levelSum[d] = (float3)(0.0f);
        const int s0 = firstSample + pass * samples;
        PathState nextPath;
        Ray nextRay;
        Camera_GenerateAt(cam, scene, pixel, px, py, s0, &nextPath, &nextRay);
        for (int s = s0; s < s0 + samples; ++s) {
            PathState path = nextPath;
            Ray ray = nextRay;
            /* The next sample's camera ray first: independent of this sample, its divisions and square root
             * overlap this sample's traversal (a long dependent chain otherwise paid in full per sample). */
            if (s + 1 < s0 + samples) Camera_GenerateAt(cam, scene, pixel, px, py, s + 1, &nextPath, &nextRay);
#ifdef CLRT_FUSED_BOUNCES
            FusedEntry stack[CLRT_FUSED_STACK_SIZE];
            int top = 0;
#endif
            for (;;) {
                ShadeResult res;
                float3 r = Fused_Path(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) lightSlots, path, ray, &res);
                if (direct) acc.xyz += r;
                else levelSum[min(path.depth, levels - 1)] += r;
#ifdef CLRT_FUSED_BOUNCES
                if (Fused_NextPath(&res, stack, &top, &path, &ray, &secondary)) continue;
#endif
                break;
            }
        }
        if (!direct)
            for (int d = 0; d < levels; ++d) acc.xyz += levelSum[d];
    }
    image[pixel] = acc;
#ifdef CLRT_FUSED_BOUNCES
    if (secondary > 0) atomic_add(&rayCounts[0], secondary);
#endif
}

#endif /* CLRT_FUSED_CL */
