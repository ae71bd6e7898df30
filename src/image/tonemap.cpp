// tonemap.cpp — the host reference of the tone-mapping operators (see tonemap.h for the conventions).
// Every float operation is written in the same order as in cl_kernels/tonemap.cl, so the device
// result differs from this one only by the precision of the OpenCL built-ins (pow, log, exp).
#include "image/tonemap.h"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "shared/type_tables.h"
#include "util/error.h"

namespace clrt {

dev::TmoKind parseTmoKind(const std::string& name, const std::string& what) {
    std::string v = name;
    for (char& c : v) c = char(std::tolower(static_cast<unsigned char>(c)));
    dev::TmoKind k;
    if (lookupType(tonemapOperators(), v, k)) return k;
    throw Error(what + ": expected photographic, aces or filmic, got '" + name + "'", ExitCode::Usage);
}

const char* tmoKindName(dev::TmoKind k) { return typeRow(tonemapOperators(), k).name; }

void validateTonemapSettings(const TonemapSettings& s, const std::string& what) {
    auto bad = [&](const std::string& m) { throw Error(what + ": " + m); };
    if (!(s.key > 0) || !std::isfinite(s.key)) bad("tone-mapping key must be a positive number");
    if (!(s.burnPercent >= 0 && s.burnPercent <= 100)) bad("burn percentage must be in [0, 100]");
    if (!(s.saturation >= 0) || !std::isfinite(s.saturation)) bad("saturation must be a number >= 0");
    if (!(s.gamma > 0) || !std::isfinite(s.gamma)) bad("gamma must be a positive number");
    if (!(s.delta > 0) || !std::isfinite(s.delta)) bad("log-average delta must be positive");
}

float tonemapSanitize(float c) { return (std::isfinite(c) && c > 0.0f) ? c : 0.0f; }

float tonemapLuminance(float r, float g, float b) {
    float y = 0.2126f * tonemapSanitize(r);
    y = y + 0.7152f * tonemapSanitize(g);
    y = y + 0.0722f * tonemapSanitize(b);
    return std::fmin(y, FLT_MAX);
}

size_t percentileIndex(size_t n, double percentile) {
    if (n == 0) return 0;
    double r = std::ceil(percentile / 100.0 * double(n)) - 1.0;
    if (!(r > 0)) return 0;
    return std::min(n - 1, size_t(r));
}

float tmoPhotographic(float L, bool hasWhite, float whiteL) {
    if (!(L > 0.0f)) return 0.0f;
    float a = L / (1.0f + L);
    if (!hasWhite) return a;
    if (!(whiteL > 0.0f)) return FLT_MAX;  // L_white = 0: everything above 0 burns out
    float b = 1.0f + L / (whiteL * whiteL);
    return a * b;
}

// Narkowicz 2015: x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14); for x > 1 with numerator and
// denominator divided by x² so that huge inputs cannot overflow.
float tmoAces(float L) {
    if (!(L > 0.0f)) return 0.0f;
    if (L <= 1.0f) return (L * (2.51f * L + 0.03f)) / (L * (2.43f * L + 0.59f) + 0.14f);
    float t = 1.0f / L;
    return (2.51f + 0.03f * t) / (2.43f + 0.59f * t + 0.14f * t * t);
}

// Hable's Uncharted 2 curve F(x) = (x(Ax + CB) + DE) / (x(Ax + B) + DF) − E/F with exposure bias 2
// and white point W = 11.2: Yo = F(2L) / F(W).
static float hableCurve(float x) {
    const float A = 0.15f, B = 0.50f, C = 0.10f, D = 0.20f, E = 0.02f, F = 0.30f;
    if (x <= 1.0f) return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
    float t = 1.0f / x;
    return (A + C * B * t + D * E * t * t) / (A + B * t + D * F * t * t) - E / F;
}

float tmoFilmic(float L) {
    if (!(L > 0.0f)) return 0.0f;
    return hableCurve(2.0f * L) / hableCurve(11.2f);
}

TonemapStats tonemapStatsFrom(double logSum, size_t n, float kthLuminance, const TonemapSettings& s) {
    TonemapStats st;
    st.logAverage = std::exp(logSum / double(std::max<size_t>(n, 1)));
    st.scale = float(double(s.key) / st.logAverage);
    st.hasWhite = s.op == dev::TMO_PHOTOGRAPHIC && s.burnPercent > 0.0f;
    st.whiteIndex = percentileIndex(n, 100.0 - double(s.burnPercent));
    st.kthLuminance = kthLuminance;
    st.whiteL = std::fmin(kthLuminance * st.scale, FLT_MAX);
    return st;
}

TonemapStats tonemapStatsHost(const ImageRGB& img, const TonemapSettings& s) {
    const size_t n = size_t(img.width) * size_t(img.height);
    std::vector<float> ys(n);
    double logSum = 0;
    for (size_t i = 0; i < n; ++i) {
        ys[i] = tonemapLuminance(img.pixels[3 * i], img.pixels[3 * i + 1], img.pixels[3 * i + 2]);
        logSum += std::log(s.delta + double(ys[i]));
    }
    const size_t k = percentileIndex(n, 100.0 - double(s.burnPercent));
    float kth = 0;
    if (n > 0) {
        std::nth_element(ys.begin(), ys.begin() + ptrdiff_t(k), ys.end());
        kth = ys[k];
    }
    return tonemapStatsFrom(logSum, n, kth, s);
}

void tonemapPixel(const float rgb[3], const TonemapSettings& s, const TonemapStats& st, float out[3]) {
    const float c[3] = {tonemapSanitize(rgb[0]), tonemapSanitize(rgb[1]), tonemapSanitize(rgb[2])};
    const float Y = tonemapLuminance(c[0], c[1], c[2]);
    if (!(Y > 0.0f)) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    const float L = std::fmin(Y * st.scale, FLT_MAX);
    float Yo = 0.0f;
    switch (s.op) {
        case dev::TMO_PHOTOGRAPHIC: Yo = tmoPhotographic(L, st.hasWhite, st.whiteL); break;
        case dev::TMO_ACES: Yo = tmoAces(L); break;
        case dev::TMO_FILMIC: Yo = tmoFilmic(L); break;
    }
    Yo = Yo >= 0.0f ? std::fmin(Yo, FLT_MAX) : 0.0f;  // NaN -> 0
    for (int i = 0; i < 3; ++i) {
        float v = Yo * std::pow(c[i] / Y, s.saturation);
        out[i] = v > 0.0f ? std::fmin(v, 1.0f) : 0.0f;  // NaN -> 0
    }
}

float srgbEncode(float v) {
    if (v >= 1.0f) return 1.0f;  // in float, 1.055 − 0.055 falls one ulp short of 1: white would be 254
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

float tonemapGammaEncode(float v, const TonemapSettings& s) {
    if (s.srgb) return srgbEncode(v);
    const float invGamma = 1.0f / s.gamma;
    return std::pow(v, invGamma);
}

unsigned char tonemapEncode(float v, const TonemapSettings& s) {
    float x = 255.0f * tonemapGammaEncode(v, s);
    x = s.truncate ? std::floor(x) : std::floor(x + 0.5f);
    return static_cast<unsigned char>(x > 0.0f ? std::fmin(x, 255.0f) : 0.0f);
}

std::vector<unsigned char> tonemapHost(const ImageRGB& img, const TonemapSettings& s, TonemapStats* stats) {
    TonemapStats st = tonemapStatsHost(img, s);
    if (stats) *stats = st;
    const size_t n = size_t(img.width) * size_t(img.height);
    std::vector<unsigned char> out(n * 3);
    for (size_t i = 0; i < n; ++i) {
        float v[3];
        tonemapPixel(&img.pixels[3 * i], s, st, v);
        for (int c = 0; c < 3; ++c) out[3 * i + c] = tonemapEncode(v[c], s);
    }
    return out;
}

}  // namespace clrt
