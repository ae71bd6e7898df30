// render_stats.h — what `clrt render` prints about a render: the -v setup lines, one line per device
// when several rendered, the `times:` line (stderr) and the `stats:` line (stdout; keys in README
// "Using it"), and in an MPI job every rank's devices and transfers gathered on rank 0. Reads no
// scene element (only the flattened scene's figures).
#pragma once
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "flatten/device_scene.h"
#include "render/multi_device.h"
#include "render/renderer.h"

namespace clrt {

// Seconds from t until now.
inline double secondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Host time of the stages before and after the render itself (the `times:` line).
struct StageTimes {
    double parse = 0, flatten = 0, build = 0, output = 0;
};

// -v: devices, kernel flags, flattening and BVH figures.
void printSetup(const DeviceScene& ds, const std::vector<std::unique_ptr<Renderer>>& renderers);

// Adds the devices' ray counts (and, with one device, its render time) to `counters`; prints one line
// per device when there are several, and with -v the device time of each kernel stage.
void sumDeviceCounters(const std::vector<DeviceWork>& work, RenderCounters& counters);

// The `times:` line (stderr) and the `stats:` line (stdout, see README); spp: the first camera's.
void printTimes(const StageTimes& t, const DeviceScene& ds, const Renderer& renderer, const RenderCounters& counters,
                const std::vector<DeviceWork>& work, int spp);

// MPI: every rank's devices become entries of rank 0's `work` ("rank R: [i] name"), and rank 0
// prints one line per rank: tiles, bytes sent, time spent waiting for tiles and sending them.
void gatherRankStats(std::vector<DeviceWork>& work);

}  // namespace clrt
