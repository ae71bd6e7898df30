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
        ds.features.backfaceCulling = ds.features.backfaceCulling || (scene.backfaceCulling && c.pathMode == 0);
    }
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
