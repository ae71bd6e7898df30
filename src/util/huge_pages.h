// huge_pages.h — host memory for the big scene arrays (BVH nodes and leaf blocks, triangles, texels,
// environment distributions): `HostArray<T>` is a std::vector whose storage, from kHugeMinBytes up, is
// 2 MiB-aligned and advised for transparent huge pages (madvise MADV_HUGEPAGE, before the first touch, so
// the pages are allocated huge; Linux's default THP mode "madvise" gives them only to advised ranges).
// On a CPU device the kernels read these arrays at random in place (cl/scene_buffers.h uses their memory
// as the buffer, CL_MEM_USE_HOST_PTR): with 2 MiB pages the TLB reaches the whole scene, and nothing is
// copied at upload. CLRT_HUGE_PAGES=0 leaves out the advice (the alignment stays). Unlike a std::vector,
// resize() leaves new trivial elements unwritten (HugePageAllocator::construct).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace clrt {

constexpr size_t kHugePageBytes = size_t(2) << 20;
constexpr size_t kHugeMinBytes = size_t(1) << 20;  // smaller arrays: plain heap memory

// `bytes` rounded up to whole 2 MiB pages, 2 MiB aligned, advised for huge pages unless
// CLRT_HUGE_PAGES=0 (*advised: whether madvise accepted it). Throws std::bad_alloc. Free with hugeFree.
void* hugeAlloc(size_t bytes, bool* advised = nullptr);
inline size_t hugeAllocSize(size_t bytes) {  // what hugeAlloc(bytes) reserves: whole 2 MiB pages, at least one
    return bytes == 0 ? kHugePageBytes : (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
}
void hugeFree(void* p) noexcept;
bool hugePagesWanted();  // CLRT_HUGE_PAGES is not "0"

template <class T>
struct HugePageAllocator {
    using value_type = T;
    HugePageAllocator() noexcept = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
    T* allocate(size_t n) {
        if (n > size_t(-1) / sizeof(T)) throw std::bad_alloc();
        if (n * sizeof(T) >= kHugeMinBytes) return static_cast<T*>(hugeAlloc(n * sizeof(T)));
        return std::allocator<T>().allocate(n);
    }
    void deallocate(T* p, size_t n) noexcept {
        if (n * sizeof(T) >= kHugeMinBytes) hugeFree(p);
        else std::allocator<T>().deallocate(p, n);
    }
    // resize(n) and emplace_back() default-initialise (a trivial element is left unwritten): every caller
    // writes the elements it makes (flatten_geometry's slots, the texel atlas, bvh4's nodes), and a fresh
    // page is zeroed by the kernel at its first touch, so value-initialising wrote it twice, on one thread.
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    friend bool operator==(const HugePageAllocator&, const HugePageAllocator&) { return true; }
    friend bool operator!=(const HugePageAllocator&, const HugePageAllocator&) { return false; }
};

template <class T>
using HostArray = std::vector<T, HugePageAllocator<T>>;

// Whether v's storage came from hugeAlloc (big enough, and 2 MiB aligned).
template <class T>
bool inHugePages(const HostArray<T>& v) {
    return v.capacity() * sizeof(T) >= kHugeMinBytes && reinterpret_cast<uintptr_t>(v.data()) % kHugePageBytes == 0;
}

}  // namespace clrt
