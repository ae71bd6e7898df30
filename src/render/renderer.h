// src/render/: the renderers, DeviceScene to pixels (wavefront, fused CPU path, several devices, progressive passes, queue compaction).
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
#include "flatten/device_scene.h"
#include "image/image.h"
#include "render/render_types.h"

namespace clrt {

// How the numbers of a pixel's samples are drawn (clrt render --sampler, SceneParams.pixelSampler).
// Stratified: camera jitter, lens, light and BSDF 2D samples stratified over a pixel's samples (a
// scrambled (0,2)-sequence, cl_kernels/common.cl); Independent: every number independent, the noise of
// renderers that sample so (tests/test_brdf.cpp); ZSobol: every dimension (camera, lens, time, picks,
// light, BSDF, roulette) from one Owen-scrambled Sobol sequence in Z order over the pixels (common.cl);
// Correlated: Stratified, but a camera sample's pixel jitter point is also its lens point and every light
// sample of the classic renderer, as the course's renderer drew them until 2022 (Sampler_Camera2D in
// common.cl; biased: only for comparing with those references).
enum class PixelSampler {
    Independent = CLRT_PIXEL_SAMPLER_INDEPENDENT,
    Stratified = CLRT_PIXEL_SAMPLER_STRATIFIED,
    ZSobol = CLRT_PIXEL_SAMPLER_ZSOBOL,
    Correlated = CLRT_PIXEL_SAMPLER_CORRELATED
};
// "stratified", "independent", "zsobol", "correlated" (the --sampler values); false for any other name.
bool parsePixelSampler(const std::string& name, PixelSampler& out);
const char* pixelSamplerName(PixelSampler s);

// The Russian roulette of RussianRoulette cameras (clrt render --rr-rule). Unbiased (the default): q =
// min(1, largest throughput component), survivors divided by q. Course: the biased rule that
// reproduces the course's hw6 references (cl_kernels/path.cl Path_CourseRoulette,
// docs/studies/2026-12-03-russian-roulette-references.md); not for MultipleImportanceSampling cameras.
enum class RouletteRule { Unbiased, Course };
// "unbiased", "course" (the --rr-rule values); false for any other name.
bool parseRouletteRule(const std::string& name, RouletteRule& out);

const char* renderStageName(int stage);  // RenderStage -> "generate", "trace camera", ...

struct RenderSettings {
    int spp = 1;
    int firstSample = 0;               // renders samples [firstSample, firstSample + spp) of each pixel
                                       // (their mean; the stratification is that of spp samples):
                                       // a pass of a progressive render (render/progressive.h)
    uint32_t seed = 0;
    size_t maxBatchPixels = 1u << 18;  // camera paths per batch (pixels x samples of each)
    int splitDepthOverride = -1;       // >= 0: force the dielectric split depth
    PixelSampler pixelSampler = PixelSampler::Stratified;  // clrt render --sampler
    RouletteRule rouletteRule = RouletteRule::Unbiased;    // clrt render --rr-rule
    const std::atomic<bool>* stop = nullptr;  // set (from any thread): end after the current sample pass
    Pipeline pipeline = Pipeline::Auto;
};

// A render program built beforehand (clrt render builds it while the scene is still being flattened):
// it must have been built on the same context with scene.features.defines().
struct BuiltProgram {
    cl::Program program;
    BuildInfo info;
};

class Renderer {
public:
    // Builds the render program for scene.features, or takes `prebuilt` when it holds one.
    Renderer(DeviceContext& dc, const DeviceScene& scene, const BuiltProgram* prebuilt = nullptr);
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
