// preview_state.h — what `clrt render --preview` and `--display-server` show, shared between the
// render thread (which publishes) and the preview's own threads (which read): per camera its size,
// ImageName, first Tonemap block, course reference, progress figures and the latest HDR image. The
// render thread only copies figures and hands over an image it already has (a shared_ptr; tone
// mapping and PNG encoding happen on the readers' threads), at most every `minInterval` seconds per
// camera, and no more often than keeps the preview's own time (publishing plus encoding, per image
// published) within `kTimeBudget` of the time between images: a large image that takes long to encode
// is published less often, so the preview never takes more than that share of one core from the render.
// Reads the scene's cameras (id, size, ImageName, Tonemap blocks).
#pragma once
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "image/image.h"
#include "shared/tonemap_settings.h"

namespace clrt {

enum class CameraPhase { Waiting, Rendering, Done };

// The figures of one camera at a pass (all optional but spp).
struct PassFigures {
    int spp = 0;                // samples per pixel in the published image
    double relMse = NAN;        // the estimate (progressive renders), NaN: none yet
    double elapsed = 0;         // seconds since the camera started
    double timeLeft = NAN;      // seconds toward --time-limit / --target-error (NaN: unknown)
    double fraction = NAN;      // 0..1 done (fixed-spp renders), NaN: unknown
    std::vector<std::pair<std::string, double>> throughput;  // device name, samples per second
};

struct CameraView {
    int id = 0;
    std::string imageName;
    int width = 0, height = 0;
    bool hasTonemap = false;    // the camera has a Tonemap block: `tonemap` is its first one
    TonemapSettings tonemap;
    bool ldrOutput = false;     // ImageName .png: radiance in 0..255 (the course's PNG convention)
    std::string referencePath;  // the course reference (_reference_outputs/<ImageName>), "" if none
    CameraPhase phase = CameraPhase::Waiting;
    PassFigures figures;
    uint64_t version = 0;       // +1 per published image
    std::shared_ptr<const ImageRGB> image;
};

class PreviewState {
public:
    static constexpr double kTimeBudget = 0.02;  // the preview's own seconds per second of render, at most

    explicit PreviewState(double minInterval = 0.25) : minInterval_(minInterval) {}

    // Render side.
    void setStage(const std::string& stage);           // "loading scene", "building kernels", ...
    void setCameras(std::vector<CameraView> cams);
    void beginCamera(int index);
    bool imageDue(int index) const;                    // the rate limit: may an image be published now?
    double imageInterval() const;                      // its interval now: minInterval, or more (kTimeBudget)
    void publishFigures(int index, const PassFigures& f);
    void publishImage(int index, const PassFigures& f, std::shared_ptr<const ImageRGB> img);
    void endCamera(int index, const PassFigures& f, std::shared_ptr<const ImageRGB> img);
    void finish(const std::string& stage);             // the render is over (done or stopped)
    // Seconds the render thread spent on the preview (means, copies, publishing) and the preview's
    // threads on encoding (their CPU time: threadCpuSeconds()): the preview's cost, reported in
    // status.json (scripts/preview_overhead.py), and what the rate limit keeps within kTimeBudget.
    void addRenderThreadSeconds(double s);
    void addServerSeconds(double s);
    double renderThreadSeconds() const;
    double serverSeconds() const;

    // Reader side: copies under the lock.
    std::vector<CameraView> cameras() const;
    bool camera(int index, CameraView& out) const;
    std::string stage() const;
    int current() const;
    bool finished() const;
    uint64_t changes() const;                          // +1 on every change
    // Waits until changes() != seen or `timeout` passes; returns changes().
    uint64_t waitForChange(uint64_t seen, std::chrono::milliseconds timeout) const;

private:
    using Clock = std::chrono::steady_clock;
    void changed();  // under mu_
    mutable std::mutex mu_;
    mutable std::condition_variable cv_;
    std::vector<CameraView> cams_;
    std::vector<Clock::time_point> lastImage_;
    std::string stage_ = "starting";
    int current_ = -1;
    bool finished_ = false;
    uint64_t changes_ = 0;
    double minInterval_;
    double renderThreadSeconds_ = 0, serverSeconds_ = 0;
    uint64_t imagesPublished_ = 0;
    double intervalLocked() const;  // under mu_
};

// CPU seconds the calling thread has used (CLOCK_THREAD_CPUTIME_ID): what an encode takes from the
// render, which wall time on a loaded CPU device would overstate.
double threadCpuSeconds();

// The course reference of a camera: <scene folder>/_reference_outputs/<ImageName> when it is a
// regular file (as scripts/check_course.py finds them), else "".
std::string courseReferencePath(const std::string& sceneFile, const std::string& imageName);

}  // namespace clrt
