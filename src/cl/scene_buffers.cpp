// scene_buffers.cpp — see scene_buffers.h.
#include "cl/scene_buffers.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>

#include "cl/check.h"

namespace clrt {

HugePageBlock::HugePageBlock(size_t bytes) {
    size_ = hugeAllocSize(bytes);
    data_ = hugeAlloc(bytes, &advised_);
}

HugePageBlock::~HugePageBlock() { hugeFree(data_, size_); }

SceneBufferUploader::SceneBufferUploader(cl::Context ctx, bool cpuDevice) : ctx_(std::move(ctx)) {
    useHuge_ = cpuDevice && hostBuffersInPlace();
}

cl::Buffer SceneBufferUploader::upload(const void* src, size_t bytes, size_t emptyBytes) {
    if (bytes == 0) {
        std::vector<unsigned char> zero(std::max<size_t>(emptyBytes, 16), 0);
        return CL_CPP(cl::Buffer(ctx_, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, zero.size(), zero.data()));
    }
    if (useHuge_ && bytes >= kHugeMinBytes) {
        auto block = std::make_unique<HugePageBlock>(bytes);
        std::memcpy(block->data(), src, bytes);
        cl::Buffer b = CL_CPP(cl::Buffer(ctx_, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, bytes, block->data()));
        blocks_.push_back(std::move(block));
        hugeBytes_ += bytes;
        return b;
    }
    copiedBytes_ += bytes;
    return CL_CPP(cl::Buffer(ctx_, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(src)));
}

cl::Buffer SceneBufferUploader::useInPlace(const void* data, size_t bytes) {
    inPlaceBytes_ += bytes;
    return CL_CPP(cl::Buffer(ctx_, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, bytes, const_cast<void*>(data)));
}

std::string SceneBufferUploader::summary() const {
    char buf[256];
    bool allAdvised = true;
    for (const auto& b : blocks_) allAdvised = allAdvised && b->advised();
    const char* pages = !hugePagesWanted() ? "" : allAdvised ? "; huge pages advised" : "; madvise refused: 4 KiB pages";
    std::snprintf(buf, sizeof buf, "%.1f MB of aligned host memory used in place, %.1f MB copied into aligned blocks, "
                  "%.1f MB copied%s%s", inPlaceBytes_ / 1e6, hugeBytes_ / 1e6, copiedBytes_ / 1e6,
                  useHuge_ ? "" : " (in place off: not a CPU device, or CLRT_HUGE_PAGES=0)", pages);
    return buf;
}

}  // namespace clrt
