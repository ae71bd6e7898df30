// camera_drivers.h — how `clrt render` renders one camera and writes its outputs: through src/dist/
// (a --part, a --checkpoint, MPI ranks), in progressive passes (--target-error, --time-limit), on one
// device, or split over several; with a progress display and the graceful Ctrl-C of cli/interrupt.h.
// Reads the Camera (size, ImageName, NumSamples, Tonemap blocks) of the scene model.
#pragma once
#include <memory>
#include <vector>

#include "cli/live_view.h"
#include "cli/render_args.h"
#include "render/multi_device.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace clrt {

// Renders one camera on every renderer and writes its outputs. Returns the samples per pixel every
// pixel reached: fewer than asked if the render was interrupted (stopRequested), and the images
// written are then partial. tOutput: the time spent writing is added to it. live (--preview,
// --display-server; may be null) gets the passes' figures and images and the final image.
int renderAndWriteCamera(const RenderArgs& a, const Camera& cam, int camIndex,
                         std::vector<std::unique_ptr<Renderer>>& renderers, std::vector<DeviceWork>& work,
                         RenderCounters& counters, double& tOutput, LiveView* live = nullptr);

}  // namespace clrt
