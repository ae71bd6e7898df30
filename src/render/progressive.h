// progressive.h — a render in sample passes that stops on an error target or a time limit (clrt
// render --target-error X, --time-limit S). Pass k renders samples [kP, (k+1)P) of every pixel
// (P = passSamples(): stratified within the pass, at least 2 so the camera jitters). Even passes are
// summed into half-image A, odd passes into half-image B: two independent estimates of every pixel.
// After each pair of passes the relMSE of the full image (A+B)/2 is estimated from the two halves
// (halvesRelativeMse, src/image/image_compare.h: the benchmark's estimate), and the render stops at
// the first of: the estimate <= targetError; the next pair would end after timeLimit (a pair takes
// as long as the last one did; at least one pair is always rendered); the next pair would pass
// maxSpp; `stopped()` (SIGINT/SIGTERM: the complete passes are kept). Without either flag clrt never
// comes here, so a render without them is unchanged bit for bit. Reads no scene element itself.
#pragma once
#include <cmath>
#include <cstddef>
#include <functional>
#include <string>

#include "flatten/device_scene.h"
#include "image/image.h"

namespace clrt {

struct StopRule {
    double targetError = 0;           // > 0: stop at an estimated relMSE <= this
    double timeLimit = -1;            // >= 0: seconds (per camera)
    int maxSpp = kMaxSamplesPerPixel;  // never more samples per pixel than this (>= 4)
    double white = 1;                  // the relMSE's white: 1 for HDR (.exr) outputs, 255 for .png
    bool active() const { return targetError > 0 || timeLimit >= 0; }
};

struct ProgressiveResult {
    ImageRGB image;          // the mean of every complete pass
    int spp = 0;             // samples per pixel in it
    int passSamples = 0;     // P
    double relMse = NAN;     // the estimate at the last complete pair (NaN: none completed)
    double seconds = 0;      // wall time of the passes
    std::string stopReason;  // "target error", "time limit", "spp limit" or "interrupted"
};

// Samples per pass for an image of `numPixels` pixels: 65536 paths per pass at least (a batch's
// worth, so a pass keeps the device busy), at least 2, at most 256 and maxSpp / 2.
int passSamples(size_t numPixels, int maxSpp);

// Renders samples [first, first + count) of every pixel and returns their mean; `reached`: the
// samples every pixel got (fewer than count only when the render was stopped).
using PassRenderer = std::function<ImageRGB(int first, int count, int& reached)>;

// After each complete pass: the result so far (spp, the last pair's relMSE, seconds) and a function
// that computes the mean of every complete pass so far (the image a stop would write), for a live
// preview; called on the render thread, which pays for the mean only when the observer asks for it.
using PassObserver = std::function<void(const ProgressiveResult& soFar, const std::function<ImageRGB()>& meanSoFar)>;

// The render loop (see above); onPair(result so far) after each pair, for progress lines; onPass
// after each pass (PassObserver). Neither changes the image.
ProgressiveResult renderProgressive(size_t numPixels, const StopRule& rule, const PassRenderer& pass,
                                    const std::function<bool()>& stopped,
                                    const std::function<void(const ProgressiveResult&)>& onPair = {},
                                    const PassObserver& onPass = {});

}  // namespace clrt
