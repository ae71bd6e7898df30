// huge_pages.cpp — see huge_pages.h.
#include "util/huge_pages.h"

#include <cstdlib>
#include <cstring>
#include <mutex>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace clrt {

namespace {

const char* hugePagesEnv() {
    const char* env = std::getenv("CLRT_HUGE_PAGES");
    return env ? env : "";
}

// The recycler's state: kept blocks (address, bytes as reserved, whether advised), open scopes.
struct Kept {
    void* p;
    size_t bytes;
    bool advised;
};
std::mutex gMutex;
std::vector<Kept> gKept;
int gScopes = 0;
size_t gRecycled = 0;

void freeKept(std::vector<Kept>& kept) {
    for (const Kept& k : kept) std::free(k.p);
    kept.clear();
}

// The smallest kept block of at least `size` bytes, taken out of gKept; on a miss every kept block is
// freed (none could serve this request, and keeping them would only raise the peak). Locked by the caller.
bool takeKept(size_t size, Kept& out) {
    size_t best = gKept.size();
    for (size_t i = 0; i < gKept.size(); ++i)
        if (gKept[i].bytes >= size && (best == gKept.size() || gKept[i].bytes < gKept[best].bytes)) best = i;
    if (best == gKept.size()) {
        freeKept(gKept);
        return false;
    }
    out = gKept[best];
    gKept.erase(gKept.begin() + std::ptrdiff_t(best));
    return true;
}

}  // namespace

bool hugePagesWanted() {
    static const bool wanted = std::strcmp(hugePagesEnv(), "1") == 0;
    return wanted;
}

bool hostBuffersInPlace() {
    static const bool inPlace = std::strcmp(hugePagesEnv(), "0") != 0;
    return inPlace;
}

void* hugeAlloc(size_t bytes, bool* advised) {
    const size_t size = hugeAllocSize(bytes);
    {
        std::lock_guard<std::mutex> lock(gMutex);
        Kept k{};
        if (gScopes > 0 && takeKept(size, k)) {
#if defined(__linux__) && defined(MADV_DONTNEED)
            // Pages past the request go back to the kernel (they may hold the last user's data).
            if (k.bytes > size) madvise(static_cast<char*>(k.p) + size, k.bytes - size, MADV_DONTNEED);
#endif
            gRecycled += size;
            if (advised) *advised = k.advised;
            return k.p;
        }
    }
    void* p = nullptr;
    if (posix_memalign(&p, kHugePageBytes, size) != 0) throw std::bad_alloc();
    bool ok = false;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (hugePagesWanted()) ok = madvise(p, size, MADV_HUGEPAGE) == 0;
#endif
    if (advised) *advised = ok;
    return p;
}

void hugeFree(void* p, size_t bytes) noexcept {
    if (!p) return;
    std::lock_guard<std::mutex> lock(gMutex);
    if (gScopes > 0) {
        try {
            // A recycled block may be bigger than its last user's request: it is kept at that size,
            // which hugeAlloc's rounding of the request gives back (the tail stays mapped, untouched).
            gKept.push_back(Kept{p, hugeAllocSize(bytes), hugePagesWanted()});
            return;
        } catch (...) {  // no room to remember it: free it
        }
    }
    std::free(p);
}

HugeRecycling::HugeRecycling() {
    std::lock_guard<std::mutex> lock(gMutex);
    ++gScopes;
}

HugeRecycling::~HugeRecycling() {
    std::lock_guard<std::mutex> lock(gMutex);
    if (--gScopes == 0) freeKept(gKept);
}

size_t hugeRecycledBytes() {
    std::lock_guard<std::mutex> lock(gMutex);
    return gRecycled;
}

size_t hugeKeptBytes() {
    std::lock_guard<std::mutex> lock(gMutex);
    size_t bytes = 0;
    for (const Kept& k : gKept) bytes += k.bytes;
    return bytes;
}

}  // namespace clrt
