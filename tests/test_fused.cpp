// The fused CPU path (issue 18, cl_kernels/fused.cl, src/render/fused_renderer.cpp): it renders the
// wavefront's image bit for bit on PoCL (same physics functions, same random streams, sums in the same order;
// Intel's runtime contracts the two programs differently: its LightMesh scenes differ by rounding, docs/architecture.md)
// on shared scenes covering every kind of path tree and light: point, area, spot, environment (multi-
// sample MIS: two shadow slots), object lights, mirrors, conductors, dielectrics with the split tree
// (per-depth sums and the explicit stack) and without, several samples per group, textures, bump maps,
// planes, depth of field, motion blur, path tracing with and without Russian roulette; and the same
// ray counts. Also: determinism, the pipeline choice (auto: fused on CPU devices, wavefront on GPUs;
// fallback to the wavefront beyond the kernel's private arrays) and `clrt render --pipeline`.
// Sizes are reduced (at most 96 pixels a side, 1-8 spp) to keep the suite fast.
#include <catch.hpp>

#include <cstring>
#include <filesystem>
#include <string>

#include "flatten/device_scene.h"
#include "render/fused_renderer.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

double imageSum(const ImageRGB& img) {
    double s = 0;
    for (float v : img.pixels) s += v;
    return s;
}

}  // namespace

TEST_CASE("fused path: the wavefront's image bit for bit, and the same ray counts", "[fused][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    struct Case {
        const char* file;
        int w, h, spp;
        int camera;  // index into the scene's cameras
        int pathMode = -1;  // >= 0: replaces the camera's (dev CLRT_PATH_* bits)
    };
    // Images under 65,536 pixels take several samples per group (per-depth sums in fused.cl);
    // dielectrics at <= 4 spp split into both children (the explicit stack).
    const Case cases[] = {
        {"hw5/cube_point.xml", 48, 48, 1, 0},
        {"hw5/cube_point.xml", 256, 256, 3, 0},  // one sample per group, 3 passes in one launch
        {"hw5/cube_point.xml", 200, 100, 8, 0},  // 3 per group: 2 passes in a launch, then a group of 2
        {"hw5/sphere_env_light_courtyard.xml", 64, 32, 4, 0},       // environment MIS: two slots, 4 per group
        {"hw5/glass_sphere_env_interior.xml", 48, 48, 1, 0},        // dielectric split tree
        {"hw5/glass_sphere_env_interior_probe.xml", 32, 32, 8, 0},  // one child chosen by Fresnel, 8 per group
        {"hw5/mirror_sphere_env_interior_probe.xml", 40, 40, 2, 0},  // mirror, probe map
        {"classic/cornellbox_recursive.xml", 48, 48, 2, 0},          // mirror + glass, point light
        {"classic/metal_glass_plates.xml", 48, 32, 1, 0},            // conductor
        {"classic/spheres_dof.xml", 40, 40, 4, 0},                   // thin lens
        {"hw4/sphere_perlin_bump.xml", 40, 40, 1, 0},                // Perlin bump map
        {"hw4/brickwall_with_normalmap.xml", 40, 40, 1, 0},          // image normal map
        {"hw5/dragon_spot_light_msaa.xml", 48, 48, 2, 0},            // spot light, mesh
        {"hw6/cornellbox_jaroslav_diffuse_area.xml", 40, 40, 2, 0},  // area light (LightMesh)
        {"hw6/cornellbox_jaroslav_glossy_area_sphere.xml", 40, 40, 2, 0},  // LightSphere, BRDFs
        {"hw6/cornellbox_jaroslav_path_diffuse.xml", 32, 32, 2, 0},  // path tracing + NEE, depth 3, per-depth sums
        {"hw6/cornellbox_jaroslav_path_diffuse.xml", 256, 256, 1, 1},  // NEE + Russian roulette: no depth cap, one group
        // MIS, depth 3: the emission-only segment at depth 4 (per-depth sums; one path per depth)
        {"hw6/cornellbox_jaroslav_path_diffuse.xml", 32, 32, 2, 0, CLRT_PATH_ON | CLRT_PATH_MIS},
        {"hw6/cornellbox_jaroslav_path_diffuse.xml", 32, 32, 1, 0, CLRT_PATH_ON | CLRT_PATH_MIS},
        {"json2025/spheres_with_plane.json", 48, 32, 1, 0},          // infinite planes
    };
    for (const Case& c : cases) {
        const std::string path = sharedDir() + "/scenes/" + c.file;
        if (!std::filesystem::exists(path)) { WARN(path << " missing: skipped"); continue; }
        INFO(c.file << " " << c.w << "x" << c.h << " at " << c.spp << " spp, camera " << c.camera);
        Scene scene = loadScene(path);
        DeviceScene ds = flattenScene(scene);
        Renderer r(testContext(), ds);
        Camera cam = scene.cameras.at(c.camera);
        if (c.pathMode >= 0) cam.pathMode = c.pathMode;
        Rendered f = renderWith(r, cam, c.w, c.h, c.spp, 3, Pipeline::Fused);
        Rendered w = renderWith(r, cam, c.w, c.h, c.spp, 3, Pipeline::Wavefront);
        CHECK(differingFloats(f.image, w.image) == 0);
        CHECK(imageSum(f.image) > 0.0);
        CHECK(f.counters.cameraRays == w.counters.cameraRays);
        CHECK(f.counters.secondaryRays == w.counters.secondaryRays);
        CHECK(f.counters.shadowRays == w.counters.shadowRays);
        CHECK(f.counters.pathSegments == w.counters.pathSegments);
    }
}

TEST_CASE("fused path: the demo and motion-blur scenes bit for bit, any batching, deterministic", "[fused]") {
    Scene scene = loadScene(std::string(CLRT_SOURCE_DIR) + "/scenes/demo.xml");
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    const Camera& cam = scene.cameras.at(0);
    Rendered w = renderWith(r, cam, 96, 72, 3, 7, Pipeline::Wavefront);
    Rendered a = renderWith(r, cam, 96, 72, 3, 7, Pipeline::Fused);
    Rendered b = renderWith(r, cam, 96, 72, 3, 7, Pipeline::Fused);
    Rendered other = renderWith(r, cam, 96, 72, 3, 8, Pipeline::Fused);
    CHECK(differingFloats(a.image, b.image) == 0);       // same seed, same image
    CHECK(differingFloats(a.image, w.image) == 0);       // the wavefront's
    CHECK(differingFloats(a.image, other.image) > 0);    // another seed, another image
    // Small pixel batches and several passes per launch: the same floats.
    Rendered batched = renderWith(r, cam, 96, 72, 3, 7, Pipeline::Fused, 1000 + 17);
    CHECK(differingFloats(a.image, batched.image) == 0);
    // Motion blur: every ray of a sample at its shutter time.
    Scene mb = loadScene(std::string(CLRT_SOURCE_DIR) + "/scenes/motion_blur.xml");
    DeviceScene mbScene = flattenScene(mb);
    Renderer mbRenderer(testContext(), mbScene);
    Rendered mbF = renderWith(mbRenderer, mb.cameras.at(0), 64, 48, 4, 5, Pipeline::Fused);
    Rendered mbW = renderWith(mbRenderer, mb.cameras.at(0), 64, 48, 4, 5, Pipeline::Wavefront);
    CHECK(differingFloats(mbF.image, mbW.image) == 0);
    CHECK(imageSum(mbF.image) > 0.0);
}

TEST_CASE("pipeline choice: auto is fused on CPU devices and the wavefront on GPUs", "[fused]") {
    DeviceInfo cpu, gpu;
    cpu.type = CL_DEVICE_TYPE_CPU;
    gpu.type = CL_DEVICE_TYPE_GPU;
    CHECK(choosePipeline(Pipeline::Auto, cpu) == Pipeline::Fused);
    CHECK(choosePipeline(Pipeline::Auto, gpu) == Pipeline::Wavefront);
    CHECK(choosePipeline(Pipeline::Wavefront, cpu) == Pipeline::Wavefront);
    CHECK(choosePipeline(Pipeline::Fused, gpu) == Pipeline::Fused);
    std::string why;
    CHECK(choosePipeline(Pipeline::Auto, cpu, kFusedMinPixels - 1, &why) == Pipeline::Wavefront);  // a tiny image
    CHECK(why.find("pixels < ") != std::string::npos);
    CHECK(choosePipeline(Pipeline::Fused, cpu, 1) == Pipeline::Fused);
    Pipeline p = Pipeline::Auto;
    CHECK(parsePipeline("fused", p));
    CHECK(p == Pipeline::Fused);
    CHECK(parsePipeline("wavefront", p));
    CHECK(p == Pipeline::Wavefront);
    CHECK_FALSE(parsePipeline("Fused", p));
    // Beyond the kernel's private arrays the wavefront renders (and -v says why).
    dev::SceneParams sp{};
    FusedPlan plan;
    plan.bounces = true;
    sp.maxDepth = 256;  // Russian roulette
    plan.group = 1;
    CHECK(fusedUnsupported(sp, plan).empty());  // one path per depth: no per-depth sums
    plan.group = 4;
    CHECK_FALSE(fusedUnsupported(sp, plan).empty());
    sp.maxDepth = CLRT_FUSED_MAX_LEVELS - 1;
    CHECK(fusedUnsupported(sp, plan).empty());
    sp.splitDepth = CLRT_FUSED_STACK_SIZE + 1;
    CHECK_FALSE(fusedUnsupported(sp, plan).empty());
    plan.bounces = false;
    CHECK(fusedUnsupported(sp, plan).empty());
}

TEST_CASE("clrt render --pipeline: -v names the pipeline, a bad value is a usage error", "[fused][cli]") {
    TempDir t;
    const std::string scene = std::string(CLRT_SOURCE_DIR) + "/scenes/demo.xml";
    const std::string base = "render " + scene + " -o " + t.path.string() + " --resolution 40x30 --spp 1 -v";
    int rc = runClrt(base + " --device cpu", t.file("auto.log"));
    INFO(readFileBytes(t.file("auto.log")));
    CHECK(rc == 0);
    CHECK(readFileBytes(t.file("auto.log")).find("pipeline fused (auto: CPU device)") != std::string::npos);
    rc = runClrt(base + " --pipeline wavefront", t.file("wave.log"));
    CHECK(rc == 0);
    CHECK(readFileBytes(t.file("wave.log")).find("pipeline wavefront (--pipeline)") != std::string::npos);
    rc = runClrt(base + " --pipeline fused", t.file("fused.log"));
    CHECK(rc == 0);
    const std::string fusedLog = readFileBytes(t.file("fused.log"));
    CHECK(fusedLog.find("pipeline fused (--pipeline)") != std::string::npos);
    CHECK(fusedLog.find(" fused ") != std::string::npos);  // the kernel time line has the fused stage
    const int badRc = runClrt("render " + scene + " -o " + t.path.string() + " --pipeline gpu", t.file("bad.log"));
    CliResult bad = cliResult(badRc, readFileBytes(t.file("bad.log")));
    CHECK(bad.rc == 1);
    CHECK(bad.errorLines == 1);
    CHECK(bad.errorLine.find("--pipeline: expected fused, lanes, wavefront or auto, got 'gpu'") != std::string::npos);
}
