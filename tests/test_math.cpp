// Device math of cl_kernels/common.cl that replaces a built-in: Math_SinCos2Pi (sin and cos of 2πt for the
// warps and the environment map's directions) against long double sin/cos and against its host replica
// sinCos2Pi (src/util/math.h, which the host mirrors of the env sampling use), on arguments where the
// reduction has edges (quarter and eighth turns, their neighbours, negatives, tiny and large t) and 200k
// random ones. A mutated replica (the quadrant rotation one step off) must fail the same bound.
#include <catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "test_helpers.h"
#include "util/math.h"

using namespace clrt;
using namespace clrt::test;

namespace {

std::vector<float> sinCosArguments() {
    std::vector<float> t;
    for (int k = -16; k <= 16; ++k) {  // multiples of 1/8 turn and their float neighbours
        const float e = float(k) / 8.0f;
        t.push_back(e);
        t.push_back(std::nextafter(e, 10.0f));
        t.push_back(std::nextafter(e, -10.0f));
    }
    for (float v : {1e-30f, 1e-12f, 1e-7f, 3e-4f, 0.49999997f, 0.99999994f, 1e3f + 0.3f, 8388607.5f, -0.3f, -0.0f})
        t.push_back(v);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f), wide(-2.0f, 2.0f);
    for (int i = 0; i < 150000; ++i) t.push_back(unit(rng));  // what the render path passes: a sample in [0, 1)
    for (int i = 0; i < 50000; ++i) t.push_back(wide(rng));
    return t;
}

// Error of v against the exact x in units of the float spacing at x; 0 where both are below 1e-3 in
// magnitude and within 1e-7 absolute (near a zero of sin or cos relative error is not meaningful).
double ulpError(float v, long double x) {
    const long double err = std::fabs(static_cast<long double>(v) - x);
    if (std::fabs(x) < 1e-3L) return err <= 1e-7L ? 0.0 : 1e9;
    const float xf = static_cast<float>(x);
    const double ulp = double(std::nextafter(std::fabs(xf), std::numeric_limits<float>::infinity()) - std::fabs(xf));
    return double(err) / ulp;
}

// The replica with the quarter-turn rotation one step off: what a wrong quadrant gives.
void sinCos2PiMutated(float t, float& c, float& s) { sinCos2Pi(t + 0.25f, c, s); }

template <class F>
double worstUlp(const std::vector<float>& ts, F f) {
    double worst = 0.0;
    for (float t : ts) {
        float c, s;
        f(t, c, s);
        const long double a = 2.0L * 3.14159265358979323846264338327950288L * static_cast<long double>(t);
        worst = std::max({worst, ulpError(c, std::cos(a)), ulpError(s, std::sin(a))});
    }
    return worst;
}

}  // namespace

TEST_CASE("Math_SinCos2Pi: within 2 ulp of sin and cos of 2πt on the device and in its host replica", "[math][cl]") {
    const std::vector<float> ts = sinCosArguments();
    const double hostWorst = worstUlp(ts, [](float t, float& c, float& s) { sinCos2Pi(t, c, s); });
    INFO("host replica: worst error " << hostWorst << " ulp");
    CHECK(hostWorst <= 2.0);
    CHECK(worstUlp(ts, sinCos2PiMutated) > 1e6);  // the bound sees a wrong quadrant

    const char* src = R"CLC(
__kernel void sincos_test(const __global float* in, __global float2* out, int n) {
    int i = get_global_id(0);
    if (i < n) out[i] = Math_SinCos2Pi(in[i]);
}
)CLC";
    const std::vector<dev::float2> out = runElementwiseKernel<dev::float2>({"common.cl"}, "sincos_test", src, ts);
    const int n = int(ts.size());
    double deviceWorst = 0.0, apart = 0.0;
    for (int i = 0; i < n; ++i) {
        const float t = ts[size_t(i)];
        const long double a = 2.0L * 3.14159265358979323846264338327950288L * static_cast<long double>(t);
        const float c = out[size_t(i)].x, s = out[size_t(i)].y;
        deviceWorst = std::max({deviceWorst, ulpError(c, std::cos(a)), ulpError(s, std::sin(a))});
        float hc, hs;
        sinCos2Pi(t, hc, hs);
        apart = std::max({apart, double(std::fabs(c - hc)), double(std::fabs(s - hs))});
    }
    INFO("device: worst error " << deviceWorst << " ulp; largest difference from the host replica " << apart);
    CHECK(deviceWorst <= 2.0);
    CHECK(apart <= 2.4e-7);  // a fused multiply-add on the device: a few ulp of 1 at most
}
