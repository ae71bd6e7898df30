// flatten_scene.cpp — flattenScene(), the driver of the flattening (see device_scene.h): the scene
// model's materials, textures, geometry (with the BVH) and lights into one DeviceScene, by the parts
// of flatten.h (one domain per flatten_*.cpp file), and the scene-wide parameters.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "flatten/device_scene.h"
#include "flatten/flatten.h"

namespace clrt {

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

namespace {

// Whether some primitive's box in the BVH (world triangles and spheres from nodes[0], instances from the top
// level's root) overlaps `box`: a conservative test, its leaves' boxes standing for their primitives.
bool bvhMeets(const Bvh8& bvh, int node, const Aabb& box) {
    const dev::Bvh8Node& n = bvh.nodes[size_t(node)];
    for (int i = 0; i < kBvhWidth; ++i) {
        const int entry = laneEntry(n, i);
        if (entry == CLRT_INVALID) continue;
        bool overlaps = true;
        for (int a = 0; a < 3; ++a)
            overlaps = overlaps && lanePlane(n, 2 * a, i) <= (&box.max.x)[a] && lanePlane(n, 2 * a + 1, i) >= (&box.min.x)[a];
        // a leaf, or an instance (the top level's lanes, Entry_Instance in intersect.cl): negative entries
        if (overlaps && (entry < 0 || bvhMeets(bvh, entry, box))) return true;
    }
    return false;
}

// Whether camera c's rays may meet a triangle between its eye (or lens) and its image plane, where by
// default they skip back faces (Camera::nearMode, CLRT_NEAR_FRONT): the box around the eye and the image
// plane's corners, widened by the aperture, against the BVH. Only then is the culling compiled in.
bool nearSegmentMeetsGeometry(const Camera& c, const DeviceScene& ds) {
    if (c.nearMode != CLRT_NEAR_FRONT || ds.bvh8.nodes.empty()) return false;
    Aabb box;
    box.grow(c.position);
    for (float x : {c.left, c.right})
        for (float y : {c.bottom, c.top}) box.grow(c.position + c.u * x + c.v * y - c.w * c.nearDistance);
    float widen = 0.0f;
    if (c.apertureSize > 0.0f && c.focusDistance > 0.0f) widen = c.apertureSize * (1.0f + c.nearDistance / c.focusDistance);
    if (!std::isfinite(widen)) return true;
    box.min = box.min - Vec3(widen);
    box.max = box.max + Vec3(widen);
    return bvhMeets(ds.bvh8, 0, box) || (ds.params.numInstances > 0 && bvhMeets(ds.bvh8, ds.params.instanceRoot, box));
}

}  // namespace

// The driver: one function per domain (flatten.h), in an order that fixes where images enter the
// atlas (textures, then environment maps); opts.onFeaturesKnown between the BVH and the lights.
DeviceScene flattenScene(const Scene& scene, const FlattenOptions& opts) {
    auto t0 = std::chrono::steady_clock::now();
    // Scratch arrays freed during flattening (the BVH builder's items and binary nodes) lend their pages
    // to the arrays made after them (util/huge_pages.h); what is left is freed on return.
    HugeRecycling recycling;
    DeviceScene ds;
    ImageAtlas atlas(scene, ds);
    flattenMaterials(scene, ds);
    flattenTextures(scene, ds, atlas);
    flattenGeometry(scene, ds, opts);
    // The last features (light kinds as flattenLights marks them, path tracing) before the lights,
    // whose environment distributions take a while: the program can build meanwhile.
    for (const Light& l : scene.lights) {
        ds.features.add(l.type);
        ds.features.envRotation = ds.features.envRotation || isEnvironmentTurned(l);
    }
    for (const Camera& c : scene.cameras) {
        ds.features.pathTracing = ds.features.pathTracing || c.pathMode != 0;
        // culling: the classic renderer's in scenes that cull, a camera's before its image plane where it may matter
        ds.features.backfaceCulling = ds.features.backfaceCulling || (scene.backfaceCulling && c.pathMode == 0) ||
                                      nearSegmentMeetsGeometry(c, ds);
    }
    ds.features.lanes = lanesFamily(ds).empty();  // the lanes kernel compiled in (cl_kernels/lanes.cl)
    if (opts.onFeaturesKnown) opts.onFeaturesKnown(ds.features);
    flattenLights(scene, ds, atlas);
    dev::SceneParams& p = ds.params;
    p.background = toFloat4(scene.backgroundColor);
    p.ambient = toFloat4(scene.ambientLight);
    p.maxDepth = std::max(0, scene.maxRecursionDepth);
    p.shadowEpsilon = std::isfinite(scene.shadowRayEpsilon) ? std::max(0.0f, scene.shadowRayEpsilon) : 0.0f;
    p.cullBackFaces = scene.backfaceCulling ? 1 : 0;
    ds.flattenSeconds = secondsSince(t0) - ds.bvhSeconds;
    return ds;
}

}  // namespace clrt
