// Tiles of a distributed render: tile t is pixels [t * tilePixels, min(numPixels, (t + 1) * tilePixels))
// in row-major order. The tile size is a function of the image size alone (or --tile-pixels), never of
// the number of ranks or devices, so that checkpoints and parts made by differently sized jobs fit
// together. Also: the tile set of part K of N, tile lists as text, and the identity hash of a render.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "cl/program.h"

namespace clrt {

// Default tile size: 1/64 of the image, at least 4096 pixels (a device needs that much work per
// launch), at most 65536.
size_t defaultTilePixels(size_t numPixels);

struct TileGrid {
    size_t numPixels = 0, tilePixels = 1;
    size_t count() const { return (numPixels + tilePixels - 1) / tilePixels; }
    size_t first(size_t t) const { return t * tilePixels; }
    size_t size(size_t t) const { return std::min(tilePixels, numPixels - first(t)); }
};

// Part k (1-based) of n: tiles t with t mod n == k - 1 (interleaved, so every part gets a share of
// the cheap and the expensive regions of the image).
std::vector<size_t> partTiles(size_t tileCount, int k, int n);

// "0-3,7,9-12" <-> sorted tile ids. parseTileList throws clrt::Error naming `what` on bad text, an
// id >= limit, or an id listed twice.
std::string formatTileList(const std::vector<size_t>& sortedTiles);
std::vector<size_t> parseTileList(const std::string& text, size_t limit, const std::string& what);

// The 16 hex digits of v (hashes: fnv1a64 of cl/program.h).
std::string hexKey(uint64_t v);

// The identity of the pixels of a render, less spp and seed: the bytes of every input file (scene,
// PLY, images), the kernel sources embedded in this clrt, and `options` (camera size, sampling
// overrides, tile size: whatever changes pixels). Throws clrt::Error naming a file it cannot read.
std::string renderIdentity(const std::vector<std::string>& inputFiles, const std::string& options);

}  // namespace clrt
