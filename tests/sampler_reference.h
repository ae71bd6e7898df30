// sampler_reference.h — host replicas of the sampling primitives of cl_kernels/common.cl, written
// from their definitions, shared by the sampler tests (test_sampler.cpp: Rng_Stratified2D;
// test_zsobol.cpp: ZSobol_2D): the PCG hash, bit reversal, the Laine–Karras permutation, Sobol's second
// dimension, nested uniform (Owen) scrambling, and the (0,m,2)-net check of elementary intervals.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace clrt {
namespace test {

inline uint32_t hashPcg(uint32_t v) {  // Rng_Hash
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
inline uint32_t reverseBits(uint32_t v) {
    uint32_t r = 0;
    for (int i = 0; i < 32; ++i) r |= ((v >> i) & 1u) << (31 - i);
    return r;
}
inline uint32_t laineKarras(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}
// Sobol's second dimension from its generator matrix (Pascal's triangle mod 2), as a 32-bit fraction.
inline uint32_t sobol1(uint32_t index) {
    uint32_t v = 1u << 31, r = 0;
    for (; index; index >>= 1, v ^= v >> 1)
        if (index & 1u) r ^= v;
    return r;
}
// Nested uniform scramble of a fraction's bits (each flipped by a hash of the bits above it in the fraction).
inline uint32_t owen(uint32_t fraction, uint32_t seed) { return reverseBits(laineKarras(reverseBits(fraction), seed)); }

struct Point { uint32_t x, y; };

inline float toFloat(uint32_t v) { return float(v >> 8) * (1.0f / 16777216.0f); }

// Whether points [0, n) (n = 2^m) put one point in every elementary interval 2^-a x 2^-(m-a).
inline bool isNet(const std::vector<Point>& p, int m) {
    const size_t n = size_t(1) << m;
    if (p.size() != n) return false;
    for (int a = 0; a <= m; ++a) {
        std::vector<int> count(n, 0);
        for (size_t i = 0; i < n; ++i) {
            const uint32_t cx = a == 0 ? 0 : p[i].x >> (32 - a), cy = (m - a) == 0 ? 0 : p[i].y >> (32 - (m - a));
            if (++count[(cx << (m - a)) | cy] > 1) return false;
        }
    }
    return true;
}

}  // namespace test
}  // namespace clrt
