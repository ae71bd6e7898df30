/* camera.cl — camera ray generation for samples [firstSample, firstSample + samples) of a range of
 * pixels, pixel-major (the samples of one pixel are adjacent). One sample per pixel: the
 * pixel centre (as the course does); more: stratified jitter over a strataX × strataY grid (box
 * filter). ApertureSize > 0: thin lens focused at FocusDistance, square aperture as in the course. */
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

/* A camera sample's stratum: the cell (sx, sy) of the strataX × strataY grid that sample `sample` of a
 * pixel jitters in (sample % cells, row-major); Camera_StratumNext steps to the next sample's, so a loop
 * over consecutive samples needs no integer division (the fused kernel; the same cells as the formula). */
typedef struct { int sx, sy; } CameraStratum;

inline CameraStratum Camera_StratumOf(CameraParams cam, int sample) {
    CameraStratum c = {0, 0};
    if (cam.spp > 1) {
        int cell = sample % (cam.strataX * cam.strataY);
        c.sx = cell % cam.strataX;
        c.sy = cell / cam.strataX;
    }
    return c;
}

inline CameraStratum Camera_StratumNext(CameraParams cam, CameraStratum c) {
    if (++c.sx == cam.strataX) {
        c.sx = 0;
        if (++c.sy == cam.strataY) c.sy = 0;
    }
    return c;
}

/* The camera ray and path of sample `sample` of pixel `pixel` = y·width + x, in stratum c
 * (Camera_StratumOf(cam, sample)). always_inline: in the fused kernel's sample loop the per-pixel part of
 * the random key and the pixel's coordinates are then computed once per pixel (the compiler hoists them). */
__attribute__((always_inline)) inline void Camera_GenerateAt(CameraParams cam, SceneParams scene, int pixel, int x,
                                                             int y, int sample, CameraStratum c, PathState* path,
                                                             Ray* ray) {
    RngKey key = Rng_Key(scene.seed, pixel, sample, 1u);
    float jx = 0.5f, jy = 0.5f;
    if (cam.spp > 1) {
        jx = ((float)c.sx + Rng_Uniform(key, 0)) / (float)cam.strataX;
        jy = ((float)c.sy + Rng_Uniform(key, 1)) / (float)cam.strataY;
    }
    float3 dir = Camera_Direction(cam, (float)x + jx, (float)y + jy);
    float3 org = cam.position.xyz;
    if (cam.apertureSize > 0.0f && cam.focusDistance > 0.0f) {
        float3 dn = normalize(dir);
        float tFocus = cam.focusDistance / dot(dn, -cam.w.xyz);
        float3 focus = org + tFocus * dn;
        float a = (Rng_Uniform(key, 2) - 0.5f) * cam.apertureSize;
        float b = (Rng_Uniform(key, 3) - 0.5f) * cam.apertureSize;
        org = org + a * cam.u.xyz + b * cam.v.xyz;
        dir = focus - org;
    }
    dir = normalize(dir);
    Ray r;
    r.origin = (float4)(org, 0.0f);
#ifdef CLRT_HAS_MOTION_BLUR
    r.origin.w = MotionBlur_Time(scene.seed, pixel, sample);
#endif
    r.direction = (float4)(dir, INFINITY);
    *ray = r;
    PathState p;
    p.throughput = (float4)(1.0f, 1.0f, 1.0f, 0.0f);
    p.pixel = pixel;
    p.sample = sample;
    p.depth = 0;
    p.pathId = 1u;
    *path = p;
}

/* The camera ray and path of sample `sample` of pixel `pixel`. */
inline void Camera_Generate(CameraParams cam, SceneParams scene, int pixel, int sample, PathState* path, Ray* ray) {
    Camera_GenerateAt(cam, scene, pixel, pixel % cam.width, pixel / cam.width, sample, Camera_StratumOf(cam, sample),
                      path, ray);
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
