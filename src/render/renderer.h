// src/render/: scene model to pixels (flattening, the wavefront renderer, several devices, device tone mapping, output files).
// The wavefront renderer on one OpenCL device: uploads a DeviceScene, builds the program specialised
// to its feature set, and renders a camera as a sequence of batches (a few samples of a pixel range;
// several samples per batch only for small images):
//   generate -> [intersect -> shade -> (sample lights -> shadow rays -> gather) -> accumulate
//   -> compact children (on the device)] until no path is left or MaxRecursionDepth is reached.
// Every figure of the result is a pure function of (scene, camera, seed): deterministic. Host and
// device memory stay flat however many samples or bounces a render takes (profiling events are
// released as batches complete; queue sizes depend only on the batch size).
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "cl/program.h"
#include "image/image.h"
#include "render/device_scene.h"

namespace clrt {

// The kernels of one bounce, for per-stage device times.
enum RenderStage {
    STAGE_GENERATE, STAGE_TRACE_CAMERA, STAGE_TRACE_SECONDARY, STAGE_SHADE, STAGE_SAMPLE_LIGHTS,
    STAGE_TRACE_SHADOW, STAGE_GATHER, STAGE_ACCUMULATE, STAGE_COMPACT,
    STAGE_FUSED,  // the fused CPU path's one kernel (src/render/fused_renderer.h): all of the above
    STAGE_COUNT
};

// Which kernels render: the wavefront (a kernel per stage, queues between them) or the fused path
// (one kernel per batch of pixels and sample passes, cl_kernels/fused.cl). Auto: fused on CPU
// devices, wavefront on the others; `clrt render --pipeline` overrides.
enum class Pipeline { Auto, Wavefront, Fused };

// How the numbers of a pixel's samples are drawn (clrt render --sampler, SceneParams.pixelSampler).
// Stratified: camera jitter, lens, light and BSDF 2D samples stratified over a pixel's samples (a
// scrambled (0,2)-sequence, cl_kernels/common.cl); Independent: every number independent, the noise of
// renderers that sample so (tests/test_brdf.cpp).
enum class PixelSampler { Independent = CLRT_PIXEL_SAMPLER_INDEPENDENT, Stratified = CLRT_PIXEL_SAMPLER_STRATIFIED };
// "stratified", "independent" (the --sampler values); false for any other name.
bool parsePixelSampler(const std::string& name, PixelSampler& out);
const char* pixelSamplerName(PixelSampler s);

const char* renderStageName(int stage);

struct RenderCounters {
    uint64_t cameraRays = 0, secondaryRays = 0, shadowRays = 0;
    uint64_t pathSegments = 0;  // path-traced cameras: camera + bounce rays (segments of the paths)
    uint64_t tiles = 0, pixels = 0;  // work done (tiles and pixels, all samples each)
    double seconds = 0;  // wall time of the render loop (device work included)
    // Device time of each stage's kernels from OpenCL profiling events (all zero when the queue was
    // made without profiling). Ray throughputs: rays of a kind / time of its trace kernel.
    double stageSeconds[STAGE_COUNT] = {};
    // By path depth, in bins 0, 1, 2 and >= 3 (kDepthBins - 1): the extension rays traced at that
    // depth (depth 0: camera rays; then the secondary rays of bounce d) and the shadow rays cast from
    // vertices of that depth, with the device time of the kernels that traced them.
    static constexpr int kDepthBins = 4;
    uint64_t extendRays[kDepthBins] = {}, shadowRaysAt[kDepthBins] = {};
    double extendSeconds[kDepthBins] = {}, shadowSeconds[kDepthBins] = {};
    bool profiled = false;
    bool fused = false;  // the fused path traced them: its one kernel has no per-depth split
    int stoppedAtSample = -1;  // >= 0: RenderSettings::stop ended the render early; the fewest samples
                               // any pixel got (tiles in progress finish their current pass, >= 1)
};

struct RenderSettings {
    int spp = 1;
    int firstSample = 0;               // renders samples [firstSample, firstSample + spp) of each pixel
                                       // (their mean; the stratification is that of spp samples):
                                       // a pass of a progressive render (render/progressive.h)
    uint32_t seed = 0;
    size_t maxBatchPixels = 1u << 18;  // camera paths per batch (pixels x samples of each)
    int splitDepthOverride = -1;       // >= 0: force the dielectric split depth
    PixelSampler pixelSampler = PixelSampler::Stratified;  // clrt render --sampler
    const std::atomic<bool>* stop = nullptr;  // set (from any thread): end after the current sample pass
    Pipeline pipeline = Pipeline::Auto;
};

class Renderer {
public:
    Renderer(DeviceContext& dc, const DeviceScene& scene);
    ~Renderer();
    const BuildInfo& buildInfo() const;
    // Renders one camera; `progress(doneBatches, totalBatches)` is called after each batch.
    ImageRGB render(const Camera& cam, const RenderSettings& settings, RenderCounters& counters,
                    const std::function<void(size_t, size_t)>& progress = {});

    // Renders the pixel ranges handed out by nextTile(first, count) (false: none left), all samples
    // of each, into `out` (width*height*3 floats, already sized). Several Renderers on different
    // devices may share `out`: tiles are disjoint, and a pixel's value does not depend on which
    // device or tile rendered it. `progress(doneBatches, totalBatches)` of the tile in hand, after
    // each batch.
    void renderTiles(const Camera& cam, const RenderSettings& settings, RenderCounters& counters,
                     const std::function<bool(size_t&, size_t&)>& nextTile, ImageRGB& out,
                     const std::function<void(size_t, size_t)>& progress = {});
    DeviceContext& context();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace clrt
