// The MPI side of a distributed render (see mpi_job.h). Compiled with or without MPI
// (CLRT_HAVE_MPI): without it every process is a one-process job, and a process that an MPI launcher
// started is refused.
#include "dist/mpi_job.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>
#include <unistd.h>

#include "util/error.h"

#ifdef CLRT_HAVE_MPI
#define OMPI_SKIP_MPICXX 1  // the C API only (no deprecated C++ bindings to link)
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace clrt {

namespace {
MpiJob gJob;
// The launcher's world size from the environment (0: not launched by an MPI launcher; -1: launched,
// size unknown).
int launcherSize() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
        if (const char* s = std::getenv(v)) return std::max(1, std::atoi(s));
    return std::getenv("PMIX_RANK") ? -1 : 0;
}
#ifdef CLRT_HAVE_MPI
double secondsSince(std::chrono::steady_clock::time_point t) {  // only the MPI transfers are timed
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
#endif
}  // namespace

bool MpiJob::builtWithMpi() {
#ifdef CLRT_HAVE_MPI
    return true;
#else
    return false;
#endif
}

MpiJob& MpiJob::get() { return gJob; }

std::pair<int, int> MpiJob::killRankHook() const {
    int r = -1, k = -1;
    const char* v = std::getenv("CLRT_KILL_RANK");
    if (!v || std::sscanf(v, "%d:%d", &r, &k) != 2 || r <= 0 || r >= size_ || k < 0) return {-1, -1};
    return {r, k};
}

#ifndef CLRT_HAVE_MPI

MpiJob& MpiJob::start(int*, char***) {
    char host[256] = "";
    gethostname(host, sizeof host - 1);
    gJob.host_ = host;
    if (launcherSize() > 1)
        throw Error("started as one of " + std::to_string(launcherSize()) +
                        " MPI ranks, but this clrt was built without MPI (install libopenmpi-dev and configure "
                        "with -DCLRT_MPI=ON)",
                    ExitCode::Usage);
    return gJob;
}
void MpiJob::serve(int, const TileGrid&, ImageRGB&, const std::function<bool(size_t&, int)>&, const std::function<void(size_t)>&,
                   const std::function<bool()>&) {}
TileFeed MpiJob::workerFeed(int, const TileGrid&, const ImageRGB&) { return {}; }
std::vector<std::string> MpiJob::gather(const std::string& mine) { return {mine}; }
void MpiJob::end(int) {}

#else

namespace {
// Worker -> rank 0 (tag kTagBase + camera): a request, or a finished tile followed by its floats.
struct Msg {
    int64_t kind;  // kRequest or kResult
    int64_t tile;
};
constexpr int64_t kRequest = 1, kResult = 2;
constexpr int kTagBase = 1000, kAssignBase = 1 << 20, kTagGather = 7;
std::mutex gMpiMutex;  // MPI_THREAD_SERIALIZED: one MPI call at a time in a process

[[noreturn]] void killedByHook(int rank, uint64_t tile) {
    std::fprintf(stderr, "rank %d: CLRT_KILL_RANK: killing this rank (SIGKILL) at tile %llu\n", rank, (unsigned long long)tile);
    std::fflush(stderr);
    kill(getpid(), SIGKILL);
    for (;;) pause();
}
}  // namespace

MpiJob& MpiJob::start(int* argc, char*** argv) {
    char host[256] = "";
    gethostname(host, sizeof host - 1);
    gJob.host_ = host;
    if (launcherSize() == 0) return gJob;
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS)
        throw Error("MPI_Init_thread failed", ExitCode::Device);
    gJob.started_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &gJob.rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &gJob.size_);
    if (provided < MPI_THREAD_SERIALIZED && gJob.size_ > 1) {
        gJob.end(int(ExitCode::Device));
        throw Error("the MPI library offers no MPI_THREAD_SERIALIZED", ExitCode::Device);
    }
    return gJob;
}

void MpiJob::serve(int cam, const TileGrid& grid, ImageRGB& img, const std::function<bool(size_t&, int)>& next,
                   const std::function<void(size_t)>& finished, const std::function<bool()>& localFailed) {
    int active = size_ - 1;
    std::vector<char> buf;
    while (active > 0) {
        int flag = 0;
        MPI_Status st;
        MPI_Iprobe(MPI_ANY_SOURCE, kTagBase + cam, MPI_COMM_WORLD, &flag, &st);
        if (!flag) {  // polling with a short sleep: a blocking receive would spin a core rank 0 renders on
            if (localFailed()) throw Error("rank 0's devices failed; ending the job", ExitCode::Device);
            std::this_thread::sleep_for(std::chrono::microseconds(100));
            continue;
        }
        auto t0 = std::chrono::steady_clock::now();
        int bytes = 0;
        MPI_Get_count(&st, MPI_BYTE, &bytes);
        buf.resize(std::max<size_t>(size_t(bytes), sizeof(Msg)));
        MPI_Recv(buf.data(), bytes, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        transfer_.bytesReceived += uint64_t(bytes);
        ++transfer_.messages;
        Msg m;
        std::memcpy(&m, buf.data(), sizeof m);
        if (m.kind == kResult) {
            const size_t t = size_t(m.tile);
            if (m.tile < 0 || t >= grid.count() || size_t(bytes) != sizeof m + grid.size(t) * 3 * sizeof(float))
                throw Error("rank " + std::to_string(st.MPI_SOURCE) + " sent a malformed tile", ExitCode::Device);
            std::memcpy(&img.pixels[grid.first(t) * 3], buf.data() + sizeof m, grid.size(t) * 3 * sizeof(float));
            finished(t);
        } else {
            size_t t = 0;
            int64_t reply = next(t, st.MPI_SOURCE) ? int64_t(t) : -1;
            MPI_Send(&reply, 1, MPI_INT64_T, st.MPI_SOURCE, kAssignBase + cam, MPI_COMM_WORLD);
            transfer_.bytesSent += sizeof reply;
            if (reply < 0) --active;
        }
        transfer_.serveSeconds += secondsSince(t0);
    }
}

TileFeed MpiJob::workerFeed(int cam, const TileGrid& grid, const ImageRGB& img) {
    TileFeed feed;
    feed.tilePixels = grid.tilePixels;
    const auto [killRank, killAt] = killRankHook();
    feed.next = [this, cam, killRank, killAt](size_t& tile) {
        std::lock_guard<std::mutex> lock(gMpiMutex);
        auto t0 = std::chrono::steady_clock::now();
        Msg m{kRequest, -1};
        MPI_Send(&m, int(sizeof m), MPI_BYTE, 0, kTagBase + cam, MPI_COMM_WORLD);
        int64_t reply = -1;
        MPI_Recv(&reply, 1, MPI_INT64_T, 0, kAssignBase + cam, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        transfer_.waitSeconds += secondsSince(t0);
        transfer_.bytesSent += sizeof m;
        transfer_.bytesReceived += sizeof reply;
        if (reply < 0) return false;
        if (rank_ == killRank && int64_t(transfer_.tiles) == killAt) killedByHook(rank_, uint64_t(reply));
        ++transfer_.tiles;
        tile = size_t(reply);
        return true;
    };
    std::vector<char> buf;
    feed.finished = [this, cam, grid, &img, buf](size_t t) mutable {
        std::lock_guard<std::mutex> lock(gMpiMutex);
        auto t0 = std::chrono::steady_clock::now();
        Msg m{kResult, int64_t(t)};
        const size_t bytes = grid.size(t) * 3 * sizeof(float);
        buf.resize(sizeof m + bytes);
        std::memcpy(buf.data(), &m, sizeof m);
        std::memcpy(buf.data() + sizeof m, &img.pixels[grid.first(t) * 3], bytes);
        MPI_Send(buf.data(), int(buf.size()), MPI_BYTE, 0, kTagBase + cam, MPI_COMM_WORLD);
        transfer_.bytesSent += buf.size();
        transfer_.sendSeconds += secondsSince(t0);
    };
    return feed;
}

std::vector<std::string> MpiJob::gather(const std::string& mine) {
    std::vector<std::string> all;
    if (size_ <= 1) return {mine};
    std::lock_guard<std::mutex> lock(gMpiMutex);
    if (rank_ != 0) {
        MPI_Send(mine.data(), int(mine.size()), MPI_CHAR, 0, kTagGather, MPI_COMM_WORLD);
        return all;
    }
    all.push_back(mine);
    for (int r = 1; r < size_; ++r) {
        MPI_Status st;
        MPI_Probe(r, kTagGather, MPI_COMM_WORLD, &st);
        int n = 0;
        MPI_Get_count(&st, MPI_CHAR, &n);
        std::string s(size_t(n), '\0');
        MPI_Recv(s.data(), n, MPI_CHAR, r, kTagGather, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        all.push_back(s);
    }
    return all;
}

void MpiJob::end(int code) {
    if (!started_) return;
    started_ = false;
    if (code != 0 && size_ > 1) MPI_Abort(MPI_COMM_WORLD, code);
    MPI_Finalize();
}

#endif

}  // namespace clrt
