// render_cmd.cpp — `clrt render` (see render_cmd.h): the pipeline load -> output checks -> device
// contexts -> memory check -> flatten/BVH, with the kernel build on another thread from the moment the
// BVH fixes the feature set (while the lights are flattened) -> one camera at a time (cli/camera_drivers.cpp) -> stats, and the refusals made
// before any work (unknown camera, outputs that are inputs, an image no device can hold, options that
// do not go together), and the warning for a material that gains energy under uncapped roulette. Reads the
// scene's cameras (id, size, RendererParams), its materials (for that warning) and its input files.
#include "cli/render_cmd.h"

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "cl/devices.h"
#include "cl/program.h"
#include "cli/camera_drivers.h"
#include "cli/interrupt.h"
#include "cli/output_names.h"
#include "cli/render_args.h"
#include "cli/render_stats.h"
#include "dist/dist_render.h"
#include "dist/mpi_job.h"
#include "dist/part_file.h"
#include "flatten/device_scene.h"
#include "flatten/memory_estimate.h"
#include "output/output.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace clrt {

namespace {

// The cameras to render (--camera, else all); an error naming the scene if none.
std::vector<const Camera*> selectCameras(const Scene& scene, const RenderArgs& a) {
    std::vector<const Camera*> cams;
    for (const Camera& c : scene.cameras)
        if (a.cameraId.empty() || std::to_string(c.id) == a.cameraId) cams.push_back(&c);
    if (cams.empty())
        throw Error(a.positional[0] + (a.cameraId.empty() ? ": the scene has no camera" : ": no camera with id " + a.cameraId));
    return cams;
}

// An image no selected device can hold is refused here, before the BVH, the kernel build and any
// host allocation of its size (the renderer checks the same limit per device).
void checkImagesFit(const RenderArgs& a, const std::vector<const Camera*>& cams, const std::vector<DeviceInfo>& devs) {
    for (const Camera* c : cams) {
        const uint64_t bytes = uint64_t(c->width) * uint64_t(c->height) * sizeof(dev::float4);
        uint64_t best = 0;
        std::string bestName;
        for (const DeviceInfo& d : devs)
            if (std::min<uint64_t>(d.maxAlloc, d.globalMem / 2) >= best) {
                best = std::min<uint64_t>(d.maxAlloc, d.globalMem / 2);
                bestName = d.name;
            }
        if (bytes > best)
            throw Error(a.positional[0] + ": camera " + std::to_string(c->id) + ": " + std::to_string(c->width) + "x" +
                            std::to_string(c->height) + " needs " + std::to_string(bytes >> 20) +
                            " MiB of image memory; device '" + bestName + "' allows " + std::to_string(best >> 20) +
                            " MiB per buffer",
                        ExitCode::BadInput);
    }
}

// The scene's memory, estimated from its counts (flatten/memory_estimate.h), against the devices' limits,
// the machine's available memory and --max-memory: exit 2 with one line before anything of its size
// is flattened or allocated.
void checkMemory(const RenderArgs& a, const Scene& scene, const std::vector<DeviceInfo>& devs) {
    MemoryPlan plan;
    plan.devices = int(devs.size());
    plan.cpuDevices = false;
    for (const DeviceInfo& d : devs) plan.cpuDevices = plan.cpuDevices || (d.type & CL_DEVICE_TYPE_CPU) != 0;
    plan.spp = a.spp;
    plan.width = a.width;
    plan.height = a.height;
    plan.residentNow = residentBytes();
    const std::vector<bool> instanced = instancedShapes(scene, a.instancing);  // as flattenScene will store them
    plan.meshInstanced.assign(scene.meshes.size(), false);
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (instanced[i]) plan.meshInstanced[size_t(scene.shapes[i].meshIndex)] = true;
    const MemoryEstimate e = estimateMemory(scene, plan);
    MemoryLimits lim;
    lim.cap = a.maxMemory;
    for (const DeviceInfo& d : devs) {
        if (lim.deviceName.empty() || d.globalMem < lim.deviceGlobal) {
            lim.deviceGlobal = d.globalMem;
            lim.deviceName = d.name;
        }
        if (lim.deviceMaxAlloc == 0 || d.maxAlloc < lim.deviceMaxAlloc) lim.deviceMaxAlloc = d.maxAlloc;
    }
    const uint64_t available = availableHostMemory();
    lim.hostAvailable = available ? available + plan.residentNow : 0;
    if (verbose())
        info("memory estimate: host peak " + formatBytes(e.hostPeak(plan)) + ", per device " + formatBytes(e.devicePeak()) +
             " (geometry " + formatBytes(e.geometry.bytes) + ", bvh " + formatBytes(e.bvh.bytes) + ", textures " +
             formatBytes(e.textures.bytes) + ", lights " + formatBytes(e.lights.bytes) + ", render " +
             formatBytes(e.render.bytes) + "); limits: host " + formatBytes(lim.hostAvailable) + ", device " +
             formatBytes(lim.deviceGlobal) + " (" + formatBytes(lim.deviceMaxAlloc) + " per buffer)" +
             (lim.cap ? ", --max-memory " + formatBytes(lim.cap) : ""));
    const std::string problem = memoryProblem(e, plan, lim);
    if (!problem.empty()) throw Error(a.positional[0] + ": " + problem, ExitCode::BadInput);
}

// One context per device, made before the memory check so that the resident memory it starts from
// holds what the OpenCL runtimes allocate for them; a device whose context fails is dropped while
// others remain.
std::vector<std::unique_ptr<DeviceContext>> makeContexts(const std::vector<DeviceInfo>& devs) {
    std::vector<std::unique_ptr<DeviceContext>> out;
    for (const DeviceInfo& d : devs) {
        try {
            out.push_back(std::make_unique<DeviceContext>(d, /*profiling=*/!std::getenv("CLRT_NO_PROFILE")));  // per-kernel times for stats
        } catch (const Error& e) {
            if (devs.size() == 1) throw;
            warn("device [" + std::to_string(d.index) + "] " + d.name + " dropped: " + e.what());
        }
    }
    if (out.empty()) throw Error("no selected device could build the renderer", ExitCode::Device);
    return out;
}

std::vector<DeviceInfo> contextInfos(const std::vector<std::unique_ptr<DeviceContext>>& contexts) {
    std::vector<DeviceInfo> out;
    for (const auto& c : contexts) out.push_back(c->info());
    return out;
}

// The render programs of every context, built on another thread (start()) from the defines the
// flattening reports once its feature set is final (FlattenOptions::onFeaturesKnown); a device's
// build error is kept for makeRenderers.
struct ProgramBuilds {
    struct Result {
        BuiltProgram built;
        std::exception_ptr error;
    };
    std::vector<std::string> defines;
    std::future<std::vector<Result>> pending;

    void start(std::vector<std::unique_ptr<DeviceContext>>& contexts, std::vector<std::string> flags) {
        for (const auto& c : contexts)
            if (c->quirks().host.buildOnContextThread) return;  // the renderers build on this thread
        defines = std::move(flags);
        pending = std::async(std::launch::async, [&contexts, this] {
            std::vector<Result> out(contexts.size());
            for (size_t i = 0; i < contexts.size(); ++i) try {
                    out[i].built.program = buildProgram(*contexts[i], KernelProgram::Render, defines, &out[i].built.info);
                } catch (...) {
                    out[i].error = std::current_exception();
                }
            return out;
        });
    }
    // The results, when they were built for `flags`; else none (the renderers build their own).
    std::vector<Result> take(const std::vector<std::string>& flags) {
        if (!pending.valid()) return {};
        std::vector<Result> out = pending.get();
        if (flags == defines) return out;
        if (verbose()) info("kernel flags changed after the early build; building again");
        return {};
    }
};

// One renderer per context, on the program built early where there is one; a device whose setup
// fails is dropped while others remain.
struct DeviceRenderers {
    std::vector<std::unique_ptr<DeviceContext>> contexts;
    std::vector<std::unique_ptr<Renderer>> renderers;
};
DeviceRenderers makeRenderers(std::vector<std::unique_ptr<DeviceContext>>& contexts, const DeviceScene& ds,
                              ProgramBuilds& builds) {
    const std::vector<ProgramBuilds::Result> early = builds.take(ds.features.defines());  // the build thread is done
    DeviceRenderers out;
    const size_t n = contexts.size();
    for (size_t i = 0; i < n; ++i) {
        const DeviceInfo& d = contexts[i]->info();
        try {
            if (i < early.size() && early[i].error) std::rethrow_exception(early[i].error);
            auto r = std::make_unique<Renderer>(*contexts[i], ds, i < early.size() ? &early[i].built : nullptr);
            out.contexts.push_back(std::move(contexts[i]));
            out.renderers.push_back(std::move(r));
        } catch (const Error& e) {
            if (n == 1) throw;
            warn("device [" + std::to_string(d.index) + "] " + d.name + " dropped: " + e.what());
        }
    }
    if (out.renderers.empty()) throw Error("no selected device could build the renderer", ExitCode::Device);
    return out;
}

// What a render writes: the cameras' outputs, or with --part K/N one part file per camera.
std::vector<PlannedOutput> plannedOutputs(const RenderArgs& a, const Scene& scene, const std::vector<const Camera*>& cams) {
    std::vector<PlannedOutput> out = planRenderOutputs(scene, cams, a.outDir);
    if (a.dist.parts == 0) return out;
    out.clear();
    for (const Camera* c : cams) {
        const std::string name = partFileName(c->imageName, a.dist.part, a.dist.parts);
        if (!plainNameProblem(name).empty())
            throw Error(a.positional[0] + ": camera " + std::to_string(c->id) + ": part file name '" + name +
                        "' is not a plain file name (" + plainNameProblem(name) + ")");
        out.push_back({(std::filesystem::path(a.outDir) / name).string(), "camera " + std::to_string(c->id) + ": part file"});
    }
    return out;
}

// A camera path traced with Russian roulette has no depth cap: a surface that gives back more light than it
// receives (energyGainingMaterial) makes its image diverge (pixels of 1e10 and more). Said once, naming it.
void warnEnergyGain(const Scene& scene, const DeviceScene& ds, const std::vector<const Camera*>& cams) {
    const auto rr = std::find_if(cams.begin(), cams.end(), [](const Camera* c) { return (c->pathMode & CLRT_PATH_RR) != 0; });
    if (rr == cams.end()) return;
    const int k = energyGainingMaterial(ds);
    if (k < 0 || size_t(k) >= scene.materials.size()) return;
    char albedo[32];
    std::snprintf(albedo, sizeof albedo, "%.2f", double(pathAlbedoBound(ds.materials[size_t(k)])));
    warnOnce(scene.path + ": material " + std::to_string(scene.materials[size_t(k)].id) + " gives back up to " + albedo +
             " times the light it receives on a path (a classic or un-normalized material reflects pi*kd), and camera " +
             std::to_string((*rr)->id) + " plays Russian roulette without a depth cap: its image may not converge; "
             "give the material a normalized BRDF or a smaller DiffuseReflectance");
}

// From here on Ctrl-C finishes the pass and writes the partial image; not in an MPI job: a signal
// there (mpirun ending every rank because one failed, or the job cancelled) exits at once, writing
// no image of a camera not yet finished, with a line naming the rank.
void setRenderInterrupts(const RenderArgs& a) {
    MpiJob& job = MpiJob::get();
    setGracefulInterrupt(!job.distributed());
    if (!job.distributed()) return;
    static std::string note;
    note = "clrt: error: rank " + std::to_string(job.rank()) + " of " + std::to_string(job.size()) + " (" + job.host() +
           "): the MPI job was ended (a rank failed, see mpirun's message naming it, or the job was cancelled); "
           "no image of an unfinished camera written" +
           (a.dist.checkpointDir.empty() ? "" : ", finished tiles kept in " + a.dist.checkpointDir);
    setImmediateExitNote(note.c_str());
}

// The scene file with the options that change the scene model applied: --env-sampling (every
// environment light's env strategy), --backface-culling, --vertex-normals, --ray-origin and --resolution (every camera at WxH, same view).
Scene loadRenderScene(const RenderArgs& a) {
    Scene scene = loadScene(a.positional[0]);
    if (!a.envStrategy.empty()) {
        dev::EnvStrategy es;
        parseEnvStrategy(a.envStrategy, es);
        overrideEnvStrategy(scene, es);
    }
    if (a.backfaceCulling >= 0) scene.backfaceCulling = a.backfaceCulling == 1;
    if (a.vertexNormals >= 0) scene.vertexNormals = a.vertexNormals == 1 ? VertexNormalWeighting::Unweighted : VertexNormalWeighting::Area;
    if (a.rayOrigin >= 0)
        for (Camera& c : scene.cameras) c.nearMode = a.rayOrigin == 1 ? CLRT_NEAR_NONE : CLRT_NEAR_ALL;
    if (a.width > 0)
        for (Camera& c : scene.cameras) {
            c.width = a.width;
            c.height = a.height;
        }
    return scene;
}

// The render of the parsed options: every selected camera, then the stats; 128 + signal if interrupted.
int renderScene(RenderArgs a) {
    if (a.positional.size() != 1) throw Error("render: expected exactly one scene file (see clrt render --help)", ExitCode::Usage);
    setVerbose(a.verbose);
    MpiJob& job = MpiJob::get();
    if (job.rank() == 0) checkOutputDirectory(a.outDir);  // exists and accepts a new file: exit 4 before any work
    if ((!a.previewAddress.empty() || !a.displayServer.empty()) && (job.distributed() || a.dist.parts > 0))
        throw Error("--preview/--display-server: not with --part or MPI ranks", ExitCode::Usage);
    std::unique_ptr<LiveView> live = LiveView::start(a);  // binds the preview's port: in use -> exit 1 here

    StageTimes times;
    auto t = std::chrono::steady_clock::now();
    Scene scene = loadRenderScene(a);
    times.parse = secondsSince(t);

    std::vector<const Camera*> cams = selectCameras(scene, a);
    // Plain .png/.exr names, no two alike, none of them a file the scene reads: exit 2 before any work.
    checkOutputsAreNotInputs(plannedOutputs(a, scene, cams), sceneInputs(scene), a.positional[0]);
    if (job.rank() == 0 && (a.dist.parts > 0 || !a.dist.checkpointDir.empty()))
        a.dist.identity = renderIdentity(sceneInputs(scene), pixelOptions(a));
    if (a.stop.active() && (a.dist.parts > 0 || !a.dist.checkpointDir.empty() || job.distributed()))
        throw Error("--target-error/--time-limit: not with --part, --checkpoint or MPI ranks", ExitCode::Usage);
    if (a.stop.active() && a.spp > 0 && a.spp < 4)
        throw Error("--target-error/--time-limit: --spp caps the samples and must be at least 4 (one pair of "
                    "2-sample passes), got " + std::to_string(a.spp), ExitCode::Usage);
    if (live) live->setCameras(cams, a.positional[0]);
    const std::vector<DeviceInfo> devs = selectDevices(a.device);
    checkImagesFit(a, cams, devs);
    std::vector<std::unique_ptr<DeviceContext>> contexts = makeContexts(devs);
    const std::vector<DeviceInfo> infos = contextInfos(contexts);
    checkMemory(a, scene, infos);

    t = std::chrono::steady_clock::now();
    auto programFeatures = [&a](FeatureSet f) {
        f.zsobol = a.pixelSampler == PixelSampler::ZSobol;  // the sampler's code only where it runs
        f.correlatedSampler = a.pixelSampler == PixelSampler::Correlated;
        f.meshLightsByArea = a.meshLightsByArea;
        if (!a.allFeatures) return f;
        FeatureSet all = FeatureSet::all();
        all.bvhStack = f.bvhStack;  // not a feature: the tree's own need
        all.meshLightsByArea = f.meshLightsByArea;  // a sampling mode, not code to include
        return all;
    };
    ProgramBuilds builds;
    FlattenOptions flattenOpts;
    flattenOpts.instancing = a.instancing;
    flattenOpts.leafOrderTriangles = false;  // only for GPUs (FlattenOptions)
    for (const DeviceInfo& d : infos)
        flattenOpts.leafOrderTriangles = flattenOpts.leafOrderTriangles || (d.type & CL_DEVICE_TYPE_CPU) == 0;
    flattenOpts.onFeaturesKnown = [&](const FeatureSet& f) { builds.start(contexts, programFeatures(f).defines()); };
    DeviceScene ds = flattenScene(scene, flattenOpts);
    times.flatten = secondsSince(t);
    ds.features = programFeatures(ds.features);
    t = std::chrono::steady_clock::now();
    if (live) live->setStage("building the kernels");
    DeviceRenderers dr = makeRenderers(contexts, ds, builds);
    std::vector<std::unique_ptr<Renderer>>& renderers = dr.renderers;
    times.build = secondsSince(t);
    if (verbose()) printSetup(ds, renderers);

    warnEnergyGain(scene, ds, cams);

    RenderCounters counters;
    std::vector<DeviceWork> work(renderers.size());
    for (size_t i = 0; i < renderers.size(); ++i)
        work[i].name = "[" + std::to_string(renderers[i]->context().info().index) + "] " + renderers[i]->context().info().name;
    std::string notRendered;  // cameras skipped after an interrupt
    bool anyPartial = false;
    int statsSpp = -1;
    setRenderInterrupts(a);
    int camIndex = 0;
    for (const Camera* cam : cams) {
        if (stopRequested().load()) {
            notRendered += (notRendered.empty() ? "" : ", ") + std::to_string(cam->id);
            continue;
        }
        const int asked = a.stop.active() ? 0 : a.spp > 0 ? a.spp : cam->numSamples;  // progressive: no target spp
        const int reached = renderAndWriteCamera(a, *cam, camIndex++, renderers, work, counters, times.output, live.get());
        if (reached < asked || (a.stop.active() && stopRequested().load())) anyPartial = true;
        if (statsSpp < 0) statsSpp = reached;  // the stats line reports the first camera's
    }
    if (job.distributed()) gatherRankStats(work);
    if (job.rank() != 0) return 0;
    sumDeviceCounters(work, counters);
    printTimes(times, ds, *renderers.front(), counters, work, std::max(statsSpp, 0));
    if (live) live->finish(stopRequested().load());
    if (stopRequested().load()) {
        std::fprintf(stderr, "clrt: interrupted (%s)%s%s%s\n", stopSignal() == SIGTERM ? "SIGTERM" : stopSignal() == SIGHUP ? "SIGHUP" : "SIGINT",
                     anyPartial ? ": partial images written (see above)" : "",
                     notRendered.empty() ? "" : "; cameras not rendered: ", notRendered.c_str());
        return 128 + stopSignal();
    }
    return 0;
}

}  // namespace

int cmdRender(int argc, char** argv) {
    RenderArgs a = parseRenderArgs(argc, argv, 2);
    if (a.help) {
        std::fputs(kRenderHelp, stdout);
        return 0;
    }
    return renderScene(a);
}

}  // namespace clrt
