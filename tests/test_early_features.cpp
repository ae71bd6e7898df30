// test_early_features.cpp — FlattenOptions::onFeaturesKnown, which clrt render uses to build the kernel
// program on another thread while the lights are flattened: called once, with exactly the feature set
// (the -D flags, BVH stack included) that the finished DeviceScene holds, on own and shared scenes
// covering lights of every kind, path tracing, spheres, motion blur, textures and instancing.
#include <catch.hpp>

#include <fstream>

#include "flatten/device_scene.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

void checkEarlyFeatures(const std::string& path, Instancing instancing) {
    INFO(path);
    const Scene scene = loadScene(path);
    int calls = 0;
    std::vector<std::string> early;
    FlattenOptions opts;
    opts.instancing = instancing;
    opts.onFeaturesKnown = [&](const FeatureSet& f) {
        ++calls;
        early = f.defines();
    };
    const DeviceScene ds = flattenScene(scene, opts);
    CHECK(calls == 1);
    CHECK(early == ds.features.defines());
}

}  // namespace

TEST_CASE("flatten: the feature set reported before the lights is the final one", "[features]") {
    for (const char* s : {"motion_blur.xml", "path_furnace_glass.xml", "transparency.xml", "mip_checker_plane.xml",
                          "perlin_octaves.xml", "demo.xml"})
        checkEarlyFeatures(std::string(CLRT_SOURCE_DIR) + "/scenes/" + s, Instancing::Auto);
    if (!haveShared()) return;
    for (const char* s : {"hw2/grass/grass_desert.xml", "hw5/head_env_light_courtyard.xml",
                          "hw3/cornellbox_area.xml", "hw6/cornellbox_jaroslav_glossy_area_sphere.xml",
                          "hw6/cornellbox_jaroslav_path_diffuse.xml", "hw4/brickwall_with_normalmap.xml"}) {
        const std::string path = sharedDir() + "/scenes/" + s;
        if (!std::ifstream(path)) continue;
        checkEarlyFeatures(path, Instancing::Auto);
        checkEarlyFeatures(path, Instancing::Flatten);
        checkEarlyFeatures(path, Instancing::TwoLevel);
    }
}
