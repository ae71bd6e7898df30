// Checkpoints of a render (--checkpoint DIR): every finished tile (all samples) is kept as a file, so
// that the same command run again renders only the tiles that are missing and gives the same image
// bit for bit. One folder per camera and render identity (scene inputs, options, spp, seed, tile size):
// DIR/<ImageName>-<key>/tile-<id>.bin, each file written to a temporary and renamed, holding a header
// (magic, key, tile, pixel range), float RGB, and an FNV-1a 64 checksum of everything before it.
// A damaged or foreign tile file is ignored with a warning and its tile rendered again; a temporary
// left by a killed writer is removed once it is ten minutes old. The files are
// kept after the render finishes (a rerun then renders nothing); delete DIR to start over.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "dist/tiles.h"
#include "image/image.h"

namespace clrt {

class Checkpoint {
public:
    // `key`: hex identity of everything that decides the camera's pixels. Creates the folder
    // (clrt::Error, ExitCode::Output, if that fails).
    Checkpoint(const std::string& dir, const std::string& imageName, const std::string& key, const TileGrid& grid);
    // Reads every valid tile file into `img` (sized already); returns which tiles it had.
    std::vector<bool> load(ImageRGB& img) const;
    // Writes tile t's pixels from `img` (atomically: temporary + rename).
    void store(size_t t, const ImageRGB& img) const;
    const std::string& folder() const { return folder_; }

private:
    std::string tilePath(size_t t) const;
    std::string folder_;
    uint64_t key_;
    TileGrid grid_;
};

}  // namespace clrt
