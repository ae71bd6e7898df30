// preview_state.cpp — the shared preview state (see preview_state.h). Reads the scene file's folder
// (for _reference_outputs/) only.
#include "preview/preview_state.h"

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <system_error>

namespace clrt {

void PreviewState::changed() {
    ++changes_;
    cv_.notify_all();
}

void PreviewState::setStage(const std::string& stage) {
    std::lock_guard<std::mutex> lk(mu_);
    stage_ = stage;
    changed();
}

void PreviewState::setCameras(std::vector<CameraView> cams) {
    std::lock_guard<std::mutex> lk(mu_);
    cams_ = std::move(cams);
    lastImage_.assign(cams_.size(), Clock::time_point{});
    changed();
}

void PreviewState::beginCamera(int index) {
    std::lock_guard<std::mutex> lk(mu_);
    if (index < 0 || size_t(index) >= cams_.size()) return;
    current_ = index;
    cams_[size_t(index)].phase = CameraPhase::Rendering;
    changed();
}

bool PreviewState::imageDue(int index) const {
    std::lock_guard<std::mutex> lk(mu_);
    if (index < 0 || size_t(index) >= cams_.size()) return false;
    return std::chrono::duration<double>(Clock::now() - lastImage_[size_t(index)]).count() >= intervalLocked();
}

double PreviewState::imageInterval() const {
    std::lock_guard<std::mutex> lk(mu_);
    return intervalLocked();
}

// The preview's own seconds per published image so far, over the budget: images then cost at most
// kTimeBudget of the time between them. Before any image is published (or viewed) it is minInterval.
double PreviewState::intervalLocked() const {
    if (imagesPublished_ == 0) return minInterval_;
    const double perImage = (renderThreadSeconds_ + serverSeconds_) / double(imagesPublished_);
    return std::max(minInterval_, perImage / kTimeBudget);
}

void PreviewState::publishFigures(int index, const PassFigures& f) {
    std::lock_guard<std::mutex> lk(mu_);
    if (index < 0 || size_t(index) >= cams_.size()) return;
    cams_[size_t(index)].figures = f;
    changed();
}

void PreviewState::publishImage(int index, const PassFigures& f, std::shared_ptr<const ImageRGB> img) {
    std::lock_guard<std::mutex> lk(mu_);
    if (index < 0 || size_t(index) >= cams_.size()) return;
    CameraView& c = cams_[size_t(index)];
    c.figures = f;
    c.image = std::move(img);
    ++c.version;
    ++imagesPublished_;
    lastImage_[size_t(index)] = Clock::now();
    changed();
}

void PreviewState::endCamera(int index, const PassFigures& f, std::shared_ptr<const ImageRGB> img) {
    std::lock_guard<std::mutex> lk(mu_);
    if (index < 0 || size_t(index) >= cams_.size()) return;
    CameraView& c = cams_[size_t(index)];
    c.figures = f;
    c.figures.timeLeft = 0;
    c.phase = CameraPhase::Done;
    if (img) {
        c.image = std::move(img);
        ++c.version;
    }
    changed();
}

void PreviewState::finish(const std::string& stage) {
    std::lock_guard<std::mutex> lk(mu_);
    finished_ = true;
    stage_ = stage;
    changed();
}

void PreviewState::addRenderThreadSeconds(double s) {
    std::lock_guard<std::mutex> lk(mu_);
    renderThreadSeconds_ += s;
}

void PreviewState::addServerSeconds(double s) {
    std::lock_guard<std::mutex> lk(mu_);
    serverSeconds_ += s;
}

double PreviewState::renderThreadSeconds() const {
    std::lock_guard<std::mutex> lk(mu_);
    return renderThreadSeconds_;
}

double PreviewState::serverSeconds() const {
    std::lock_guard<std::mutex> lk(mu_);
    return serverSeconds_;
}

std::vector<CameraView> PreviewState::cameras() const {
    std::lock_guard<std::mutex> lk(mu_);
    return cams_;
}

bool PreviewState::camera(int index, CameraView& out) const {
    std::lock_guard<std::mutex> lk(mu_);
    if (index < 0 || size_t(index) >= cams_.size()) return false;
    out = cams_[size_t(index)];
    return true;
}

std::string PreviewState::stage() const {
    std::lock_guard<std::mutex> lk(mu_);
    return stage_;
}

int PreviewState::current() const {
    std::lock_guard<std::mutex> lk(mu_);
    return current_;
}

bool PreviewState::finished() const {
    std::lock_guard<std::mutex> lk(mu_);
    return finished_;
}

uint64_t PreviewState::changes() const {
    std::lock_guard<std::mutex> lk(mu_);
    return changes_;
}

uint64_t PreviewState::waitForChange(uint64_t seen, std::chrono::milliseconds timeout) const {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait_for(lk, timeout, [&] { return changes_ != seen; });
    return changes_;
}

std::string courseReferencePath(const std::string& sceneFile, const std::string& imageName) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path p = fs::path(sceneFile).parent_path() / "_reference_outputs" / imageName;
    return fs::is_regular_file(p, ec) ? p.string() : std::string();
}

double threadCpuSeconds() {
    timespec ts{};
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return 0;
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace clrt
