// simd4.h — four floats (x, y, z and a fourth lane that only rides along) for the BVH builder
// (bvh.cpp): one SSE register where there is SSE, else plain floats with the same results.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define CLRT_BVH_SSE 1
#endif

namespace clrt {
namespace simd4 {

#ifdef CLRT_BVH_SSE
struct F4 {
    __m128 v;
};
inline F4 f4(float x, float y, float z) { return {_mm_set_ps(0.f, z, y, x)}; }
inline F4 f4(float s) { return {_mm_set_ps(0.f, s, s, s)}; }
inline F4 load4(const float* p) { return {_mm_load_ps(p)}; }  // p 16-byte aligned
inline F4 xyz(F4 a) { return {_mm_and_ps(a.v, _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)))}; }  // w = 0
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4 min4(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }  // a < b ? a : b per lane
inline F4 max4(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }  // a > b ? a : b per lane
inline void store(F4 a, float out[4]) { _mm_storeu_ps(out, a.v); }
inline void truncate(F4 a, int out[4]) { _mm_storeu_si128((__m128i*)out, _mm_cvttps_epi32(a.v)); }
// d = hi - lo in double (x, y, z); false if lo > hi on some axis.
inline bool extent(F4 lo, F4 hi, double d[3]) {
    if ((_mm_movemask_ps(_mm_cmple_ps(lo.v, hi.v)) & 7) != 7) return false;
    __m128d xy = _mm_sub_pd(_mm_cvtps_pd(hi.v), _mm_cvtps_pd(lo.v));
    __m128d z = _mm_sub_sd(_mm_cvtps_pd(_mm_movehl_ps(hi.v, hi.v)), _mm_cvtps_pd(_mm_movehl_ps(lo.v, lo.v)));
    _mm_storeu_pd(d, xy);
    _mm_store_sd(d + 2, z);
    return true;
}
#else
struct F4 {
    float v[4];
};
inline F4 f4(float x, float y, float z) { return {{x, y, z, 0.f}}; }
inline F4 f4(float s) { return {{s, s, s, 0.f}}; }
inline F4 load4(const float* p) { return {{p[0], p[1], p[2], 0.f}}; }  // the fourth lane is never used
inline F4 xyz(F4 a) { return {{a.v[0], a.v[1], a.v[2], 0.f}}; }
template <class Op>
inline F4 lanes(F4 a, F4 b, Op op) {
    return {{op(a.v[0], b.v[0]), op(a.v[1], b.v[1]), op(a.v[2], b.v[2]), op(a.v[3], b.v[3])}};
}
inline F4 operator+(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x + y; }); }
inline F4 operator-(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x - y; }); }
inline F4 operator*(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x * y; }); }
inline F4 min4(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x < y ? x : y; }); }
inline F4 max4(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x > y ? x : y; }); }
inline void store(F4 a, float out[4]) { std::memcpy(out, a.v, sizeof a.v); }
inline void truncate(F4 a, int out[4]) {  // as cvttps2dq: NaN and out of range give INT_MIN
    for (int k = 0; k < 4; ++k) out[k] = std::fabs(a.v[k]) < 2147483648.f ? int(a.v[k]) : INT32_MIN;
}
inline bool extent(F4 lo, F4 hi, double d[3]) {
    for (int k = 0; k < 3; ++k)
        if (!(lo.v[k] <= hi.v[k])) return false;
    for (int k = 0; k < 3; ++k) d[k] = double(hi.v[k]) - lo.v[k];
    return true;
}
#endif

}  // namespace simd4
}  // namespace clrt
