// progressive.cpp — sample passes, two half-images and the stop rule (see progressive.h).
#include "render/progressive.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "image/image_compare.h"

namespace clrt {

int passSamples(size_t numPixels, int maxSpp) {
    const size_t wanted = (size_t(65536) + std::max<size_t>(numPixels, 1) - 1) / std::max<size_t>(numPixels, 1);
    return int(std::max<size_t>(2, std::min<size_t>({wanted, 256, size_t(std::max(maxSpp, 4) / 2)})));
}

namespace {

// Sums of the pass images of one half, in double, in pass order (deterministic).
struct HalfSum {
    std::vector<double> sum;
    int passes = 0;
    void add(const ImageRGB& img) {
        if (sum.empty()) sum.assign(img.pixels.size(), 0.0);
        for (size_t i = 0; i < sum.size(); ++i) sum[i] += img.pixels[i];
        ++passes;
    }
};

// (a.sum + b.sum) / (a.passes + b.passes), or one of them alone, as an image of `shape`'s size.
ImageRGB meanOf(const HalfSum& a, const HalfSum& b, const ImageRGB& shape, bool useB = true) {
    ImageRGB out = shape;
    const int n = a.passes + (useB ? b.passes : 0);
    for (size_t i = 0; i < out.pixels.size(); ++i) {
        double s = (a.passes ? a.sum[i] : 0.0) + (useB && b.passes ? b.sum[i] : 0.0);
        out.pixels[i] = n > 0 ? float(s / n) : 0.0f;
    }
    return out;
}

double secondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

ProgressiveResult renderProgressive(size_t numPixels, const StopRule& rule, const PassRenderer& pass,
                                    const std::function<bool()>& stopped,
                                    const std::function<void(const ProgressiveResult&)>& onPair,
                                    const PassObserver& onPass) {
    const auto t0 = std::chrono::steady_clock::now();
    ProgressiveResult r;
    const int P = r.passSamples = passSamples(numPixels, rule.maxSpp);
    HalfSum half[2];
    ImageRGB shape, partial;  // partial: an interrupted first pass (the only samples there are)
    auto pairStart = t0;
    for (int k = 0;; ++k) {
        int reached = 0;
        ImageRGB img = pass(k * P, P, reached);
        if (reached < P) {  // interrupted within the pass: it is dropped unless nothing else exists
            if (k == 0) {
                partial = std::move(img);
                r.spp = reached;
            }
            r.stopReason = "interrupted";
            break;
        }
        if (k == 0) shape = img;
        half[k & 1].add(img);
        r.spp = (k + 1) * P;
        if (onPass) {
            r.seconds = secondsSince(t0);
            onPass(r, [&] { return meanOf(half[0], half[1], shape); });
        }
        if ((k & 1) == 0) {
            if (!stopped()) continue;
            r.stopReason = "interrupted";
            break;
        }
        const double pairSeconds = secondsSince(pairStart);
        pairStart = std::chrono::steady_clock::now();
        r.relMse = halvesRelativeMse(meanOf(half[0], half[1], shape, false), meanOf(half[1], half[0], shape, false),
                                     rule.white);
        r.seconds = secondsSince(t0);
        if (onPair) onPair(r);
        if (rule.targetError > 0 && r.relMse <= rule.targetError) r.stopReason = "target error";
        else if (rule.timeLimit >= 0 && r.seconds + pairSeconds >= rule.timeLimit) r.stopReason = "time limit";
        else if (size_t(k + 3) * size_t(P) > size_t(rule.maxSpp)) r.stopReason = "spp limit";
        else if (stopped()) r.stopReason = "interrupted";
        if (!r.stopReason.empty()) break;
    }
    r.image = half[0].passes > 0 ? meanOf(half[0], half[1], shape) : std::move(partial);
    r.seconds = secondsSince(t0);
    return r;
}

}  // namespace clrt
