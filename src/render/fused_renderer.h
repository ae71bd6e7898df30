// The fused CPU path (issue 18): one kernel, render_fused (cl_kernels/fused.cl), per batch of pixels
// and sample passes, instead of the wavefront's eight kernels per bounce with queues between them.
// Renderer (renderer.cpp) owns one FusedPath per device and dispatches each tile to it or to the
// wavefront (choosePipeline); the image is the same, bit for bit, either way. Reads the scene through
// the kernel's scene group (bound by Renderer::Impl, src/shared/kernel_params.h CLRT_PARAMS_FUSED_SCENE).
#pragma once
#include <CL/opencl.hpp>

#include <functional>
#include <string>

#include "cl/devices.h"
#include "cl/kernel_args.h"
#include "render/render_types.h"
#include "shared/device_types.h"

namespace clrt {

// "fused", "lanes", "wavefront" or "auto".
const char* pipelineName(Pipeline p);
// Parses "fused" | "lanes" | "wavefront" | "auto"; false for anything else.
bool parsePipeline(const std::string& s, Pipeline& out);

// What the batches of a render look like, as far as the fused path cares (renderer.cpp's BatchPlan).
struct FusedPlan {
    int group = 1;       // samples of each pixel per pass (the wavefront's batch group: same sums)
    int lightSlots = 1;  // shadow-ray slots per light (2: multi-sample MIS environment light)
    bool bounces = false;
    bool tree = false;   // a path may have several children beyond the split depth (--rr-rule course with a
                         // mirror, conductor or dielectric): per-depth sums, as with a split
};

// Auto: fused on CPU devices for images of at least kFusedMinPixels pixels (the fused kernel has one
// work-item per pixel, the wavefront one per sample: a tiny image would leave cores idle), wavefront
// elsewhere; an explicit request is kept. *why (optional): the reason, for -v.
constexpr size_t kFusedMinPixels = 1024;
Pipeline choosePipeline(Pipeline requested, const DeviceInfo& device, size_t numPixels = kFusedMinPixels,
                        std::string* why = nullptr);

// Why render_lanes cannot render this camera ("" when it can): the scene is not of its family
// (notFamily: lanesFamily's reason, src/flatten/device_scene.h), or the camera or settings ask for what it lacks (the
// course's roulette, a split or tree of paths, a device other than a CPU).
std::string lanesUnsupported(const dev::SceneParams& sp, const FusedPlan& plan, const std::string& notFamily, bool cpuDevice);

// Why the fused path cannot render this plan ("" when it can): more depths than CLRT_FUSED_MAX_LEVELS
// with per-depth sums, or a dielectric split deeper than CLRT_FUSED_STACK_SIZE.
std::string fusedUnsupported(const dev::SceneParams& sp, const FusedPlan& plan);

class FusedPath {
public:
    FusedPath() = default;
    // localSize: the device's work-group size (DeviceContext::quirks().host; 0: the runtime's choice).
    FusedPath(cl::Context& ctx, const cl::Program& program, size_t localSize);
    // The kernel, for binding its scene group (Renderer::Impl::setRenderArgs).
    KernelArgs& kernel() { return k_; }
    // render_lanes (cl_kernels/lanes.cl), when the program has it (FeatureSet::lanes); null otherwise.
    KernelArgs* lanesKernel() { return hasLanes_ ? &lanes_ : nullptr; }

    // Renders every sample of pixels [tileFirst, tileEnd) into the bound image (as the wavefront's
    // renderTile), in launches of at most kPathsPerLaunch camera paths and at least kLaunchesPerTile
    // launches when there are that many sample groups (progress moves within a tile), unless stopped()
    // turns true between two launches. Returns the samples each pixel got.
    // lanes: with render_lanes (lanesKernel() must exist), in launches of four samples per pixel (one group
    // when a group has more), whatever the tile.
    int renderTile(cl::CommandQueue& q, bool profiling, size_t tileFirst, size_t tileEnd, size_t maxBatchPixels,
                   int spp, const FusedPlan& plan, const dev::SceneParams& sp, RenderCounters& counters,
                   const std::function<void(size_t, size_t)>& progress, const std::function<bool()>& stopped,
                   bool lanes = false);

    // RenderSettings::firstSample of the render in progress: samples [sampleBase, sampleBase + spp)
    // (the progressive passes of --target-error / --time-limit, render/progressive.h).
    int sampleBase = 0;
    // Paths per camera sample (SceneParams.split, the camera's SplittingFactor): a stop request ends the
    // tile only where every camera sample has all its paths.
    int split = 1;

    static constexpr size_t kPathsPerLaunch = size_t(1) << 18;
    static constexpr int kLaunchesPerTile = 32;

private:
    KernelArgs k_, lanes_;
    bool hasLanes_ = false;
    cl::Buffer rayCounts_;
    size_t localSize_ = 0;
};

}  // namespace clrt
