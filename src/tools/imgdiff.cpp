// src/tools/: command-line helpers built beside clrt (clrt-imgdiff).
// clrt-imgdiff A B: how far image A is from reference B (EXR or PNG, read by src/image). Prints one
// line of metrics and, with --max-relmse / --max-bad, exits 1 when A is further than allowed.
// Used by scripts/device_check.sh to compare a GPU render with PoCL's, and by hand.
//   relmse  mean over pixels and channels of (a-b)^2 / (b^2 + 1e-2)       (Rousselle et al. 2011)
//   psnr    dB over values clamped to [0,1] (8-bit PNGs are divided by 255 first)
//   bad     fraction of pixels where some channel differs by more than 1e-3 * max(1, |b|)
//   maxabs  largest |a-b| over all channels
// --box N: both images are first averaged over N×N blocks (noise of sampled renders); the line then
// also gives ratio=r,g,b, the per-channel ratio of A's mean to B's.
// Exit codes: 0 within the limits, 1 over a limit, 2 unreadable input or different sizes.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "image/image.h"
#include "image/image_compare.h"
#include "util/error.h"

using namespace clrt;

namespace {

struct Metrics {
    double relMse = 0, psnr = 0, badFraction = 0, maxAbs = 0;
};

Metrics compare(const ImageRGB& a, const ImageRGB& b) {
    const double scaleA = a.isHdr ? 1.0 : 1.0 / 255.0, scaleB = b.isHdr ? 1.0 : 1.0 / 255.0;
    double rel = 0, se = 0;
    size_t bad = 0, n = size_t(a.width) * a.height;
    Metrics m;
    for (size_t p = 0; p < n; ++p) {
        bool pixelBad = false;
        for (int c = 0; c < 3; ++c) {
            double va = a.pixels[p * 3 + c] * scaleA, vb = b.pixels[p * 3 + c] * scaleB;
            double d = va - vb;
            rel += d * d / (vb * vb + 1e-2);
            double ca = std::fmin(std::fmax(va, 0.0), 1.0), cb = std::fmin(std::fmax(vb, 0.0), 1.0);
            se += (ca - cb) * (ca - cb);
            m.maxAbs = std::fmax(m.maxAbs, std::fabs(d));
            pixelBad |= std::fabs(d) > 1e-3 * std::fmax(1.0, std::fabs(vb));
        }
        bad += pixelBad;
    }
    m.relMse = rel / double(3 * n);
    double mse = se / double(3 * n);
    m.psnr = mse > 0 ? 10.0 * std::log10(1.0 / mse) : INFINITY;
    m.badFraction = double(bad) / double(n);
    return m;
}

double numberArg(const char* opt, const char* v) {
    char* end = nullptr;
    double x = v ? std::strtod(v, &end) : NAN;
    if (!v || end == v || *end || !std::isfinite(x) || x < 0) {
        std::fprintf(stderr, "clrt-imgdiff: error: %s needs a non-negative number\n", opt);
        std::exit(2);
    }
    return x;
}

}  // namespace

int main(int argc, char** argv) {
    std::string files[2];
    int nFiles = 0;
    double maxRel = INFINITY, maxBad = INFINITY;
    int box = 1;
    for (int i = 1; i < argc; ++i) {
        std::string s = argv[i];
        if (s == "--max-relmse") maxRel = numberArg("--max-relmse", i + 1 < argc ? argv[++i] : nullptr);
        else if (s == "--box") box = int(numberArg("--box", i + 1 < argc ? argv[++i] : nullptr));
        else if (s == "--max-bad") maxBad = numberArg("--max-bad", i + 1 < argc ? argv[++i] : nullptr);
        else if (s == "-h" || s == "--help") {
            std::printf("usage: clrt-imgdiff A B [--box N] [--max-relmse X] [--max-bad FRACTION]\n");
            return 0;
        } else if (nFiles < 2) files[nFiles++] = s;
        else { std::fprintf(stderr, "clrt-imgdiff: error: unexpected argument '%s'\n", s.c_str()); return 2; }
    }
    if (nFiles != 2) { std::fprintf(stderr, "usage: clrt-imgdiff A B [--box N] [--max-relmse X] [--max-bad FRACTION]\n"); return 2; }
    try {
        ImageRGB a = readImage(files[0]), b = readImage(files[1]);
        if (a.width != b.width || a.height != b.height) {
            std::fprintf(stderr, "clrt-imgdiff: error: %s is %dx%d but %s is %dx%d\n", files[0].c_str(), a.width,
                         a.height, files[1].c_str(), b.width, b.height);
            return 2;
        }
        if (box > 1) {
            a = boxDownsample(a, box);
            b = boxDownsample(b, box);
        }
        Metrics m = compare(a, b);
        bool ok = m.relMse <= maxRel && m.badFraction <= maxBad;
        std::printf("relmse=%.3g psnr=%.2f bad=%.5f maxabs=%.4g", m.relMse, m.psnr, m.badFraction, m.maxAbs);
        if (box > 1) {
            std::array<double, 3> r = meanRatio(a, b);
            std::printf(" ratio=%.4f,%.4f,%.4f", r[0], r[1], r[2]);
        }
        std::printf(" %s\n", ok ? "ok" : "OVER LIMIT");
        return ok ? 0 : 1;
    } catch (const Error& e) {
        std::fprintf(stderr, "clrt-imgdiff: error: %s\n", e.what());
        return 2;
    }
}
