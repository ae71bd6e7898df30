// live_view.cpp — the preview and tev hooks of `clrt render` (see live_view.h). Reads the cameras'
// id, size, ImageName and Tonemap blocks.
#include "cli/live_view.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>
#include <unistd.h>

#include "cli/interrupt.h"
#include "output/output.h"

namespace clrt {

std::unique_ptr<LiveView> LiveView::start(const RenderArgs& a) {
    if (a.previewAddress.empty() && a.displayServer.empty()) return nullptr;
    std::unique_ptr<LiveView> lv(new LiveView());
    lv->keep_ = a.previewKeep;
    lv->verbose_ = a.verbose;
    if (!a.previewAddress.empty()) {
        const PreviewAddress addr = parsePreviewAddress("--preview", a.previewAddress);
        // Stop: exactly what Ctrl-C does (cli/interrupt.h's signal thread takes it; a second one exits).
        // Raised 50 ms later, from a thread of its own, so that the page gets its answer first (after the
        // render, with --preview-keep, the signal exits at once).
        lv->server_ = std::make_unique<PreviewServer>(lv->state_, [] {
            std::thread([] {
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
                ::kill(::getpid(), SIGINT);
            }).detach();
        });
        lv->server_->start(addr);
        std::fprintf(stderr, "preview: %s\n", lv->server_->url().c_str());
        std::fflush(stderr);
    }
    if (!a.displayServer.empty()) {
        PreviewState* state = &lv->state_;  // declared before tev_: outlives its thread
        lv->tev_ = std::make_unique<TevClient>(a.displayServer, [state](double s) { state->addServerSeconds(s); });
    }
    lv->state_.setStage("loading the scene");
    return lv;
}

LiveView::~LiveView() = default;

void LiveView::setCameras(const std::vector<const Camera*>& cams, const std::string& sceneFile) {
    std::vector<CameraView> views;
    for (const Camera* c : cams) {
        CameraView v;
        v.id = c->id;
        v.imageName = c->imageName;
        v.width = c->width;
        v.height = c->height;
        v.hasTonemap = !c->tonemaps.empty();
        if (v.hasTonemap) v.tonemap = c->tonemaps.front();
        v.ldrOutput = lowerExtension(c->imageName) == ".png";
        v.referencePath = courseReferencePath(sceneFile, c->imageName);
        views.push_back(std::move(v));
        names_.push_back(c->imageName.empty() ? "camera " + std::to_string(c->id) : c->imageName);
    }
    state_.setCameras(std::move(views));
}

void LiveView::beginCamera(int index, const Camera& cam) {
    state_.beginCamera(index);
    state_.setStage("rendering camera " + std::to_string(cam.id));
    if (tev_ && size_t(index) < names_.size()) tev_->createImage(names_[size_t(index)], cam.width, cam.height);
}

void LiveView::image(int index, const PassFigures& f, std::shared_ptr<const ImageRGB> img) {
    if (tev_ && size_t(index) < names_.size()) tev_->updateImage(names_[size_t(index)], img);
    state_.publishImage(index, f, std::move(img));
}

void LiveView::endCamera(int index, const PassFigures& f, const ImageRGB& img) {
    const auto t0 = std::chrono::steady_clock::now();
    auto shared = std::make_shared<const ImageRGB>(img);
    if (tev_ && size_t(index) < names_.size()) tev_->updateImage(names_[size_t(index)], shared);
    state_.endCamera(index, f, std::move(shared));
    state_.addRenderThreadSeconds(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

void LiveView::finish(bool interrupted) {
    state_.finish(interrupted ? "stopped" : "finished");
    if (!server_) return;
    if (!keep_ || interrupted) {
        server_->linger(3.0);
        // -v: what the preview cost (scripts/preview_overhead.py reads this line).
        if (verbose_)
            std::fprintf(stderr, "preview: render thread %.4f s, server threads %.4f s\n", state_.renderThreadSeconds(),
                         state_.serverSeconds());
        return;
    }
    std::fprintf(stderr, "preview: the render is over; still serving %s (--preview-keep) until Ctrl-C\n",
                 server_->url().c_str());
    std::fflush(stderr);
    setGracefulInterrupt(false);  // Ctrl-C (or the page's Stop) now exits at once
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}

}  // namespace clrt
