// huge_pages.h — host memory for the big scene arrays (BVH nodes and leaf blocks, triangles, texels,
// environment distributions) and the flattening's big scratch arrays (the BVH builder's items and binary
// nodes): `HostArray<T>` is a std::vector whose storage, from kHugeMinBytes up, is 2 MiB-aligned (and
// advised for transparent huge pages where CLRT_HUGE_PAGES asks: see hugePagesWanted). On a CPU device
// the kernels read the scene arrays in place (cl/scene_buffers.h uses their memory as the buffer,
// CL_MEM_USE_HOST_PTR): nothing is copied at upload. Unlike a std::vector, resize() leaves new trivial
// elements unwritten (HugePageAllocator::construct), and storage may come back recycled (HugeRecycling):
// every caller writes the elements it makes.
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

// `bytes` rounded up to whole 2 MiB pages, 2 MiB aligned, advised for huge pages when hugePagesWanted()
// (*advised: whether madvise accepted it), or a recycled block (HugeRecycling). Throws std::bad_alloc.
// Free with hugeFree(p, the same bytes).
void* hugeAlloc(size_t bytes, bool* advised = nullptr);
inline size_t hugeAllocSize(size_t bytes) {  // what hugeAlloc(bytes) reserves: whole 2 MiB pages, at least one
    return bytes == 0 ? kHugePageBytes : (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
}
void hugeFree(void* p, size_t bytes) noexcept;
// Whether hugeAlloc advises transparent huge pages: only with CLRT_HUGE_PAGES=1. Advised memory makes
// random reads cheaper (TLB reach; 3-7% on the Audi TT, docs/studies/2026-11-30-huge-pages.md) but its
// first touch dearer where the kernel must compact or a hypervisor back 2 MiB at once: 1.6-3.4 s per GB
// against 0.36-0.9 s with 4 KiB pages on the test VM, seconds of setup on a big scene
// (docs/studies/2026-12-04-setup-scale.md, session 17). CLRT_HUGE_PAGES=0: scene buffers are copied
// instead of used in place (cl/scene_buffers.h).
bool hugePagesWanted();
bool hostBuffersInPlace();  // CLRT_HUGE_PAGES is not "0"

// While one of these lives (flattenScene holds one), hugeFree keeps the blocks it is given and hugeAlloc
// hands out the smallest kept block that holds a request (the pages past it given back to the kernel),
// so an array made after another was freed (the 8-wide nodes in the builder's items, the leaf blocks in
// the binary tree's nodes) reuses pages already written instead of fresh ones, which the kernel must
// zero (and a VM's host back) at first touch. A request no kept block holds frees them all first, so
// the peak memory is never above what freeing at once gives. The last one to end frees what is kept.
class HugeRecycling {
public:
    HugeRecycling();
    ~HugeRecycling();
    HugeRecycling(const HugeRecycling&) = delete;
    HugeRecycling& operator=(const HugeRecycling&) = delete;
};
size_t hugeRecycledBytes();  // bytes served from kept blocks so far (for tests)
size_t hugeKeptBytes();      // bytes kept now, waiting for a request (0 outside every HugeRecycling scope)

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
        if (n * sizeof(T) >= kHugeMinBytes) hugeFree(p, n * sizeof(T));
        else std::allocator<T>().deallocate(p, n);
    }
    // resize(n) and emplace_back() default-initialise (a trivial element is left unwritten): every caller
    // writes the elements it makes (flatten_geometry's slots, the texel atlas, bvh8's nodes), and a fresh
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
