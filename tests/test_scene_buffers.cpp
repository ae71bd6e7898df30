// cl/scene_buffers: the scene arrays a kernel reads are the host's, byte for byte, whether they went into
// aligned host memory used in place (CPU devices, arrays of >= 1 MiB) or into copied buffers; the blocks
// are 2 MiB aligned and advised for transparent huge pages with CLRT_HUGE_PAGES=1 where the kernel offers
// them; CLRT_HUGE_PAGES=0 and non-CPU devices copy.
#include <catch.hpp>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "cl/check.h"
#include "cl/scene_buffers.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// Reads every uint of `in` back through a kernel (not a buffer read, which a runtime may serve from
// the host pointer): the values the device sees.
std::vector<uint32_t> readThroughKernel(const cl::Buffer& in, size_t n) {
    static const char* src = R"CLC(
__kernel void copy_uints(const __global uint* in, __global uint* out, int n) {
    int i = get_global_id(0);
    if (i < n) out[i] = in[i];
}
)CLC";
    DeviceContext& dc = testContext();
    static cl::Program program = buildProgramFromSources(dc, {{"copy_uints.cl", src}}, {});
    cl::Kernel k = CL_CPP(cl::Kernel(program, "copy_uints"));
    cl::Buffer out = CL_CPP(cl::Buffer(dc.context(), CL_MEM_WRITE_ONLY, std::max<size_t>(n, 1) * 4));
    k.setArg(0, in);
    k.setArg(1, out);
    k.setArg(2, int(n));
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange((n + 63) / 64 * 64), cl::NDRange(64)));
    std::vector<uint32_t> v(n);
    if (n) CL_CPP(dc.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * 4, v.data()));
    return v;
}

std::vector<uint32_t> pattern(size_t n, uint32_t seed) {
    std::vector<uint32_t> v(n);
    uint32_t x = seed;
    for (auto& e : v) e = x = x * 1664525u + 1013904223u;
    return v;
}

bool thpOffered() {  // "always" or "madvise" selected in the kernel's THP mode
    std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    return s.find("[always]") != std::string::npos || s.find("[madvise]") != std::string::npos;
}

}  // namespace

TEST_CASE("scene buffers: kernels read the host's arrays, huge-page or copied", "[cl][scene_buffers]") {
    DeviceContext& dc = testContext();
    const bool cpu = (dc.info().type & CL_DEVICE_TYPE_CPU) != 0;
    for (bool cpuDevice : {true, false}) {
        INFO("uploader told cpuDevice=" << cpuDevice);
        SceneBufferUploader up(dc.context(), cpuDevice);
        // Under, at and over the 1 MiB threshold; one over a 2 MiB page (a block of two pages).
        const size_t counts[] = {1, 1000, SceneBufferUploader::kHugeMinBytes / 4 - 1, SceneBufferUploader::kHugeMinBytes / 4,
                                 (size_t(5) << 20) / 4 + 3};
        size_t expectHuge = 0, expectCopied = 0;
        std::vector<std::vector<uint32_t>> arrays;
        std::vector<cl::Buffer> buffers;
        for (size_t n : counts) {
            arrays.push_back(pattern(n, uint32_t(n)));
            buffers.push_back(up.upload(arrays.back()));
            const bool huge = up.hugePages() && n * 4 >= SceneBufferUploader::kHugeMinBytes;
            (huge ? expectHuge : expectCopied) += n * 4;
        }
        CHECK(up.hugePages() == (cpuDevice && !(std::getenv("CLRT_HUGE_PAGES") && std::string(std::getenv("CLRT_HUGE_PAGES")) == "0")));
        CHECK(up.hugeBytes() == expectHuge);
        CHECK((up.summary().find("in place off") == std::string::npos) == up.hugePages());
        CHECK(up.copiedBytes() == expectCopied);
        for (size_t i = 0; i < arrays.size(); ++i) {
            INFO(arrays[i].size() << " uints");
            const std::vector<uint32_t> seen = readThroughKernel(buffers[i], arrays[i].size());
            size_t differ = 0;  // a count, not the vectors: Catch2 would print millions of elements
            for (size_t j = 0; j < seen.size(); ++j) differ += seen[j] != arrays[i][j];
            CHECK(differ == 0);
        }
        // An empty array: a zero-filled buffer of one element (here 16 bytes), never null.
        cl::Buffer empty = up.upload(std::vector<uint32_t>{});
        CHECK(empty.getInfo<CL_MEM_SIZE>() == 16);
        CHECK(readThroughKernel(empty, 4) == std::vector<uint32_t>(4, 0u));
    }
    if (!cpu) WARN("the test device is not a CPU device: its huge-page path was exercised through the uploader only");
}

TEST_CASE("scene buffers: huge-page blocks are 2 MiB aligned whole pages, advised where asked and THP is offered",
          "[scene_buffers]") {
    for (size_t bytes : {size_t(1), HugePageBlock::kPage, HugePageBlock::kPage + 1, size_t(7) << 20}) {
        HugePageBlock b(bytes);
        INFO(bytes << " bytes");
        CHECK(reinterpret_cast<uintptr_t>(b.data()) % HugePageBlock::kPage == 0);
        CHECK(b.size() % HugePageBlock::kPage == 0);
        CHECK(b.size() >= bytes);
        CHECK(b.size() < bytes + HugePageBlock::kPage);
#if defined(__linux__)
        if (thpOffered() && hugePagesWanted()) CHECK(b.advised());
#endif
        if (!hugePagesWanted()) CHECK(!b.advised());  // CLRT_HUGE_PAGES=1 only (util/huge_pages.h)
    }
}

TEST_CASE("scene buffers: a HostArray in huge pages is the buffer's memory (no copy); small ones are copied",
          "[cl][scene_buffers]") {
    DeviceContext& dc = testContext();
    SceneBufferUploader up(dc.context(), true);
    const size_t counts[] = {1000, kHugeMinBytes / 4 - 1, kHugeMinBytes / 4, (size_t(5) << 20) / 4 + 3};
    std::vector<HostArray<uint32_t>> arrays;
    std::vector<cl::Buffer> buffers;
    size_t expectInPlace = 0, expectCopied = 0;
    for (size_t n : counts) {
        std::vector<uint32_t> p = pattern(n, uint32_t(n));
        arrays.emplace_back(p.begin(), p.end());
        const bool big = n * 4 >= kHugeMinBytes;
        CHECK(inHugePages(arrays.back()) == big);
        if (big) CHECK(reinterpret_cast<uintptr_t>(arrays.back().data()) % kHugePageBytes == 0);
        buffers.push_back(up.upload(arrays.back()));
        const bool inPlace = up.hugePages() && big;
        (inPlace ? expectInPlace : expectCopied) += n * 4;
        // In place: the buffer's host pointer is the array's own storage.
        void* host = buffers.back().getInfo<CL_MEM_HOST_PTR>();
        CHECK((host == static_cast<void*>(arrays.back().data())) == inPlace);
    }
    CHECK(up.inPlaceBytes() == expectInPlace);
    CHECK(up.copiedBytes() == expectCopied);
    CHECK(up.hugeBytes() == 0);
    for (size_t i = 0; i < arrays.size(); ++i) {
        INFO(arrays[i].size() << " uints");
        const std::vector<uint32_t> seen = readThroughKernel(buffers[i], arrays[i].size());
        size_t differ = 0;
        for (size_t j = 0; j < seen.size(); ++j) differ += seen[j] != arrays[i][j];
        CHECK(differ == 0);
    }
}
