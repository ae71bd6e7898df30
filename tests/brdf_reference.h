// brdf_reference.h — plain C++ reference of cl_kernels/brdf.cl (the course's hw6 BRDFs: value,
// importance sampler, pdf), written from the formulas in that file's header, for tests/test_brdf.cpp
// (device vs host, chi-square, ∫pdf = 1, albedo) and the render tests. Floats, like the device.
#pragma once
#include <algorithm>
#include <cmath>

#include "shared/device_types.h"
#include "util/math.h"

namespace clrt::test {

struct HostBrdf {
    int kind = dev::BRDF_ORIGINAL_BLINN_PHONG;
    float exponent = 1;
    int flags = 0;
    float eta = 1, k = 0;
    Vec3 kd, ks;
};

constexpr float kBrdfPi = 3.14159265358979323846f;
constexpr float kBrdfInvPi = 0.31830988618379067154f;

inline float brdfPow(float x, float e) { return x > 0 ? std::exp2(e * std::log2(x)) : std::pow(x, e); }
inline Vec3 brdfReflect(const Vec3& w, const Vec3& n) { return 2.0f * dot(w, n) * n - w; }
inline Vec3 brdfMul(const Vec3& a, const Vec3& b) { return Vec3(a.x * b.x, a.y * b.y, a.z * b.z); }

// The frame of common.cl's makeBasis (Duff et al.), so host and device warps agree.
inline void brdfBasis(const Vec3& n, Vec3& t, Vec3& b) {
    float sign = n.z >= 0 ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    t = Vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = Vec3(c, sign + n.y * n.y * a, -n.y);
}

inline float hostFresnelConductor(float cosI, float n, float k) {
    float c2 = cosI * cosI, nk = n * n + k * k;
    float rs = (nk - 2 * n * cosI + c2) / (nk + 2 * n * cosI + c2);
    float rp = (nk * c2 - 2 * n * cosI + 1) / (nk * c2 + 2 * n * cosI + 1);
    return 0.5f * (rs + rp);
}

inline Vec3 hostBrdfEval(const HostBrdf& b, const Vec3& n, const Vec3& wo, const Vec3& wi) {
    float cosI = dot(n, wi), cosO = dot(n, wo);
    if (!(cosI > 0) || !(cosO > 0)) return Vec3(0, 0, 0);
    Vec3 diffuse = b.kd * kBrdfInvPi;
    float cosR = std::max(0.0f, dot(brdfReflect(wi, n), wo));
    Vec3 hs = wi + wo;
    float hl = length(hs);
    float cosH = hl > 0 ? std::max(0.0f, dot(n, hs) / hl) : 0.0f;
    float p = b.exponent;
    bool normalized = b.flags & CLRT_BRDF_NORMALIZED;
    // Diffuse: kd/π in the normalized BRDFs and Torrance-Sparrow, kd in the others.
    switch (b.kind) {
    case dev::BRDF_ORIGINAL_PHONG: return b.kd + b.ks * (brdfPow(cosR, p) / cosI);
    case dev::BRDF_ORIGINAL_BLINN_PHONG: return b.kd + b.ks * (brdfPow(cosH, p) / cosI);
    case dev::BRDF_MODIFIED_PHONG:
        if (!normalized) return b.kd + b.ks * brdfPow(cosR, p);
        return diffuse + b.ks * (brdfPow(cosR, p) * ((p + 2) * (0.5f * kBrdfInvPi)));
    case dev::BRDF_MODIFIED_BLINN_PHONG:
        if (!normalized) return b.kd + b.ks * brdfPow(cosH, p);
        return diffuse + b.ks * (brdfPow(cosH, p) * ((p + 8) * (0.125f * kBrdfInvPi)));
    case dev::BRDF_TORRANCE_SPARROW: {
        Vec3 h = normalize(wi + wo);
        float ch = std::max(0.0f, dot(n, h)), woH = dot(wo, h);
        float d = (p + 2) * (0.5f * kBrdfInvPi) * brdfPow(ch, p);
        float g = std::min(1.0f, std::min(2 * ch * cosO / woH, 2 * ch * cosI / woH));
        float f = hostFresnelConductor(cosI, b.eta, b.k);  // at θi, as brdf.cl
        Vec3 kd = (b.flags & CLRT_BRDF_KD_FRESNEL) ? b.kd * (1 - f) : b.kd;
        return kd * kBrdfInvPi + b.ks * (d * f * g / (4 * cosI * cosO));
    }
    default: return Vec3(0, 0, 0);
    }
}

inline float hostGlossyWeight(const HostBrdf& b) {
    float d = b.kd.x + b.kd.y + b.kd.z, s = b.ks.x + b.ks.y + b.ks.z;
    return d + s > 0 ? s / (d + s) : 0.0f;
}
inline bool hostLobeHalfVector(const HostBrdf& b) {
    return b.kind != dev::BRDF_ORIGINAL_PHONG && b.kind != dev::BRDF_MODIFIED_PHONG;
}
inline float hostLobeExponent(const HostBrdf& b) {
    return b.kind == dev::BRDF_TORRANCE_SPARROW ? b.exponent + 1 : b.exponent;
}
inline float hostPowerCosinePdf(float q, float c) { return c > 0 ? (q + 1) * (0.5f * kBrdfInvPi) * brdfPow(c, q) : 0.0f; }

inline float hostGlossyPdf(const HostBrdf& b, const Vec3& n, const Vec3& wo, const Vec3& wi) {
    float q = hostLobeExponent(b);
    if (!hostLobeHalfVector(b)) return hostPowerCosinePdf(q, dot(brdfReflect(wo, n), wi));
    Vec3 h = wi + wo;
    float l = length(h);
    if (!(l > 0)) return 0;
    h = h * (1.0f / l);
    if (dot(n, h) < 0) h = h * -1.0f;
    float woH = std::fabs(dot(wo, h));
    return woH > 0 ? hostPowerCosinePdf(q, dot(n, h)) / (4 * woH) : 0.0f;
}

inline float hostBrdfPdf(const HostBrdf& b, const Vec3& n, const Vec3& wo, const Vec3& wi) {
    if (!(dot(n, wi) > 0)) return 0;
    float s = hostGlossyWeight(b);
    float pd = dot(n, wi) * kBrdfInvPi;
    return (1 - s) * pd + (s > 0 ? s * hostGlossyPdf(b, n, wo, wi) : 0.0f);
}

inline Vec3 hostWarpPowerCosine(const Vec3& axis, float q, float u1, float u2, float& c) {
    c = brdfPow(u1, 1.0f / (q + 1));
    float s = std::sqrt(std::max(0.0f, 1 - c * c)), phi = 2 * kBrdfPi * u2;
    Vec3 t, bt;
    brdfBasis(axis, t, bt);
    return normalize(t * (s * std::cos(phi)) + bt * (s * std::sin(phi)) + axis * c);
}

// Draws wi; pdf from the warp. False when the glossy lobe's direction is below the surface.
inline bool hostBrdfSample(const HostBrdf& b, const Vec3& n, const Vec3& wo, float ux, float uy, Vec3& wi, float& pdf) {
    float s = hostGlossyWeight(b), c;
    if (ux < s) {
        float u1 = std::min(ux / s, 1.0f), q = hostLobeExponent(b);
        if (hostLobeHalfVector(b)) {
            Vec3 h = hostWarpPowerCosine(n, q, u1, uy, c);
            float woH = dot(wo, h);
            if (!(std::fabs(woH) > 0)) return false;
            wi = normalize(h * (2 * woH) - wo);
            if (!(dot(n, wi) > 0)) return false;
            pdf = s * hostPowerCosinePdf(q, c) / (4 * std::fabs(woH)) + (1 - s) * std::max(0.0f, dot(n, wi)) * kBrdfInvPi;
        } else {
            wi = hostWarpPowerCosine(brdfReflect(wo, n), q, u1, uy, c);
            if (!(dot(n, wi) > 0)) return false;
            pdf = s * hostPowerCosinePdf(q, c) + (1 - s) * std::max(0.0f, dot(n, wi)) * kBrdfInvPi;
        }
        return pdf > 0 && isFinite(wi);
    }
    float u1 = std::min((ux - s) / (1 - s), 1.0f);
    float r = std::sqrt(u1), phi = 2 * kBrdfPi * uy, z = std::sqrt(std::max(0.0f, 1 - u1));
    Vec3 t, bt;
    brdfBasis(n, t, bt);
    wi = normalize(t * (r * std::cos(phi)) + bt * (r * std::sin(phi)) + n * z);
    pdf = (1 - s) * z * kBrdfInvPi + (s > 0 ? s * hostGlossyPdf(b, n, wo, wi) : 0.0f);
    return pdf > 0 && isFinite(wi);
}

}  // namespace clrt::test

namespace clrt::test {
// The probability that hostBrdfSample rejects (a glossy direction below the surface), integrated in
// the lobe's own domain (h about n, or directions about wo mirrored in n): independent of the
// solid-angle pdf, so ∫ pdf dω over the hemisphere + this = 1 checks the Jacobian.
template <class Integrate> double hostRejectedMass(const HostBrdf& b, const Vec3& n, const Vec3& wo, Integrate integrate) {
    float s = hostGlossyWeight(b), q = hostLobeExponent(b);
    if (s == 0) return 0;
    if (hostLobeHalfVector(b)) {
        return s * integrate(n, [&](const Vec3& h) {
                   Vec3 wi = h * (2 * dot(wo, h)) - wo;
                   return dot(n, wi) > 0 ? 0.0 : double(hostPowerCosinePdf(q, dot(n, h)));
               });
    }
    Vec3 r = brdfReflect(wo, n);
    return s * integrate(r, [&](const Vec3& w) { return dot(n, w) > 0 ? 0.0 : double(hostPowerCosinePdf(q, dot(r, w))); });
}
}  // namespace clrt::test
