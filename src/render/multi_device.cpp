// Dynamic tile scheduling over several devices (see multi_device.h).
#include "render/multi_device.h"

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <deque>
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
    const size_t totalTiles = (numPixels + tile - 1) / tile;
    std::mutex mutex;
    size_t nextTile = 0, doneTiles = 0;
    // Progress in thousandths of a tile: finished tiles plus each device's part of the tile in hand,
    // so it moves within a tile too (a 1x1 image at many samples is one tile). Reported only when it
    // grows (a failed device's partial tile goes back to the pool).
    const size_t kUnits = 1000;
    std::vector<size_t> partial(renderers.size(), 0);
    size_t reported = 0;
    auto report = [&] {  // with `mutex` held
        size_t done = doneTiles * kUnits;
        for (size_t p : partial) done += p;
        if (progress && done > reported) progress(reported = done, totalTiles * kUnits);
    };
    std::deque<size_t> returned;  // tiles of failed devices
    int throttleDev = -100, throttleMs = 0, failDev = -100, failAfter = 0;
    envPair("CLRT_THROTTLE_DEVICE", throttleDev, throttleMs);
    envPair("CLRT_FAIL_DEVICE", failDev, failAfter);

    auto worker = [&](size_t d) {
        DeviceWork& w = work[d];
        size_t current = SIZE_MAX;  // tile in hand
        int started = 0;
        auto take = [&](size_t& first, size_t& count) {
            std::lock_guard<std::mutex> lock(mutex);
            if (current != SIZE_MAX) {
                ++doneTiles;
                partial[d] = 0;
                report();
                current = SIZE_MAX;
            }
            if (!returned.empty()) {
                current = returned.front();
                returned.pop_front();
            } else if (nextTile < totalTiles) {
                current = nextTile++;
            } else {
                return false;
            }
            first = current * tile;
            count = std::min(tile, numPixels - first);
            return true;
        };
        try {
            renderers[d]->renderTiles(cam, settings, w.counters, [&](size_t& first, size_t& count) {
                if (started > 0 && int(d) == throttleDev)
                    std::this_thread::sleep_for(std::chrono::milliseconds(throttleMs));
                bool ok = take(first, count);
                if (ok && (int(d) == failDev || failDev == -1) && started == failAfter)
                    throw Error("injected failure (CLRT_FAIL_DEVICE)", ExitCode::Device);
                started += ok;
                return ok;
            }, out, [&](size_t done, size_t total) {
                std::lock_guard<std::mutex> lock(mutex);
                partial[d] = total ? std::min(kUnits - 1, done * kUnits / total) : 0;
                report();
            });
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(mutex);
            w.failed = true;
            w.error = e.what();
            partial[d] = 0;
            if (current != SIZE_MAX) returned.push_back(current);
            warn("device '" + w.name + "' failed and was dropped: " + w.error);
        }
    };

    // Rounds: a tile returned by a device that failed after the others finished is picked up by a
    // new round over the devices still alive.
    for (;;) {
        std::vector<std::thread> threads;
        std::vector<size_t> alive;
        for (size_t d = 0; d < renderers.size(); ++d)
            if (!work[d].failed) alive.push_back(d);
        if (alive.empty()) throw Error("every rendering device failed (last: " + work.back().error + ")", ExitCode::Device);
        for (size_t d : alive) threads.emplace_back(worker, d);
        for (std::thread& t : threads) t.join();
        std::lock_guard<std::mutex> lock(mutex);
        if (returned.empty() && nextTile >= totalTiles) break;
        if (settings.stop && settings.stop->load()) {  // tiles never started: pixels with no sample
            for (DeviceWork& w : work) w.counters.stoppedAtSample = 0;
            break;
        }
    }
    return out;
}

}  // namespace clrt
