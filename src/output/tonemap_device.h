// tonemap_device.h — tone mapping on an OpenCL device (cl_kernels/tonemap.cl). The device computes
// the luminance, the compensated partial log-sums (added up here in double) and the exact k-th
// smallest luminance (radix select: four 8-bit histogram passes over the float bit patterns); the
// host turns them into TonemapStats (src/image/tonemap.h) and the device maps every pixel.
#pragma once
#include <memory>
#include <vector>

#include "cl/program.h"
#include "image/image.h"
#include "image/tonemap.h"

namespace clrt {

// The map kernels' parameters for settings `s` and the image statistics `stats` of numPixels pixels.
dev::TonemapParams tonemapDeviceParams(const TonemapSettings& s, const TonemapStats& stats, size_t numPixels);

struct TonemapDeviceResult {
    std::vector<unsigned char> rgb8;  // width*height*3, row-major (8-bit mode)
    std::vector<float> display;       // width*height*3 gamma-encoded values in [0,1] (float mode)
    TonemapStats stats;
    double logSum = 0;                // Σ log(δ + Y)
    float kthLuminance = 0;           // the Y of rank stats.whiteIndex (Photographic with burn > 0)
};

class TonemapDevice {
public:
    explicit TonemapDevice(DeviceContext& dc);  // builds KernelProgram::Tonemap
    ~TonemapDevice();
    const BuildInfo& buildInfo() const;

    // Uploads `img` (kept until the next upload) and tone-maps it with one or several settings.
    void upload(const ImageRGB& img);
    // floatDisplay: fill `display` (not quantised) instead of `rgb8`.
    TonemapDeviceResult map(const TonemapSettings& s, bool floatDisplay = false);
    // upload + map.
    TonemapDeviceResult run(const ImageRGB& img, const TonemapSettings& s);

    // The k-th smallest (0-based) luminance of the uploaded image, exactly (for tests).
    float kthLuminance(size_t k, double delta = 1e-6);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace clrt
