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

// Where renderOnDevices takes its tiles from when the caller schedules them (src/dist/: a part of the
// image, tiles already in a checkpoint, tiles handed out to MPI ranks). Tile t is pixels
// [t * tilePixels, min(numPixels, (t + 1) * tilePixels)). The functions are called from the device
// threads, one call at a time (under one lock).
struct TileFeed {
    size_t tilePixels = 4096;
    std::function<bool(size_t& tile)> next;      // the next tile to render; false: none left (not asked again)
    std::function<void(size_t tile)> finished;   // tile's pixels, all samples, are in the image
    std::function<void(size_t units)> inHand;    // optional: thousandths of tiles in hand on the devices
};

// renderOnDevices over the tiles of `feed`, into `out` (already sized width*height*3; pixels of tiles
// not handed out are left as they are). A tile is reported finished only when complete: a render
// stopped by settings.stop reports no tile it cut short.
void renderFedTiles(const std::vector<Renderer*>& renderers, const Camera& cam, const RenderSettings& settings,
                    std::vector<DeviceWork>& work, const TileFeed& feed, ImageRGB& out);

}  // namespace clrt
