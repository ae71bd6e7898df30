// Wavefront renderer driver (see renderer.h). Queue layout: paths/rays/hits of the current depth at
// [0, n); children at slots 2i and 2i+1 of the next-queue buffers, then compacted in order with
// indices from a prefix sum, so paths of one pixel stay adjacent and summation order is fixed.
#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "cl/check.h"
#include "util/error.h"

namespace clrt {

namespace {
template <class T> cl::Buffer uploadBuffer(cl::Context& ctx, const std::vector<T>& v) {
    return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * std::max<size_t>(v.size(), 1),
                             const_cast<T*>(v.data())));
}
}  // namespace

struct Renderer::Impl {
    DeviceContext& dc;
    const DeviceScene& scene;
    BuildInfo build;
    cl::Program program;
    cl::Kernel kGenerate, kIntersect, kShadow, kShade, kLights, kGather, kAccumulate, kCompact;
    cl::Buffer nodes, primRefs, tris, triShading, spheres, planes, materials, textureSets, textures, images, texels, lights, envDist;
    // Queue buffers (sized per render).
    size_t queueCapacity = 0, shadowCapacity = 0;
    cl::Buffer paths, rays, hits, points, pathRadiance, nextPaths, nextRays, childValid, compactTarget, shadows;

    Impl(DeviceContext& d, const DeviceScene& s) : dc(d), scene(s) {
        cl_command_queue_properties qp = 0;
        CL_CHECK(clGetCommandQueueInfo(dc.queue()(), CL_QUEUE_PROPERTIES, sizeof qp, &qp, nullptr));
        profiling = (qp & CL_QUEUE_PROFILING_ENABLE) != 0;
        std::vector<std::string> defines = scene.features.defines();
        program = buildProgram(dc, KernelProgram::Render, defines, &build);
        auto mk = [&](const char* name) { return CL_CPP(cl::Kernel(program, name)); };
        kGenerate = mk("generate_camera_rays");
        kIntersect = mk("intersect_closest");
        kShadow = mk("intersect_shadow");
        kShade = mk("shade_hits");
        kLights = mk("sample_lights");
        kGather = mk("gather_shadows");
        kAccumulate = mk("accumulate");
        kCompact = mk("compact_paths");
        cl::Context& ctx = dc.context();
        nodes = uploadBuffer(ctx, scene.bvh4.nodes);
        primRefs = uploadBuffer(ctx, scene.bvh.primRefs);
        tris = uploadBuffer(ctx, scene.triangles);
        triShading = uploadBuffer(ctx, scene.triangleShading);
        spheres = uploadBuffer(ctx, scene.spheres);
        planes = uploadBuffer(ctx, scene.planes);
        materials = uploadBuffer(ctx, scene.materials);
        textureSets = uploadBuffer(ctx, scene.textureSets);
        textures = uploadBuffer(ctx, scene.textures);
        images = uploadBuffer(ctx, scene.images);
        texels = uploadBuffer(ctx, scene.texels);
        lights = uploadBuffer(ctx, scene.lights);
        envDist = uploadBuffer(ctx, scene.envDistribution);
    }

    void ensureQueues(size_t capacity, size_t shadowSlots) {
        cl::Context& ctx = dc.context();
        auto rw = [&](size_t bytes) { return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, std::max<size_t>(bytes, 16))); };
        if (capacity > queueCapacity) {
            queueCapacity = capacity;
            paths = rw(sizeof(dev::PathState) * capacity);
            rays = rw(sizeof(dev::Ray) * capacity);
            hits = rw(sizeof(dev::Hit) * capacity);
            points = rw(sizeof(dev::ShadingPoint) * capacity);
            pathRadiance = rw(sizeof(dev::float4) * capacity);
            nextPaths = rw(sizeof(dev::PathState) * capacity * 2);
            nextRays = rw(sizeof(dev::Ray) * capacity * 2);
            childValid = rw(sizeof(int) * capacity * 2);
            compactTarget = rw(sizeof(int) * capacity * 2);
        }
        if (shadowSlots > shadowCapacity) {
            shadowCapacity = shadowSlots;
            shadows = rw(sizeof(dev::ShadowRay) * shadowSlots);
        }
    }

    // A fixed work-group size: PoCL compiles a kernel once per distinct local size, so letting the
    // runtime choose (it varies with the global size) would recompile at every queue length.
    size_t localSize = 64;
    // With a profiling queue, every launch keeps its event and stage until collectProfile().
    bool profiling = false;
    std::vector<std::pair<int, cl::Event>> events;
    void run(cl::Kernel& k, size_t n, int stage) {
        if (n == 0) return;
        cl::Event ev;
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, localSize)),
                                               cl::NDRange(localSize), nullptr, profiling ? &ev : nullptr));
        if (profiling) events.emplace_back(stage, ev);
    }
    // Adds the device time of the finished launches to `c` (the queue must have been drained).
    void collectProfile(RenderCounters& c) {
        for (auto& [stage, ev] : events) {
            cl_ulong start = 0, end = 0;
            CL_CHECK(clGetEventProfilingInfo(ev(), CL_PROFILING_COMMAND_START, sizeof start, &start, nullptr));
            CL_CHECK(clGetEventProfilingInfo(ev(), CL_PROFILING_COMMAND_END, sizeof end, &end, nullptr));
            c.stageSeconds[stage] += end > start ? double(end - start) * 1e-9 : 0.0;
        }
        events.clear();
    }
};

const char* renderStageName(int stage) {
    static const char* names[STAGE_COUNT] = {"generate", "trace camera", "trace secondary", "shade", "sample lights",
                                             "trace shadow", "gather", "accumulate", "compact"};
    return stage >= 0 && stage < STAGE_COUNT ? names[stage] : "?";
}

Renderer::Renderer(DeviceContext& dc, const DeviceScene& scene) : impl_(new Impl(dc, scene)) {}
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

void Renderer::renderTiles(const Camera& cam, const RenderSettings& settings, RenderCounters& counters,
                           const std::function<bool(size_t&, size_t&)>& nextTile, ImageRGB& out,
                           const std::function<void(size_t, size_t)>& progress) {
    Impl& m = *impl_;
    auto t0 = std::chrono::steady_clock::now();
    const DeviceScene& ds = m.scene;
    dev::CameraParams cp = makeCameraParams(cam);
    setSamplesPerPixel(cp, settings.spp);
    const size_t numPixels = size_t(cam.width) * cam.height;
    const size_t imageBytes = numPixels * sizeof(dev::float4);
    checkImageFits(m.dc.info(), cam);

    // The split depth depends only on the image and the batch limit, never on the tile: every
    // device and every tiling computes each pixel identically.
    const size_t batch = std::min(numPixels, settings.maxBatchPixels);
    const bool bounces = ds.features.mirror || ds.features.dielectric || ds.features.conductor;
    dev::SceneParams sp = ds.params;
    sp.seed = settings.seed;
    // Dielectrics split into both children while the queue can hold them and few samples are taken;
    // beyond that (or with many samples) one child is chosen by Fresnel weight (same expectation).
    int split = 0;
    if (ds.features.dielectric && cp.spp <= 4) {
        while (split < sp.maxDepth && (batch << (split + 1)) <= (size_t(1) << 21)) ++split;
    }
    if (settings.splitDepthOverride >= 0) split = settings.splitDepthOverride;
    sp.splitDepth = split;
    const size_t capacity = bounces ? batch << split : batch;
    const int numLights = sp.numLights;
    size_t lightChunk = 0;
    if (numLights > 0) {
        size_t budget = (size_t(256) << 20) / sizeof(dev::ShadowRay);
        lightChunk = std::max<size_t>(1, std::min<size_t>(numLights, budget / capacity));
    }
    m.ensureQueues(capacity, capacity * std::max<size_t>(lightChunk, 1));

    cl::CommandQueue& q = m.dc.queue();
    cl::Buffer image = CL_CPP(cl::Buffer(m.dc.context(), CL_MEM_READ_WRITE, imageBytes));
    CL_CPP(q.enqueueFillBuffer(image, dev::float4{0, 0, 0, 0}, 0, imageBytes));

    // Kernel arguments that do not change within the render.
    cl::Kernel& kg = m.kGenerate;
    kg.setArg(0, sizeof(cp), &cp);
    kg.setArg(1, sizeof(sp), &sp);
    kg.setArg(5, m.paths);
    kg.setArg(6, m.rays);
    auto setGeometry = [&](cl::Kernel& k) {
        k.setArg(0, m.nodes); k.setArg(1, m.primRefs); k.setArg(2, m.tris); k.setArg(3, m.spheres);
        k.setArg(4, sp.numTriangles);
    };
    setGeometry(m.kIntersect);
    m.kIntersect.setArg(5, m.rays);
    m.kIntersect.setArg(6, m.hits);
    const int firstPlaneRef = sp.numTriangles + sp.numSpheres;
    m.kIntersect.setArg(8, m.planes); m.kIntersect.setArg(9, sp.numPlanes); m.kIntersect.setArg(10, firstPlaneRef);
    m.kShadow.setArg(7, m.planes); m.kShadow.setArg(8, sp.numPlanes); m.kShadow.setArg(9, firstPlaneRef);
    setGeometry(m.kShadow);
    m.kShadow.setArg(5, m.shadows);
    cl::Kernel& ks = m.kShade;
    ks.setArg(0, sizeof(sp), &sp);
    ks.setArg(1, sizeof(cp), &cp);
    {
        int a = 3;
        for (cl::Buffer* b : {&m.paths, &m.rays, &m.hits, &m.tris, &m.triShading, &m.spheres, &m.materials,
                              &m.textureSets, &m.textures, &m.images, &m.texels, &m.points, &m.pathRadiance,
                              &m.nextPaths, &m.nextRays, &m.childValid, &m.planes})
            ks.setArg(a++, *b);
    }
    cl::Kernel& kl = m.kLights;
    kl.setArg(0, sizeof(sp), &sp);
    kl.setArg(4, m.paths); kl.setArg(5, m.points); kl.setArg(6, m.lights); kl.setArg(7, m.shadows);
    kl.setArg(8, m.images); kl.setArg(9, m.texels); kl.setArg(10, m.envDist);
    m.kGather.setArg(2, m.shadows); m.kGather.setArg(3, m.pathRadiance);
    m.kAccumulate.setArg(1, m.paths); m.kAccumulate.setArg(2, m.pathRadiance); m.kAccumulate.setArg(3, image);
    m.kCompact.setArg(1, m.compactTarget); m.kCompact.setArg(2, m.nextPaths); m.kCompact.setArg(3, m.nextRays);
    m.kCompact.setArg(4, m.paths); m.kCompact.setArg(5, m.rays);

    std::vector<int> valid, target;
    std::vector<dev::float4> tilePixels;
    const float inv = 1.0f / float(cp.spp);
    size_t tileFirst = 0, tileCount = 0;
    while (nextTile(tileFirst, tileCount)) {
        const size_t tileEnd = std::min(numPixels, tileFirst + tileCount);
        const size_t totalBatches = size_t(cp.spp) * ((tileEnd - tileFirst + batch - 1) / batch);
        size_t doneBatches = 0;
        for (int sample = 0; sample < cp.spp; ++sample) {
            for (size_t first = tileFirst; first < tileEnd; first += batch) {
                int n = int(std::min(batch, tileEnd - first));
                kg.setArg(2, int(first)); kg.setArg(3, sample); kg.setArg(4, n);
                m.run(kg, n, STAGE_GENERATE);
                counters.cameraRays += n;
                for (int depth = 0; n > 0; ++depth) {
                    m.kIntersect.setArg(7, n);
                    m.run(m.kIntersect, n, depth == 0 ? STAGE_TRACE_CAMERA : STAGE_TRACE_SECONDARY);
                    ks.setArg(2, n);
                    m.run(ks, n, STAGE_SHADE);
                    for (int l0 = 0; l0 < numLights; l0 += int(lightChunk)) {
                        int l1 = std::min(numLights, l0 + int(lightChunk));
                        int slots = n * (l1 - l0);
                        kl.setArg(1, n); kl.setArg(2, l0); kl.setArg(3, l1);
                        m.run(kl, n, STAGE_SAMPLE_LIGHTS);
                        m.kShadow.setArg(6, slots);
                        m.run(m.kShadow, slots, STAGE_TRACE_SHADOW);
                        m.kGather.setArg(0, n); m.kGather.setArg(1, l1 - l0);
                        m.run(m.kGather, n, STAGE_GATHER);
                        counters.shadowRays += slots;
                    }
                    m.kAccumulate.setArg(0, n);
                    m.run(m.kAccumulate, n, STAGE_ACCUMULATE);
                    if (!bounces || depth >= sp.maxDepth) break;
                    // Order-preserving compaction of the children.
                    size_t slots = size_t(n) * 2;
                    valid.resize(slots);
                    target.resize(slots);
                    CL_CPP(q.enqueueReadBuffer(m.childValid, CL_TRUE, 0, slots * sizeof(int), valid.data()));
                    int next = 0;
                    for (size_t i = 0; i < slots; ++i) target[i] = valid[i] ? next++ : -1;
                    if (next == 0) break;
                    // Blocking: `target` is resized on the next pass, so the copy must be done before then.
                    CL_CPP(q.enqueueWriteBuffer(m.compactTarget, CL_TRUE, 0, slots * sizeof(int), target.data()));
                    m.kCompact.setArg(0, int(slots));
                    m.run(m.kCompact, slots, STAGE_COMPACT);
                    n = next;
                    counters.secondaryRays += n;
                }
                ++doneBatches;
                if (progress) {
                    CL_CPP(q.finish());
                    progress(doneBatches, totalBatches);
                }
            }
        }
        // Read the tile back: each tile's pixels are written by exactly one device.
        tilePixels.resize(tileEnd - tileFirst);
        CL_CPP(q.enqueueReadBuffer(image, CL_TRUE, tileFirst * sizeof(dev::float4),
                                   tilePixels.size() * sizeof(dev::float4), tilePixels.data()));
        for (size_t i = 0; i < tilePixels.size(); ++i) {
            float* o = &out.pixels[(tileFirst + i) * 3];
            o[0] = tilePixels[i].x * inv;
            o[1] = tilePixels[i].y * inv;
            o[2] = tilePixels[i].z * inv;
        }
        counters.tiles += 1;
        counters.pixels += tileEnd - tileFirst;
        m.collectProfile(counters);  // the blocking read above drained the queue
    }
    counters.profiled = counters.profiled || m.profiling;
    counters.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace clrt
