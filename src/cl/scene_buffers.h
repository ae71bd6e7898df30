// scene_buffers.h — read-only scene arrays (BVH nodes and leaf blocks, triangles, texels, environment
// distributions, ...) uploaded to an OpenCL device. On a CPU device the kernels read host memory, and they
// read these arrays at random: beyond the TLB's reach (a few MB with 4 KiB pages) nearly every cache miss
// is also a page walk, which in a virtual machine costs several memory accesses (pointer chase measured on
// the 2-core VM: 500 ns per load over 64 MB with 4 KiB pages, 170 ns with 2 MiB pages). So on CPU devices
// arrays of at least kHugeMinBytes live in 2 MiB-aligned host memory (advised for transparent huge pages
// with CLRT_HUGE_PAGES=1: util/huge_pages.h says why not by default) and the buffer uses that memory in
// place (CL_MEM_USE_HOST_PTR: PoCL and Intel's CPU runtime do not copy an aligned host pointer):
//   - a HostArray (the DeviceScene's big arrays are HostArrays) is used where it is: no copy at all;
//     the array must outlive every buffer made from it (a Renderer holds its DeviceScene by reference);
//   - any other array is copied once into a HugePageBlock the uploader owns.
// Elsewhere (GPUs, small arrays, CLRT_HUGE_PAGES=0) a plain copied buffer.
// The uploader owns its blocks: it must outlive every buffer it made and every command using them.
#pragma once
#include <CL/opencl.hpp>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "util/huge_pages.h"

namespace clrt {

// Host memory behind CL_MEM_USE_HOST_PTR buffers: `bytes` rounded up to whole 2 MiB pages, 2 MiB aligned,
// advised for huge pages with CLRT_HUGE_PAGES=1 where the system has them.
class HugePageBlock {
public:
    static constexpr size_t kPage = kHugePageBytes;
    explicit HugePageBlock(size_t bytes);  // throws std::bad_alloc
    ~HugePageBlock();
    HugePageBlock(const HugePageBlock&) = delete;
    HugePageBlock& operator=(const HugePageBlock&) = delete;
    void* data() const { return data_; }
    size_t size() const { return size_; }
    bool advised() const { return advised_; }  // madvise(MADV_HUGEPAGE) accepted the range

private:
    void* data_ = nullptr;
    size_t size_ = 0;
    bool advised_ = false;
};

class SceneBufferUploader {
public:
    // cpuDevice: the device reads host memory (CL_DEVICE_TYPE_CPU). CLRT_HUGE_PAGES=0 turns the in-place
    // path off (for measuring it, and for oclgrind's uninitialised-value pass).
    SceneBufferUploader(cl::Context ctx, bool cpuDevice);
    static constexpr size_t kHugeMinBytes = ::clrt::kHugeMinBytes;

    // A read-only buffer holding a copy of bytes at src. OpenCL has no zero-size buffers: bytes == 0 gives
    // emptyBytes (at least 16) zero bytes, one element of an empty array, which the kernels never read.
    cl::Buffer upload(const void* src, size_t bytes, size_t emptyBytes = 16);
    template <class T> cl::Buffer upload(const std::vector<T>& v) {
        return upload(v.data(), sizeof(T) * v.size(), sizeof(T));
    }
    // In place on CPU devices when v's storage is in huge pages (inHugePages): v must outlive the buffer.
    template <class T> cl::Buffer upload(const HostArray<T>& v) {
        if (useHuge_ && inHugePages(v)) return useInPlace(v.data(), sizeof(T) * v.size());
        return upload(v.data(), sizeof(T) * v.size(), sizeof(T));
    }

    // One line for -v: where the arrays went, e.g. "79.6 MB of aligned host memory used in place, ...".
    std::string summary() const;
    size_t hugeBytes() const { return hugeBytes_; }    // bytes uploaded into HugePageBlocks
    size_t inPlaceBytes() const { return inPlaceBytes_; }  // HostArray bytes used where they are
    size_t copiedBytes() const { return copiedBytes_; }  // bytes uploaded as copied buffers
    bool hugePages() const { return useHuge_; }

private:
    cl::Context ctx_;
    bool useHuge_ = false;
    size_t hugeBytes_ = 0, copiedBytes_ = 0, inPlaceBytes_ = 0;
    cl::Buffer useInPlace(const void* data, size_t bytes);
    std::vector<std::unique_ptr<HugePageBlock>> blocks_;
};

}  // namespace clrt
