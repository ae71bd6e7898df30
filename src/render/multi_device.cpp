// Dynamic tile scheduling over several devices (see multi_device.h).
#include "render/multi_device.h"

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

#include "util/error.h"

namespace clrt {
namespace {
// Parses "i:n" from an environment variable; returns false when unset or malformed.
bool envPair(const char* name, int& i, int& n) {
    const char* v = std::getenv(name);
    return v && std::sscanf(v, "%d:%d", &i, &n) == 2;
}

// The tiles of one render, handed out to the devices' threads (thread-safe); the tile of a failed
// device goes back to the pool. Progress in thousandths of a tile: finished tiles plus each device's
// part of the tile in hand, so it moves within a tile too (a 1x1 image at many samples is one tile),
// reported only when it grows (a failed device's partial tile goes back to the pool).
class TilePool {
public:
    TilePool(size_t numPixels, size_t tile, size_t devices, const std::function<void(size_t, size_t)>& progress)
        : numPixels_(numPixels), tile_(tile), totalTiles_((numPixels + tile - 1) / tile), partial_(devices, 0),
          progress_(progress) {}

    // Device d finished the tile in hand (`current`, SIZE_MAX if none) and asks for the next one.
    bool take(size_t d, size_t& current, size_t& first, size_t& count) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (current != SIZE_MAX) {
            ++doneTiles_;
            partial_[d] = 0;
            report();
            current = SIZE_MAX;
        }
        if (!returned_.empty()) {
            current = returned_.front();
            returned_.pop_front();
        } else if (nextTile_ < totalTiles_) {
            current = nextTile_++;
        } else {
            return false;
        }
        first = current * tile_;
        count = std::min(tile_, numPixels_ - first);
        return true;
    }
    void progress(size_t d, size_t done, size_t total) {
        std::lock_guard<std::mutex> lock(mutex_);
        partial_[d] = total ? std::min(kUnits - 1, done * kUnits / total) : 0;
        report();
    }
    // Device d failed with `current` in hand: that tile goes back to the pool.
    void fail(size_t d, size_t current, DeviceWork& w, const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        w.failed = true;
        w.error = e.what();
        partial_[d] = 0;
        if (current != SIZE_MAX) returned_.push_back(current);
        warn("device '" + w.name + "' failed and was dropped: " + w.error);
    }
    bool allHandedOut() {
        std::lock_guard<std::mutex> lock(mutex_);
        return returned_.empty() && nextTile_ >= totalTiles_;
    }

private:
    static constexpr size_t kUnits = 1000;
    void report() {  // with mutex_ held
        size_t done = doneTiles_ * kUnits;
        for (size_t p : partial_) done += p;
        if (progress_ && done > reported_) progress_(reported_ = done, totalTiles_ * kUnits);
    }
    const size_t numPixels_, tile_, totalTiles_;
    std::mutex mutex_;
    size_t nextTile_ = 0, doneTiles_ = 0, reported_ = 0;
    std::vector<size_t> partial_;
    std::deque<size_t> returned_;  // tiles of failed devices
    const std::function<void(size_t, size_t)>& progress_;
};

// Test hooks: CLRT_THROTTLE_DEVICE=i:ms sleeps before each tile but the first of device i;
// CLRT_FAIL_DEVICE=i:k fails device i (-1: every device) when it takes its tile k.
struct FaultHooks {
    int throttleDev = -100, throttleMs = 0, failDev = -100, failAfter = 0;
    FaultHooks() {
        envPair("CLRT_THROTTLE_DEVICE", throttleDev, throttleMs);
        envPair("CLRT_FAIL_DEVICE", failDev, failAfter);
    }
};

// One device's thread: renders tiles from the pool until none is left or the device fails.
void renderWorker(size_t d, Renderer& renderer, TilePool& pool, const FaultHooks& hooks, const Camera& cam,
                  const RenderSettings& settings, DeviceWork& w, ImageRGB& out) {
    size_t current = SIZE_MAX;  // tile in hand
    int started = 0;
    try {
        renderer.renderTiles(cam, settings, w.counters, [&](size_t& first, size_t& count) {
            if (started > 0 && int(d) == hooks.throttleDev)
                std::this_thread::sleep_for(std::chrono::milliseconds(hooks.throttleMs));
            bool ok = pool.take(d, current, first, count);
            if (ok && (int(d) == hooks.failDev || hooks.failDev == -1) && started == hooks.failAfter)
                throw Error("injected failure (CLRT_FAIL_DEVICE)", ExitCode::Device);
            started += ok;
            return ok;
        }, out, [&](size_t done, size_t total) { pool.progress(d, done, total); });
    } catch (const std::exception& e) {
        pool.fail(d, current, w, e);
    }
}
}  // namespace

ImageRGB renderOnDevices(const std::vector<Renderer*>& renderers, const Camera& cam, const RenderSettings& settings,
                         std::vector<DeviceWork>& work, const std::function<void(size_t, size_t)>& progress) {
    const size_t numPixels = size_t(cam.width) * cam.height;
    ImageRGB out;
    out.width = cam.width;
    out.height = cam.height;
    out.isHdr = true;
    out.pixels.assign(numPixels * 3, 0.0f);
    work.resize(renderers.size());

    // Enough tiles for balancing, large enough to keep each device busy.
    const size_t tile = std::max<size_t>(4096, std::min(settings.maxBatchPixels, numPixels / (16 * renderers.size()) + 1));
    TilePool pool(numPixels, tile, renderers.size(), progress);
    const FaultHooks hooks;

    // Rounds: a tile returned by a device that failed after the others finished is picked up by a
    // new round over the devices still alive.
    for (;;) {
        std::vector<std::thread> threads;
        std::vector<size_t> alive;
        for (size_t d = 0; d < renderers.size(); ++d)
            if (!work[d].failed) alive.push_back(d);
        if (alive.empty()) throw Error("every rendering device failed (last: " + work.back().error + ")", ExitCode::Device);
        for (size_t d : alive)
            threads.emplace_back(renderWorker, d, std::ref(*renderers[d]), std::ref(pool), std::cref(hooks),
                                 std::cref(cam), std::cref(settings), std::ref(work[d]), std::ref(out));
        for (std::thread& t : threads) t.join();
        if (pool.allHandedOut()) break;
        if (settings.stop && settings.stop->load()) {  // tiles never started: pixels with no sample
            for (DeviceWork& w : work) w.counters.stoppedAtSample = 0;
            break;
        }
    }
    return out;
}

}  // namespace clrt
