// The wavefront's queue compaction on the device (cl_kernels/compact.cl, src/render/queue_compact.h)
// against a host reference: for random valid masks of awkward lengths (empty, one slot, around the
// work-group and block sizes, several chunks of block sums), densities (none, all, half, sparse) and
// launch bounds above the true length, the device writes exactly the valid children, in slot order,
// to [0, total), leaves every slot beyond untouched, and writes total to the next-count int; with a paths
// buffer shorter than the valid children (the course rule's three-way splits) it keeps the first ones, in
// slot order, writes nothing beyond the buffer's length and counts only those.
#include <catch.hpp>

#include <random>
#include <vector>

#include "cl/check.h"
#include "render/queue_compact.h"
#include "shared/device_types.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

struct CompactCase {
    size_t slots;        // mask length: queue length * childSlots
    int childSlots;      // 1, 2 or 3
    double density;      // probability of a valid slot
    size_t extraBound;   // the launch bound exceeds the mask by this much
    size_t pathCapacity = 0;  // the paths buffer's length given to the compactor (0: the whole buffer)
};

// Compacts a random mask on the device; checks against std's stable order on the host.
void checkCompaction(QueueCompactor& qc, const CompactCase& c, uint32_t seed) {
    DeviceContext& dc = testContext();
    cl::Context& ctx = dc.context();
    cl::CommandQueue& q = dc.queue();
    std::mt19937 rng(seed);
    std::bernoulli_distribution valid(c.density);
    const size_t n = c.slots, cap = n + c.extraBound + 1;
    std::vector<int> mask(cap, 1);  // slots beyond n are marked valid: the kernels must not read them
    std::vector<dev::PathState> next(cap);
    std::vector<dev::Ray> nextRays(cap);
    for (size_t i = 0; i < cap; ++i) {
        if (i < n) mask[i] = valid(rng) ? int(1 + rng() % 3) : 0;  // any non-zero value counts as valid
        next[i].pixel = int(i);
        next[i].sample = int(i * 7 + 1);
        nextRays[i].origin = {float(i), 0, 0, 0};
    }
    dev::PathState sentinel{};
    sentinel.pixel = -5;
    std::vector<dev::PathState> out(cap, sentinel);
    std::vector<dev::Ray> outRays(cap, dev::Ray{{-5, 0, 0, 0}, {0, 0, 0, 0}});
    auto buf = [&](auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof(T) * v.size(), v.data()));
    };
    cl::Buffer maskBuf = buf(mask), nextBuf = buf(next), nextRayBuf = buf(nextRays), outBuf = buf(out),
               outRayBuf = buf(outRays);
    std::vector<int> count{int(n / size_t(c.childSlots))}, nextCount{-1};
    cl::Buffer countBuf = buf(count), nextCountBuf = buf(nextCount);
    const size_t pathCapacity = c.pathCapacity ? c.pathCapacity : cap;
    qc.setBuffers(ctx, cap, pathCapacity, maskBuf, nextBuf, nextRayBuf, outBuf, outRayBuf);
    const QueueCompactor::Launch launch = [&](KernelArgs& k, size_t items, size_t local) {
        CL_CPP(q.enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(items), cl::NDRange(local)));
    };
    qc.enqueue(launch, countBuf, nextCountBuf, c.childSlots, n + c.extraBound);
    CL_CPP(q.enqueueReadBuffer(outBuf, CL_TRUE, 0, sizeof(dev::PathState) * cap, out.data()));
    CL_CPP(q.enqueueReadBuffer(outRayBuf, CL_TRUE, 0, sizeof(dev::Ray) * cap, outRays.data()));
    CL_CPP(q.enqueueReadBuffer(nextCountBuf, CL_TRUE, 0, sizeof(int), nextCount.data()));

    std::vector<int> expected;  // the host reference: valid slots in order
    for (size_t i = 0; i < n; ++i)
        if (mask[i] != 0 && expected.size() < pathCapacity) expected.push_back(int(i));
    INFO("slots " << n << ", childSlots " << c.childSlots << ", density " << c.density << ", bound +" << c.extraBound);
    REQUIRE(nextCount[0] == int(expected.size()));
    size_t wrong = 0, touched = 0;
    for (size_t j = 0; j < expected.size(); ++j) {
        const int i = expected[j];
        wrong += out[j].pixel != i || out[j].sample != i * 7 + 1 || outRays[j].origin.x != float(i);
    }
    for (size_t j = expected.size(); j < cap; ++j) touched += out[j].pixel != -5 || outRays[j].origin.x != -5.0f;
    CHECK(wrong == 0);
    CHECK(touched == 0);
}

}  // namespace

TEST_CASE("queue compaction on the device equals the host's stable compaction", "[compact]") {
    DeviceContext& dc = testContext();
    cl::Program program = buildProgram(dc, {"compact.cl"}, {});
    QueueCompactor qc(program);
    const size_t block = size_t(CLRT_COMPACT_GROUP) * CLRT_COMPACT_ITEMS;
    uint32_t seed = 1;
    SECTION("awkward lengths, one slot per path") {
        for (size_t slots : {size_t(0), size_t(1), size_t(255), size_t(256), size_t(257), block - 1, block, block + 1,
                             size_t(100000)})
            for (double density : {0.0, 1.0, 0.5, 0.01}) checkCompaction(qc, {slots, 1, density, 0}, seed++);
    }
    SECTION("two child slots per path (the renderer's layout), launch bounds above the length") {
        for (size_t slots : {size_t(2), size_t(256), size_t(258), size_t(100000)})
            for (size_t extra : {size_t(0), size_t(1), size_t(600), size_t(5000)})
                checkCompaction(qc, {slots, 2, 0.5, extra}, seed++);
    }
    SECTION("three child slots per path, and a paths buffer shorter than the children (kept: the first ones)") {
        for (size_t slots : {size_t(3), size_t(300), size_t(100002)})
            for (size_t capacity : {size_t(0), size_t(1), size_t(100), slots / 3})
                checkCompaction(qc, {slots, 3, 0.6, 7, capacity}, seed++);
    }
    SECTION("more blocks than one work-group scans at once (the block-sum scan loops)") {
        const size_t slots = block * block + 3 * block + 17;  // 516 blocks and a partial one
        checkCompaction(qc, {slots, 1, 0.3, 0}, seed++);
        checkCompaction(qc, {slots + 1, 1, 1.0, 1000}, seed++);
    }
}
