// Several OpenCL devices on one image: pixel tiles (all samples each) are handed out dynamically
// from one counter, so a fast device simply takes more tiles and all finish together. A device that
// fails (build error, lost device, any clrt::Error) is dropped with a warning and its unfinished
// tile goes back to the pool; with no device left the render fails. Every pixel is computed by one
// device exactly as a single-device render computes it (same random streams, same summation order).
//
// Test hooks (environment): CLRT_THROTTLE_DEVICE="i:ms" sleeps ms after each tile on the i-th
// selected device; CLRT_FAIL_DEVICE="i:k" makes the i-th device (every device for i = -1) fail when it
// starts its (k+1)th tile.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace clrt {

struct DeviceWork {
    std::string name;
    RenderCounters counters;
    bool failed = false;
    std::string error;
};

// `work` gets one entry per renderer (created if empty). progress(done, total) in thousandths of a
// tile, moving within tiles too; called from the device threads, one call at a time.
ImageRGB renderOnDevices(const std::vector<Renderer*>& renderers, const Camera& cam, const RenderSettings& settings,
                         std::vector<DeviceWork>& work, const std::function<void(size_t, size_t)>& progress = {});

}  // namespace clrt
