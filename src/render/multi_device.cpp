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

// The tiles of one render, handed out to the devices' threads (thread-safe) from a TileFeed; the tile
// of a failed device goes back to the pool first. Progress in thousandths of a tile: each device's
// part of the tile in hand (reported to the feed's inHand), so it moves within a tile too.
class TilePool {
public:
    TilePool(size_t numPixels, size_t devices, const TileFeed& feed)
        : numPixels_(numPixels), feed_(feed), partial_(devices, 0) {}

    // Device d finished the tile in hand (`current`, SIZE_MAX if none) and asks for the next one.
    // Renderer::renderTiles asks for a next tile only after a complete one (a stopped render leaves
    // its loop instead), so every tile reported finished here has all its samples.
    bool take(size_t d, size_t& current, size_t& first, size_t& count) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (current != SIZE_MAX) {
            partial_[d] = 0;
            reportInHand();  // before the finished tile counts, so that progress never overshoots
            feed_.finished(current);
            current = SIZE_MAX;
        }
        if (!returned_.empty()) {
            current = returned_.front();
            returned_.pop_front();
        } else if (exhausted_ || !feed_.next(current)) {
            exhausted_ = true;
            current = SIZE_MAX;
            return false;
        }
        first = current * feed_.tilePixels;
        count = std::min(feed_.tilePixels, numPixels_ - first);
        return true;
    }
    void progress(size_t d, size_t done, size_t total) {
        std::lock_guard<std::mutex> lock(mutex_);
        partial_[d] = total ? std::min(kUnits - 1, done * kUnits / total) : 0;
        reportInHand();
    }
    // Device d failed with `current` in hand: that tile goes back to the pool.
    void fail(size_t d, size_t current, DeviceWork& w, const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        w.failed = true;
        w.error = e.what();
        partial_[d] = 0;
        if (current != SIZE_MAX) returned_.push_back(current);
        warn("device '" + w.name + "' failed and was dropped: " + w.error);
        reportInHand();
    }
    bool allHandedOut() {
        std::lock_guard<std::mutex> lock(mutex_);
        return returned_.empty() && exhausted_;
    }

private:
    static constexpr size_t kUnits = 1000;
    void reportInHand() {  // with mutex_ held
        size_t units = 0;
        for (size_t p : partial_) units += p;
        if (feed_.inHand) feed_.inHand(units);
    }
    const size_t numPixels_;
    const TileFeed& feed_;
    std::mutex mutex_;
    bool exhausted_ = false;  // feed_.next said no
    std::vector<size_t> partial_;
    std::deque<size_t> returned_;  // tiles of failed devices
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

void renderFedTiles(const std::vector<Renderer*>& renderers, const Camera& cam, const RenderSettings& settings,
                    std::vector<DeviceWork>& work, const TileFeed& feed, ImageRGB& out) {
    const size_t numPixels = size_t(cam.width) * cam.height;
    work.resize(renderers.size());
    TilePool pool(numPixels, renderers.size(), feed);
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
}

ImageRGB renderOnDevices(const std::vector<Renderer*>& renderers, const Camera& cam, const RenderSettings& settings,
                         std::vector<DeviceWork>& work, const std::function<void(size_t, size_t)>& progress) {
    const size_t numPixels = size_t(cam.width) * cam.height;
    ImageRGB out;
    out.width = cam.width;
    out.height = cam.height;
    out.isHdr = true;
    out.pixels.assign(numPixels * 3, 0.0f);

    // Enough tiles for balancing, large enough to keep each device busy; handed out in order.
    TileFeed feed;
    feed.tilePixels =
        std::max<size_t>(4096, std::min(settings.maxBatchPixels, numPixels / (16 * renderers.size()) + 1));
    const size_t totalTiles = (numPixels + feed.tilePixels - 1) / feed.tilePixels;
    size_t nextTile = 0, doneTiles = 0, inHand = 0, reported = 0;
    // Progress only when it grows (a failed device's partial tile goes back to the pool).
    auto report = [&] {
        size_t done = doneTiles * 1000 + inHand;
        if (progress && done > reported) progress(reported = done, totalTiles * 1000);
    };
    feed.next = [&](size_t& tile) {
        if (nextTile >= totalTiles) return false;
        tile = nextTile++;
        return true;
    };
    feed.finished = [&](size_t) {
        ++doneTiles;
        report();
    };
    feed.inHand = [&](size_t units) {
        inHand = units;
        report();
    };
    renderFedTiles(renderers, cam, settings, work, feed, out);
    return out;
}

}  // namespace clrt
