// preview_images.h — the preview's images, made on the preview's threads from a camera's HDR image:
// the tone-mapped 8-bit view (the host reference of image/tonemap.h with the camera's first Tonemap
// block, or a linear view), a box-filtered thumbnail, and the EXR file's bytes in memory (no file is
// written). Reads the camera's Tonemap block and ImageName extension (through CameraView).
#pragma once
#include <string>
#include <vector>

#include "image/image.h"
#include "preview/preview_state.h"

namespace clrt {

// What the page asks for: "scene" (the camera's first Tonemap block, else linear), "photographic",
// "aces", "filmic" or "linear"; exposure in stops (multiplies the key of the operators, the
// radiance of the linear view).
struct ViewSettings {
    std::string tmo = "scene";
    double exposure = 0;
    int maxWidth = 0;  // > 0: box-filtered down to at most this width first (thumbnails)
};

// false when `tmo` is not one of the names above or exposure is not finite / outside [-20, 20].
bool validViewSettings(const ViewSettings& v);

// The view of `img` as 8-bit RGB rows; `ldr`: the image holds 0..255 radiance (a .png ImageName or a
// PNG reference): its linear view is the course's plain clamp, else sRGB of the radiance clamped to
// [0,1]. Sets width/height to the view's size.
std::vector<unsigned char> previewView(const ImageRGB& img, bool ldr, bool hasTonemap, const TonemapSettings& scene,
                                       const ViewSettings& v, int& width, int& height);

// `img` box-filtered to at most maxWidth pixels wide (aspect kept; itself when already narrower).
ImageRGB boxDownscale(const ImageRGB& img, int maxWidth);

// The bytes of a float RGB OpenEXR file of `img` (ZIP, written on the calling thread) with string
// attributes.
std::string exrBytes(const ImageRGB& img, const std::vector<std::pair<std::string, std::string>>& attributes);

}  // namespace clrt
