// tonemap.h — tone-mapping operators on the host (their settings: TonemapSettings, in
// shared/tonemap_settings.h): the plain C++ reference of every operator (Photographic = Reinhard et
// al. 2002 global, ACES = Narkowicz's 2015 fit, Filmic = Hable's Uncharted 2 curve), and the
// per-image statistics they need.
// The OpenCL kernels in cl_kernels/tonemap.cl implement the same formulas; tests compare the two.
//
// Conventions (chosen because they reproduce the course's reference PNGs, see README "Tone mapping"):
//   * a channel that is NaN, infinite or negative counts as 0; Y = 0.2126R + 0.7152G + 0.0722B;
//   * log-average Ȳ = exp(mean(log(δ + Y))) over all pixels, δ = 1e-6 (summed in double);
//   * L = Y·(key/Ȳ) (the float factor key/Ȳ is computed once, in double, then rounded to float);
//   * L_white = k-th smallest L (0-based) with k = percentileIndex(N, 100 − burn), see below;
//     burn = 0: no white point (Yo = L/(1+L)); L_white = 0: every L > 0 maps to white;
//   * RGBo = Yo·(RGB/Y)^s, clamped to [0,1]; 8-bit value = floor or round of 255·RGBo^(1/g), or of
//     255·sRGB(RGBo) with <Gamma>sRGB</Gamma>.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "image/image.h"
#include "shared/device_types.h"    // dev::TmoKind, the one operator enum (host, kernels, scene model)
#include "shared/tonemap_settings.h"  // TonemapSettings, shared with the scene model (a camera's Tonemap blocks)

namespace clrt {

// "photographic", "aces", "filmic" (case-insensitive); throws clrt::Error (Usage) naming `what`.
dev::TmoKind parseTmoKind(const std::string& name, const std::string& what = "--tmo");
const char* tmoKindName(dev::TmoKind k);  // lower case

// Throws clrt::Error naming `what` when a setting is out of range (key <= 0, burn outside [0,100],
// saturation < 0, gamma <= 0, any NaN).
void validateTonemapSettings(const TonemapSettings& s, const std::string& what);

// The figures the per-pixel mapping needs; computed once per image.
struct TonemapStats {
    double logAverage = 0;   // Ȳ
    float scale = 0;         // key / Ȳ as float: L = Y * scale
    bool hasWhite = false;   // Photographic with burn > 0
    float whiteL = 0;        // L_white (when hasWhite)
    float kthLuminance = 0;  // the luminance Y of rank whiteIndex (L_white = Y_k * scale)
    size_t whiteIndex = 0;   // its rank k in the sorted luminances
};

// The sanitised channel value (NaN, ±Inf, negative -> 0) and the luminance of a pixel, exactly as the
// kernels compute them (no fused multiply-add; clamped to FLT_MAX).
float tonemapSanitize(float c);
float tonemapLuminance(float r, float g, float b);

// 0-based index into the ascending luminances of the `percentile`th percentile of n values:
// nearest rank, k = ceil(percentile/100 · n) − 1, clamped to [0, n−1].
size_t percentileIndex(size_t n, double percentile);

// Ȳ, scale and L_white of an image (L_white by std::nth_element: the sorted-array percentile).
TonemapStats tonemapStatsHost(const ImageRGB& img, const TonemapSettings& s);
// Same from the log-sum and the k-th smallest luminance (the device path computes these two).
TonemapStats tonemapStatsFrom(double logSum, size_t n, float kthLuminance, const TonemapSettings& s);

// The sRGB transfer curve (IEC 61966-2-1) of a display value v in [0,1]: 12.92·v up to 0.0031308,
// else 1.055·v^(1/2.4) − 0.055; exactly 1 from 1 up.
float srgbEncode(float v);
// The gamma-encoded display value: srgbEncode(v) with s.srgb, else v^(1/gamma).
float tonemapGammaEncode(float v, const TonemapSettings& s);

// The tone-mapped display value in [0,1] of one pixel (before gamma), and its 8-bit encoding.
void tonemapPixel(const float rgb[3], const TonemapSettings& s, const TonemapStats& st, float out[3]);
unsigned char tonemapEncode(float v, const TonemapSettings& s);

// The whole reference pipeline: 8-bit RGB, row-major (as writePng8 takes it).
std::vector<unsigned char> tonemapHost(const ImageRGB& img, const TonemapSettings& s, TonemapStats* stats = nullptr);

// The display curves alone (input L >= 0, output >= 0, not clamped).
float tmoPhotographic(float L, bool hasWhite, float whiteL);
float tmoAces(float L);
float tmoFilmic(float L);

}  // namespace clrt
