// image_compare.cpp — box downsampling, relMSE and mean ratios of images (see image_compare.h).
#include "image/image_compare.h"

#include <algorithm>
#include <cmath>

namespace clrt {

ImageRGB boxDownsample(const ImageRGB& img, int n) {
    n = std::max(1, n);
    ImageRGB out;
    out.width = (img.width + n - 1) / n;
    out.height = (img.height + n - 1) / n;
    out.isHdr = img.isHdr;
    out.pixels.assign(size_t(out.width) * out.height * 3, 0.0f);
    for (int by = 0; by < out.height; ++by)
        for (int bx = 0; bx < out.width; ++bx) {
            double sum[3] = {0, 0, 0};
            int count = 0;
            for (int y = by * n; y < std::min(img.height, (by + 1) * n); ++y)
                for (int x = bx * n; x < std::min(img.width, (bx + 1) * n); ++x, ++count)
                    for (int c = 0; c < 3; ++c) sum[c] += img.at(x, y, c);
            for (int c = 0; c < 3; ++c) out.at(bx, by, c) = float(sum[c] / std::max(count, 1));
        }
    return out;
}

double relativeMse(const ImageRGB& a, const ImageRGB& b) {
    double rel = 0;
    for (size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i) {
        double d = double(a.pixels[i]) - b.pixels[i];
        rel += d * d / (double(b.pixels[i]) * b.pixels[i] + 1e-2);
    }
    return a.pixels.empty() ? 0.0 : rel / double(a.pixels.size());
}

double halvesRelativeMse(const ImageRGB& a, const ImageRGB& b, double white) {
    double rel = 0;
    const size_t n = std::min(a.pixels.size(), b.pixels.size());
    for (size_t i = 0; i < n; ++i) {
        const double d = double(a.pixels[i]) - b.pixels[i], m = 0.5 * (double(a.pixels[i]) + b.pixels[i]);
        rel += d * d / 4.0 / (m * m + 1e-2 * white * white);
    }
    return n == 0 ? 0.0 : rel / double(n);
}

std::array<double, 3> meanRatio(const ImageRGB& a, const ImageRGB& b) {
    double sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};
    for (size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i) {
        sa[i % 3] += a.pixels[i];
        sb[i % 3] += b.pixels[i];
    }
    std::array<double, 3> r;
    for (int c = 0; c < 3; ++c) r[size_t(c)] = sb[c] != 0 ? sa[c] / sb[c] : NAN;
    return r;
}

}  // namespace clrt
