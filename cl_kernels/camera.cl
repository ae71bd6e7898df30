/* camera.cl — camera ray generation for samples [firstSample, firstSample + samples) of a range of
 * pixels, pixel-major (the samples of one pixel are adjacent). One sample per pixel: the
 * pixel centre (as the course does); more: jitter over the pixel (box filter), from the stratified
 * sampler (CLRT_PIXEL_SAMPLER_STRATIFIED: a scrambled (0,2)-net per pixel; _ZSOBOL: Z-ordered Sobol),
 * else independent uniforms.
 * ApertureSize > 0: thin lens focused at FocusDistance, square aperture as in the course (its 2D sample
 * stratified likewise; under CLRT_PIXEL_SAMPLER_CORRELATED the jitter's own point, Sampler_Camera2D).
 * Between the eye (or lens) and the image plane camera rays see only triangles' front faces (CLRT_NEAR_FRONT,
 * the default: back faces closer than the plane are skipped), everything (CLRT_NEAR_ALL), or, for a pinhole,
 * nothing (CLRT_NEAR_NONE: the ray starts at the pixel's point on the image plane); docs/scene-format.md. */
#ifndef CLRT_CAMERA_CL
#define CLRT_CAMERA_CL

#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"
#include "common.cl"

inline float3 Camera_Direction(CameraParams cam, float px, float py) {
    float su = (px / (float)cam.width);
    float sv = (py / (float)cam.height);
    float uc = cam.nearPlane.x + (cam.nearPlane.y - cam.nearPlane.x) * su;  /* left..right */
    float vc = cam.nearPlane.w - (cam.nearPlane.w - cam.nearPlane.z) * sv;  /* top..bottom */
    return uc * cam.u.xyz + vc * cam.v.xyz - cam.nearDistance * cam.w.xyz;
}

/* The camera ray and path of sample `sample` of pixel `pixel` = y·width + x. always_inline: in the fused
 * kernel's sample loop the per-pixel part of the random key is then computed once per pixel (the
 * compiler hoists it), and the pixel's coordinates come from the caller (no division per sample).
 * With scene.split = k > 1 (the camera's SplittingFactor) path samples s = k·c .. k·c + k − 1 share camera
 * sample c (its jitter, lens point and shutter time: one camera ray, k paths from it); the path's own
 * numbers (path.sample = s) stay its own. */
__attribute__((always_inline)) inline void Camera_GenerateAt(CameraParams cam, SceneParams scene, int pixel, int x,
                                                             int y, int sample, PathState* path, Ray* ray) {
    const int split = max(scene.split, 1); /* no integer division where there is no splitting (nearly always) */
    const int cameraSample = split > 1 ? sample / split : sample, cameraSamples = split > 1 ? cam.spp / split : cam.spp;
    RngKey key = Rng_Key(scene.seed, pixel, cameraSample, 1u);
    float jx = 0.5f, jy = 0.5f;
    if (cameraSamples > 1 && CLRT_SAMPLER_IS_ZSOBOL(scene)) {
        /* dimensions (0, 1) of the camera's path id 1 (common.cl) */
        const float2 j = ZSobol_2D(scene, pixel, cameraSample, 1u, 0u);
        jx = j.x;
        jy = j.y;
    } else if (cameraSamples > 1 && scene.pixelSampler != CLRT_PIXEL_SAMPLER_INDEPENDENT) {
        /* the pixel's samples spread over a (0,2)-net: stratified in x and y alone too (common.cl) */
        const float2 j = Sampler_Camera2D(key, cameraSample);
        jx = j.x;
        jy = j.y;
    } else if (cameraSamples > 1) {
        jx = Rng_Uniform(key, 0);
        jy = Rng_Uniform(key, 1);
    }
    float3 dir = Camera_Direction(cam, (float)x + jx, (float)y + jy);
    float3 org = cam.position.xyz;
    if (cam.apertureSize > 0.0f && cam.focusDistance > 0.0f) {
        float3 dn = normalize(dir);
        float tFocus = cam.focusDistance / dot(dn, -cam.w.xyz);
        float3 focus = org + tFocus * dn;
        const float2 ab = CLRT_SAMPLER_IS_ZSOBOL(scene)                          ? ZSobol_2D(scene, pixel, cameraSample, 1u, 2u)
                          : scene.pixelSampler == CLRT_PIXEL_SAMPLER_STRATIFIED  ? Rng_Stratified2D(key, cameraSample, 2u)
                          : CLRT_SAMPLER_IS_CORRELATED(scene)                   ? Sampler_Camera2D(key, cameraSample)
                                                                                 : (float2)(Rng_Uniform(key, 2), Rng_Uniform(key, 3));
        float a = (ab.x - 0.5f) * cam.apertureSize;
        float b = (ab.y - 0.5f) * cam.apertureSize;
        org = org + a * cam.u.xyz + b * cam.v.xyz;
        dir = focus - org;
    } else if (cam.nearMode == CLRT_NEAR_NONE) {
        org += dir; /* the pixel's point on the image plane (docs/scene-format.md, conventions) */
    }
    dir = normalize(dir);
    Ray r;
    r.origin = (float4)(org, 0.0f);
#ifdef CLRT_HAS_MOTION_BLUR
    r.origin.w = Sampler_Time(scene, pixel, cameraSample);
#endif
    r.direction = (float4)(dir, INFINITY);
#ifdef CLRT_HAS_BACKFACE_CULLING
    /* Back faces are skipped everywhere where the scene culls them (the classic renderer's camera rays), else
     * before the image plane, nearDistance along -w from the eye's (or lens's) plane (Ray, Ray_Closest). */
    const float tPlane = cam.nearDistance / dot(dir, -cam.w.xyz);
    if (scene.cullBackFaces && scene.pathMode == 0) r.direction.w = -INFINITY;
    else if (cam.nearMode == CLRT_NEAR_FRONT && tPlane > 0.0f && tPlane < INFINITY) r.direction.w = -tPlane;
#endif
    *ray = r;
    PathState p;
    p.throughput = (float4)(1.0f, 1.0f, 1.0f, 0.0f);
    p.pixel = pixel;
    p.sample = sample;
    p.depth = 0;
    p.pathId = 1u;
    p.coneWidth = 0.0f;
    p.pathPad[0] = p.pathPad[1] = p.pathPad[2] = 0;
    *path = p;
}

/* The camera ray and path of sample `sample` of pixel `pixel`. */
inline void Camera_Generate(CameraParams cam, SceneParams scene, int pixel, int sample, PathState* path, Ray* ray) {
    Camera_GenerateAt(cam, scene, pixel, pixel % cam.width, pixel / cam.width, sample, path, ray);
}

/* Parameters: src/shared/kernel_params.h. */
__kernel void generate_camera_rays(CLRT_KERNEL_PARAMS(generate_camera_rays)) {
    int i = get_global_id(0);
    if (i >= count) return;
    PathState p;
    Ray r;
    Camera_Generate(cam, scene, firstPixel + i / samples, firstSample + i % samples, &p, &r);
    rays[i] = r;
    paths[i] = p;
}

#endif /* CLRT_CAMERA_CL */
