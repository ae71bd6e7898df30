// Inputs shared by the BVH tests (test_bvh.cpp, test_bvh8.cpp).
#pragma once
#include <cmath>
#include <vector>

#include "bvh/bvh.h"

namespace clrt::test {

// Boxes of 241 primitives each twice as far along x as the previous one (2^-120 .. 2^120, each 1e-3 of its
// distance across): binned SAH peels them off one or two at a time, a chain far deeper than the device stack
// unless the builder's depth cap steps in.
inline std::vector<Aabb> exponentialBoxes() {
    std::vector<Aabb> boxes;
    for (int i = -120; i <= 120; ++i) {
        const float x = std::ldexp(1.f, i);
        Aabb b;
        b.grow(Vec3(x, 0, 0));
        b.grow(Vec3(x, 0, 0) + Vec3(x * 1e-3f));
        boxes.push_back(b);
    }
    return boxes;
}

}  // namespace clrt::test
