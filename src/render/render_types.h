// The types the renderers share (renderer.h and fused_renderer.h): the kernel stages a
// render times, which pipeline renders (wavefront or fused), and the counters a render fills in.
// Kept apart from renderer.h so that the fused path needs no part of the wavefront renderer.
#pragma once
#include <cstdint>

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
// Lanes: the fused path with four paths per work-item in vector lanes (cl_kernels/lanes.cl), for scenes
// of its family (lanesFamily, lanesUnsupported); auto takes it there on CPU devices.
enum class Pipeline { Auto, Wavefront, Fused, Lanes };

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
    bool lanes = false;  // ... with render_lanes (Pipeline::Lanes)
    uint64_t fullQueues = 0;   // bounces whose child queue reached its capacity (--rr-rule course's three-way
                               // splits, renderer.cpp kCourseQueueGrowth): children beyond it were dropped
    int stoppedAtSample = -1;  // >= 0: RenderSettings::stop ended the render early; the fewest samples
                               // any pixel got (tiles in progress finish their current pass, >= 1)
};

}  // namespace clrt
