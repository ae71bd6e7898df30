// One image over the ranks of an MPI job (OpenMPI; any MPI with MPI_THREAD_SERIALIZED). Every rank
// loads the scene itself (same path: shared storage) and renders with its own devices (--device per
// rank). Rank 0 schedules: the other ranks ask it for a tile (16 bytes), get a tile id (8 bytes), and
// send each finished tile back as float RGB (16 + 12 bytes a pixel); rank 0 renders tiles too, writes
// them into the image (and the checkpoint) and writes the outputs. Each rank renders a pixel exactly
// as a one-process render does, so the image is the same bit for bit on the same kind of device.
// A rank that dies ends the whole job (mpirun ends every rank and names the one that failed); outputs
// are only ever renamed into place complete, so no partial image replaces a good one.
// MPI starts only in a process that mpirun/srun launched (OMPI_COMM_WORLD_SIZE, PMI_SIZE or
// PMIX_RANK in the environment); a build without MPI (CLRT_MPI=OFF or no MPI found) refuses such a
// launch with an error instead of rendering the whole image N times.
// Test hook: CLRT_KILL_RANK="r:k" (r > 0) kills rank r with SIGKILL when it is handed its tile number
// k (k = 0: its first), as a crashed node would die. So that this happens whatever the timing, rank 0
// then keeps the last k + 1 tiles for rank r alone (killRankHook()).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "dist/tiles.h"
#include "image/image.h"
#include "render/multi_device.h"

namespace clrt {

// What one rank's transfers cost (printed by rank 0 per rank; README "Scaling").
struct RankTransfer {
    uint64_t tiles = 0, bytesSent = 0, bytesReceived = 0, messages = 0;  // messages: rank 0, received
    double waitSeconds = 0;  // worker: from asking for a tile to having its id
    double sendSeconds = 0;  // worker: sending finished tiles
    double serveSeconds = 0; // rank 0: handling the others' messages (receive, copy, checkpoint)
};

class MpiJob {
public:
    // Starts MPI if this process was launched as an MPI rank; else a one-process job.
    static MpiJob& start(int* argc, char*** argv);
    static MpiJob& get();
    static bool builtWithMpi();
    bool distributed() const { return size_ > 1; }
    int rank() const { return rank_; }
    int size() const { return size_; }
    const std::string& host() const { return host_; }

    // CLRT_KILL_RANK's rank and tile number ({-1, -1} when unset or not an MPI job).
    std::pair<int, int> killRankHook() const;

    // Rank 0, camera number `cam`: answers the other ranks' requests from `next(tile, rank)` and puts their tiles
    // into `img` (then calls `finished`) until every other rank was told there is no tile left.
    // `localFailed()` is polled: true ends the wait with clrt::Error.
    void serve(int cam, const TileGrid& grid, ImageRGB& img, const std::function<bool(size_t&, int)>& next,
               const std::function<void(size_t)>& finished, const std::function<bool()>& localFailed);
    // Other ranks, camera number `cam`: tiles from rank 0; finished tiles (read from `img`) go back.
    TileFeed workerFeed(int cam, const TileGrid& grid, const ImageRGB& img);

    // After the last camera: every rank's text `mine` gathered on rank 0 (index = rank), empty elsewhere.
    std::vector<std::string> gather(const std::string& mine);
    RankTransfer& transfer() { return transfer_; }

    // Ends the job: MPI_Finalize (code 0) or MPI_Abort(code) when distributed; no-op otherwise.
    void end(int code);

private:
    int rank_ = 0, size_ = 1;
    bool started_ = false;
    std::string host_;
    RankTransfer transfer_;
};

}  // namespace clrt
