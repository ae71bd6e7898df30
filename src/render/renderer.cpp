// Wavefront renderer driver (see renderer.h). Queue layout: paths/rays/hits of the current depth at
// [0, n); children at slots 2i and 2i+1 of the next-queue buffers, then compacted in order on the
// device (render/queue_compact.h), so paths of one pixel stay adjacent and summation order is fixed.
// The queue length n lives on the device (queueCount); the host launches each bounce over a bound
// and learns n one bounce late from a non-blocking read, so the device never waits for the host.
#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "cl/check.h"
#include "cl/kernel_args.h"
#include "cl/scene_buffers.h"
#include "render/queue_compact.h"
#include "render/fused_renderer.h"
#include "shared/kernel_params.h"
#include "util/error.h"

namespace clrt {

struct BatchPlan;

struct Renderer::Impl {
    DeviceContext& dc;
    const DeviceScene& ds;
    // Owns the host memory of the scene buffers on CPU devices (cl/scene_buffers.h): declared before every
    // buffer, so destroyed after them; ~Impl waits for the queue first.
    SceneBufferUploader uploader;
    BuildInfo build;
    cl::Program program;
    KernelArgs kGenerate, kIntersect, kShadow, kShade, kLights, kGather, kAccumulate;
    QueueCompactor compactor;
    FusedPath fused;  // the fused CPU path (fused_renderer.h), bound to the same scene buffers
    // Every kernel argument, each named as the kernel parameter it is bound to (src/shared/kernel_params.h):
    // bindAll() binds each kernel's whole parameter list from these members, by name.
    cl::Buffer nodes, leaves, tris, triShading, triAttributes, spheres, planes, instances, materials, textureSets, textures, images, texels, lights, envDist, lightData;
    // Queue buffers (sized per render).
    size_t queueCapacity = 0, childCapacity = 0, shadowCapacity = 0;
    int childSlots = 2;  // child slots per path of the current render (CLRT_CHILD_SLOTS)
    cl::Buffer paths, rays, hits, hitInstances, points, pathRadiance, nextPaths, nextRays, childValid, shadows;
    // The queue length on the device (one int each): the current bounce's, and the next one's that
    // the compaction writes (swapped after it). hostCounts[d]: the length at depth d, read back
    // without blocking (countReads[d] completes it).
    cl::Buffer queueCount, nextCount;
    std::vector<int> hostCounts = std::vector<int>(kMaxRecursionDepth + 2, 0);
    std::vector<cl::Event> countReads = std::vector<cl::Event>(kMaxRecursionDepth + 2);
    std::vector<size_t> countReadMarks = std::vector<size_t>(kMaxRecursionDepth + 2, 0);  // events.size() then
    // Per render: the image and the parameter blocks. Per launch (set again before each): the rest.
    cl::Buffer image;
    dev::SceneParams scene{};
    dev::CameraParams cam{};
    int count = 0, firstPixel = 0, firstSample = 0, samples = 1, lightBegin = 0, lightEnd = 0, lightSlots = 1, chunk = 0,
        raysPerPath = 0;
    int sampleBase = 0;  // RenderSettings::firstSample of the render in progress

    Impl(DeviceContext& d, const DeviceScene& s, const BuiltProgram* prebuilt)
        : dc(d), ds(s), uploader(d.context(), (d.info().type & CL_DEVICE_TYPE_CPU) != 0) {
        cl_command_queue_properties qp = 0;
        CL_CHECK(clGetCommandQueueInfo(dc.queue()(), CL_QUEUE_PROPERTIES, sizeof qp, &qp, nullptr));
        profiling = (qp & CL_QUEUE_PROFILING_ENABLE) != 0;
        if (prebuilt && prebuilt->program()) {
            program = prebuilt->program;
            build = prebuilt->info;
        } else {
            program = buildProgram(dc, KernelProgram::Render, ds.features.defines(), &build);
        }
        kGenerate = KernelArgs(program, "generate_camera_rays");
        kIntersect = KernelArgs(program, "intersect_closest");
        kShadow = KernelArgs(program, "intersect_shadow");
        kShade = KernelArgs(program, "shade_hits");
        kLights = KernelArgs(program, "sample_lights");
        kGather = KernelArgs(program, "gather_shadows");
        kAccumulate = KernelArgs(program, "accumulate");
        compactor = QueueCompactor(program);
        const char* bounds = std::getenv("CLRT_QUEUE_BOUNDS");
        exactBounds = bounds && *bounds ? std::string(bounds) == "exact" : (dc.info().type & CL_DEVICE_TYPE_CPU) != 0;
        cl::Context& ctx = dc.context();
        queueCount = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(int)));
        nextCount = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(int)));
        fused = FusedPath(ctx, program, localSize);
        nodes = uploader.upload(ds.bvh8.nodes);
        leaves = uploader.upload(ds.bvh8.leaves);
        tris = uploader.upload(ds.triangles);
        triShading = uploader.upload(ds.triangleShading);
        triAttributes = uploader.upload(ds.triangleAttributes);
        spheres = uploader.upload(ds.spheres);
        planes = uploader.upload(ds.planes);
        instances = uploader.upload(ds.instances);
        materials = uploader.upload(ds.materials);
        textureSets = uploader.upload(ds.textureSets);
        textures = uploader.upload(ds.textures);
        images = uploader.upload(ds.images);
        texels = uploader.upload(ds.texels);
        lights = uploader.upload(ds.lights);
        envDist = uploader.upload(ds.envDistribution);
        lightData = uploader.upload(ds.lightData);
        if (verbose()) info("scene buffers on " + dc.info().name + ": " + uploader.summary());
    }

    ~Impl() {
        try {
            dc.queue().finish();  // no command may still read the uploader's memory
        } catch (...) {
        }
    }

    // `capacity` paths per queue, `slotsPerPath` child slots per path, `shadowSlots` shadow rays.
    void ensureQueues(size_t capacity, int slotsPerPath, size_t shadowSlots) {
        cl::Context& ctx = dc.context();
        auto rw = [&](size_t bytes) { return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, std::max<size_t>(bytes, 16))); };
        if (capacity > queueCapacity || capacity * size_t(slotsPerPath) > childCapacity) {
            queueCapacity = std::max(queueCapacity, capacity);
            childCapacity = std::max(childCapacity, capacity * size_t(slotsPerPath));
            // Sized by the largest request so far: a render with fewer paths but more child slots per path
            // than an earlier one reallocates here too, and must not shrink the path buffers.
            paths = rw(sizeof(dev::PathState) * queueCapacity);
            rays = rw(sizeof(dev::Ray) * queueCapacity);
            hits = rw(sizeof(dev::Hit) * queueCapacity);
            // Written by every intersect_closest of a program built with CLRT_HAS_INSTANCES (--all-features
            // too, instances or not: oclgrind caught the writes past a 16 B buffer), read with it.
            hitInstances = rw(ds.features.instances ? sizeof(int) * queueCapacity : 0);
            points = rw(sizeof(dev::ShadingPoint) * queueCapacity);
            pathRadiance = rw(sizeof(dev::float4) * queueCapacity);
            nextPaths = rw(sizeof(dev::PathState) * childCapacity);
            nextRays = rw(sizeof(dev::Ray) * childCapacity);
            childValid = rw(sizeof(int) * childCapacity);
            compactor.setBuffers(ctx, childCapacity, queueCapacity, childValid, nextPaths, nextRays, paths, rays);
        }
        if (shadowSlots > shadowCapacity) {
            shadowCapacity = shadowSlots;
            shadows = rw(sizeof(dev::ShadowRay) * shadowSlots);
        }
    }

    // The device's work-group size (quirk FIXED_WORK_GROUP, src/cl/quirks.cpp: 64 on every device, as
    // PoCL compiles a kernel once per distinct local size); 0 would let the runtime choose.
    size_t localSize = dc.quirks().host.workGroupSize;
    // With a profiling queue, each launch keeps its event and stage until collectProfile(), which runs
    // whenever the queue is drained (at least every batch and every kProfileEvents launches), so
    // host memory stays flat however many samples or bounces a render takes.
    static constexpr size_t kProfileEvents = 256;
    bool profiling = false;
    struct Launched {
        int stage, depthBin;
        cl::Event ev;
    };
    std::vector<Launched> events;
    int depthBin = 0;  // RenderCounters' depth bin of the bounce being enqueued
    // Launch each bounce over its exact queue length (wait for it) rather than a bound (see traceBatch):
    // CPU devices; CLRT_QUEUE_BOUNDS=exact|lagged overrides (for measuring both).
    bool exactBounds = false;
    // n work-items (rounded up to whole work-groups of `local`, default localSize).
    void run(KernelArgs& k, size_t n, int stage, size_t local = 0) {
        if (n == 0) return;
        if (local == 0) local = localSize;
        cl::Event ev;
        CL_CPP(dc.queue().enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(roundUp(n, local)),
                                               local ? cl::NDRange(local) : cl::NullRange, nullptr,
                                               profiling ? &ev : nullptr));
        if (profiling) events.push_back({stage, depthBin, ev});
    }
    // Adds the device time of the first `upTo` launches (all by default; they must have finished:
    // the queue drained, or a later command waited for) to `c` and releases their events.
    void collectProfile(RenderCounters& c, size_t upTo = SIZE_MAX) {
        upTo = std::min(upTo, events.size());
        for (size_t i = 0; i < upTo; ++i) {
            cl_ulong start = 0, end = 0;
            CL_CHECK(clGetEventProfilingInfo(events[i].ev(), CL_PROFILING_COMMAND_START, sizeof start, &start, nullptr));
            CL_CHECK(clGetEventProfilingInfo(events[i].ev(), CL_PROFILING_COMMAND_END, sizeof end, &end, nullptr));
            const double s = end > start ? double(end - start) * 1e-9 : 0.0;
            const int stage = events[i].stage;
            c.stageSeconds[stage] += s;
            if (stage == STAGE_TRACE_CAMERA || stage == STAGE_TRACE_SECONDARY) c.extendSeconds[events[i].depthBin] += s;
            if (stage == STAGE_TRACE_SHADOW) c.shadowSeconds[events[i].depthBin] += s;
        }
        events.erase(events.begin(), events.begin() + std::ptrdiff_t(upTo));
        for (size_t& mark : countReadMarks) mark = mark > upTo ? mark - upTo : 0;
    }

    // Binds every parameter of every kernel from the member of the same name: the per-render values
    // given here, the per-launch ones with their current values (the loop sets those again).
    void setRenderArgs(const dev::CameraParams& cp, const dev::SceneParams& sp, const cl::Buffer& img);
    // Traces `n` camera paths (already generated) through every bounce and accumulates them into the
    // image (see traceBatch in renderer.cpp).
    void traceBatch(int n, const BatchPlan& plan, RenderCounters& counters);
    void enqueueBounce(size_t bound, const BatchPlan& plan);
    void enqueueCompaction(int depth, size_t bound);
    int queueLength(int depth, RenderCounters& counters);
    void countBounce(int depth, int length, const BatchPlan& plan, RenderCounters& counters);
    // Every batch of pixels [tileFirst, tileEnd), all samples (after setRenderArgs), unless stopped()
    // turns true between two sample groups. Returns the samples each pixel got.
    int renderTile(size_t tileFirst, size_t tileEnd, const BatchPlan& plan, RenderCounters& counters,
                   const std::function<void(size_t, size_t)>& progress, const std::function<bool()>& stopped);

    // Reads pixels [first, end) back into `out`, scaled by `inv` (each tile's pixels are written by
    // exactly one device). Blocking, so the queue is drained afterwards.
    void readTile(cl::Buffer& image, size_t first, size_t end, float inv, ImageRGB& out) {
        tilePixels.resize(end - first);
        CL_CPP(dc.queue().enqueueReadBuffer(image, CL_TRUE, first * sizeof(dev::float4),
                                            tilePixels.size() * sizeof(dev::float4), tilePixels.data()));
        for (size_t i = 0; i < tilePixels.size(); ++i) {
            float* o = &out.pixels[(first + i) * 3];
            o[0] = tilePixels[i].x * inv;
            o[1] = tilePixels[i].y * inv;
            o[2] = tilePixels[i].z * inv;
        }
    }
    std::vector<dev::float4> tilePixels;
};

// Why the program has no render_lanes: the scene's reason, or a program built without it (--all-features).
static std::string lanesFamilyOrBuild(const DeviceScene& ds) {
    const std::string why = lanesFamily(ds);
    return why.empty() ? "the program was built without CLRT_HAS_LANES" : why;
}

void Renderer::Impl::setRenderArgs(const dev::CameraParams& cp, const dev::SceneParams& sp, const cl::Buffer& img) {
    cam = cp;
    scene = sp;
    image = img;
    CLRT_BIND_GROUP(kGenerate, CLRT_KERNEL_generate_camera_rays, *this);
    CLRT_BIND_GROUP(kIntersect, CLRT_KERNEL_intersect_closest, *this);
    CLRT_BIND_GROUP(kShadow, CLRT_KERNEL_intersect_shadow, *this);
    CLRT_BIND_GROUP(kShade, CLRT_KERNEL_shade_hits, *this);
    CLRT_BIND_GROUP(kLights, CLRT_KERNEL_sample_lights, *this);
    CLRT_BIND_GROUP(kGather, CLRT_KERNEL_gather_shadows, *this);
    CLRT_BIND_GROUP(kAccumulate, CLRT_KERNEL_accumulate, *this);
    CLRT_BIND_GROUP(fused.kernel(), CLRT_PARAMS_FUSED_SCENE, *this);
    if (KernelArgs* lanes = fused.lanesKernel()) CLRT_BIND_GROUP((*lanes), CLRT_PARAMS_FUSED_SCENE, *this);
}

const char* renderStageName(int stage) {
    static const char* names[STAGE_COUNT] = {"generate", "trace camera", "trace secondary", "shade", "sample lights",
                                             "trace shadow", "gather", "accumulate", "compact", "fused"};
    return stage >= 0 && stage < STAGE_COUNT ? names[stage] : "?";
}

// The --sampler names, one row per PixelSampler.
static const struct { PixelSampler kind; const char* name; } kPixelSamplers[] = {
    {PixelSampler::Stratified, "stratified"}, {PixelSampler::Independent, "independent"}, {PixelSampler::ZSobol, "zsobol"},
    {PixelSampler::Correlated, "correlated"}};

bool parsePixelSampler(const std::string& name, PixelSampler& out) {
    for (const auto& row : kPixelSamplers)
        if (name == row.name) {
            out = row.kind;
            return true;
        }
    return false;
}

bool parseRouletteRule(const std::string& name, RouletteRule& out) {
    if (name != "unbiased" && name != "course") return false;
    out = name == "course" ? RouletteRule::Course : RouletteRule::Unbiased;
    return true;
}

const char* pixelSamplerName(PixelSampler s) {
    for (const auto& row : kPixelSamplers)
        if (s == row.kind) return row.name;
    return "?";
}

Renderer::Renderer(DeviceContext& dc, const DeviceScene& scene, const BuiltProgram* prebuilt)
    : impl_(new Impl(dc, scene, prebuilt)) {}
Renderer::~Renderer() = default;
const BuildInfo& Renderer::buildInfo() const { return impl_->build; }
DeviceContext& Renderer::context() { return impl_->dc; }

// Refuses an image whose float buffer the device cannot hold, before anything of its size is allocated.
static void checkImageFits(const DeviceInfo& di, const Camera& cam) {
    const uint64_t imageBytes = uint64_t(cam.width) * uint64_t(cam.height) * sizeof(dev::float4);
    if (imageBytes > di.maxAlloc || imageBytes > di.globalMem / 2)
        throw Error("camera " + std::to_string(cam.id) + ": " + std::to_string(cam.width) + "x" +
                        std::to_string(cam.height) + " needs " + std::to_string(imageBytes >> 20) +
                        " MiB of image memory; device '" + di.name + "' allows " + std::to_string(di.maxAlloc >> 20) +
                        " MiB per buffer",
                    ExitCode::BadInput);
}

ImageRGB Renderer::render(const Camera& cam, const RenderSettings& settings, RenderCounters& counters,
                          const std::function<void(size_t, size_t)>& progress) {
    checkImageFits(impl_->dc.info(), cam);
    ImageRGB out;
    out.width = cam.width;
    out.height = cam.height;
    out.isHdr = true;
    out.pixels.assign(size_t(cam.width) * cam.height * 3, 0.0f);
    bool handedOut = false;
    renderTiles(
        cam, settings, counters,
        [&](size_t& first, size_t& count) {
            if (handedOut) return false;
            handedOut = true;
            first = 0;
            count = size_t(cam.width) * cam.height;
            return true;
        },
        out, progress);
    return out;
}

// Samples of each pixel per batch. A small image takes several, so that a launch has enough work
// (a 1x1 image at 1M spp: 4096 batches instead of 1M). A function of the image size and spp only,
// never of the tile or the batch limit: each pixel sums its paths in the same order on every device
// and under every tiling, so its value does not depend on them.
static int samplesPerBatch(size_t numPixels, int spp) {
    const size_t targetPaths = size_t(1) << 16, maxSamples = 256;
    return int(std::min({std::max<size_t>(1, targetPaths / std::max<size_t>(numPixels, 1)), maxSamples, size_t(spp)}));
}

// How a render is cut into batches and how large the queues are. A batch is `group` samples of each
// of `batch` pixels, pixel-major. Every figure depends only on the image, the settings and the scene,
// never on the tile: every device and every tiling computes each pixel identically.
struct BatchPlan {
    int group = 1;          // samples of each pixel per batch
    size_t batch = 1;       // pixels per batch
    size_t capacity = 0;    // queue slots: batch * group paths, times 2^splitDepth when materials bounce
                            // (times kCourseQueueGrowth under the course rule's three-way splits)
    int childSlots = 2;     // child slots per path (CLRT_CHILD_SLOTS)
    int maxChildren = 1;    // children a path may have beyond the split depth: 3 under courseSplit
    size_t lightChunk = 0;  // lights per sample_lights launch (0: the scene has none)
    int lightSlots = 1;     // shadow-ray slots per light: 2 with a multi-sample MIS environment light
    bool bounces = false;   // some material spawns children
};

// Under the course rule's three-way splits (planBatches) the queue holds this many times a batch's camera
// paths; a deeper queue keeps its first paths (compact.cl), which the course's glass box never reaches
// (its children mostly end at their next hit).
constexpr size_t kCourseQueueGrowth = 4;

// The plan for `numPixels` pixels at cp.spp samples; sets the split depth (and seed, depth cap) in `sp`.
static BatchPlan planBatches(const DeviceScene& ds, size_t numPixels, const RenderSettings& settings,
                             const dev::CameraParams& cp, dev::SceneParams& sp) {
    BatchPlan plan;
    // --rr-rule course: the course references' roulette (needs the BSDF pdf slot MIS uses: not with MIS)
    if ((sp.pathMode & CLRT_PATH_RR) && !(sp.pathMode & CLRT_PATH_MIS) && settings.rouletteRule == RouletteRule::Course)
        sp.pathMode |= CLRT_PATH_RR_COURSE;
    // Under it a specular material traces all its children (up to three, Path_CourseSpecularChildren): the
    // queue holds kCourseQueueGrowth times a batch's paths, the batch shrinking by as much (same memory).
    const bool courseSplit = (sp.pathMode & CLRT_PATH_RR_COURSE) &&
                             (ds.features.has(dev::MATERIAL_DIELECTRIC) || ds.features.has(dev::MATERIAL_MIRROR) ||
                              ds.features.has(dev::MATERIAL_CONDUCTOR));
    const size_t growth = courseSplit ? kCourseQueueGrowth : 1;
    plan.childSlots = CLRT_CHILD_SLOTS(sp.pathMode);
    plan.maxChildren = courseSplit ? 3 : 1;
    plan.group = samplesPerBatch(numPixels, cp.spp);
    plan.batch = std::max<size_t>(1, std::min(numPixels, settings.maxBatchPixels / size_t(plan.group) / growth));
    const size_t batchPaths = plan.batch * size_t(plan.group);
    plan.bounces = ds.features.bounces() || sp.pathMode != 0;
    sp.seed = settings.seed;
    sp.pixelSampler = int(settings.pixelSampler);
    sp.samplerWidth = cp.width;  // the Z order and index width of CLRT_PIXEL_SAMPLER_ZSOBOL
    sp.samplerLog2Spp = 0;
    while (sp.samplerLog2Spp < 31 && (1 << sp.samplerLog2Spp) < cp.spp) ++sp.samplerLog2Spp;
    // Path tracing with Russian roulette has no depth cap (the course's references show none): the
    // roulette ends paths, kMaxRecursionDepth is the backstop.
    if (sp.pathMode & CLRT_PATH_RR) sp.maxDepth = kMaxRecursionDepth;
    sp.maxDepth = std::min(sp.maxDepth, kMaxRecursionDepth);
    // Dielectrics split into both children while the queue can hold them and few samples are taken;
    // beyond that (or with many samples) one child is chosen by Fresnel weight (same expectation).
    int split = 0;
    if (ds.features.has(dev::MATERIAL_DIELECTRIC) && cp.spp <= 4 && sp.pathMode == 0) {
        while (split < sp.maxDepth && (batchPaths << (split + 1)) <= (size_t(1) << 21)) ++split;
    }
    if (settings.splitDepthOverride >= 0) split = settings.splitDepthOverride;
    sp.splitDepth = split;
    plan.capacity = plan.bounces ? (batchPaths << split) * growth : batchPaths;
    for (const dev::Light& l : ds.lights)
        if (l.kind == dev::LIGHT_ENVIRONMENT && l.envStrategy == dev::ENV_STRATEGY_MIS && l.distribution != CLRT_INVALID)
            plan.lightSlots = 2;  // sample_lights' EnvLight_SampleMis: a light and a cosine sample
    if (sp.numLights > 0) {
        size_t budget = (size_t(256) << 20) / sizeof(dev::ShadowRay) / size_t(plan.lightSlots);
        plan.lightChunk = std::max<size_t>(1, std::min<size_t>(sp.numLights, budget / plan.capacity));
    }
    return plan;
}

// Enqueues the kernels of one bounce over `bound` paths: the queue holds *queueCount <= bound of them
// on the device, and each kernel returns beyond that.
void Renderer::Impl::enqueueBounce(size_t bound, const BatchPlan& plan) {
    run(kIntersect, bound, depthBin == 0 ? STAGE_TRACE_CAMERA : STAGE_TRACE_SECONDARY);
    run(kShade, bound, STAGE_SHADE);
    const int numLights = scene.numLights;
    for (int l0 = 0; l0 < numLights; l0 += int(plan.lightChunk)) {
        const int l1 = std::min(numLights, l0 + int(plan.lightChunk));
        const int perPath = (l1 - l0) * plan.lightSlots;
        kLights.set("lightBegin", l0).set("lightEnd", l1).set("lightSlots", plan.lightSlots);
        run(kLights, bound, STAGE_SAMPLE_LIGHTS);
        kShadow.set("raysPerPath", perPath);
        run(kShadow, bound * size_t(perPath), STAGE_TRACE_SHADOW);
        kGather.set("chunk", perPath);
        run(kGather, bound, STAGE_GATHER);
    }
    run(kAccumulate, bound, STAGE_ACCUMULATE);
}

// Compacts the children of depth `depth` (childSlots per path, at most childSlots * bound) on the device into the
// next queue, reads its length into hostCounts[depth + 1] without blocking, and makes it current.
void Renderer::Impl::enqueueCompaction(int depth, size_t bound) {
    const QueueCompactor::Launch launch = [this](KernelArgs& k, size_t items, size_t local) {
        run(k, items, STAGE_COMPACT, local);
    };
    compactor.enqueue(launch, queueCount, nextCount, childSlots, size_t(childSlots) * bound);
    CL_CPP(dc.queue().enqueueReadBuffer(nextCount, CL_FALSE, 0, sizeof(int), &hostCounts[size_t(depth) + 1], nullptr,
                                        &countReads[size_t(depth) + 1]));
    countReadMarks[size_t(depth) + 1] = events.size();  // the launches before the read
    std::swap(queueCount, nextCount);
    for (KernelArgs* k : {&kIntersect, &kShadow, &kShade, &kLights, &kGather, &kAccumulate}) k->set("queueCount", queueCount);
}

// The length of the queue at depth >= 1, waiting for its read (enqueued a bounce earlier, so the
// device still has the current bounce to work on). Releases the profiling events it has finished.
int Renderer::Impl::queueLength(int depth, RenderCounters& counters) {
    CL_CPP(countReads[size_t(depth)].wait());
    countReads[size_t(depth)] = cl::Event();
    if (countReadMarks[size_t(depth)] >= kProfileEvents) collectProfile(counters, countReadMarks[size_t(depth)]);
    return hostCounts[size_t(depth)];
}

// Rays traced at `depth` for a queue of `length` paths (shadow slots: one per path, light and slot).
void Renderer::Impl::countBounce(int depth, int length, const BatchPlan& plan, RenderCounters& counters) {
    const uint64_t n = uint64_t(length), shadowRays = n * uint64_t(scene.numLights) * uint64_t(plan.lightSlots);
    if (depth > 0) counters.secondaryRays += n;
    if (depth > 0 && scene.pathMode != 0) counters.pathSegments += n;
    counters.extendRays[depthBin] += n;
    counters.shadowRays += shadowRays;
    counters.shadowRaysAt[depthBin] += shadowRays;
}

// Every bounce of a batch of n camera paths. Lagged (GPUs): the host learns each queue length one
// bounce late, so each bounce is launched over a bound, the length two depths back times the children
// a path may have (2 while dielectrics split, else 1), at most the queue capacity; the device always
// has the next bounce queued. Exact (CPU devices): the host waits for each length as soon as the
// compaction has run and launches the next bounce over exactly that many paths (a CPU pays for
// every launched work-group, and the host's wait idles nothing). Ends after MaxRecursionDepth or at
// the first empty queue (lagged: one empty bounce may already be enqueued; its kernels return at once).
void Renderer::Impl::traceBatch(int n, const BatchPlan& plan, RenderCounters& counters) {
    CL_CPP(dc.queue().enqueueFillBuffer(queueCount, n, 0, sizeof(int)));
    size_t bound = size_t(n);
    int length = n;  // the length of the queue at `depth`, once known
    for (int depth = 0;; ++depth) {
        depthBin = std::min(depth, RenderCounters::kDepthBins - 1);
        enqueueBounce(bound, plan);
        const bool last = !plan.bounces || depth >= CLRT_LAST_DEPTH(scene.maxDepth, scene.pathMode);
        if (!last) enqueueCompaction(depth, bound);
        if (depth > 0 && !exactBounds) length = queueLength(depth, counters);
        countBounce(depth, length, plan, counters);
        if (depth > 0 && size_t(length) >= plan.capacity && plan.maxChildren > 1) ++counters.fullQueues;
        if (last || length == 0) break;
        bound = std::min(plan.capacity, size_t(length) * size_t(depth < scene.splitDepth ? 2 : plan.maxChildren));
        if (!exactBounds) continue;
        length = queueLength(depth + 1, counters);  // waits for this bounce's compaction
        bound = size_t(length);
        if (length > 0 && size_t(length) >= plan.capacity && plan.maxChildren > 1) ++counters.fullQueues;
        if (length == 0) break;
    }
}

int Renderer::Impl::renderTile(size_t tileFirst, size_t tileEnd, const BatchPlan& plan, RenderCounters& counters,
                               const std::function<void(size_t, size_t)>& progress,
                               const std::function<bool()>& stopped) {
    const int spp = cam.spp;
    const size_t totalBatches =
        ((size_t(spp) + plan.group - 1) / plan.group) * ((tileEnd - tileFirst + plan.batch - 1) / plan.batch);
    size_t doneBatches = 0;
    for (int sample = 0; sample < spp; sample += plan.group) {
        if (sample > 0 && sample % std::max(scene.split, 1) == 0 && stopped()) {
            counters.stoppedAtSample = counters.stoppedAtSample < 0 ? sample : std::min(counters.stoppedAtSample, sample);
            return sample;
        }
        const int samples = std::min(plan.group, spp - sample);
        for (size_t first = tileFirst; first < tileEnd; first += plan.batch) {
            const int n = int(std::min(plan.batch, tileEnd - first)) * samples;
            kGenerate.set("firstPixel", int(first)).set("firstSample", sampleBase + sample).set("samples", samples);
            kGenerate.set("count", n);
            run(kGenerate, n, STAGE_GENERATE);
            counters.cameraRays += n;
            if (scene.pathMode != 0) counters.pathSegments += n;
            traceBatch(n, plan, counters);
            ++doneBatches;
            if (progress || events.size() >= kProfileEvents) {
                CL_CPP(dc.queue().finish());
                collectProfile(counters);
                if (progress) progress(doneBatches, totalBatches);
            }
        }
    }
    return spp;
}

void Renderer::renderTiles(const Camera& cam, const RenderSettings& settings, RenderCounters& counters,
                           const std::function<bool(size_t&, size_t&)>& nextTile, ImageRGB& out,
                           const std::function<void(size_t, size_t)>& progress) {
    Impl& m = *impl_;
    auto t0 = std::chrono::steady_clock::now();
    dev::CameraParams cp = makeCameraParams(cam);
    // The loader and the command line already cap both (with a warning); this is the backstop for
    // scenes built in code. With a SplittingFactor k each camera sample carries k paths: the kernels run
    // k·spp path samples, path sample s taking camera sample s / k (camera.cl), and everything below
    // counts path samples; settings and counters count camera samples.
    const int split = std::clamp(cam.splittingFactor, 1, kMaxSamplesPerPixel);
    setSamplesPerPixel(cp, int(std::min<int64_t>(int64_t(settings.spp) * split, kMaxSamplesPerPixel / split * split)));
    if (int64_t(settings.firstSample) * split > int64_t(INT32_MAX) - cp.spp)
        throw Error("camera " + std::to_string(cam.id) + ": samples beyond 2^31 per pixel (SplittingFactor " +
                    std::to_string(split) + " x " + std::to_string(settings.firstSample) + " samples before this pass)");
    const size_t numPixels = size_t(cam.width) * cam.height;
    const size_t imageBytes = numPixels * sizeof(dev::float4);
    checkImageFits(m.dc.info(), cam);
    dev::SceneParams sp = m.ds.params;
    sp.pathMode = cam.pathMode;  // per camera: <Renderer>PathTracing (compiled in when any camera has it)
    if (cam.maxRecursionDepth >= 0) sp.maxDepth = cam.maxRecursionDepth;  // the camera's own (2025 scenes)
    sp.rrMinDepth = std::max(0, cam.minRecursionDepth);                    // likewise: no roulette before it
    sp.split = split;                                                      // and its SplittingFactor
    if (sp.pathMode != 0 && !m.ds.features.pathTracing)
        throw Error("camera " + std::to_string(cam.id) + " is path traced but the program was built without CLRT_HAS_PATH_TRACING");
    if (settings.pixelSampler == PixelSampler::ZSobol && !m.ds.features.zsobol)
        throw Error("--sampler zsobol, but the program was built without CLRT_HAS_ZSOBOL (FeatureSet::zsobol)");
    if (settings.pixelSampler == PixelSampler::Correlated && !m.ds.features.correlatedSampler)
        throw Error("--sampler correlated, but the program was built without CLRT_HAS_CORRELATED_SAMPLER (FeatureSet::correlatedSampler)");
    const BatchPlan plan = planBatches(m.ds, numPixels, settings, cp, sp);
    m.ensureQueues(plan.capacity, plan.childSlots, plan.capacity * std::max<size_t>(plan.lightChunk, 1) * size_t(plan.lightSlots));
    m.childSlots = plan.childSlots;

    cl::Buffer image = CL_CPP(cl::Buffer(m.dc.context(), CL_MEM_READ_WRITE, imageBytes));
    CL_CPP(m.dc.queue().enqueueFillBuffer(image, dev::float4{0, 0, 0, 0}, 0, imageBytes));
    m.setRenderArgs(cp, sp, image);
    m.sampleBase = settings.firstSample * split;
    m.fused.sampleBase = settings.firstSample * split;
    m.fused.split = split;
    const int stoppedBefore = counters.stoppedAtSample;
    counters.stoppedAtSample = -1;
    // Fused (CPU devices) or wavefront: the same image either way (fused_renderer.h).
    const FusedPlan fusedPlan{plan.group, plan.lightSlots, plan.bounces, plan.maxChildren > 1};
    std::string why;
    Pipeline pipeline = choosePipeline(settings.pipeline, m.dc.info(), numPixels, &why);
    // Lanes where the camera can have it: on request, and by default on CPU devices (auto chose fused).
    // They also take cameras whose depths outnumber render_fused's per-depth sums (roulette, several
    // samples per group): their sums put the deepest levels together, which changes only rounding.
    std::string notLanes;
    if (pipeline == Pipeline::Lanes || (pipeline == Pipeline::Fused && settings.pipeline == Pipeline::Auto)) {
        notLanes = lanesUnsupported(sp, fusedPlan, m.fused.lanesKernel() ? "" : lanesFamilyOrBuild(m.ds),
                                    (m.dc.info().type & CL_DEVICE_TYPE_CPU) != 0);
        if (notLanes.empty() && settings.pipeline == Pipeline::Auto)
            notLanes = lanesNoGain(m.ds, sp.pathMode == 0, plan.lightSlots == 2);
        pipeline = notLanes.empty() ? Pipeline::Lanes : Pipeline::Fused;
    }
    const std::string notFused = pipeline == Pipeline::Fused ? fusedUnsupported(sp, fusedPlan) : "";
    if (!notFused.empty()) pipeline = Pipeline::Wavefront;
    if (verbose())
        info("camera " + std::to_string(cam.id) + " on " + m.dc.info().name + ": pipeline " + pipelineName(pipeline) +
             " (" + why + ")" + (notFused.empty() ? "" : "; not fused: " + notFused) +
             (notLanes.empty() ? "" : "; not lanes: " + notLanes));

    // settings.stop: a tile in progress ends after its current group of samples (at least one), no
    // new tile is started after the first.
    const std::function<bool()> stopped = [&] { return settings.stop && settings.stop->load(); };
    size_t tileFirst = 0, tileCount = 0, tilesHere = 0;
    while (!(tilesHere++ > 0 && stopped()) && nextTile(tileFirst, tileCount)) {
        const size_t tileEnd = std::min(numPixels, tileFirst + tileCount);
        const int reached =
            pipeline != Pipeline::Wavefront
                ? m.fused.renderTile(m.dc.queue(), m.profiling, tileFirst, tileEnd, settings.maxBatchPixels, cp.spp,
                                     fusedPlan, sp, counters, progress, stopped, pipeline == Pipeline::Lanes)
                : m.renderTile(tileFirst, tileEnd, plan, counters, progress, stopped);
        m.readTile(image, tileFirst, tileEnd, 1.0f / float(reached), out);
        counters.tiles += 1;
        counters.pixels += tileEnd - tileFirst;
        m.collectProfile(counters);  // the blocking read above drained the queue
    }
    if (counters.stoppedAtSample >= 0) counters.stoppedAtSample /= split;  // a multiple of split: camera samples
    if (stoppedBefore >= 0)
        counters.stoppedAtSample = counters.stoppedAtSample < 0 ? stoppedBefore : std::min(stoppedBefore, counters.stoppedAtSample);
    m.image = cl::Buffer();  // released with the render (the kernels' binding is replaced on the next)
    counters.profiled = counters.profiled || m.profiling;
    counters.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace clrt
