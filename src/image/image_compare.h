// image_compare.h — comparing a sampled render with a reference: N×N box downsampling, relMSE
// (Rousselle et al. 2011: mean over pixels and channels of (a−b)² / (b² + 1e-2)) and the per-channel
// ratio of means. Used by clrt-imgdiff (--box) and the hw6 comparisons (tests/test_object_lights.cpp,
// scripts/compare_hw6_area.sh).
#pragma once
#include <array>

#include "image/image.h"

namespace clrt {

// The mean of each n×n block (a partial block at the right/bottom edge is averaged over its pixels).
ImageRGB boxDownsample(const ImageRGB& img, int n);
// relMSE of a against reference b (same size; values as stored, no 8-bit scaling).
double relativeMse(const ImageRGB& a, const ImageRGB& b);
// The relMSE of the mean (a+b)/2 of two independent, equally sampled renders a and b of one image,
// estimated from their difference alone: E|a-b|^2 = 2 Var(half) and Var((a+b)/2) = Var(half)/2, so
// each value's squared error is estimated by |a-b|^2/4, relative to ((a+b)/2)^2 + 1e-2 white^2
// (white: 1 for HDR images, 255 for the course's LDR ones; bench/bench.py's reference estimate).
double halvesRelativeMse(const ImageRGB& a, const ImageRGB& b, double white = 1.0);
// mean(a_c) / mean(b_c) per channel (NaN where b's mean is 0).
std::array<double, 3> meanRatio(const ImageRGB& a, const ImageRGB& b);

}  // namespace clrt
