// The tile scheduler of rank 0 / the only process, and the per-camera driver (see dist_render.h).
#include "dist/dist_render.h"

#include <atomic>
#include <cstdio>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

#include "dist/checkpoint.h"
#include "util/error.h"

namespace clrt {

namespace {

// The tiles still to render, handed out to the local devices and the other ranks; finished tiles go
// to the checkpoint. Progress in thousandths of the job's tiles: finished ones (checkpointed ones
// included) plus what the local devices have of the tiles in hand. Thread-safe.
// With the CLRT_KILL_RANK=r:k test hook the last k + 1 tiles are kept for rank r alone, so that it is
// handed its tile k (and dies) however fast the others are.
class TileScheduler {
public:
    TileScheduler(std::deque<size_t> todo, size_t jobTiles, const Checkpoint* cp, const ImageRGB& img,
                  const std::function<void(size_t, size_t)>& progress, std::pair<int, int> killHook)
        : todo_(std::move(todo)), total_(jobTiles), done_(jobTiles - todo_.size()), cp_(cp), img_(img),
          progress_(progress), reservedFor_(killHook.first) {
        for (int i = 0; reservedFor_ > 0 && i <= killHook.second && !todo_.empty(); ++i) {
            reserved_.push_front(todo_.back());
            todo_.pop_back();
        }
        std::lock_guard<std::mutex> lock(mutex_);
        report();
    }
    // The next tile for `rank` (0: this process's devices).
    bool next(size_t& tile, int rank) {
        std::lock_guard<std::mutex> lock(mutex_);
        std::deque<size_t>& q = rank == reservedFor_ ? reserved_ : todo_;
        if (q.empty()) return false;
        tile = q.front();
        q.pop_front();
        return true;
    }
    void finished(size_t tile) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (cp_) cp_->store(tile, img_);
        ++done_;
        report();
    }
    void inHand(size_t units) {
        std::lock_guard<std::mutex> lock(mutex_);
        inHand_ = units;
        report();
    }
    bool complete() {
        std::lock_guard<std::mutex> lock(mutex_);
        return done_ == total_;
    }

private:
    void report() {  // with mutex_ held; only when it grows
        const size_t units = std::min(done_ * 1000 + inHand_, total_ * 1000);
        if (progress_ && (units > reported_ || (!started_ && (started_ = true)))) progress_(reported_ = units, total_ * 1000);
    }
    std::mutex mutex_;
    std::deque<size_t> todo_, reserved_;
    const size_t total_;
    size_t done_, inHand_ = 0, reported_ = 0;
    bool started_ = false;
    const Checkpoint* cp_;
    const ImageRGB& img_;
    const std::function<void(size_t, size_t)>& progress_;
    const int reservedFor_;
};

TileFeed localFeed(TileScheduler& s, size_t tilePixels) {
    TileFeed f;
    f.tilePixels = tilePixels;
    f.next = [&s](size_t& t) { return s.next(t, 0); };
    f.finished = [&s](size_t t) { s.finished(t); };
    f.inHand = [&s](size_t u) { s.inHand(u); };
    return f;
}

// Rank 0 of an MPI job: its own devices render on a thread while this one serves the other ranks.
void renderAsRoot(const std::vector<Renderer*>& renderers, const Camera& cam, int camIndex,
                  const RenderSettings& settings, std::vector<DeviceWork>& work, MpiJob& job, TileScheduler& sched,
                  DistResult& r) {
    const TileFeed feed = localFeed(sched, r.grid.tilePixels);
    std::exception_ptr localError;
    std::atomic<bool> localDone{false};
    std::thread local([&] {
        try {
            renderFedTiles(renderers, cam, settings, work, feed, r.image);
        } catch (...) {
            localError = std::current_exception();
        }
        localDone.store(true);
    });
    try {
        job.serve(camIndex, r.grid, r.image, [&](size_t& t, int rank) { return sched.next(t, rank); },
                  [&](size_t t) { sched.finished(t); }, [&] { return localDone.load() && localError; });
    } catch (...) {
        local.join();
        if (localError) std::rethrow_exception(localError);
        throw;
    }
    local.join();
    if (localError) std::rethrow_exception(localError);
}

}  // namespace

std::string checkpointKey(const DistSettings& ds, const Camera& cam, const RenderSettings& settings, size_t tilePixels) {
    const std::string s = ds.identity + ";camera=" + std::to_string(cam.id) + ";size=" + std::to_string(cam.width) + "x" +
                          std::to_string(cam.height) + ";spp=" + std::to_string(settings.spp) +
                          ";seed=" + std::to_string(settings.seed) + ";tile=" + std::to_string(tilePixels);
    return hexKey(fnv1a64(s.data(), s.size()));
}

DistResult renderDistributed(const std::vector<Renderer*>& renderers, const Camera& cam, int camIndex,
                             const RenderSettings& settings, std::vector<DeviceWork>& work, const DistSettings& ds,
                             MpiJob& job, const std::function<void(size_t, size_t)>& progress) {
    DistResult r;
    const size_t numPixels = size_t(cam.width) * cam.height;
    r.grid = TileGrid{numPixels, ds.tilePixels ? ds.tilePixels : defaultTilePixels(numPixels)};
    if (ds.parts > 0) {
        r.tiles = partTiles(r.grid.count(), ds.part, ds.parts);
    } else {
        for (size_t t = 0; t < r.grid.count(); ++t) r.tiles.push_back(t);
    }
    r.image.width = cam.width;
    r.image.height = cam.height;
    r.image.isHdr = true;
    r.image.pixels.assign(numPixels * 3, 0.0f);
    if (job.rank() != 0) {  // a worker rank: tiles from rank 0, results back to it
        r.writesOutputs = false;
        renderFedTiles(renderers, cam, settings, work, job.workerFeed(camIndex, r.grid, r.image), r.image);
        r.image = ImageRGB();
        return r;
    }
    std::unique_ptr<Checkpoint> cp;
    std::vector<bool> have(r.grid.count(), false);
    if (!ds.checkpointDir.empty()) {
        cp = std::make_unique<Checkpoint>(ds.checkpointDir, cam.imageName, checkpointKey(ds, cam, settings, r.grid.tilePixels),
                                          r.grid);
        have = cp->load(r.image);
        r.checkpointFolder = cp->folder();
    }
    std::deque<size_t> todo;
    for (size_t t : r.tiles) {
        if (have[t]) ++r.fromCheckpoint;
        else todo.push_back(t);
    }
    if (cp)
        std::fprintf(stderr, "checkpoint %s: %zu of %zu tiles were there already\n", r.checkpointFolder.c_str(),
                     r.fromCheckpoint, r.tiles.size());
    TileScheduler sched(std::move(todo), r.tiles.size(), cp.get(), r.image, progress, job.killRankHook());
    if (job.distributed()) {
        renderAsRoot(renderers, cam, camIndex, settings, work, job, sched, r);
    } else {
        renderFedTiles(renderers, cam, settings, work, localFeed(sched, r.grid.tilePixels), r.image);
    }
    r.complete = sched.complete();
    return r;
}

}  // namespace clrt
