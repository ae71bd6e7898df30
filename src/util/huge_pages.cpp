// huge_pages.cpp — see huge_pages.h.
#include "util/huge_pages.h"

#include <cstdlib>
#include <cstring>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace clrt {

bool hugePagesWanted() {
    static const bool wanted = [] {
        const char* env = std::getenv("CLRT_HUGE_PAGES");
        return !(env && std::strcmp(env, "0") == 0);
    }();
    return wanted;
}

void* hugeAlloc(size_t bytes, bool* advised) {
    const size_t size = hugeAllocSize(bytes);
    void* p = nullptr;
    if (posix_memalign(&p, kHugePageBytes, size) != 0) throw std::bad_alloc();
    bool ok = false;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (hugePagesWanted()) ok = madvise(p, size, MADV_HUGEPAGE) == 0;
#endif
    if (advised) *advised = ok;
    return p;
}

void hugeFree(void* p) noexcept { std::free(p); }

}  // namespace clrt
