// clrt command line: `clrt devices`, `clrt render SCENE [options]`, `clrt tonemap` (src/cli/).
// Parses arguments, checks the outputs (src/cli/output_names.h), runs the pipeline (load ->
// flatten/BVH -> kernel build -> render -> write), prints progress and per-stage times, and turns
// every clrt::Error into one line on stderr and its exit code. Ctrl-C / SIGTERM: src/cli/interrupt.h.
#include <CL/opencl.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "cl/devices.h"
#include "cl/program.h"
#include "cli/interrupt.h"
#include "cli/merge_cmd.h"
#include "cli/output_names.h"
#include "cli/tonemap_cmd.h"
#include "dist/dist_render.h"
#include "dist/mpi_job.h"
#include "dist/part_file.h"
#include "image/image.h"
#include "flatten/device_scene.h"
#include "render/multi_device.h"
#include "output/output.h"
#include "render/progressive.h"
#include "render/fused_renderer.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "util/error.h"

using namespace clrt;

namespace {

const char* kMainHelp =
    "clrt — an OpenCL ray tracer for CENG795 scenes\n"
    "\n"
    "usage: clrt <command> [options]\n"
    "\n"
    "commands:\n"
    "  devices                 list every OpenCL platform/device with its index\n"
    "  render SCENE [options]  render every camera of SCENE (XML or JSON); see `clrt render --help`\n"
    "  tonemap IN.exr [options] tone-map an HDR image to PNG on the device; see `clrt tonemap --help`\n"
    "  merge PARTS... -o DIR   put together the parts of `clrt render --part K/N`; see `clrt merge --help`\n"
    "\n"
    "`mpirun -np N clrt render SCENE ...` renders one image over N MPI ranks (see `clrt render --help`).\n"
    "\n"
    "options:\n"
    "  -h, --help              this text\n"
    "\n"
    "exit codes: 0 ok, 1 usage, 2 bad input, 3 device failure, 4 output failure,\n"
    "            130/143/129 interrupted by SIGINT/SIGTERM/SIGHUP (a render writes its partial image first)\n";

const char* kRenderHelp =
    "usage: clrt render SCENE [options]\n"
    "\n"
    "Renders every camera of SCENE (or one, with --camera) and writes each image under its ImageName\n"
    "into OUTDIR (.png: clamped and rounded; .exr: float radiance, plus one tone-mapped .png per\n"
    "Tonemap block of the camera: stem.png, or stem<Extension>.png / stem_<tmo>.png for several).\n"
    "Before any work, every output must be a plain file name ending in .png/.exr, no two alike, none\n"
    "of them a file the scene reads (exit 2), and OUTDIR must accept a new file (exit 4).\n"
    "Ctrl-C (or SIGTERM) ends the render after its current pass and writes the partial image (the EXR's\n"
    "spp attribute says how many samples it has); a second one exits at once.\n"
    "\n"
    "options:\n"
    "  -o, --output DIR      output directory (default: the current directory); must exist\n"
    "  --device SPEC         OpenCL device: an index from `clrt devices`, cpu (PoCL's CPU\n"
    "                        device(s) when several CPU implementations are installed), gpu, a name\n"
    "                        substring, platform:NAME (every device of a platform whose name\n"
    "                        contains NAME, e.g. platform:portable = PoCL, platform:intel), `all`,\n"
    "                        or a comma list (0,2) to render on several devices at once\n"
    "                        (default: the first GPU, else the CPU device)\n"
    "  --spp N               samples per pixel (1 to 1048576), overriding each camera's NumSamples\n"
    "  --seed N              random seed (default 0); the same seed gives the same image\n"
    "  --sampler S           stratified (default): camera jitter, light and BSDF samples stratified\n"
    "                        over a pixel's samples (scrambled (0,2)-sequence); independent: every\n"
    "                        number drawn independently (the noise of a plain Monte Carlo renderer)\n"
    "  --target-error X      render in passes until the estimated relMSE of the image is <= X (> 0):\n"
    "                        even and odd passes form two independent half-images, and their\n"
    "                        difference estimates the error (relative to 1, or to 255 for .png\n"
    "                        outputs); the camera's NumSamples is ignored, --spp (>= 4) caps the\n"
    "                        samples. Prints the estimate, the spp and the time, and writes them into\n"
    "                        the EXR header (relMseEstimate, spp, renderTime, stopReason)\n"
    "  --time-limit S        the same passes until the next pair of passes would end after S seconds\n"
    "                        (per camera; at least one pair); with --target-error, whichever comes\n"
    "                        first. Neither: the image is rendered as before, bit for bit\n"
    "  --camera ID           render only the camera with this id\n"
    "  --resolution WxH      render every camera at W x H pixels (same view) instead of its\n"
    "                        ImageResolution: tiny renders for checking kernels (oclgrind)\n"
    "  --ldr-quantize MODE   round (default) or floor: how .png outputs turn clamped radiance into\n"
    "                        8 bits; the course's reference renders truncate (floor)\n"
    "  --env-sampling S      sampler of every SphericalDirectionalLight: uniform, cosine, importance or\n"
    "                        mis (default: the scene's sampler=, else mis)\n"
    "  --pipeline P          fused (one kernel per sample pass), wavefront (a kernel per stage) or\n"
    "                        auto (default: fused on CPU devices for images of >= 1024 pixels,\n"
    "                        wavefront otherwise); the image is\n"
    "                        the same either way; -v says which one rendered\n"
    "  --all-features        build the kernels with every feature, not only what the scene uses\n"
    "                        (for measuring what specialisation gains)\n"
    "  --exr-half            write .exr outputs with half-float channels (default: float)\n"
    "  --part K/N            render only tile set K of N (every N-th tile from the K-th) of each\n"
    "                        camera into OUTDIR/<ImageName>.part<K>of<N>.exr; `clrt merge` joins them\n"
    "  --checkpoint DIR      keep every finished tile in DIR; the same command run again renders only\n"
    "                        the tiles still missing (same image, bit for bit)\n"
    "  --tile-pixels N       pixels per tile of --part, --checkpoint and MPI renders (default: 1/64\n"
    "                        of the image, 4096 to 65536)\n"
    "  -v, --verbose         print the kernel build flags and other details\n"
    "  -h, --help            this text\n"
    "\n"
    "MPI: `mpirun -np N clrt render SCENE ...` renders one image over N ranks (the scene at the same\n"
    "path on each): rank 0 hands out tiles, renders too, and writes the outputs; --device applies per\n"
    "rank. A rank that fails ends the job and nothing is written; with --checkpoint a rerun goes on.\n"
    "\n"
    "limits: at most 1048576 samples per pixel and a MaxRecursionDepth of 256; larger scene values\n"
    "are capped with a warning naming the scene file.\n";

struct Args {
    std::vector<std::string> positional;
    std::string outDir = ".", device, cameraId;
    int spp = 0, width = 0, height = 0;  // width/height: --resolution (0: the camera's own)
    uint32_t seed = 0;
    bool verbose = false, help = false, truncatePng = false, exrHalf = false, allFeatures = false;
    bool independent = false;  // --sampler independent (RenderSettings::stratified = false)
    std::string envSampling;  // --env-sampling: overrides every environment light's sampler
    StopRule stop;            // --target-error, --time-limit (render/progressive.h)
    Pipeline pipeline = Pipeline::Auto;  // --pipeline
    DistSettings dist;        // --part, --checkpoint, --tile-pixels (src/dist/)
};

int parseInt(const std::string& opt, const std::string& v, long lo, long hi) {
    char* end = nullptr;
    errno = 0;
    long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || errno != 0 || x < lo || x > hi)
        throw Error(opt + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" + v + "'",
                    ExitCode::Usage);
    return int(x);
}

// A finite number >= lo (> lo when `open`), for --target-error and --time-limit.
double parseNumber(const std::string& opt, const std::string& v, double lo, bool open) {
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || errno != 0 || !std::isfinite(x) || x < lo || (open && x == lo))
        throw Error(opt + ": expected a number " + (open ? "> " : ">= ") + std::to_string(int(lo)) + ", got '" + v + "'",
                    ExitCode::Usage);
    return x;
}

static_assert(kMaxSamplesPerPixel == 1048576 && kMaxRecursionDepth == 256, "update kRenderHelp and README");

Args parseRenderArgs(int argc, char** argv, int start) {
    Args a;
    for (int i = start; i < argc; ++i) {
        std::string s = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw Error(s + ": missing value", ExitCode::Usage);
            return argv[++i];
        };
        if (s == "-h" || s == "--help") a.help = true;
        else if (s == "-o" || s == "--output") a.outDir = value();
        else if (s == "--device") a.device = value();
        else if (s == "--spp") a.spp = parseInt(s, value(), 1, kMaxSamplesPerPixel);
        else if (s == "--seed") a.seed = uint32_t(parseInt(s, value(), 0, 2147483647));
        else if (s == "--sampler") {
            const std::string v = value();
            if (v != "stratified" && v != "independent")
                throw Error("--sampler: expected stratified or independent, got '" + v + "'", ExitCode::Usage);
            a.independent = v == "independent";
        }
        else if (s == "--camera") a.cameraId = value();
        else if (s == "--target-error") a.stop.targetError = parseNumber(s, value(), 0, true);
        else if (s == "--time-limit") a.stop.timeLimit = parseNumber(s, value(), 0, false);
        else if (s == "--resolution") {
            std::string v = value();
            size_t x = v.find('x');
            if (x == std::string::npos) throw Error("--resolution: expected WxH, got '" + v + "'", ExitCode::Usage);
            a.width = parseInt(s, v.substr(0, x), 1, 1 << 16);
            a.height = parseInt(s, v.substr(x + 1), 1, 1 << 16);
        }
        else if (s == "-v" || s == "--verbose") a.verbose = true;
        else if (s == "--exr-half") a.exrHalf = true;
        else if (s == "--checkpoint") a.dist.checkpointDir = value();
        else if (s == "--tile-pixels") a.dist.tilePixels = size_t(parseInt(s, value(), 1, 1 << 24));
        else if (s == "--part") {
            std::string v = value();
            size_t slash = v.find('/');
            if (slash == std::string::npos) throw Error("--part: expected K/N, got '" + v + "'", ExitCode::Usage);
            a.dist.parts = parseInt(s, v.substr(slash + 1), 1, 1 << 20);
            a.dist.part = parseInt(s, v.substr(0, slash), 1, a.dist.parts);
        }
        else if (s == "--all-features") a.allFeatures = true;
        else if (s == "--pipeline") {
            std::string v = value();
            if (!parsePipeline(v, a.pipeline))
                throw Error("--pipeline: expected fused, wavefront or auto, got '" + v + "'", ExitCode::Usage);
        }
        else if (s == "--env-sampling") {
            a.envSampling = value();
            dev::EnvSamplerKind es;
            if (!parseEnvSampler(a.envSampling, es))
                throw Error("--env-sampling: expected uniform, cosine, importance or mis, got '" + a.envSampling + "'",
                            ExitCode::Usage);
        }
        else if (s == "--ldr-quantize") {
            std::string v = value();
            if (v != "round" && v != "floor") throw Error("--ldr-quantize: expected round or floor, got '" + v + "'", ExitCode::Usage);
            a.truncatePng = v == "floor";
        }
        else if (!s.empty() && s[0] == '-') throw Error("unknown option '" + s + "' (see clrt render --help)", ExitCode::Usage);
        else a.positional.push_back(s);
    }
    return a;
}

double since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// A bar on a terminal; otherwise one line when a camera starts, one per 10% and one when it ends.
class Progress {
public:
    explicit Progress(std::string label)
        : label_(std::move(label)), tty_(isatty(STDERR_FILENO)), lastPct_(tty_ ? -1 : 0) {
        if (!tty_) std::fprintf(stderr, "%s: rendering\n", label_.c_str());
        std::fflush(stderr);
    }
    void update(size_t done, size_t total) {
        int pct = total ? int(100 * done / total) : 100;
        if (tty_ && pct == lastPct_ && done != total) return;  // redraw only when the percentage moves
        if (tty_) {
            lastPct_ = pct;
            int bar = pct * 30 / 100;
            std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%", label_.c_str(), bar, "##############################", 30 - bar, "", pct);
            if (done == total) std::fprintf(stderr, "\n");
        } else if (done == total) {
            std::fprintf(stderr, "%s done\n", label_.c_str());
        } else if (pct >= lastPct_ + 10) {  // not a terminal: a line every 10%
            lastPct_ = pct - pct % 10;
            std::fprintf(stderr, "%s %d%%\n", label_.c_str(), lastPct_);
        }
        std::fflush(stderr);
    }
    void interrupted(int reached, int spp) {
        std::fprintf(stderr, "%s%s interrupted after %d of %d samples per pixel\n", tty_ ? "\n" : "", label_.c_str(), reached, spp);
        std::fflush(stderr);
    }

private:
    std::string label_;
    bool tty_;
    int lastPct_;  // the percentage last drawn (tty) or printed (one line per 10% otherwise)
};

int cmdDevices() {
    printDevices(std::cout);  // no device: clrt::Error (exit 3) naming the cause
    return 0;
}

// A camera through src/dist/ (a part, a checkpoint, MPI ranks). Returns false when this process
// writes no outputs for it: an MPI rank other than 0, or a part (its part file is written here, when
// complete).
bool renderCameraDist(const Args& a, const Camera& cam, int camIndex, const RenderSettings& rs,
                      std::vector<std::unique_ptr<Renderer>>& renderers, std::vector<DeviceWork>& work,
                      std::optional<Progress>& prog, ImageRGB& img) {
    std::vector<Renderer*> rp;
    for (auto& r : renderers) rp.push_back(r.get());
    auto t0 = std::chrono::steady_clock::now();
    DistResult dr = renderDistributed(rp, cam, camIndex, rs, work, a.dist, MpiJob::get(),
                                      [&](size_t d, size_t n) { prog->update(d, n); });
    if (!dr.writesOutputs) return false;
    if (a.dist.parts == 0) {
        img = std::move(dr.image);
        return true;
    }
    if (!dr.complete) {
        std::fprintf(stderr, "camera %d: part %d/%d not written: the render was interrupted%s\n", cam.id, a.dist.part,
                     a.dist.parts, a.dist.checkpointDir.empty() ? "" : " (its finished tiles are in the checkpoint)");
        return false;
    }
    PartHeader h;
    h.identity = a.dist.identity;
    h.sceneFile = a.positional[0];
    h.cameraId = cam.id;
    h.spp = rs.spp;
    h.seed = rs.seed;
    h.imageName = cam.imageName;
    h.tilePixels = dr.grid.tilePixels;
    h.part = a.dist.part;
    h.parts = a.dist.parts;
    h.tiles = dr.tiles;
    h.truncatePng = a.truncatePng;
    h.exrHalf = a.exrHalf;
    h.tonemaps = cam.tonemaps;
    h.renderSeconds = since(t0);
    h.device = renderers.front()->context().info().name;
    const std::string path = (std::filesystem::path(a.outDir) / partFileName(cam.imageName, a.dist.part, a.dist.parts)).string();
    writePartFile(path, h, dr.image);
    std::fprintf(stderr, "wrote %s (part %d/%d: %zu of %zu tiles)\n", path.c_str(), h.part, h.parts, h.tiles.size(),
                 dr.grid.count());
    return false;
}

// Renders samples [first, first + count) of every pixel of `cam` on every renderer; `reached`: the
// samples every pixel got (fewer only when interrupted).
ImageRGB renderPass(const Camera& cam, RenderSettings rs, std::vector<std::unique_ptr<Renderer>>& renderers,
                    std::vector<DeviceWork>& work, int first, int count, int& reached) {
    rs.firstSample = first;
    rs.spp = count;
    for (DeviceWork& w : work) w.counters.stoppedAtSample = -1;
    std::vector<Renderer*> rp;
    for (auto& r : renderers) rp.push_back(r.get());
    ImageRGB img = rp.size() == 1 ? rp[0]->render(cam, rs, work[0].counters) : renderOnDevices(rp, cam, rs, work);
    reached = count;
    for (const DeviceWork& w : work)
        if (w.counters.stoppedAtSample >= 0) reached = std::min(reached, w.counters.stoppedAtSample);
    return img;
}

// One camera in sample passes until --target-error or --time-limit (render/progressive.h): prints
// the estimate, spp and time (a line at 1, 2, 4, 8... pairs of passes, and one at the end) and puts
// them into the outputs' options (EXR header attributes).
ImageRGB renderCameraProgressive(const Args& a, const Camera& cam, const RenderSettings& rs,
                                 std::vector<std::unique_ptr<Renderer>>& renderers, std::vector<DeviceWork>& work,
                                 RenderCounters& counters, OutputOptions& oo) {
    StopRule rule = a.stop;
    rule.maxSpp = a.spp > 0 ? a.spp : kMaxSamplesPerPixel;
    rule.white = lowerExtension(cam.imageName) == ".png" ? 255.0 : 1.0;
    const PassRenderer pass = [&](int first, int count, int& reached) {
        // The two halves must be independent estimates, but the stratified sampler correlates the samples
        // of a pixel (it spreads them over one net): so pass k renders pass k / 2 of its half k % 2, the
        // odd half under a seed of its own. Each half is then a progressive stratified render.
        const int k = first / count;
        RenderSettings hs = rs;
        if (k & 1) hs.seed = rs.seed ^ 0x2545f491u;
        return renderPass(cam, hs, renderers, work, (k >> 1) * count, count, reached);
    };
    int pairs = 0;
    const auto onPair = [&](const ProgressiveResult& r) {
        ++pairs;
        if ((pairs & (pairs - 1)) == 0)
            std::fprintf(stderr, "camera %d: %d spp, relMSE estimate %.4g, %.2f s\n", cam.id, r.spp, r.relMse, r.seconds);
    };
    const auto t0 = std::chrono::steady_clock::now();
    ProgressiveResult r = renderProgressive(size_t(cam.width) * size_t(cam.height), rule, pass,
                                            [] { return stopRequested().load(); }, onPair);
    if (renderers.size() > 1) counters.seconds += since(t0);  // one device: its counters have it
    const auto number = [](const char* format, double x) {
        char buf[64];
        std::snprintf(buf, sizeof buf, format, x);
        return std::string(buf);
    };
    oo.attributes["relMseEstimate"] = number("%.6g", r.relMse);
    oo.attributes["stopReason"] = r.stopReason;
    oo.attributes["passSamples"] = std::to_string(r.passSamples);
    if (rule.targetError > 0) oo.attributes["targetError"] = number("%g", rule.targetError);
    if (rule.timeLimit >= 0) oo.attributes["timeLimit"] = number("%g s", rule.timeLimit);
    std::fprintf(stderr, "camera %d: stopped (%s) at %d spp after %.3f s; relMSE estimate %.6g\n", cam.id,
                 r.stopReason.c_str(), r.spp, r.seconds, r.relMse);
    oo.spp = r.spp;
    if (r.stopReason == "interrupted")
        oo.partial = "interrupted after " + std::to_string(r.spp) + " samples per pixel (--target-error/--time-limit)";
    return std::move(r.image);
}

// Renders one camera on every renderer and writes its outputs. Returns the samples per pixel every
// pixel reached: fewer than asked if the render was interrupted (stopRequested), and the images
// written are then partial.
int renderAndWriteCamera(const Args& a, const Camera& cam, int camIndex, std::vector<std::unique_ptr<Renderer>>& renderers,
                         std::vector<DeviceWork>& work, RenderCounters& counters, double& tOutput) {
    RenderSettings rs;
    rs.spp = a.spp > 0 ? a.spp : cam.numSamples;
    rs.seed = a.seed;
    rs.stratified = !a.independent;
    rs.stop = &stopRequested();
    rs.pipeline = a.pipeline;
    for (DeviceWork& w : work) w.counters.stoppedAtSample = -1;
    std::optional<Progress> prog;  // rank 0 (or the only process) shows the progress of the whole image
    if (MpiJob::get().rank() == 0)
        prog.emplace("camera " + std::to_string(cam.id) + " (" + cam.imageName + ", " + std::to_string(cam.width) + "x" +
                     std::to_string(cam.height) + ", " + (a.stop.active() ? "passes" : std::to_string(rs.spp) + " spp") + ")");
    ImageRGB img;
    OutputOptions oo;
    auto tr = std::chrono::steady_clock::now();
    if (distActive(a.dist, MpiJob::get())) {
        auto w0 = std::chrono::steady_clock::now();
        const bool write = renderCameraDist(a, cam, camIndex, rs, renderers, work, prog, img);
        counters.seconds += since(w0);
        if (!write) return rs.spp;  // another rank, or a part (an interrupted one is not written: nothing partial)
    } else if (a.stop.active()) {
        img = renderCameraProgressive(a, cam, rs, renderers, work, counters, oo);
    } else if (renderers.size() == 1) {
        img = renderers.front()->render(cam, rs, work[0].counters, [&](size_t d, size_t n) { prog->update(d, n); });
    } else {
        std::vector<Renderer*> rp;
        for (auto& r : renderers) rp.push_back(r.get());
        auto w0 = std::chrono::steady_clock::now();
        img = renderOnDevices(rp, cam, rs, work, [&](size_t d, size_t n) { prog->update(d, n); });
        counters.seconds += since(w0);
    }
    const double camSeconds = since(tr);
    auto to = std::chrono::steady_clock::now();
    oo.outDir = a.outDir;
    oo.truncatePng = a.truncatePng;
    oo.exrHalf = a.exrHalf;
    if (!a.stop.active()) oo.spp = rs.spp;
    for (const DeviceWork& w : work)  // an interrupted render: the samples every pixel has
        if (!a.stop.active() && w.counters.stoppedAtSample >= 0) oo.spp = std::min(oo.spp, w.counters.stoppedAtSample);
    if (!a.stop.active() && oo.spp < rs.spp) {
        prog->interrupted(oo.spp, rs.spp);
        oo.partial = "interrupted after " + std::to_string(oo.spp) + " of " + std::to_string(rs.spp) +
                     " samples per pixel" + (oo.spp == 0 ? " (some tiles not rendered)" : "");
    }
    oo.renderSeconds = camSeconds;
    for (auto& r : renderers) oo.deviceName += (oo.deviceName.empty() ? "" : ", ") + r->context().info().name;
    std::vector<std::string> written = writeCameraOutputs(cam, img, oo, renderers.front()->context());
    tOutput += since(to);
    for (const std::string& w : written)
        std::fprintf(stderr, "wrote %s%s\n", w.c_str(), oo.partial.empty() ? "" : " (partial image)");
    return oo.spp;
}

// The cameras to render (--camera, else all); an error naming the scene if none.
std::vector<const Camera*> selectCameras(const Scene& scene, const Args& a) {
    std::vector<const Camera*> cams;
    for (const Camera& c : scene.cameras)
        if (a.cameraId.empty() || std::to_string(c.id) == a.cameraId) cams.push_back(&c);
    if (cams.empty())
        throw Error(a.positional[0] + (a.cameraId.empty() ? ": the scene has no camera" : ": no camera with id " + a.cameraId));
    return cams;
}

// An image no selected device can hold is refused here, before the BVH, the kernel build and any
// host allocation of its size (the renderer checks the same limit per device).
void checkImagesFit(const Args& a, const std::vector<const Camera*>& cams, const std::vector<DeviceInfo>& devs) {
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

// One context and renderer (program) per device; a device whose setup fails is dropped while others
// remain.
struct DeviceRenderers {
    std::vector<std::unique_ptr<DeviceContext>> contexts;
    std::vector<std::unique_ptr<Renderer>> renderers;
};
DeviceRenderers makeRenderers(const std::vector<DeviceInfo>& devs, const DeviceScene& ds) {
    DeviceRenderers out;
    for (const DeviceInfo& d : devs) {
        try {
            auto dc = std::make_unique<DeviceContext>(d, /*profiling=*/!std::getenv("CLRT_NO_PROFILE"));  // per-kernel times for stats
            auto r = std::make_unique<Renderer>(*dc, ds);
            out.contexts.push_back(std::move(dc));
            out.renderers.push_back(std::move(r));
        } catch (const Error& e) {
            if (devs.size() == 1) throw;
            warn("device [" + std::to_string(d.index) + "] " + d.name + " dropped: " + e.what());
        }
    }
    if (out.renderers.empty()) throw Error("no selected device could build the renderer", ExitCode::Device);
    return out;
}

// -v: devices, kernel flags, flattening and BVH figures.
void printSetup(const DeviceScene& ds, const std::vector<std::unique_ptr<Renderer>>& renderers) {
    std::string flags;
    for (const std::string& d : ds.features.defines()) flags += " " + d;
    for (auto& r : renderers) info("device: [" + std::to_string(r->context().info().index) + "] " + r->context().info().name +
                                   " (" + r->context().info().platformName + ")");
    info("kernel flags:" + flags + (renderers.front()->buildInfo().cacheHit ? " (cached binary)" : ""));
    info("flatten: images read in " + std::to_string(ds.imageSeconds) + " s, environment distributions built in " +
         std::to_string(ds.envDistSeconds) + " s");
    info("primitives: " + std::to_string(ds.params.numTriangles) + " triangles, " + std::to_string(ds.params.numSpheres) +
         " spheres; BVH SAH cost " + std::to_string(ds.bvh.sahCost) + ", depth " + std::to_string(ds.bvh.depth));
}

struct StageTimes {
    double parse = 0, flatten = 0, build = 0, output = 0;
};

// Adds the devices' ray counts (and, with one device, its render time) to `counters`; prints one line
// per device when there are several, and with -v the device time of each kernel stage.
void sumDeviceCounters(const std::vector<DeviceWork>& work, RenderCounters& counters) {
    double deviceSeconds = 0;
    for (const DeviceWork& w : work) {
        counters.cameraRays += w.counters.cameraRays;
        counters.secondaryRays += w.counters.secondaryRays;
        counters.shadowRays += w.counters.shadowRays;
        counters.pathSegments += w.counters.pathSegments;
        deviceSeconds = std::max(deviceSeconds, w.counters.seconds);
    }
    if (work.size() == 1) counters.seconds = deviceSeconds;
    if (work.size() > 1)
        for (const DeviceWork& w : work) {
            double r = double(w.counters.cameraRays + w.counters.secondaryRays + w.counters.shadowRays);
            std::fprintf(stderr, "device %s: %llu tiles, %llu pixels, %.2f Mrays/s%s\n", w.name.c_str(),
                         (unsigned long long)w.counters.tiles, (unsigned long long)w.counters.pixels,
                         w.counters.seconds > 0 ? r / w.counters.seconds * 1e-6 : 0.0, w.failed ? " (failed)" : "");
        }
    if (!verbose()) return;
    double stage[STAGE_COUNT] = {}, kernels = 0;
    for (const DeviceWork& w : work)
        for (int k = 0; k < STAGE_COUNT; ++k) stage[k] += w.counters.stageSeconds[k];
    std::string line = "kernel time:";
    for (int k = 0; k < STAGE_COUNT; ++k) {
        char buf[64];
        std::snprintf(buf, sizeof buf, " %s %.3fs", renderStageName(k), stage[k]);
        line += buf;
        kernels += stage[k];
    }
    char buf[96];
    std::snprintf(buf, sizeof buf, "; all kernels %.3fs of %.3fs render", kernels, counters.seconds);
    info(line + buf);
}

// Path-traced cameras: path segments (camera and bounce rays) per second of render wall time, in
// millions, summed over devices: the throughput of the whole path pipeline (trace, shade, NEE).
double pathSegmentRate(const std::vector<DeviceWork>& work) {
    double r = 0;
    for (const DeviceWork& w : work)
        if (w.counters.seconds > 0) r += double(w.counters.pathSegments) / w.counters.seconds * 1e-6;
    return r;
}

// Rays per second of their trace kernels' device time, in millions, of the rays traced at depth bin
// `bin` (RenderCounters::kDepthBins), summed over devices: extension rays, or shadow rays.
double depthRate(const std::vector<DeviceWork>& work, int bin, bool shadow) {
    double r = 0;
    for (const DeviceWork& w : work) {
        const RenderCounters& c = w.counters;
        const double rays = double(shadow ? c.shadowRaysAt[bin] : c.extendRays[bin]);
        const double s = c.profiled ? (shadow ? c.shadowSeconds[bin] : c.extendSeconds[bin]) : c.seconds;
        if (s > 0) r += rays / s * 1e-6;
    }
    return r;
}

// The `stats:` line's rays per depth: secondary rays of bounces 1, 2, >= 3 and shadow rays cast from
// vertices at depth 0 (camera hits), 1, 2, >= 3 (README "Using it"); left out when a device rendered
// with the fused path, whose one kernel traces every depth (--pipeline wavefront splits them).
std::string depthStats(const std::vector<DeviceWork>& work) {
    static_assert(RenderCounters::kDepthBins == 4, "update the key names");
    for (const DeviceWork& w : work)
        if (w.counters.fused) return "";
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  " secondary_mrays_d1=%.2f secondary_mrays_d2=%.2f secondary_mrays_d3plus=%.2f shadow_mrays_d0=%.2f"
                  " shadow_mrays_d1=%.2f shadow_mrays_d2=%.2f shadow_mrays_d3plus=%.2f",
                  depthRate(work, 1, false), depthRate(work, 2, false), depthRate(work, 3, false), depthRate(work, 0, true),
                  depthRate(work, 1, true), depthRate(work, 2, true), depthRate(work, 3, true));
    return buf;
}

// The `times:` line (stderr) and the `stats:` line (stdout, see README).
void printTimes(const StageTimes& t, const DeviceScene& ds, const Renderer& renderer, const RenderCounters& counters,
                const std::vector<DeviceWork>& work, int spp) {
    double rays = double(counters.cameraRays + counters.secondaryRays + counters.shadowRays);
    double secs = std::max(counters.seconds, 1e-9);
    // Ray throughput of each kind: its rays over its trace kernel's device time, summed over devices
    // (they run concurrently); without profiling, over the whole render time.
    auto rate = [&](uint64_t RenderCounters::*rayCount, int stage) {
        double r = 0;
        for (const DeviceWork& w : work) {
            // the fused path traces every kind in its one kernel: its rays over that kernel's time
            double s = w.counters.profiled ? w.counters.stageSeconds[stage] + w.counters.stageSeconds[STAGE_FUSED]
                                           : w.counters.seconds;
            if (s > 0) r += double(w.counters.*rayCount) / s * 1e-6;
        }
        return r;
    };
    std::fprintf(stderr, "times: parse %.3fs, bvh %.3fs (flatten %.3fs), kernel build %.3fs%s, render %.3fs, output %.3fs; %.2f Mrays/s\n",
                 t.parse, ds.bvhSeconds, t.flatten - ds.bvhSeconds, t.build, renderer.buildInfo().cacheHit ? " (cached)" : "",
                 counters.seconds, t.output, rays / secs * 1e-6);
    std::printf("stats: parse=%.3fs flatten=%.3fs bvh=%.3fs build=%.3fs render=%.3fs output=%.3fs camera_mrays=%.2f "
                "shadow_mrays=%.2f secondary_mrays=%.2f path_segments_mps=%.2f%s spp=%d\n",
                t.parse, t.flatten - ds.bvhSeconds, ds.bvhSeconds, t.build, counters.seconds, t.output,
                rate(&RenderCounters::cameraRays, STAGE_TRACE_CAMERA), rate(&RenderCounters::shadowRays, STAGE_TRACE_SHADOW),
                rate(&RenderCounters::secondaryRays, STAGE_TRACE_SECONDARY), pathSegmentRate(work),
                depthStats(work).c_str(), spp);
}

// What a render writes: the cameras' outputs, or with --part K/N one part file per camera.
std::vector<PlannedOutput> plannedOutputs(const Args& a, const Scene& scene, const std::vector<const Camera*>& cams) {
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

// The command-line options that change pixels, for the render identity of parts and checkpoints
// (the camera size, spp and seed are part of it elsewhere).
std::string pixelOptions(const Args& a) {
    return "env=" + a.envSampling + ";all-features=" + std::to_string(a.allFeatures) +
           ";sampler=" + (a.independent ? "independent" : "stratified") +
           ";resolution=" + std::to_string(a.width) + "x" + std::to_string(a.height) +
           ";tile=" + std::to_string(a.dist.tilePixels);
}

// One rank's devices and transfers as text, for rank 0's summary (gatherRankStats).
std::string rankStatsText(const std::vector<DeviceWork>& work) {
    const RankTransfer& t = MpiJob::get().transfer();
    std::ostringstream o;
    o.precision(17);
    o << t.tiles << ' ' << t.bytesSent << ' ' << t.bytesReceived << ' ' << t.waitSeconds << ' ' << t.sendSeconds << ' '
      << t.serveSeconds << '\n';
    for (const DeviceWork& w : work) {
        const RenderCounters& c = w.counters;
        o << c.cameraRays << ' ' << c.secondaryRays << ' ' << c.shadowRays << ' ' << c.tiles << ' ' << c.pixels << ' '
          << c.seconds << ' ' << c.profiled << ' ' << w.failed;
        for (double st : c.stageSeconds) o << ' ' << st;
        for (int b = 0; b < RenderCounters::kDepthBins; ++b)
            o << ' ' << c.extendRays[b] << ' ' << c.shadowRaysAt[b] << ' ' << c.extendSeconds[b] << ' ' << c.shadowSeconds[b];
        o << ' ' << w.name << '\n';
    }
    return o.str();
}

// MPI: every rank's devices become entries of rank 0's `work` ("rank R: [i] name"), and rank 0
// prints one line per rank: tiles, bytes sent, time spent waiting for tiles and sending them.
void gatherRankStats(std::vector<DeviceWork>& work) {
    MpiJob& job = MpiJob::get();
    std::vector<std::string> all = job.gather(rankStatsText(work));
    if (job.rank() != 0) return;
    uint64_t ownTiles = 0;
    for (DeviceWork& w : work) {
        w.name = "rank 0: " + w.name;
        ownTiles += w.counters.tiles;
    }
    const RankTransfer& own = job.transfer();
    std::fprintf(stderr, "rank 0 (%s): %llu tiles; served the other ranks for %.4f s in all (%llu messages, %.1f KB)\n",
                 job.host().c_str(), (unsigned long long)ownTiles, own.serveSeconds, (unsigned long long)own.messages,
                 double(own.bytesReceived) / 1024);
    for (size_t r = 1; r < all.size(); ++r) {
        std::istringstream in(all[r]);
        RankTransfer t;
        in >> t.tiles >> t.bytesSent >> t.bytesReceived >> t.waitSeconds >> t.sendSeconds >> t.serveSeconds;
        for (std::string line; std::getline(in >> std::ws, line);) {
            std::istringstream l(line);
            DeviceWork w;
            RenderCounters& c = w.counters;
            l >> c.cameraRays >> c.secondaryRays >> c.shadowRays >> c.tiles >> c.pixels >> c.seconds >> c.profiled >> w.failed;
            for (double& st : c.stageSeconds) l >> st;
            for (int b = 0; b < RenderCounters::kDepthBins; ++b)
                l >> c.extendRays[b] >> c.shadowRaysAt[b] >> c.extendSeconds[b] >> c.shadowSeconds[b];
            std::getline(l >> std::ws, w.name);
            w.name = "rank " + std::to_string(r) + ": " + w.name;
            work.push_back(w);
        }
        const double n = std::max<double>(1, double(t.tiles));
        std::fprintf(stderr, "rank %zu: %llu tiles, sent %.1f KB (%.1f KB a tile); per tile %.3f ms waiting for its id, "
                             "%.3f ms sending it\n", r, (unsigned long long)t.tiles, double(t.bytesSent) / 1024,
                     double(t.bytesSent) / 1024 / n, t.waitSeconds * 1e3 / n, t.sendSeconds * 1e3 / n);
    }
}

// From here on Ctrl-C finishes the pass and writes the partial image; not in an MPI job: a signal
// there (mpirun ending every rank because one failed, or the job cancelled) exits at once, writing
// no image of a camera not yet finished, with a line naming the rank.
void setRenderInterrupts(const Args& a) {
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

int cmdRender(Args a) {
    if (a.positional.size() != 1) throw Error("render: expected exactly one scene file (see clrt render --help)", ExitCode::Usage);
    setVerbose(a.verbose);
    MpiJob& job = MpiJob::get();
    if (job.rank() == 0) checkOutputDirectory(a.outDir);  // exists and accepts a new file: exit 4 before any work

    StageTimes times;
    auto t = std::chrono::steady_clock::now();
    Scene scene = loadScene(a.positional[0]);
    if (!a.envSampling.empty()) {
        dev::EnvSamplerKind es;
        parseEnvSampler(a.envSampling, es);
        overrideEnvSampling(scene, es);
    }
    times.parse = since(t);
    if (a.width > 0)  // --resolution: every camera at WxH, same view
        for (Camera& c : scene.cameras) {
            c.width = a.width;
            c.height = a.height;
        }

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
    std::vector<DeviceInfo> devs = selectDevices(a.device);
    checkImagesFit(a, cams, devs);

    t = std::chrono::steady_clock::now();
    DeviceScene ds = flattenScene(scene);
    times.flatten = since(t);
    if (a.allFeatures) {
        const int stack = ds.features.bvhStack;  // not a feature: the tree's own need
        ds.features = FeatureSet::all();
        ds.features.bvhStack = stack;
    }
    t = std::chrono::steady_clock::now();
    DeviceRenderers dr = makeRenderers(devs, ds);
    std::vector<std::unique_ptr<Renderer>>& renderers = dr.renderers;
    times.build = since(t);
    if (verbose()) printSetup(ds, renderers);

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
        const int reached = renderAndWriteCamera(a, *cam, camIndex++, renderers, work, counters, times.output);
        if (reached < asked || (a.stop.active() && stopRequested().load())) anyPartial = true;
        if (statsSpp < 0) statsSpp = reached;  // the stats line reports the first camera's
    }
    if (job.distributed()) gatherRankStats(work);
    if (job.rank() != 0) return 0;
    sumDeviceCounters(work, counters);
    printTimes(times, ds, *renderers.front(), counters, work, std::max(statsSpp, 0));
    if (stopRequested().load()) {
        std::fprintf(stderr, "clrt: interrupted (%s)%s%s%s\n", stopSignal() == SIGTERM ? "SIGTERM" : stopSignal() == SIGHUP ? "SIGHUP" : "SIGINT",
                     anyPartial ? ": partial images written (see above)" : "",
                     notRendered.empty() ? "" : "; cameras not rendered: ", notRendered.c_str());
        return 128 + stopSignal();
    }
    return 0;
}


// The command named by argv[1]; its exit code, or a thrown error.
int runCommand(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help")) {
        std::fputs(kMainHelp, argc < 2 ? stderr : stdout);
        return argc < 2 ? 1 : 0;
    }
    std::string cmd = argv[1];
    if (cmd == "devices") return cmdDevices();
    if (cmd == "tonemap") return cmdTonemap(argc, argv);
    if (cmd == "merge") return cmdMerge(argc, argv);
    if (cmd == "render") {
        Args a = parseRenderArgs(argc, argv, 2);
        if (a.help) {
            std::fputs(kRenderHelp, stdout);
            return 0;
        }
        return cmdRender(a);
    }
    throw Error("unknown command '" + cmd + "' (see clrt --help)", ExitCode::Usage);
}

}  // namespace

int main(int argc, char** argv) {
    installInterruptHandling();  // before any thread exists (MPI's included)
    int rc = 0;
    std::string who;  // "rank R: " in an MPI job of several ranks
    try {
        if (argc >= 2 && !std::strcmp(argv[1], "render")) {
            MpiJob& job = MpiJob::start(&argc, &argv);  // only when an MPI launcher started this process
            if (job.distributed()) who = "rank " + std::to_string(job.rank()) + " (" + job.host() + "): ";
        }
        rc = runCommand(argc, argv);
    } catch (const Error& e) {
        std::fprintf(stderr, "clrt: error: %s%s\n", who.c_str(), e.what());
        rc = int(e.code());
    } catch (const cl::Error& e) {
        std::fprintf(stderr, "clrt: error: %sOpenCL %s (%d)\n", who.c_str(), e.what(), e.err());
        rc = int(ExitCode::Device);
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "clrt: error: %sout of host memory\n", who.c_str());
        rc = int(ExitCode::Device);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "clrt: error: %s%s\n", who.c_str(), e.what());
        rc = 2;
    }
    std::fflush(stderr);
    MpiJob::get().end(rc);  // MPI_Finalize, or MPI_Abort after an error (ends the other ranks)
    return rc;
}
