// queue_compact.h — order-preserving compaction of the wavefront's child queue on the device
// (cl_kernels/compact.cl): children at slots [0, *queueCount * childSlots) of nextPaths/nextRays
// whose childValid flag is set go, in slot order, to [0, total) of paths/rays, and total goes to the
// device int nextCount. Nothing is read back: the next bounce's kernels read nextCount on the device.
// Three launches: a per-block scan, one work-group scanning the block sums, a scatter; integer sums,
// so the result is exact and identical on every device. Scratch: one int per slot, one per block.
#pragma once
#include <CL/opencl.hpp>

#include <cstddef>
#include <functional>

#include "cl/kernel_args.h"

namespace clrt {

class QueueCompactor {
public:
    // Enqueues kernel `k` over `globalItems` work-items (a multiple of `localItems`) in work-groups of
    // `localItems`; the renderer's launcher also records the launch's profiling event.
    using Launch = std::function<void(KernelArgs& k, size_t globalItems, size_t localItems)>;

    QueueCompactor() = default;
    // The three kernels of `program`, which must include compact.cl (the render program does).
    explicit QueueCompactor(const cl::Program& program);

    // The queue buffers, named as the kernel parameters they are bound to, and scratch for up to
    // `maxSlots` child slots (allocated on growth only).
    // `pathCapacity`: the length of paths/rays; children beyond it (in slot order) are dropped.
    void setBuffers(cl::Context& ctx, size_t maxSlots, size_t pathCapacity, const cl::Buffer& childValid,
                    const cl::Buffer& nextPaths, const cl::Buffer& nextRays, const cl::Buffer& paths, const cl::Buffer& rays);

    // Enqueues the compaction of the *queueCount * childSlots slots (the host knows only the bound
    // `slotBound` >= that many, <= maxSlots; launches are sized by it) and writes the survivors'
    // count into *nextCount. Both are one-int device buffers.
    void enqueue(const Launch& launch, const cl::Buffer& queueCountBuf, const cl::Buffer& nextCountBuf, int slotsPerPath,
                 size_t slotBound);

    // Members named as the parameters of cl_kernels/compact.cl's kernels (CLRT_BIND_GROUP reads them).
    cl::Buffer queueCount, nextCount, childValid, compactTarget, blockSums, nextPaths, nextRays, paths, rays;
    int childSlots = 2;
    int queueCapacity = 0;

private:
    KernelArgs scanBlocks_, scanSums_, scatter_;
    size_t slotCapacity_ = 0;
};

}  // namespace clrt
