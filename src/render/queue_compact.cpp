// queue_compact.cpp — the host side of the device queue compaction (see queue_compact.h).
#include "render/queue_compact.h"

#include <algorithm>

#include "cl/check.h"
#include "cl/program.h"
#include "shared/device_types.h"
#include "shared/kernel_params.h"

namespace clrt {

namespace {
constexpr size_t kBlock = size_t(CLRT_COMPACT_GROUP) * CLRT_COMPACT_ITEMS;  // slots per block sum
constexpr size_t kScatterLocal = 64;
}  // namespace

QueueCompactor::QueueCompactor(const cl::Program& program)
    : scanBlocks_(program, "compact_scan_blocks"), scanSums_(program, "compact_scan_sums"),
      scatter_(program, "compact_scatter") {}

void QueueCompactor::setBuffers(cl::Context& ctx, size_t maxSlots, size_t pathCapacity, const cl::Buffer& valid,
                                const cl::Buffer& nextP, const cl::Buffer& nextR, const cl::Buffer& p, const cl::Buffer& r) {
    queueCapacity = int(std::min<size_t>(pathCapacity, size_t(INT32_MAX)));
    childValid = valid;
    nextPaths = nextP;
    nextRays = nextR;
    paths = p;
    rays = r;
    if (maxSlots > slotCapacity_ || !compactTarget()) {
        slotCapacity_ = std::max<size_t>(maxSlots, 1);
        compactTarget = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(int) * slotCapacity_));
        blockSums = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(int) * ((slotCapacity_ + kBlock - 1) / kBlock)));
    }
}

void QueueCompactor::enqueue(const Launch& launch, const cl::Buffer& queueCountBuf, const cl::Buffer& nextCountBuf,
                             int slotsPerPath, size_t slotBound) {
    queueCount = queueCountBuf;
    nextCount = nextCountBuf;
    childSlots = slotsPerPath;
    slotBound = std::min(slotBound, slotCapacity_);
    CLRT_BIND_GROUP(scanBlocks_, CLRT_KERNEL_compact_scan_blocks, *this);
    CLRT_BIND_GROUP(scanSums_, CLRT_KERNEL_compact_scan_sums, *this);
    CLRT_BIND_GROUP(scatter_, CLRT_KERNEL_compact_scatter, *this);
    const size_t blocks = std::max<size_t>(1, (slotBound + kBlock - 1) / kBlock);
    launch(scanBlocks_, blocks * CLRT_COMPACT_GROUP, CLRT_COMPACT_GROUP);
    launch(scanSums_, CLRT_COMPACT_GROUP, CLRT_COMPACT_GROUP);  // also writes *nextCount = 0 for an empty queue
    if (slotBound > 0) launch(scatter_, roundUp(slotBound, kScatterLocal), kScatterLocal);
}

}  // namespace clrt
