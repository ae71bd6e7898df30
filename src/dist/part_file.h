// Partial images of a job array (`clrt render --part K/N`, `clrt merge`). A part file is a float RGB
// OpenEXR of the whole camera image in which only the part's tiles hold pixels (the rest is zero),
// with header attributes saying what it covers and what it belongs to: the render identity (scene
// inputs and pixel-affecting options), camera id, ImageName, spp, seed, tile size, "K/N", the tile
// list, and what the final outputs need (Tonemap blocks, --ldr-quantize, --exr-half). `clrt merge`
// checks the parts against each other and writes the camera's usual outputs.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "image/image.h"
#include "scene/scene.h"

namespace clrt {

struct PartHeader {
    std::string identity;  // renderIdentity() of the render
    std::string sceneFile; // the scene's path when rendered (messages only)
    int cameraId = 0, width = 0, height = 0, spp = 0;
    uint32_t seed = 0;
    std::string imageName;
    size_t tilePixels = 0;
    int part = 0, parts = 0;   // K of N
    std::vector<size_t> tiles; // sorted
    bool truncatePng = true, exrHalf = false;
    std::vector<TonemapSettings> tonemaps;
    double renderSeconds = 0;
    std::string device;
};

// "<ImageName>.part<K>of<N>.exr".
std::string partFileName(const std::string& imageName, int k, int n);

// Writes the part file (atomically); pixels of tiles outside h.tiles are written as zero.
void writePartFile(const std::string& path, const PartHeader& h, const ImageRGB& img);

// Reads a part file's header; clrt::Error naming `path` if it is not a clrt part file or its header is
// inconsistent (tiles beyond the image, a size that does not match).
PartHeader readPartHeader(const std::string& path);

}  // namespace clrt
