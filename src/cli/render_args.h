// render_args.h — the options of `clrt render SCENE [options]` (its --help text, the parsed options,
// and their part of a render's identity). Reads no scene element; src/cli/render_cmd.cpp uses them.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "dist/dist_render.h"
#include "flatten/device_scene.h"
#include "render/progressive.h"
#include "render/renderer.h"

namespace clrt {

extern const char* const kRenderHelp;

struct RenderArgs {
    std::vector<std::string> positional;
    std::string outDir = ".", device, cameraId;
    int spp = 0, width = 0, height = 0;  // width/height: --resolution (0: the camera's own)
    uint32_t seed = 0;
    bool verbose = false, help = false, truncatePng = true, exrHalf = false, allFeatures = false;
    uint64_t maxMemory = 0;  // --max-memory: cap on the estimated host peak and device memory (0: none)
    PixelSampler pixelSampler = PixelSampler::Stratified;  // --sampler
    RouletteRule rouletteRule = RouletteRule::Unbiased;    // --rr-rule
    bool meshLightsByArea = false;  // --mesh-light-sampling area
    Instancing instancing = Instancing::Auto;              // --instancing
    int backfaceCulling = -1;  // --backface-culling: -1 auto (the scene's form decides), 0 off, 1 on
    int vertexNormals = -1;    // --vertex-normals: -1 auto (Scene::vertexNormals' default, area), 0 area, 1 unweighted
    int rayOrigin = -1;        // --ray-origin: -1 auto (Camera::nearMode's default), 0 eye, 1 plane
    std::string envStrategy;  // --env-sampling: overrides every environment light's env strategy ("" keeps the scene's)
    StopRule stop;            // --target-error, --time-limit (render/progressive.h)
    Pipeline pipeline = Pipeline::Auto;  // --pipeline
    DistSettings dist;        // --part, --checkpoint, --tile-pixels (src/dist/)
    std::string previewAddress;  // --preview [ADDR:]PORT ("" : none); --preview-keep
    bool previewKeep = false;
    std::string displayServer;   // --display-server HOST:PORT (tev)
};

// argv[start..): the options and the scene file; throws clrt::Error (ExitCode::Usage) on a bad one.
RenderArgs parseRenderArgs(int argc, char** argv, int start);

// The command-line options that change pixels, for the render identity of parts and checkpoints
// (the camera size, spp and seed are part of it elsewhere).
std::string pixelOptions(const RenderArgs& a);

}  // namespace clrt
