// The fused CPU path's host side (see fused_renderer.h): the launch loop over passes and pixel batches,
// the choice of pipeline per device, and the limits of the kernel's private arrays.
#include "render/fused_renderer.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "cl/check.h"
#include "cl/program.h"
#include "shared/kernel_params.h"

namespace clrt {

const char* pipelineName(Pipeline p) {
    switch (p) {
    case Pipeline::Fused: return "fused";
    case Pipeline::Lanes: return "lanes";
    case Pipeline::Wavefront: return "wavefront";
    default: return "auto";
    }
}

bool parsePipeline(const std::string& s, Pipeline& out) {
    if (s == "fused") out = Pipeline::Fused;
    else if (s == "lanes") out = Pipeline::Lanes;
    else if (s == "wavefront") out = Pipeline::Wavefront;
    else if (s == "auto") out = Pipeline::Auto;
    else return false;
    return true;
}

Pipeline choosePipeline(Pipeline requested, const DeviceInfo& device, size_t numPixels, std::string* why) {
    auto say = [&](const std::string& w) { if (why) *why = w; };
    if (requested != Pipeline::Auto) {
        say("--pipeline");
        return requested;
    }
    if (!(device.type & CL_DEVICE_TYPE_CPU)) {
        say(std::string("auto: ") + deviceTypeName(device.type) + " device");
        return Pipeline::Wavefront;
    }
    if (numPixels < kFusedMinPixels) {
        say("auto: CPU device, " + std::to_string(numPixels) + " pixels < " + std::to_string(kFusedMinPixels) +
            ": one work-item per pixel would leave cores idle");
        return Pipeline::Wavefront;
    }
    say("auto: CPU device");
    return Pipeline::Fused;
}

std::string lanesUnsupported(const dev::SceneParams& sp, const FusedPlan& plan, const std::string& notFamily, bool cpuDevice) {
    if (!cpuDevice) return "not a CPU device";
    if (!notFamily.empty()) return "scene: " + notFamily;
    if (sp.pathMode & CLRT_PATH_RR_COURSE) return "--rr-rule course";
    if (plan.tree || sp.splitDepth > 0) return "a tree of paths (splits)";
    return "";
}

std::string fusedUnsupported(const dev::SceneParams& sp, const FusedPlan& plan) {
    if (!plan.bounces) return "";
    if (sp.splitDepth > CLRT_FUSED_STACK_SIZE)
        return "dielectric split depth " + std::to_string(sp.splitDepth) + " > " + std::to_string(CLRT_FUSED_STACK_SIZE);
    const bool perDepthSums = plan.group > 1 || sp.splitDepth > 0 || plan.tree;  // as render_fused's `direct`
    const int depths = CLRT_LAST_DEPTH(sp.maxDepth, sp.pathMode) + 1;
    if (perDepthSums && depths > CLRT_FUSED_MAX_LEVELS)
        return "per-depth sums of " + std::to_string(depths) + " depths > " + std::to_string(CLRT_FUSED_MAX_LEVELS);
    return "";
}

namespace {
// Adds the device time of finished launches to the fused stage and releases their events.
void collectEvents(std::vector<cl::Event>& events, RenderCounters& counters) {
    for (cl::Event& e : events) {
        cl_ulong t0 = 0, t1 = 0;
        CL_CHECK(clGetEventProfilingInfo(e(), CL_PROFILING_COMMAND_START, sizeof t0, &t0, nullptr));
        CL_CHECK(clGetEventProfilingInfo(e(), CL_PROFILING_COMMAND_END, sizeof t1, &t1, nullptr));
        counters.stageSeconds[STAGE_FUSED] += t1 > t0 ? double(t1 - t0) * 1e-9 : 0.0;
    }
    events.clear();
}
}  // namespace

FusedPath::FusedPath(cl::Context& ctx, const cl::Program& program, size_t localSize)
    : k_(program, "render_fused"), localSize_(localSize) {
    size_t n = 0;
    CL_CHECK(clGetProgramInfo(program(), CL_PROGRAM_KERNEL_NAMES, 0, nullptr, &n));
    std::string names(n, '\0');
    CL_CHECK(clGetProgramInfo(program(), CL_PROGRAM_KERNEL_NAMES, n, &names[0], nullptr));
    hasLanes_ = (";" + std::string(names.c_str()) + ";").find(";render_lanes;") != std::string::npos;
    if (hasLanes_) lanes_ = KernelArgs(program, "render_lanes");
    rayCounts_ = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, 16));
}

int FusedPath::renderTile(cl::CommandQueue& q, bool profiling, size_t tileFirst, size_t tileEnd,
                          size_t maxBatchPixels, int spp, const FusedPlan& plan, const dev::SceneParams& sp,
                          RenderCounters& counters, const std::function<void(size_t, size_t)>& progress,
                          const std::function<bool()>& stopped, bool lanes) {
    KernelArgs& k = lanes ? lanes_ : k_;
    const int group = std::max(1, plan.group);
    const size_t batch = std::max<size_t>(1, std::min(tileEnd - tileFirst, maxBatchPixels / size_t(group)));
    const int allGroups = spp / group;  // whole groups; a partial last one is a launch of its own
    int maxPasses = int(std::max<size_t>(
        1, std::min<size_t>(kPathsPerLaunch / (batch * size_t(group)), size_t(allGroups / kLaunchesPerTile))));
    // The lanes kernel: launches of four samples per pixel (or one group of more), the same for every tile
    // and batch, so that a pixel's sums are made in the same order however the image is cut (its per-launch
    // sums follow the launches, render_fused's the passes).
    if (lanes) maxPasses = std::max(1, std::min(allGroups, (3 + group) / group));
    const size_t pixelBatches = (tileEnd - tileFirst + batch - 1) / batch;
    const size_t steps = size_t((allGroups + maxPasses - 1) / maxPasses) + (spp % group ? 1 : 0);
    const size_t totalBatches = steps * pixelBatches;
    const uint64_t shadowPerPath = uint64_t(std::max(sp.numLights, 0)) * uint64_t(plan.lightSlots);
    size_t doneBatches = 0;
    std::vector<cl::Event> events;
    const cl_uint zero[4] = {0, 0, 0, 0};
    counters.fused = true;
    counters.lanes = counters.lanes || lanes;
    k.set("lightSlots", plan.lightSlots).set("rayCounts", rayCounts_);
    for (int sample = 0; sample < spp;) {
        if (sample > 0 && sample % split == 0 && stopped()) {
            counters.stoppedAtSample = counters.stoppedAtSample < 0 ? sample : std::min(counters.stoppedAtSample, sample);
            return sample;
        }
        // Whole groups, several per launch; a last partial group alone (one `samples` per launch).
        const int fullGroups = (spp - sample) / group;
        const int samples = fullGroups > 0 ? group : spp - sample;
        const int passes = fullGroups > 0 ? std::min(fullGroups, maxPasses) : 1;
        for (size_t first = tileFirst; first < tileEnd; first += batch) {
            const int n = int(std::min(batch, tileEnd - first));
            if (plan.bounces) CL_CPP(q.enqueueWriteBuffer(rayCounts_, CL_FALSE, 0, sizeof zero, zero));
            k.set("count", n).set("firstPixel", int(first)).set("firstSample", sampleBase + sample).set("samples", samples);
            k.set("passes", passes);
            cl::Event ev;
            CL_CPP(q.enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(roundUp(size_t(n), localSize_)),
                                          localSize_ ? cl::NDRange(localSize_) : cl::NullRange, nullptr,
                                          profiling ? &ev : nullptr));
            const uint64_t cameraRays = uint64_t(n) * uint64_t(samples) * uint64_t(passes);
            uint64_t secondary = 0;
            if (plan.bounces) {  // blocking: the count of this launch (a 32-bit counter per launch)
                cl_uint c[4] = {0, 0, 0, 0};
                CL_CPP(q.enqueueReadBuffer(rayCounts_, CL_TRUE, 0, sizeof c, c));
                secondary = c[0];
            }
            counters.cameraRays += cameraRays;
            counters.secondaryRays += secondary;
            counters.shadowRays += (cameraRays + secondary) * shadowPerPath;
            if (sp.pathMode != 0) counters.pathSegments += cameraRays + secondary;
            if (profiling) events.push_back(ev);
            ++doneBatches;
            if (progress || plan.bounces || events.size() >= 64) {
                CL_CPP(q.finish());
                collectEvents(events, counters);
                if (progress) progress(doneBatches, totalBatches);
            }
        }
        sample += samples * passes;
    }
    CL_CPP(q.finish());
    collectEvents(events, counters);
    return spp;
}

}  // namespace clrt
