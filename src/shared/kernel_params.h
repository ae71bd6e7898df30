/* kernel_params.h — THE parameter list of every kernel, declared once, as X-macro rows P(KIND, TYPE, NAME):
 *   VAL  TYPE passed by value          IN  const __global TYPE*          BUF  __global TYPE*
 * Groups that several kernels share are macros of their own (CLRT_PARAMS_GEOMETRY, ...).
 *
 * Device: a kernel's signature is generated from its list, `__kernel void k(CLRT_KERNEL_PARAMS(k))`.
 * Host:   src/cl/kernel_args.h builds a table of (name, kind, value size) from the same lists, and
 *         KernelArgs binds arguments by these names (no index is ever written by hand): a name that
 *         is not a parameter, a buffer for a value, a value of the wrong size, or a parameter left
 *         unbound throws before any launch. tests/test_cl.cpp checks, with -cl-kernel-arg-info, that
 *         every kernel of every program has exactly the declared parameters, in order.
 * Adding a parameter: add its row here (or to a group) and bind it where the kernel is set up;
 * the kernel body sees it under its name. Included by the kernel files and by the host. */
#ifndef CLRT_KERNEL_PARAMS_H
#define CLRT_KERNEL_PARAMS_H

/* ---- parameter groups ------------------------------------------------------------------------ */

/* What the intersection kernels traverse (instances: the two-level BVH's, see Instance). */
#define CLRT_PARAMS_GEOMETRY(P)                                                                    \
    P(IN, Bvh8Node, nodes) P(IN, LeafBlock, leaves) P(IN, Triangle, tris) P(IN, Sphere, spheres)    \
    P(IN, Plane, planes) P(IN, Instance, instances)

/* The surfaces as shading sees them (a hit's position, normals, uv, material); triAttributes: the
 * triangles' optional vertex normals and uvs (TriangleShading.attributes). */
#define CLRT_PARAMS_SURFACES(P)                                                                    \
    P(IN, Triangle, tris) P(IN, TriangleShading, triShading) P(IN, float, triAttributes)           \
    P(IN, Sphere, spheres) P(IN, Plane, planes) P(IN, Instance, instances)

#define CLRT_PARAMS_MATERIALS(P) P(IN, Material, materials) P(IN, TextureSet, textureSets) P(IN, TextureMap, textures)

/* The texel atlas: textures, background and environment maps. */
#define CLRT_PARAMS_IMAGES(P) P(IN, ImageInfo, images) P(IN, float4, texels)

/* ---- render program (camera.cl, intersect.cl, shade.cl, compact.cl) -------------------------- */

/* The wavefront's queue length lives on the device (one int, written by the host before a batch and
 * by the compaction after each bounce): the kernels of a bounce are launched over an upper bound and
 * return at get_global_id(0) >= *queueCount, so no bounce waits for the host to read a length. */

/* count = pixels x samples: samples [firstSample, firstSample + samples) of pixels from firstPixel. */
#define CLRT_KERNEL_generate_camera_rays(P)                                                        \
    P(VAL, int, count) P(VAL, int, firstPixel) P(VAL, int, firstSample) P(VAL, int, samples)       \
    P(VAL, CameraParams, cam) P(VAL, SceneParams, scene) P(BUF, PathState, paths) P(BUF, Ray, rays)

/* hitInstances: each hit's Instance (Hit), written and read only under CLRT_HAS_INSTANCES. */
#define CLRT_KERNEL_intersect_closest(P)                                                           \
    P(IN, int, queueCount) P(VAL, SceneParams, scene) CLRT_PARAMS_GEOMETRY(P) P(IN, Ray, rays) P(BUF, Hit, hits)  \
    P(BUF, int, hitInstances)

/* The shadow queue: raysPerPath slots for each of the *queueCount paths. */
#define CLRT_KERNEL_intersect_shadow(P)                                                            \
    P(IN, int, queueCount) P(VAL, int, raysPerPath) P(VAL, SceneParams, scene) CLRT_PARAMS_GEOMETRY(P) P(BUF, ShadowRay, shadows)

#define CLRT_KERNEL_shade_hits(P)                                                                  \
    P(IN, int, queueCount) P(VAL, SceneParams, scene) P(VAL, CameraParams, cam) P(IN, PathState, paths) \
    P(IN, Ray, rays) P(IN, Hit, hits) P(IN, int, hitInstances) CLRT_PARAMS_SURFACES(P) CLRT_PARAMS_MATERIALS(P)              \
    CLRT_PARAMS_IMAGES(P) P(IN, Light, lights) P(BUF, ShadingPoint, points) P(BUF, float4, pathRadiance) \
    P(IN, float, envDist) P(IN, float4, lightData) P(BUF, PathState, nextPaths) P(BUF, Ray, nextRays)          \
    P(BUF, int, childValid)

#define CLRT_KERNEL_sample_lights(P)                                                               \
    P(IN, int, queueCount) P(VAL, int, lightBegin) P(VAL, int, lightEnd) P(VAL, int, lightSlots)       \
    P(VAL, SceneParams, scene) P(IN, PathState, paths) P(IN, ShadingPoint, points) P(IN, Material, materials) \
    P(IN, Light, lights) CLRT_PARAMS_IMAGES(P) \
    P(IN, float, envDist) P(IN, float4, lightData) P(BUF, ShadowRay, shadows)

#define CLRT_KERNEL_gather_shadows(P)                                                              \
    P(IN, int, queueCount) P(VAL, int, chunk) P(IN, ShadowRay, shadows) P(BUF, float4, pathRadiance)

#define CLRT_KERNEL_accumulate(P)                                                                  \
    P(IN, int, queueCount) P(IN, PathState, paths) P(IN, float4, pathRadiance) P(BUF, float4, image)

/* Compaction (compact.cl): the child slots i < *queueCount * childSlots; nextCount gets the survivors,
 * at most queueCapacity (the paths queue's length; the first ones in slot order are kept). */
#define CLRT_PARAMS_COMPACT(P) P(IN, int, queueCount) P(VAL, int, childSlots) P(VAL, int, queueCapacity)

#define CLRT_KERNEL_compact_scan_blocks(P)                                                         \
    CLRT_PARAMS_COMPACT(P) P(IN, int, childValid) P(BUF, int, compactTarget) P(BUF, int, blockSums)

#define CLRT_KERNEL_compact_scan_sums(P) CLRT_PARAMS_COMPACT(P) P(BUF, int, blockSums) P(BUF, int, nextCount)

#define CLRT_KERNEL_compact_scatter(P)                                                             \
    CLRT_PARAMS_COMPACT(P) P(IN, int, childValid) P(IN, int, compactTarget) P(IN, int, blockSums)   \
    P(IN, PathState, nextPaths) P(IN, Ray, nextRays) P(BUF, PathState, paths) P(BUF, Ray, rays)

/* ---- fused CPU path (fused.cl; host: src/render/fused_renderer.cpp) ----------------------------
 * The scene group is bound by the renderer with the wavefront's (Renderer::Impl's members), the launch
 * group by the fused path: `count` pixels from firstPixel, `passes` groups of `samples` samples each
 * from firstSample; lightSlots as sample_lights'; rayCounts[0] += secondary rays traced. */
#define CLRT_PARAMS_FUSED_SCENE(P)                                                                 \
    P(VAL, CameraParams, cam) P(VAL, SceneParams, scene) CLRT_PARAMS_GEOMETRY(P)                   \
    P(IN, TriangleShading, triShading) P(IN, float, triAttributes) CLRT_PARAMS_MATERIALS(P) CLRT_PARAMS_IMAGES(P)               \
    P(IN, Light, lights) P(IN, float, envDist) P(IN, float4, lightData) P(BUF, float4, image)
#define CLRT_PARAMS_FUSED_LAUNCH(P)                                                                \
    P(VAL, int, count) P(VAL, int, firstPixel) P(VAL, int, firstSample) P(VAL, int, samples)       \
    P(VAL, int, passes) P(VAL, int, lightSlots) P(BUF, uint, rayCounts)
#define CLRT_KERNEL_render_fused(P) CLRT_PARAMS_FUSED_LAUNCH(P) CLRT_PARAMS_FUSED_SCENE(P)
/* cl_kernels/lanes.cl (only in programs built with CLRT_HAS_LANES): the same parameters */
#define CLRT_KERNEL_render_lanes(P) CLRT_KERNEL_render_fused(P)

/* ---- tone-mapping program (tonemap.cl) -------------------------------------------------------- */

#define CLRT_KERNEL_Tonemap_Luminance(P)                                                           \
    P(IN, float, rgb) P(VAL, uint, n) P(VAL, float, delta) P(BUF, float, lum) P(BUF, float2, partials)

#define CLRT_KERNEL_Tonemap_Histogram(P)                                                           \
    P(IN, float, lum) P(VAL, uint, n) P(VAL, uint, prefix) P(VAL, uint, mask) P(VAL, uint, shift)  \
    P(BUF, uint, hist)

#define CLRT_KERNEL_Tonemap_Map(P) P(IN, float, rgb) P(VAL, TonemapParams, p) P(BUF, uchar, out)
#define CLRT_KERNEL_Tonemap_MapFloat(P) P(IN, float, rgb) P(VAL, TonemapParams, p) P(BUF, float, out)

/* ---- layout program (layout.cl) --------------------------------------------------------------- */

#define CLRT_KERNEL_layout_report(P) P(BUF, int, out)

/* Every kernel, by program (the host's table and the tests iterate these). */
#define CLRT_RENDER_KERNELS(K)                                                                     \
    K(generate_camera_rays) K(intersect_closest) K(intersect_shadow) K(shade_hits) K(sample_lights) \
    K(gather_shadows) K(accumulate) K(compact_scan_blocks) K(compact_scan_sums) K(compact_scatter) K(render_fused) K(render_lanes)
#define CLRT_TONEMAP_KERNELS(K) K(Tonemap_Luminance) K(Tonemap_Histogram) K(Tonemap_Map) K(Tonemap_MapFloat)
#define CLRT_LAYOUT_KERNELS(K) K(layout_report)

/* ---- the device side: a kernel's signature from its list ------------------------------------- */
#ifdef __OPENCL_C_VERSION__
#define CLRT_PARAM_TYPE_VAL(T) T
#define CLRT_PARAM_TYPE_IN(T) const __global T*
#define CLRT_PARAM_TYPE_BUF(T) __global T*
#define CLRT_PARAM_DECL_(KIND, T, name) , CLRT_PARAM_TYPE_##KIND(T) name
#define CLRT_DROP_FIRST_(first, ...) __VA_ARGS__
#define CLRT_APPLY_(m, ...) m(__VA_ARGS__)
/* Every row expands to ", TYPE NAME"; the first comma is dropped. */
#define CLRT_KERNEL_PARAMS(K_) CLRT_APPLY_(CLRT_DROP_FIRST_, CLRT_KERNEL_##K_(CLRT_PARAM_DECL_))
/* A helper that takes a whole group as its first parameters, and a call passing them on:
 *   inline float f(CLRT_GROUP_PARAMS(CLRT_PARAMS_X) int more) ... f(CLRT_GROUP_ARGS(CLRT_PARAMS_X) more) */
#define CLRT_GROUP_PARAM_DECL_(KIND, T, name) CLRT_PARAM_TYPE_##KIND(T) name,
#define CLRT_GROUP_ARG_(KIND, T, name) name,
#define CLRT_GROUP_PARAMS(GROUP) GROUP(CLRT_GROUP_PARAM_DECL_)
#define CLRT_GROUP_ARGS(GROUP) GROUP(CLRT_GROUP_ARG_)
#endif

#endif /* CLRT_KERNEL_PARAMS_H */
