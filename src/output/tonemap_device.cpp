// tonemap_device.cpp — the host driver of cl_kernels/tonemap.cl (see tonemap_device.h): buffers,
// launches with the device's work-group size (quirk FIXED_WORK_GROUP: 64), the double sum
// of the per-work-item compensated partials, the radix select of the percentile luminance, and the
// map kernels at kPixelsPerMapItem pixels per work-item.
#include "output/tonemap_device.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "cl/check.h"
#include "cl/kernel_args.h"
#include "shared/device_types.h"
#include "util/error.h"

namespace clrt {

dev::TonemapParams tonemapDeviceParams(const TonemapSettings& s, const TonemapStats& stats, size_t numPixels) {
    dev::TonemapParams p{};
    p.op = int(s.op);
    p.scale = stats.scale;
    p.whiteL = stats.whiteL;
    p.hasWhite = stats.hasWhite ? 1 : 0;
    p.saturation = s.saturation;
    p.invGamma = 1.0f / s.gamma;
    p.srgb = s.srgb ? 1 : 0;
    p.truncate = s.truncate ? 1 : 0;
    p.numPixels = cl_uint(numPixels);
    return p;
}

namespace {
constexpr size_t kMaxWorkItems = 16384;  // partial sums / histogram work-items per launch
// Pixels per work-item of Tonemap_Map / Tonemap_MapFloat: TONEMAP_VEC in tonemap.cl (its pow calls
// run on float16 vectors, ~15x faster on PoCL's CPU device than one scalar pow per pixel).
constexpr size_t kPixelsPerMapItem = 16;
size_t mapWorkItems(size_t numPixels) { return (numPixels + kPixelsPerMapItem - 1) / kPixelsPerMapItem; }
}  // namespace

struct TonemapDevice::Impl {
    DeviceContext& dc;
    const size_t local;  // work-group size (src/cl/quirks.h); the partial sums' order follows it
    BuildInfo build;
    cl::Program program;
    KernelArgs kLum, kHist, kMap, kMapFloat;  // bound by parameter name (src/shared/kernel_params.h)
    cl::Buffer rgb, lum, partials, hist, out, outFloat;
    size_t numPixels = 0, capacity = 0;
    size_t workItems = 0;
    int width = 0, height = 0;
    bool lumValid = false;
    double lumDelta = -1, logSum = 0;

    explicit Impl(DeviceContext& d) : dc(d), local(d.quirks().host.workGroupSize) {
        program = buildProgram(dc, KernelProgram::Tonemap, {}, &build);
        kLum = KernelArgs(program, "Tonemap_Luminance");
        kHist = KernelArgs(program, "Tonemap_Histogram");
        kMap = KernelArgs(program, "Tonemap_Map");
        kMapFloat = KernelArgs(program, "Tonemap_MapFloat");
        hist = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, 256 * sizeof(cl_uint)));
        partials = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, kMaxWorkItems * 2 * sizeof(float)));
    }

    void launch(KernelArgs& k, size_t globalItems) {
        CL_CPP(dc.queue().enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(roundUp(globalItems, local)),
                                               local ? cl::NDRange(local) : cl::NullRange));
    }

    void upload(const ImageRGB& img) {
        const size_t n = size_t(img.width) * size_t(img.height);
        if (img.width <= 0 || img.height <= 0 || img.pixels.size() != n * 3)
            throw Error("tone mapping: bad image of " + std::to_string(img.width) + "x" + std::to_string(img.height));
        if (n > size_t(UINT32_MAX) / 4)
            throw Error("tone mapping: image of " + std::to_string(n) + " pixels is too large");
        const uint64_t bytes = uint64_t(n) * 3 * sizeof(float);
        if (bytes > dc.info().maxAlloc)
            throw Error("tone mapping: a " + std::to_string(img.width) + "x" + std::to_string(img.height) + " image needs " +
                            std::to_string(bytes >> 20) + " MiB; device '" + dc.info().name + "' allows " +
                            std::to_string(dc.info().maxAlloc >> 20) + " MiB per buffer",
                        ExitCode::Device);
        if (n > capacity) {
            rgb = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_ONLY, n * 3 * sizeof(float)));
            lum = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, n * sizeof(float)));
            out = CL_CPP(cl::Buffer(dc.context(), CL_MEM_WRITE_ONLY, std::max<size_t>(n * 3, 16)));
            outFloat = cl::Buffer();  // allocated on first use
            capacity = n;
        }
        CL_CPP(dc.queue().enqueueWriteBuffer(rgb, CL_FALSE, 0, n * 3 * sizeof(float), img.pixels.data()));
        numPixels = n;
        width = img.width;
        height = img.height;
        workItems = std::min(roundUp(n, local), kMaxWorkItems);
        lumValid = false;
    }

    // Luminance buffer and Σ log(δ + Y) (partials summed in double, in a fixed order).
    void luminance(double delta) {
        if (lumValid && lumDelta == delta) return;
        if (numPixels == 0) throw Error("tone mapping: no image uploaded");
        kLum.set("rgb", rgb).set("n", cl_uint(numPixels)).set("delta", float(delta)).set("lum", lum);
        kLum.set("partials", partials);
        launch(kLum, workItems);
        std::vector<float> p(roundUp(workItems, local) * 2);
        CL_CPP(dc.queue().enqueueReadBuffer(partials, CL_TRUE, 0, p.size() * sizeof(float), p.data()));
        double sum = 0;
        for (size_t i = 0; i < p.size(); i += 2) sum += double(p[i]) + double(p[i + 1]);
        logSum = sum;
        lumValid = true;
        lumDelta = delta;
    }

    // Radix select over the bit patterns of the (non-negative) luminances: exact k-th smallest.
    float select(size_t k) {
        cl_uint prefix = 0, mask = 0;
        size_t rank = std::min(k, numPixels - 1);
        for (int shift = 24; shift >= 0; shift -= 8) {
            const cl_uint zero = 0;
            CL_CPP(dc.queue().enqueueFillBuffer(hist, zero, 0, 256 * sizeof(cl_uint)));
            kHist.set("lum", lum).set("n", cl_uint(numPixels)).set("prefix", prefix).set("mask", mask);
            kHist.set("shift", cl_uint(shift)).set("hist", hist);
            launch(kHist, workItems);
            cl_uint h[256];
            CL_CPP(dc.queue().enqueueReadBuffer(hist, CL_TRUE, 0, sizeof(h), h));
            size_t below = 0;
            int bin = -1;
            for (int b = 0; b < 256; ++b) {
                if (rank < below + h[b]) {
                    bin = b;
                    break;
                }
                below += h[b];
            }
            if (bin < 0) throw Error("tone mapping: percentile selection lost its rank (device histogram is inconsistent)",
                                     ExitCode::Device);
            rank -= below;
            prefix |= cl_uint(bin) << shift;
            mask |= 255u << shift;
        }
        float v;
        static_assert(sizeof(v) == sizeof(prefix), "float is 32 bits");
        std::memcpy(&v, &prefix, sizeof(v));
        return v;
    }

    TonemapDeviceResult map(const TonemapSettings& s, bool floatDisplay) {
        validateTonemapSettings(s, "tone mapping");
        luminance(s.delta);
        TonemapDeviceResult r;
        r.logSum = logSum;
        const bool needWhite = s.op == dev::TMO_PHOTOGRAPHIC && s.burnPercent > 0.0f;
        const size_t k = percentileIndex(numPixels, 100.0 - double(s.burnPercent));
        r.kthLuminance = needWhite ? select(k) : 0.0f;
        r.stats = tonemapStatsFrom(logSum, numPixels, r.kthLuminance, s);

        const dev::TonemapParams p = tonemapDeviceParams(s, r.stats, numPixels);
        if (floatDisplay) {
            if (outFloat() == nullptr)
                outFloat = CL_CPP(cl::Buffer(dc.context(), CL_MEM_WRITE_ONLY, capacity * 3 * sizeof(float)));
            kMapFloat.set("rgb", rgb).set("p", p).set("out", outFloat);
            launch(kMapFloat, mapWorkItems(numPixels));
            r.display.resize(numPixels * 3);
            CL_CPP(dc.queue().enqueueReadBuffer(outFloat, CL_TRUE, 0, r.display.size() * sizeof(float), r.display.data()));
            return r;
        }
        kMap.set("rgb", rgb).set("p", p).set("out", out);
        launch(kMap, mapWorkItems(numPixels));
        r.rgb8.resize(numPixels * 3);
        CL_CPP(dc.queue().enqueueReadBuffer(out, CL_TRUE, 0, r.rgb8.size(), r.rgb8.data()));
        return r;
    }
};

TonemapDevice::TonemapDevice(DeviceContext& dc) : impl_(new Impl(dc)) {}
TonemapDevice::~TonemapDevice() = default;
const BuildInfo& TonemapDevice::buildInfo() const { return impl_->build; }
void TonemapDevice::upload(const ImageRGB& img) { impl_->upload(img); }
TonemapDeviceResult TonemapDevice::map(const TonemapSettings& s, bool floatDisplay) { return impl_->map(s, floatDisplay); }
TonemapDeviceResult TonemapDevice::run(const ImageRGB& img, const TonemapSettings& s) {
    impl_->upload(img);
    return impl_->map(s, false);
}
float TonemapDevice::kthLuminance(size_t k, double delta) {
    impl_->luminance(delta);
    return impl_->select(k);
}

}  // namespace clrt
