// render_stats.cpp — the lines `clrt render` prints about a render (see render_stats.h): ray
// throughputs per kind and per depth from the devices' counters and profiling times, and the MPI
// ranks' counters sent to rank 0 as text. Reads no scene element.
#include "cli/render_stats.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "dist/mpi_job.h"
#include "flatten/memory_estimate.h"
#include "util/error.h"

namespace clrt {

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
    int meshLights = 0, enclosed = 0;
    for (int i = 0; i < ds.params.numLights; ++i)
        if (ds.lights[size_t(i)].kind == dev::LIGHT_MESH) {
            ++meshLights;
            enclosed += ds.lights[size_t(i)].position.w > 0;
        }
    if (meshLights > 0)
        info("LightMesh: " + std::to_string(enclosed) + " of " + std::to_string(meshLights) +
             " enclosed (a closed convex volume: their inner sides get no light samples; flatten/light_enclosure.h)");
}

void sumDeviceCounters(const std::vector<DeviceWork>& work, RenderCounters& counters) {
    double deviceSeconds = 0;
    for (const DeviceWork& w : work) {
        counters.cameraRays += w.counters.cameraRays;
        counters.secondaryRays += w.counters.secondaryRays;
        counters.shadowRays += w.counters.shadowRays;
        counters.pathSegments += w.counters.pathSegments;
        counters.fullQueues += w.counters.fullQueues;
        deviceSeconds = std::max(deviceSeconds, w.counters.seconds);
    }
    if (counters.fullQueues > 0)
        warn(std::to_string(counters.fullQueues) + " bounce queue(s) of --rr-rule course's splits were full: the "
             "children beyond them were dropped, so the image is darker than the rule's");
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

namespace {

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

}  // namespace

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
    // build: the wait for the program after flattening plus the buffers; the program itself (its
    // own time in parentheses) starts building once the BVH is done (cli/render_cmd.cpp).
    std::fprintf(stderr, "times: parse %.3fs, bvh %.3fs (flatten %.3fs), kernel build %.3fs (program %.3fs%s), render %.3fs, output %.3fs; %.2f Mrays/s\n",
                 t.parse, ds.bvhSeconds, t.flatten - ds.bvhSeconds, t.build, renderer.buildInfo().seconds,
                 renderer.buildInfo().cacheHit ? ", cached" : "",
                 counters.seconds, t.output, rays / secs * 1e-6);
    if (verbose()) std::fprintf(stderr, "memory: peak resident %.1f MB so far\n", double(peakResidentBytes()) / (1 << 20));
    std::printf("stats: parse=%.3fs flatten=%.3fs bvh=%.3fs build=%.3fs render=%.3fs output=%.3fs camera_mrays=%.2f "
                "shadow_mrays=%.2f secondary_mrays=%.2f path_segments_mps=%.2f%s spp=%d\n",
                t.parse, t.flatten - ds.bvhSeconds, ds.bvhSeconds, t.build, counters.seconds, t.output,
                rate(&RenderCounters::cameraRays, STAGE_TRACE_CAMERA), rate(&RenderCounters::shadowRays, STAGE_TRACE_SHADOW),
                rate(&RenderCounters::secondaryRays, STAGE_TRACE_SECONDARY), pathSegmentRate(work),
                depthStats(work).c_str(), spp);
}

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

}  // namespace clrt
