// camera_drivers.cpp — one camera of `clrt render` (see camera_drivers.h): the progress display, the
// src/dist/ path (and the part file it writes), the progressive passes and their EXR attributes, the
// plain render on one or several devices, and the writing of the camera's outputs. Reads the Camera
// (size, ImageName, NumSamples, Tonemap blocks).
#include "cli/camera_drivers.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <unistd.h>

#include "cli/interrupt.h"
#include "cli/render_stats.h"
#include "dist/dist_render.h"
#include "dist/mpi_job.h"
#include "dist/part_file.h"
#include "output/output.h"
#include "render/progressive.h"

namespace clrt {

namespace {

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

// A camera through src/dist/ (a part, a checkpoint, MPI ranks). Returns false when this process
// writes no outputs for it: an MPI rank other than 0, or a part (its part file is written here, when
// complete).
bool renderCameraDist(const RenderArgs& a, const Camera& cam, int camIndex, const RenderSettings& rs,
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
    h.renderSeconds = secondsSince(t0);
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

// Samples per second of each device so far (its pixels x the samples each got, over its time).
std::vector<std::pair<std::string, double>> deviceThroughput(const std::vector<DeviceWork>& work, int samplesPerPixel) {
    std::vector<std::pair<std::string, double>> out;
    for (const DeviceWork& w : work)
        if (w.counters.seconds > 0) out.emplace_back(w.name, double(w.counters.pixels) * samplesPerPixel / w.counters.seconds);
    return out;
}

// The progressive loop's observer for --preview/--display-server: figures after every pass (the time
// left: toward --time-limit, and toward --target-error assuming relMSE falls as 1/spp), the mean image
// only when the rate limit allows one.
PassObserver livePassObserver(LiveView& live, int camIndex, const StopRule& rule, const std::vector<DeviceWork>& work) {
    return [&live, camIndex, rule, &work](const ProgressiveResult& r, const std::function<ImageRGB()>& mean) {
        const auto t0 = std::chrono::steady_clock::now();
        PassFigures f;
        f.spp = r.spp;
        f.relMse = r.relMse;
        f.elapsed = r.seconds;
        double left = NAN;
        if (rule.timeLimit >= 0) left = std::max(0.0, rule.timeLimit - r.seconds);
        if (rule.targetError > 0 && std::isfinite(r.relMse) && r.relMse > 0) {
            const double toTarget = std::max(0.0, r.seconds * (r.relMse / rule.targetError - 1.0));
            left = std::isnan(left) ? toTarget : std::min(left, toTarget);
        }
        f.timeLeft = left;
        f.throughput = deviceThroughput(work, r.passSamples);
        if (live.imageDue(camIndex)) live.image(camIndex, f, std::make_shared<const ImageRGB>(mean()));
        else live.figures(camIndex, f);
        live.addRenderThreadSeconds(secondsSince(t0));
    };
}

// One camera in sample passes until --target-error or --time-limit (render/progressive.h): prints
// the estimate, spp and time (a line at 1, 2, 4, 8... pairs of passes, and one at the end) and puts
// them into the outputs' options (EXR header attributes).
ImageRGB renderCameraProgressive(const RenderArgs& a, const Camera& cam, int camIndex, const RenderSettings& rs,
                                 std::vector<std::unique_ptr<Renderer>>& renderers, std::vector<DeviceWork>& work,
                                 RenderCounters& counters, OutputOptions& oo, LiveView* live) {
    StopRule rule = a.stop;
    rule.maxSpp = a.spp > 0 ? a.spp : kMaxSamplesPerPixel;
    rule.white = lowerExtension(cam.imageName) == ".png" ? 255.0 : 1.0;
    const PassRenderer pass = [&](int first, int count, int& reached) {
        // The two halves must be independent estimates, but the stratified pixel sampler correlates the
        // samples of a pixel (it spreads them over one net): so pass k renders pass k / 2 of its half k % 2,
        // the odd half under a seed of its own. Each half is then a progressive stratified render.
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
                                            [] { return stopRequested().load(); }, onPair,
                                            live ? livePassObserver(*live, camIndex, rule, work) : PassObserver{});
    if (renderers.size() > 1) counters.seconds += secondsSince(t0);  // one device: its counters have it
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

}  // namespace

int renderAndWriteCamera(const RenderArgs& a, const Camera& cam, int camIndex, std::vector<std::unique_ptr<Renderer>>& renderers,
                         std::vector<DeviceWork>& work, RenderCounters& counters, double& tOutput, LiveView* live) {
    RenderSettings rs;
    rs.spp = a.spp > 0 ? a.spp : cam.numSamples;
    rs.seed = a.seed;
    rs.pixelSampler = a.pixelSampler;
    rs.rouletteRule = a.rouletteRule;
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
    if (live) live->beginCamera(camIndex, cam);
    const auto progress = [&](size_t d, size_t n) {
        prog->update(d, n);
        if (!live) return;
        PassFigures f;
        f.fraction = n ? double(d) / double(n) : 1.0;
        f.elapsed = secondsSince(tr);
        live->figures(camIndex, f);
    };
    if (distActive(a.dist, MpiJob::get())) {
        auto w0 = std::chrono::steady_clock::now();
        const bool write = renderCameraDist(a, cam, camIndex, rs, renderers, work, prog, img);
        counters.seconds += secondsSince(w0);
        if (!write) return rs.spp;  // another rank, or a part (an interrupted one is not written: nothing partial)
    } else if (a.stop.active()) {
        img = renderCameraProgressive(a, cam, camIndex, rs, renderers, work, counters, oo, live);
    } else if (renderers.size() == 1) {
        img = renderers.front()->render(cam, rs, work[0].counters, progress);
    } else {
        std::vector<Renderer*> rp;
        for (auto& r : renderers) rp.push_back(r.get());
        auto w0 = std::chrono::steady_clock::now();
        img = renderOnDevices(rp, cam, rs, work, progress);
        counters.seconds += secondsSince(w0);
    }
    const double camSeconds = secondsSince(tr);
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
    if (live) {
        PassFigures f;
        f.spp = oo.spp;
        f.elapsed = camSeconds;
        f.fraction = 1;
        if (oo.attributes.count("relMseEstimate")) f.relMse = std::strtod(oo.attributes["relMseEstimate"].c_str(), nullptr);
        live->endCamera(camIndex, f, img);
    }
    std::vector<std::string> written = writeCameraOutputs(cam, img, oo, renderers.front()->context());
    tOutput += secondsSince(to);
    for (const std::string& w : written)
        std::fprintf(stderr, "wrote %s%s\n", w.c_str(), oo.partial.empty() ? "" : " (partial image)");
    return oo.spp;
}

}  // namespace clrt
