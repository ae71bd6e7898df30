/* layout.cl — reports how the OpenCL compiler lays out every struct of src/shared/device_types.h, so
 * the host can compare it with its own layout (src/cl/layout_check.cpp, tests/test_cl.cpp).
 *
 * The table is written ONCE, here, as the X-macro CLRT_LAYOUT_TABLE(S, M): S(T) is a struct row,
 * M(T, m) a member row; members are listed in declaration order. The C++ host includes this file too
 * (only the macro is visible to it; the kernel is compiled by the OpenCL compiler alone).
 * Kernel output: out[0] = number of rows; then two ints per row:
 *   struct row: sizeof(T), alignof(T);   member row: offsetof(T, m), sizeof(member).
 * When a struct in device_types.h changes, update its rows here (the tests check that every struct is
 * listed and that the listed members tile each struct exactly). */
#ifndef CLRT_LAYOUT_CL
#define CLRT_LAYOUT_CL
#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"
#ifndef CLRT_LAYOUT_TABLE
#define CLRT_LAYOUT_TABLE(S, M)                                                                   \
    S(Bvh8Node) M(Bvh8Node, planes) M(Bvh8Node, entry) M(Bvh8Node, pad)                          \
    S(LeafBlock) M(LeafBlock, vertex) M(LeafBlock, prim)                                            \
    S(Triangle) M(Triangle, v0) M(Triangle, v1) M(Triangle, v2)                                   \
    S(TriangleShading) M(TriangleShading, material) M(TriangleShading, textureSet)                 \
        M(TriangleShading, light) M(TriangleShading, attributes)                                   \
    S(Instance) M(Instance, objectToWorld) M(Instance, worldToObject) M(Instance, motion)                \
        M(Instance, rootNode) M(Instance, material) M(Instance, textureSet) M(Instance, mirrored)   \
    S(Sphere) M(Sphere, centerRadius) M(Sphere, worldToObject) M(Sphere, objectToWorld)           \
        M(Sphere, motion) M(Sphere, material) M(Sphere, textureSet) M(Sphere, light)              \
        M(Sphere, pad1)                                                                           \
    S(Plane) M(Plane, point) M(Plane, normal) M(Plane, material) M(Plane, textureSet)              \
        M(Plane, pad0) M(Plane, pad1)                                                             \
    S(TextureSet) M(TextureSet, texture) M(TextureSet, worldToObject)                           \
    S(Material) M(Material, ambient) M(Material, diffuse) M(Material, specular)                   \
        M(Material, mirror) M(Material, absorption) M(Material, phongExponent)                    \
        M(Material, refractionIndex) M(Material, absorptionIndex) M(Material, roughness)          \
        M(Material, kind) M(Material, brdf) M(Material, brdfExponent) M(Material, brdfFlags)                   \
    S(TextureMap) M(TextureMap, blackColor) M(TextureMap, whiteColor) M(TextureMap, kind)         \
        M(TextureMap, decal) M(TextureMap, interpolation) M(TextureMap, image)                    \
        M(TextureMap, normalizer) M(TextureMap, bumpFactor) M(TextureMap, scale)                  \
        M(TextureMap, offset) M(TextureMap, noiseScale) M(TextureMap, noiseAbs)                   \
        M(TextureMap, octaves) M(TextureMap, mipLevels)                                                   \
    S(ImageInfo) M(ImageInfo, offset) M(ImageInfo, width) M(ImageInfo, height) M(ImageInfo, format) \
    S(Light) M(Light, position) M(Light, direction) M(Light, radiance) M(Light, edgeU)            \
        M(Light, edgeV) M(Light, cosCoverageHalf) M(Light, cosFalloffHalf) M(Light, area)         \
        M(Light, kind) M(Light, image) M(Light, mapping) M(Light, envStrategy) M(Light, distribution)  \
        M(Light, objFirst) M(Light, objCount) M(Light, objRadius) M(Light, envCosine)                 \
    S(CameraParams) M(CameraParams, position) M(CameraParams, u) M(CameraParams, v)               \
        M(CameraParams, w) M(CameraParams, nearPlane) M(CameraParams, nearDistance)               \
        M(CameraParams, focusDistance) M(CameraParams, apertureSize) M(CameraParams, width)       \
        M(CameraParams, height) M(CameraParams, spp) M(CameraParams, nearMode) M(CameraParams, cameraPad)                   \
    S(SceneParams) M(SceneParams, background) M(SceneParams, ambient)                             \
        M(SceneParams, numTriangles) M(SceneParams, numSpheres) M(SceneParams, numLights)         \
        M(SceneParams, maxDepth) M(SceneParams, backgroundTexture) M(SceneParams, envLight)       \
        M(SceneParams, seed) M(SceneParams, splitDepth) M(SceneParams, envScale)                  \
        M(SceneParams, envImage) M(SceneParams, envMapping) M(SceneParams, numPlanes)               \
        M(SceneParams, pathMode) M(SceneParams, pixelSampler) M(SceneParams, shadowEpsilon)   \
        M(SceneParams, samplerWidth) M(SceneParams, samplerLog2Spp)                               \
        M(SceneParams, numInstances) M(SceneParams, instanceRoot) M(SceneParams, rrMinDepth) M(SceneParams, split)  \
        M(SceneParams, cullBackFaces) M(SceneParams, emitterTest) M(SceneParams, scenePad)           \
        M(SceneParams, emitterLo) M(SceneParams, emitterHi)                                         \
    S(Ray) M(Ray, origin) M(Ray, direction)                                                       \
    S(Hit) M(Hit, t) M(Hit, prim) M(Hit, u) M(Hit, v)  \
    S(PathState) M(PathState, throughput) M(PathState, pixel) M(PathState, sample)                \
        M(PathState, depth) M(PathState, pathId) M(PathState, coneWidth) M(PathState, pathPad)                                                \
    S(ShadowRay) M(ShadowRay, origin) M(ShadowRay, direction) M(ShadowRay, contribution)        \
    S(ShadingPoint) M(ShadingPoint, position) M(ShadingPoint, normal)                             \
        M(ShadingPoint, geomNormal) M(ShadingPoint, wo) M(ShadingPoint, kd) M(ShadingPoint, ks)    \
        M(ShadingPoint, material) M(ShadingPoint, pad0) M(ShadingPoint, pad1) M(ShadingPoint, pad2) \
    S(TonemapParams) M(TonemapParams, op) M(TonemapParams, scale) M(TonemapParams, whiteL)        \
        M(TonemapParams, hasWhite) M(TonemapParams, saturation) M(TonemapParams, invGamma)        \
        M(TonemapParams, truncate) M(TonemapParams, numPixels)                                  \
        M(TonemapParams, srgb) M(TonemapParams, pad0) M(TonemapParams, pad1) M(TonemapParams, pad2)
#endif

#ifdef __OPENCL_C_VERSION__
__kernel void layout_report(CLRT_KERNEL_PARAMS(layout_report)) { /* src/shared/kernel_params.h */
    if (get_global_id(0) != 0) return;
    int i = 1;
#define CLRT_LAYOUT_S(T)                 \
    out[i++] = (int)sizeof(T);           \
    out[i++] = (int)__alignof__(T);
#define CLRT_LAYOUT_M(T, m)                      \
    out[i++] = (int)__builtin_offsetof(T, m);    \
    out[i++] = (int)sizeof(((T*)0)->m);
    CLRT_LAYOUT_TABLE(CLRT_LAYOUT_S, CLRT_LAYOUT_M)
#undef CLRT_LAYOUT_S
#undef CLRT_LAYOUT_M
    out[0] = (i - 1) / 2;
}
#endif

#endif /* CLRT_LAYOUT_CL */
