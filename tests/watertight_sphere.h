// A closed triangulated sphere and 100,000 rays from inside it, many aimed exactly at its vertices and at
// points on its edges: a watertight triangle test lets none of them escape. Used by tests/test_robustness.cpp
// (clrt's device test) and bench/embree_watertight.cpp (the same rays through Embree's two modes).
#pragma once
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "shared/device_types.h"
#include "util/math.h"

namespace clrt {
namespace test {

struct WatertightCase {
    std::vector<Vec3> vertices;       // the icosphere's shared vertices
    std::vector<int> indices;         // three per triangle
    std::vector<dev::Triangle> tris;  // the same triangles, as the device stores them
    std::vector<dev::Ray> rays;       // tMax infinite
};

// An icosahedron subdivided `levels` times, projected onto the sphere (centre c, radius r), vertices shared.
inline void icosphere(int levels, const Vec3& c, float r, WatertightCase& out) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    std::vector<Vec3> dirs = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<int> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6,
                          7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (Vec3& d : dirs) d = normalize(d);
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<int, int>, int> mid;
        auto midpoint = [&](int a, int b) {
            auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            dirs.push_back(normalize(dirs[a] + dirs[b]));
            return mid[key] = int(dirs.size()) - 1;
        };
        std::vector<int> nf;
        for (size_t i = 0; i < f.size(); i += 3) {
            int a = f[i], b = f[i + 1], cc = f[i + 2];
            int ab = midpoint(a, b), bc = midpoint(b, cc), ca = midpoint(cc, a);
            nf.insert(nf.end(), {a, ab, ca, b, bc, ab, cc, ca, bc, ab, bc, ca});
        }
        f.swap(nf);
    }
    out.vertices.clear();
    for (const Vec3& d : dirs) out.vertices.push_back(c + d * r);
    out.indices = f;
}

// The sphere of 3 subdivisions (1280 triangles, 642 vertices) and its rays: from the centre and from random
// inside points exactly at every vertex; at edge points (midpoints, quarter and third points rounded to
// float: on or beside the edge); then random directions, some axis-aligned (zero direction components).
inline WatertightCase watertightSphere(const Vec3& centre, float radius) {
    WatertightCase wc;
    icosphere(3, centre, radius, wc);
    const std::vector<Vec3>& v = wc.vertices;
    const std::vector<int>& idx = wc.indices;
    auto f4 = [](const Vec3& p, float w) { return dev::float4{p.x, p.y, p.z, w}; };
    for (size_t i = 0; i < idx.size(); i += 3) wc.tris.push_back({f4(v[idx[i]], 0), f4(v[idx[i + 1]], 0), f4(v[idx[i + 2]], 0)});
    auto ray = [&](const Vec3& o, const Vec3& d) { return dev::Ray{f4(o, 0), f4(d, INFINITY)}; };
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    auto insidePoint = [&]() {
        for (;;) {
            Vec3 p(u(rng), u(rng), u(rng));
            if (length(p) < 0.85f) return centre + p * radius;
        }
    };
    std::vector<dev::Ray>& rays = wc.rays;
    const size_t total = 100000;
    for (const Vec3& p : v) {
        rays.push_back(ray(centre, p - centre));
        Vec3 o = insidePoint();
        rays.push_back(ray(o, p - o));
    }
    for (size_t i = 0; i < idx.size() && rays.size() < total / 2; i += 3)
        for (int e = 0; e < 3; ++e) {
            const Vec3& a = v[idx[i + e]];
            const Vec3& b = v[idx[i + (e + 1) % 3]];
            for (float s : {0.5f, 0.25f, 1.0f / 3.0f}) {
                Vec3 target = a + (b - a) * s;
                Vec3 o = (e == 0) ? centre : insidePoint();
                rays.push_back(ray(o, target - o));
            }
        }
    while (rays.size() < total) {
        Vec3 o = rays.size() % 7 == 0 ? centre : insidePoint();
        Vec3 d(u(rng), u(rng), u(rng));
        if (rays.size() % 11 == 0) d = Vec3(0, 0, rays.size() % 2 ? 1.f : -1.f);
        if (rays.size() % 13 == 0) d = Vec3(1, -1, 0);
        rays.push_back(ray(o, d));
    }
    return wc;
}

}  // namespace test
}  // namespace clrt
