// src/output/: a camera's output files (PNG; EXR + tone-mapped PNGs, committed together) and tone mapping on the OpenCL device.
// output.h — writing a rendered camera image (the `clrt tonemap` command is in src/cli/).
// An ImageName ending in .png is clamped and quantised (floor by default, as the course's reference PNGs; round with --ldr-quantize round);
// one ending in .exr is written as float (or half) RGB OpenEXR, ZIP-compressed, with header
// attributes (renderer, spp, renderTime, device), and next to it one tone-mapped PNG per Tonemap block
// of the camera, tone-mapped on the OpenCL device (output/tonemap_device.h) while the EXR is written on
// a second thread. Every file is written to a temporary sibling; they are renamed into place only when
// all of them are complete, so a tone-mapping or write failure changes none of them (only a failing
// rename, after the others succeeded, can leave a partial set).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "cl/program.h"
#include "image/image.h"
#include "image/tonemap.h"
#include "scene/scene.h"

namespace clrt {

struct OutputOptions {
    std::string outDir = ".";      // must exist
    bool truncatePng = true;       // .png ImageName: floor (the default, as the course's PNGs) or round (--ldr-quantize round)
    bool tonemapTruncate = true;   // tone-mapped PNGs: floor (the course's references) or round
    bool exrHalf = false;          // --exr-half: HALF channels instead of FLOAT
    int spp = 0;                   // header attributes of the EXR
    double renderSeconds = 0;
    std::string deviceName;
    std::string partial;           // non-empty: an interrupted render; the EXR's "partial" attribute
    std::map<std::string, std::string> attributes;  // more EXR header attributes (--target-error, ...)
};

// "" if `name` is a plain file name clrt may create: not empty, no '/' or '\\', no control
// character, no leading '.' (".", "..", hidden files such as .bashrc, and clrt's own temporaries),
// at most 200 bytes (room for the temporary's suffix); else the reason it is not.
std::string plainNameProblem(const std::string& name);
// The lowercase extension of a file name (".png", ".exr", ...; "" if none).
std::string lowerExtension(const std::string& name);

// The PNG paths of the tone-mapped images of `hdrPath` (its extension replaced): one block -> stem +
// its Extension (usually none) + ".png"; several -> stem + (Extension, or "_<tmo>") + ".png", a
// name already taken getting "_<block number>" appended (with a warning).
std::vector<std::string> tonemapPngPaths(const std::string& hdrPath, const std::vector<TonemapSettings>& blocks);

// Writes the outputs of one camera (see above) into opts.outDir; returns the paths written. Throws
// clrt::Error if the ImageName or a derived name is not a plain .png/.exr file name.
std::vector<std::string> writeCameraOutputs(const Camera& cam, const ImageRGB& radiance, const OutputOptions& opts,
                                            DeviceContext& dc);

}  // namespace clrt
