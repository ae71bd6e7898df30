// live_view.h — the render's side of `clrt render --preview` and `--display-server` (src/preview/):
// starts the HTTP server (binding before any work, so a port in use exits 1 at once) and the tev
// connection, registers the selected cameras, and takes what the render loop publishes: figures
// after every pass, an image at most 4 times a second per camera (rate-limited here, encoded on the
// preview's threads), and each camera's final image. Reads the cameras (id, size, ImageName, Tonemap
// blocks) and the scene file's folder (course references).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "cli/render_args.h"
#include "preview/preview_server.h"
#include "preview/preview_state.h"
#include "preview/tev_client.h"
#include "scene/scene.h"

namespace clrt {

class LiveView {
public:
    // Null when neither --preview nor --display-server was given. Binds the preview's port and
    // prints its URL (stderr); throws clrt::Error (exit 1) with one line when the port is in use.
    static std::unique_ptr<LiveView> start(const RenderArgs& a);
    ~LiveView();

    void setStage(const std::string& stage) { state_.setStage(stage); }
    void setCameras(const std::vector<const Camera*>& cams, const std::string& sceneFile);
    void beginCamera(int index, const Camera& cam);
    // May an image be published for this camera now (the rate limit)?
    bool imageDue(int index) const { return state_.imageDue(index); }
    void figures(int index, const PassFigures& f) { state_.publishFigures(index, f); }
    void addRenderThreadSeconds(double s) { state_.addRenderThreadSeconds(s); }
    void image(int index, const PassFigures& f, std::shared_ptr<const ImageRGB> img);
    void endCamera(int index, const PassFigures& f, const ImageRGB& img);
    // The render is over: the page is told so; then the server lingers until a page has seen it (at
    // most 3 s), or with --preview-keep serves until Ctrl-C.
    void finish(bool interrupted);
    PreviewServer* server() { return server_.get(); }

private:
    LiveView() = default;
    PreviewState state_;
    std::unique_ptr<PreviewServer> server_;
    std::unique_ptr<TevClient> tev_;
    std::vector<std::string> names_;  // tev image names, per camera index
    bool keep_ = false, verbose_ = false;
};

}  // namespace clrt
