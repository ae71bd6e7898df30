// src/dist/: one image over MPI ranks, job-array parts (--part K/N, clrt merge), checkpoints.
// Reads the scene's input files (to hash them), never the scene model itself.
// One camera rendered as a set of tiles that may come from elsewhere: a part of a job array
// (--part K/N), tiles already in a checkpoint (--checkpoint DIR), tiles rendered by other MPI ranks.
// Rank 0 (or the only process) schedules the tiles that are still missing over its own devices and
// the other ranks, keeps finished ones in the checkpoint, and shows one progress line for the job.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "dist/mpi_job.h"
#include "dist/tiles.h"
#include "render/multi_device.h"
#include "render/renderer.h"

namespace clrt {

struct DistSettings {
    int part = 0, parts = 0;     // --part K/N (0: the whole image)
    std::string checkpointDir;   // --checkpoint DIR ("" none)
    size_t tilePixels = 0;       // --tile-pixels (0: defaultTilePixels)
    std::string identity;        // renderIdentity() of the render (without spp and seed)
};

struct DistResult {
    bool writesOutputs = true;   // rank 0 / the only process
    ImageRGB image;              // the job's tiles (others zero); empty on other ranks
    TileGrid grid;
    std::vector<size_t> tiles;   // the job's tiles: the part's, or all
    size_t fromCheckpoint = 0;   // tiles read from the checkpoint instead of rendered
    bool complete = false;       // every tile of the job has all samples
    std::string checkpointFolder;
};

// True when a camera needs this path rather than the plain render (a part, a checkpoint, MPI).
inline bool distActive(const DistSettings& ds, const MpiJob& job) {
    return ds.parts > 0 || !ds.checkpointDir.empty() || job.distributed();
}

// Renders camera number `camIndex` (the same on every rank) as described above; progress(done,
// total) is called on rank 0 only, one call at a time.
DistResult renderDistributed(const std::vector<Renderer*>& renderers, const Camera& cam, int camIndex,
                             const RenderSettings& settings, std::vector<DeviceWork>& work, const DistSettings& ds,
                             MpiJob& job, const std::function<void(size_t, size_t)>& progress);

// The hex key of a camera's checkpoint: identity, camera, spp, seed, tile size.
std::string checkpointKey(const DistSettings& ds, const Camera& cam, const RenderSettings& settings, size_t tilePixels);

}  // namespace clrt
