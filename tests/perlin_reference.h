// perlin_reference.h — the host reference of the course's Perlin noise (cl_kernels/textures.cl,
// Perlin_Noise): the 16 gradients and permutation of src/shared, weight 1 − 6|t|⁵ + 15|t|⁴ − 10|t|³,
// in double precision. Read by tests/test_hw4.cpp and tests/test_textures.cpp.
#pragma once
#include <cmath>
#include <cstdlib>

#include "shared/device_types.h"

namespace clrt::test {

inline double perlinNoise(double x, double y, double z) {
    static const int kPerm[16] = {CLRT_PERLIN_PERM_VALUES};
    static const float kGrad[16][3] = {CLRT_PERLIN_GRAD_VALUES};
    double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z), sum = 0;
    auto w = [](double t) {
        t = std::fabs(t);
        return t >= 1 ? 0.0 : 1 - 6 * std::pow(t, 5) + 15 * std::pow(t, 4) - 10 * std::pow(t, 3);
    };
    for (int c = 0; c < 8; ++c) {
        int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
        int i = int(fx) + dx, j = int(fy) + dy, k = int(fz) + dz;
        int g = kPerm[std::abs(i + kPerm[std::abs(j + kPerm[std::abs(k) % 16]) % 16]) % 16];
        double vx = x - (fx + dx), vy = y - (fy + dy), vz = z - (fz + dz);
        sum += w(vx) * w(vy) * w(vz) * (kGrad[g][0] * vx + kGrad[g][1] * vy + kGrad[g][2] * vz);
    }
    return sum;
}

}  // namespace clrt::test
