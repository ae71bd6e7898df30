// Tests for the BVH builder (src/bvh/bvh.cpp) and the host reference intersection routines
// (src/bvh/host_intersect.h): structure of the flattened tree on random and degenerate inputs,
// the same tree bit for bit on any number of threads, closest/any hit through the BVH against
// brute force, watertightness of the triangle test on a closed mesh and on shared edges/vertices,
// and ray/sphere precision against a long-double reference. The 1M-triangle build timing is
// tagged [.perf] (run: test_bvh "[.perf]").
#include <catch.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "bvh/bvh.h"
#include "bvh/host_intersect.h"
#include "bvh_test_inputs.h"

using namespace clrt;

namespace {

using Tri = std::array<Vec3, 3>;
struct Ball {
    Vec3 c;
    float r;
};

// Primitive reference p < tris.size() is a triangle, else sphere p - tris.size() (as on the device).
struct Scene {
    std::vector<Tri> tris;
    std::vector<Ball> balls;
    std::vector<Aabb> bounds() const {
        std::vector<Aabb> b;
        for (const Tri& t : tris) {
            Aabb a;
            for (const Vec3& v : t) a.grow(v);
            b.push_back(a);
        }
        for (const Ball& s : balls) {
            Aabb a;
            a.grow(s.c - Vec3(s.r));
            a.grow(s.c + Vec3(s.r));
            b.push_back(a);
        }
        return b;
    }
    bool intersect(int prim, const Vec3& o, const Vec3& d, float tMax, float& t) const {
        float b1, b2;
        if (prim < int(tris.size())) {
            const Tri& tr = tris[size_t(prim)];
            return intersectTriangleWatertight(o, d, tr[0], tr[1], tr[2], tMax, t, b1, b2);
        }
        const Ball& s = balls[size_t(prim) - tris.size()];
        return intersectSphere(o, d, s.c, s.r, tMax, t);
    }
    int size() const { return int(tris.size() + balls.size()); }
};

struct HitRec {
    int prim = -1;
    float t = INFINITY;
};

HitRec bruteClosest(const Scene& s, const Vec3& o, const Vec3& d) {
    HitRec h;
    for (int p = 0; p < s.size(); ++p) {
        float t;
        if (s.intersect(p, o, d, h.t, t)) { h.t = t; h.prim = p; }
    }
    return h;
}

HitRec bvhClosest(const Bvh& bvh, const Scene& s, const Vec3& o, const Vec3& d) {
    HitRec h;
    traverseBvh(bvh, o, d, h.t, [&](int p, float& tMax) {
        float t;
        if (s.intersect(p, o, d, tMax, t)) { tMax = t; h.prim = p; }
    });
    return h;
}

bool bvhAny(const Bvh& bvh, const Scene& s, const Vec3& o, const Vec3& d, float tMax) {
    return anyHit(bvh, o, d, tMax, [&](int p, float tm) {
        float t;
        return s.intersect(p, o, d, tm, t);
    });
}

// Number of primitives the ray hits anywhere along (0, inf), found through the BVH.
int countAllHits(const Bvh& bvh, const Scene& s, const Vec3& o, const Vec3& d) {
    int n = 0;
    float tMax = INFINITY;
    traverseBvh(bvh, o, d, tMax, [&](int p, float& tm) {
        float t;
        if (s.intersect(p, o, d, tm, t)) ++n;
    });
    return n;
}

struct Rng {
    std::mt19937 gen;
    explicit Rng(unsigned seed) : gen(seed) {}
    float uni(float a = 0, float b = 1) { return std::uniform_real_distribution<float>(a, b)(gen); }
    float logUni(float a, float b) { return a * std::pow(b / a, uni()); }
    Vec3 inCube(float h) { return {uni(-h, h), uni(-h, h), uni(-h, h)}; }
    Vec3 unitVec() {
        for (;;) {
            Vec3 v = inCube(1);
            float l = length(v);
            if (l > 0.05f && l <= 1) return v / l;
        }
    }
};

bool inside(const Aabb& outer, const Vec3& lo, const Vec3& hi) {
    return outer.min.x <= lo.x && outer.min.y <= lo.y && outer.min.z <= lo.z && hi.x <= outer.max.x &&
           hi.y <= outer.max.y && hi.z <= outer.max.z;
}
double areaD(const Aabb& b) {  // in double: exponential test scenes overflow float areas
    double dx = double(b.max.x) - b.min.x, dy = double(b.max.y) - b.min.y, dz = double(b.max.z) - b.min.z;
    if (!(dx >= 0 && dy >= 0 && dz >= 0)) return 0;
    return 2 * (dx * dy + dy * dz + dz * dx);
}
Aabb nodeBox(const BvhNode& n) {
    Aabb a;
    a.min = {n.boundsMin.x, n.boundsMin.y, n.boundsMin.z};
    a.max = {n.boundsMax.x, n.boundsMax.y, n.boundsMax.z};
    return a;
}

// Checks every structural invariant of a built tree over `boxes`.
void checkStructure(const Bvh& bvh, const std::vector<Aabb>& boxes, int maxLeaf) {
    const int n = int(boxes.size());
    REQUIRE(bvh.primRefs.size() == boxes.size());
    REQUIRE(!bvh.nodes.empty());
    REQUIRE(bvh.depth >= 1);
    REQUIRE(bvh.depth <= CLRT_BVH_STACK_SIZE - 8);
    std::vector<int> seen(size_t(n), 0);
    // Pre-order walk, left first: must visit nodes 0, 1, 2, ... (depth-first flattening).
    std::vector<std::pair<int, int>> stack{{0, 1}};
    int expectNext = 0, maxDepth = 0, badChild = 0, badLeaf = 0, badBox = 0;
    double rootArea = areaD(nodeBox(bvh.nodes[0])), sah = 0;
    while (!stack.empty()) {
        auto [i, lvl] = stack.back();
        stack.pop_back();
        REQUIRE(i == expectNext);
        ++expectNext;
        maxDepth = std::max(maxDepth, lvl);
        const BvhNode& nd = bvh.nodes[size_t(i)];
        Aabb box = nodeBox(nd);
        double rel = rootArea > 0 ? areaD(box) / rootArea : 1.0;
        if (nd.count > 0) {
            sah += rel * nd.count;
            if (nd.count > maxLeaf || nd.first < 0 || nd.first + nd.count > n) { ++badLeaf; continue; }
            for (int k = nd.first; k < nd.first + nd.count; ++k) {
                int p = bvh.primRefs[size_t(k)];
                REQUIRE(p >= 0);
                REQUIRE(p < n);
                seen[size_t(p)]++;
                const Aabb& pb = boxes[size_t(p)];
                if (pb.valid() && isFinite(pb.min) && isFinite(pb.max) && !inside(box, pb.min, pb.max)) ++badBox;
            }
        } else {
            sah += rel;
            REQUIRE(nd.count == 0);
            REQUIRE(nd.axis >= 0);
            REQUIRE(nd.axis <= 2);
            int left = i + 1, right = nd.first;
            REQUIRE(right > left);
            REQUIRE(right < int(bvh.nodes.size()));
            for (int c : {left, right}) {
                Aabb cb = nodeBox(bvh.nodes[size_t(c)]);
                if (cb.valid() && !inside(box, cb.min, cb.max)) ++badChild;
            }
            stack.push_back({right, lvl + 1});
            stack.push_back({left, lvl + 1});
        }
    }
    CHECK(expectNext == int(bvh.nodes.size()));
    CHECK(maxDepth == bvh.depth);
    CHECK(badLeaf == 0);
    CHECK(badChild == 0);
    CHECK(badBox == 0);
    int wrongCount = 0;
    for (int c : seen) wrongCount += (c != 1);
    CHECK(wrongCount == 0);
    REQUIRE(std::isfinite(bvh.sahCost));
    CHECK(bvh.sahCost == Approx(sah).epsilon(1e-4));
}

Scene randomScene(Rng& rng, int numTris, int numBalls) {
    Scene s;
    for (int i = 0; i < numTris; ++i) {
        Vec3 c = rng.inCube(10);
        float size = rng.logUni(1e-3f, 5.f);
        Tri t{c + rng.inCube(size), c + rng.inCube(size), c + rng.inCube(size)};
        switch (i % 10) {
            case 0: t[2] = t[0] + (t[1] - t[0]) * 0.3f; break;  // collinear
            case 1: t[1] = t[2] = t[0]; break;                   // a point
            case 2: t[1].z = t[2].z = t[0].z; break;             // axis-aligned plane: flat box
            case 3: t[1].x = t[2].x = t[0].x; break;
            default: break;
        }
        s.tris.push_back(t);
    }
    for (int i = 0; i < numBalls; ++i) s.balls.push_back({rng.inCube(10), rng.logUni(1e-3f, 2.f)});
    return s;
}

// Rays through the scene: random, axis-aligned (zero direction components), aimed at vertices.
void randomRay(Rng& rng, const Scene& s, int i, Vec3& o, Vec3& d) {
    o = rng.inCube(12);
    switch (i % 5) {
        case 0: {
            d = Vec3(0);
            d[i % 3] = rng.uni() < 0.5f ? -1.f : 1.f;
            break;
        }
        case 1: {
            const Tri& t = s.tris[size_t(rng.gen() % s.tris.size())];
            d = t[rng.gen() % 3] - o;
            break;
        }
        case 2: {
            const Tri& t = s.tris[size_t(rng.gen() % s.tris.size())];
            d = (t[0] + t[1] + t[2]) * (1.f / 3) - o;
            break;
        }
        default: d = rng.unitVec() * rng.logUni(0.1f, 10.f); break;
    }
}

// An icosphere (subdivided icosahedron projected onto the sphere), consistently wound.
std::vector<Tri> icosphere(int levels, const Vec3& centre, float radius) {
    const float p = (1 + std::sqrt(5.f)) / 2;
    std::vector<Vec3> v = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                           {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
    std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                         {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (Vec3& x : v) x = normalize(x);
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<int, int>, int> mids;
        auto mid = [&](int a, int b) {
            auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = mids.find(key);
            if (it != mids.end()) return it->second;
            v.push_back(normalize(v[size_t(a)] + v[size_t(b)]));
            return mids[key] = int(v.size()) - 1;
        };
        std::vector<std::array<int, 3>> g;
        for (auto& t : f) {
            int a = mid(t[0], t[1]), b = mid(t[1], t[2]), c = mid(t[2], t[0]);
            g.push_back({t[0], a, c});
            g.push_back({t[1], b, a});
            g.push_back({t[2], c, b});
            g.push_back({a, b, c});
        }
        f.swap(g);
    }
    std::vector<Vec3> w;
    for (const Vec3& x : v) w.push_back(centre + x * radius);
    std::vector<Tri> tris;
    for (auto& t : f) tris.push_back({w[size_t(t[0])], w[size_t(t[1])], w[size_t(t[2])]});
    return tris;
}

// Long-double reference ray/sphere: nearest root in (0, inf) (or -1) and the distance from the
// centre to the ray's line.
struct SphereRef {
    double t = -1;
    double offset = 0;
};
SphereRef refSphere(const Vec3& o, const Vec3& d, const Vec3& c, float r) {
    long double f[3] = {(long double)o.x - c.x, (long double)o.y - c.y, (long double)o.z - c.z};
    long double dd[3] = {d.x, d.y, d.z};
    long double a = 0, b = 0, ff = 0;
    for (int k = 0; k < 3; ++k) { a += dd[k] * dd[k]; b += f[k] * dd[k]; ff += f[k] * f[k]; }
    SphereRef ref;
    ref.offset = double(std::sqrt(std::max((long double)0, ff - b * b / a)));
    long double cc = ff - (long double)r * r;
    long double disc = b * b - a * cc;
    if (disc < 0) return ref;
    long double q = -(b + std::copysign(std::sqrt(disc), b));
    long double t0 = q / a, t1 = cc / q;
    if (t0 > t1) std::swap(t0, t1);
    ref.t = t0 > 0 ? double(t0) : (t1 > 0 ? double(t1) : -1);
    return ref;
}

}  // namespace

TEST_CASE("BVH of an empty and of a one-primitive input", "[bvh]") {
    Bvh empty = buildBvh(std::vector<Aabb>{});
    REQUIRE(empty.nodes.size() == 1);
    CHECK(empty.primRefs.empty());
    int calls = 0;
    float tMax = INFINITY;
    traverseBvh(empty, Vec3(0), Vec3(1, 0, 0), tMax, [&](int, float&) { ++calls; });
    CHECK(calls == 0);

    Aabb a;
    a.grow(Vec3(1, 2, 3));
    a.grow(Vec3(2, 3, 4));
    Bvh one = buildBvh({a});
    REQUIRE(one.nodes.size() == 1);
    CHECK(one.nodes[0].count == 1);
    CHECK(one.primRefs == std::vector<int>{0});
    CHECK(one.nodes[0].boundsMin.x == 1.f);
    CHECK(one.nodes[0].boundsMax.z == 4.f);
    CHECK(one.sahCost == Approx(1.0));
}

TEST_CASE("BVH structure on random scenes", "[bvh]") {
    Rng rng(7);
    Scene s = randomScene(rng, 5000, 500);
    for (int leaf : {1, 4, 8}) {
        BvhBuildOptions o;
        o.maxLeafSize = leaf;
        auto boxes = s.bounds();
        Bvh bvh = buildBvh(boxes, o);
        INFO("maxLeafSize " << leaf);
        checkStructure(bvh, boxes, leaf);
        // SAH must beat one big leaf by far on 5500 scattered primitives.
        CHECK(bvh.sahCost < 0.02 * s.size());
    }
}

TEST_CASE("BVH build is the same on any number of threads", "[bvh]") {
    Rng rng(17);
    std::vector<Aabb> boxes(300000);
    for (Aabb& b : boxes) {
        Vec3 c = rng.inCube(50);
        b = Aabb();
        b.grow(c);
        b.grow(c + rng.inCube(rng.logUni(1e-3f, 1.f)));
    }
    BvhBuildOptions one, three;
    one.maxThreads = 1;
    three.maxThreads = 3;
    Bvh a = buildBvh(boxes, one), b = buildBvh(boxes, three);
    checkStructure(b, boxes, 4);
    REQUIRE(a.nodes.size() == b.nodes.size());
    CHECK(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(BvhNode)) == 0);
    CHECK(a.primRefs == b.primRefs);
    CHECK(a.depth == b.depth);
    CHECK(a.sahCost == b.sahCost);
}

TEST_CASE("BVH build is the same on any number of threads, degenerate inputs and options too", "[bvh]") {
    // Big enough for the parallel build: a far cluster (a lopsided root split), points with +0 and
    // -0 coordinates (min/max must pick the same zero whoever builds what), identical boxes,
    // non-finite and inverted boxes, and small random ones.
    Rng rng(23);
    std::vector<Aabb> boxes(200000);
    for (size_t i = 0; i < boxes.size(); ++i) {
        Aabb& b = boxes[i];
        switch (i % 8) {
            case 0: b.grow(Vec3(i % 16 ? 0.f : -0.f, rng.uni(-1, 1), i % 24 ? -0.f : 0.f)); break;
            case 1: b.grow(Vec3(1, 2, 3)); b.grow(Vec3(1, 2, 3.5f)); break;
            case 2:
                b.grow(rng.inCube(5));
                if (i % 48 == 2) b.min.y = std::numeric_limits<float>::quiet_NaN();
                if (i % 48 == 10) b.max.z = INFINITY;
                if (i % 48 == 18) b = Aabb();
                break;
            case 3: b.grow(Vec3(1e4f) + rng.inCube(1)); b.grow(Vec3(1e4f) + rng.inCube(1)); break;
            default: {
                Vec3 c = rng.inCube(20);
                b.grow(c);
                b.grow(c + rng.inCube(rng.logUni(1e-3f, 1.f)));
            }
        }
    }
    BvhBuildOptions plain, odd;
    odd.bins = 7;  // not a multiple of 4
    odd.maxLeafSize = 1;
    for (BvhBuildOptions o : {plain, odd}) {
        INFO("bins " << o.bins << ", maxLeafSize " << o.maxLeafSize);
        o.maxThreads = 1;
        Bvh ref = buildBvh(boxes, o);
        checkStructure(ref, boxes, o.maxLeafSize);
        for (int threads : {2, 3, 8}) {
            INFO(threads << " threads");
            o.maxThreads = threads;
            Bvh b = buildBvh(boxes, o);
            REQUIRE(b.nodes.size() == ref.nodes.size());
            CHECK(std::memcmp(b.nodes.data(), ref.nodes.data(), b.nodes.size() * sizeof(BvhNode)) == 0);
            CHECK(b.primRefs == ref.primRefs);
            CHECK(b.depth == ref.depth);
            CHECK(b.sahCost == ref.sahCost);
        }
    }
}

TEST_CASE("BVH structure on degenerate inputs", "[bvh]") {
    Rng rng(11);
    SECTION("identical boxes") {
        Aabb a;
        a.grow(Vec3(1, 1, 1));
        a.grow(Vec3(2, 3, 1));  // flat
        std::vector<Aabb> boxes(10000, a);
        Bvh bvh = buildBvh(boxes);
        checkStructure(bvh, boxes, 4);
    }
    SECTION("points, some coincident") {
        std::vector<Aabb> boxes;
        for (int i = 0; i < 20000; ++i) {
            Aabb a;
            a.grow(i % 3 == 0 ? Vec3(0.5f, 0.5f, 0.5f) : rng.inCube(1));
            boxes.push_back(a);
        }
        Bvh bvh = buildBvh(boxes);
        checkStructure(bvh, boxes, 4);
    }
    SECTION("collinear segments") {
        std::vector<Aabb> boxes;
        for (int i = 0; i < 5000; ++i) {
            Aabb a;
            float x = rng.uni(-3, 3);
            a.grow(Vec3(x, 2, -1));
            a.grow(Vec3(x + rng.uni(0, 0.01f), 2, -1));
            boxes.push_back(a);
        }
        Bvh bvh = buildBvh(boxes);
        checkStructure(bvh, boxes, 4);
    }
    SECTION("non-finite and inverted boxes are referenced once") {
        std::vector<Aabb> boxes;
        for (int i = 0; i < 1000; ++i) {
            Aabb a;
            a.grow(rng.inCube(5));
            a.grow(rng.inCube(5));
            if (i % 97 == 0) a.min.y = std::numeric_limits<float>::quiet_NaN();
            if (i % 89 == 0) a.max.x = INFINITY;
            if (i % 83 == 0) a = Aabb();  // inverted (default)
            boxes.push_back(a);
        }
        Bvh bvh = buildBvh(boxes);
        checkStructure(bvh, boxes, 4);
        for (const auto& nd : bvh.nodes) {
            CHECK(!std::isnan(nd.boundsMin.x + nd.boundsMin.y + nd.boundsMin.z));
            CHECK(!std::isnan(nd.boundsMax.x + nd.boundsMax.y + nd.boundsMax.z));
        }
    }
    SECTION("exponentially spaced primitives keep the depth bounded") {
        // Each primitive twice as far as the previous one (bvh_test_inputs.h).
        const std::vector<Aabb> boxes = test::exponentialBoxes();
        BvhBuildOptions o;
        o.maxLeafSize = 1;
        Bvh bvh = buildBvh(boxes, o);
        checkStructure(bvh, boxes, 1);
        std::printf("exponential input: depth %d\n", bvh.depth);
        CHECK(bvh.depth >= CLRT_BVH_STACK_SIZE - 12);  // adversarial indeed (balanced: 9 levels)
        CHECK(bvh.depth <= CLRT_BVH_STACK_SIZE - 8);

        // Triangles the same way (kept below 2^40: the float triangle test overflows for
        // triangles ~1e13 across): traversal finds each one.
        Scene sc;
        for (int i = -40; i < 40; ++i) {
            float x = std::ldexp(1.f, i), h = x * 1e-3f;
            sc.tris.push_back({Vec3(x, 0, 0), Vec3(x + h, h, 0), Vec3(x, h, h)});
        }
        Bvh tb = buildBvh(sc.bounds(), o);
        checkStructure(tb, sc.bounds(), 1);
        int mismatches = 0;
        for (const Tri& t : sc.tris) {
            Vec3 target = (t[0] + t[1] + t[2]) * (1.f / 3);
            Vec3 o2(target.x, target.y, target.z + 4 * t[1].y);
            Vec3 d(0, 0, -1);
            HitRec a = bvhClosest(tb, sc, o2, d), b = bruteClosest(sc, o2, d);
            mismatches += (a.prim != b.prim || a.t != b.t || b.prim < 0);
        }
        CHECK(mismatches == 0);
    }
}

TEST_CASE("BVH closest hit and any hit equal brute force", "[bvh]") {
    Rng rng(1234);
    Scene s = randomScene(rng, 3000, 300);
    Bvh bvh = buildBvh(s.bounds());
    int hits = 0, closestMismatch = 0, anyMismatch = 0;
    const int numRays = 4000;
    for (int i = 0; i < numRays; ++i) {
        Vec3 o, d;
        randomRay(rng, s, i, o, d);
        HitRec ref = bruteClosest(s, o, d), got = bvhClosest(bvh, s, o, d);
        // Same t; the primitive too, unless two primitives tie exactly.
        bool same = got.t == ref.t && (got.prim == ref.prim || ref.prim >= 0);
        if (!same) {
            ++closestMismatch;
            UNSCOPED_INFO("ray " << i << " ref " << ref.prim << " t=" << ref.t << " got " << got.prim
                                 << " t=" << got.t);
        }
        hits += ref.prim >= 0;
        // Any hit: found with an open bound; none strictly before the closest hit.
        bool anyInf = bvhAny(bvh, s, o, d, INFINITY);
        anyMismatch += anyInf != (ref.prim >= 0);
        if (ref.prim >= 0) {
            anyMismatch += bvhAny(bvh, s, o, d, ref.t);
            anyMismatch += !bvhAny(bvh, s, o, d, std::nextafter(ref.t, INFINITY));
        }
    }
    CHECK(closestMismatch == 0);
    CHECK(anyMismatch == 0);
    CHECK(hits > numRays / 4);  // the rays really test something
}

TEST_CASE("Watertight: rays from inside a closed icosphere never escape", "[bvh][watertight]") {
    Rng rng(99);
    const Vec3 centre(3.7f, -1.3f, 0.55f);
    Scene s;
    s.tris = icosphere(4, centre, 2.5f);  // 5120 triangles
    // Flip the winding of some triangles: the test must not depend on orientation.
    for (size_t i = 0; i < s.tris.size(); i += 3) std::swap(s.tris[i][1], s.tris[i][2]);
    Bvh bvh = buildBvh(s.bounds());
    checkStructure(bvh, s.bounds(), 4);

    int escaped = 0, notOnce = 0, total = 0;
    const int numRays = 100000;
    for (int i = 0; i < numRays; ++i) {
        Vec3 o = i % 4 == 0 ? centre : centre + rng.unitVec() * rng.uni(0, 1.5f);
        const Tri& t = s.tris[size_t(rng.gen() % s.tris.size())];
        Vec3 target;
        switch (i % 3) {
            case 0: target = t[rng.gen() % 3]; break;                              // a vertex
            case 1: target = (t[0] + t[1]) * 0.5f; break;                          // edge midpoint
            default: target = o + rng.unitVec(); break;                            // anywhere
        }
        Vec3 d = target - o;
        if (!(length(d) > 0)) continue;
        ++total;
        HitRec h = bvhClosest(bvh, s, o, d);
        escaped += h.prim < 0;
        // Convex closed surface, origin inside: exactly one crossing, counted once.
        notOnce += countAllHits(bvh, s, o, d) != 1;
    }
    CHECK(total > numRays * 9 / 10);
    CHECK(escaped == 0);
    CHECK(notOnce == 0);

    // A subset against brute force (counts all crossings without the BVH).
    int bruteNotOnce = 0;
    for (int i = 0; i < 300; ++i) {
        Vec3 o = centre;
        const Tri& t = s.tris[size_t(rng.gen() % s.tris.size())];
        Vec3 d = (i % 2 ? t[0] : (t[1] + t[2]) * 0.5f) - o;
        int n = 0;
        for (int p = 0; p < s.size(); ++p) {
            float th;
            n += s.intersect(p, o, d, INFINITY, th);
        }
        bruteNotOnce += n != 1;
    }
    CHECK(bruteNotOnce == 0);
}

TEST_CASE("Watertight: shared edges and vertices are hit exactly once", "[bvh][watertight]") {
    auto countHits = [](const std::vector<Tri>& ts, const Vec3& o, const Vec3& d) {
        int n = 0;
        for (const Tri& t : ts) {
            float th, b1, b2;
            n += intersectTriangleWatertight(o, d, t[0], t[1], t[2], INFINITY, th, b1, b2);
        }
        return n;
    };
    SECTION("axis-aligned square split along its diagonal") {
        Vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(0, 1, 0);
        std::vector<Tri> ts = {{a, b, c}, {a, c, d}};
        for (float s : {0.125f, 0.25f, 0.5f, 0.75f}) {
            CHECK(countHits(ts, Vec3(s, s, 1), Vec3(0, 0, -1)) == 1);
            CHECK(countHits(ts, Vec3(s, s, -1), Vec3(0, 0, 1)) == 1);
            CHECK(countHits(ts, Vec3(s - 1, s + 2, 4), Vec3(1, -2, -4)) == 1);  // oblique, exact
        }
        // Opposite winding on one triangle changes nothing.
        ts[1] = {a, d, c};
        CHECK(countHits(ts, Vec3(0.5f, 0.5f, 1), Vec3(0, 0, -1)) == 1);
        // A ray exactly along the shared edge's line, off the square: no hit.
        CHECK(countHits(ts, Vec3(2, 2, 1), Vec3(0, 0, -1)) == 0);
    }
    SECTION("fan of triangles around a vertex") {
        for (int n : {3, 4, 6, 7}) {
            std::vector<Tri> ts;
            for (int k = 0; k < n; ++k) {
                float a0 = 2 * float(M_PI) * k / n, a1 = 2 * float(M_PI) * (k + 1) / n;
                Vec3 p0(std::cos(a0), std::sin(a0), 0), p1(std::cos(a1), std::sin(a1), 0);
                if (k == n - 1) p1 = ts.empty() ? p1 : ts[0][1];
                ts.push_back({Vec3(0, 0, 0), p0, p1});
            }
            INFO("fan of " << n);
            CHECK(countHits(ts, Vec3(0, 0, 1), Vec3(0, 0, -1)) == 1);
            CHECK(countHits(ts, Vec3(0.3f, -0.2f, 2), Vec3(-0.3f, 0.2f, -2)) == 1);
            // Each spoke (shared edge) at its midpoint.
            for (const Tri& t : ts) {
                Vec3 m = t[1] * 0.5f;
                CHECK(countHits(ts, m + Vec3(0, 0, 1), Vec3(0, 0, -1)) == 1);
            }
        }
    }
    SECTION("random quads in space, rays through the shared diagonal") {
        Rng rng(5);
        int bad = 0;
        for (int q = 0; q < 200; ++q) {
            Vec3 p0 = rng.inCube(100), e1 = rng.inCube(10), e2 = rng.inCube(10);
            Vec3 p1 = p0 + e1, p2 = p0 + e1 + e2, p3 = p0 + e2;
            std::vector<Tri> ts = {{p0, p1, p2}, {p0, p2, p3}};
            if (q % 2) ts[0] = {p2, p1, p0};
            for (int r = 0; r < 100; ++r) {
                float s = rng.uni(0.05f, 0.95f);
                Vec3 target = p0 + (p2 - p0) * s, o = target + rng.inCube(50);
                Vec3 d = target - o;
                Vec3 n = cross(e1, e2);
                if (std::fabs(dot(normalize(n), normalize(d))) < 0.05f) continue;  // too grazing
                bad += countHits(ts, o, d) != 1;
            }
        }
        CHECK(bad == 0);
    }
}

TEST_CASE("Triangle test: barycentrics, t > 0 strictly, tMax exclusive", "[bvh]") {
    Vec3 v0(0, 0, 0), v1(2, 0, 0), v2(0, 2, 0);
    float t, b1, b2;
    REQUIRE(intersectTriangleWatertight(Vec3(0.5f, 0.25f, 3), Vec3(0, 0, -2), v0, v1, v2, INFINITY, t, b1, b2));
    CHECK(t == Approx(1.5));
    CHECK(b1 == Approx(0.25));
    CHECK(b2 == Approx(0.125));
    CHECK(!intersectTriangleWatertight(Vec3(0.5f, 0.25f, 3), Vec3(0, 0, -2), v0, v1, v2, 1.5f, t, b1, b2));
    CHECK(!intersectTriangleWatertight(Vec3(0.5f, 0.25f, 3), Vec3(0, 0, 2), v0, v1, v2, INFINITY, t, b1, b2));
    CHECK(!intersectTriangleWatertight(Vec3(0.5f, 0.25f, 0), Vec3(0, 0, 1), v0, v1, v2, INFINITY, t, b1, b2));
    CHECK(!intersectTriangleWatertight(Vec3(3, 3, 1), Vec3(0, 0, -1), v0, v1, v2, INFINITY, t, b1, b2));
    CHECK(!intersectTriangleWatertight(Vec3(0.5f, 0.25f, 3), Vec3(0, 0, 0), v0, v1, v2, INFINITY, t, b1, b2));
    // Degenerate (collinear) triangle: never hit.
    CHECK(!intersectTriangleWatertight(Vec3(1, 0, 1), Vec3(0, 0, -1), v0, v1, Vec3(1, 0, 0), INFINITY, t, b1, b2));
}

TEST_CASE("Sphere test against a long-double reference", "[bvh][sphere]") {
    Rng rng(42);
    // Float inputs are exact, but a float algorithm still rounds at the problem's scale
    // S = |o - c| + r: hit/miss is only asked where the ray's line passes farther than 64 ulps of S
    // (or 1e-4 r) from the silhouette, and t must be within 4 ulps of S times the grazing
    // amplification 1 + r / sqrt(r^2 - offset^2) (over |dir|). The naive b^2 - c form fails both
    // for the tiny sphere.
    const double eps = FLT_EPSILON;
    struct Case {
        const char* name;
        float r, distLo, distHi;
    };
    for (Case cs : {Case{"tiny", 1e-4f, 1e-3f, 10.f}, Case{"unit", 1.f, 1.01f, 100.f},
                    Case{"huge", 1e6f, 1e6f + 1.f, 1.1e6f}}) {
        INFO(cs.name);
        int wrongHit = 0, wrongMiss = 0, badT = 0, hits = 0;
        double worst = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3 c = rng.inCube(cs.r < 10 ? 5.f : 1e3f);
            Vec3 o = c + rng.unitVec() * rng.logUni(cs.distLo, cs.distHi);
            if (i % 10 == 0) o = c + rng.unitVec() * (cs.r * rng.uni(0, 0.9f));  // inside
            // Aim at a point off the centre by a fraction of r: < 1 hits, > 1 misses, ~1 grazes.
            float frac = i % 4 == 0 ? rng.uni(0.999f, 0.99999f) : rng.uni(0, 1.5f);
            Vec3 toC = normalize(c - o), side = normalize(cross(toC, rng.unitVec()));
            Vec3 target = c + side * (cs.r * frac);
            Vec3 d = (target - o) * rng.logUni(0.01f, 100.f);
            if (!(length(d) > 0)) continue;  // target rounded onto the origin
            SphereRef ref = refSphere(o, d, c, cs.r);
            float t = -1;
            bool hit = intersectSphere(o, d, c, cs.r, INFINITY, t);
            double r = cs.r, scale = length(o - c) + r;
            double margin = std::max(1e-4 * r, 64 * eps * scale);
            if (ref.offset < r - margin && ref.t > 0 && !hit) ++wrongMiss;
            if (ref.offset > r + margin && hit) ++wrongHit;
            if (hit && ref.t > 0) {
                ++hits;
                double sinGraze = std::sqrt(std::max(1 - (ref.offset / r) * (ref.offset / r), 1e-12));
                double err = std::fabs(t - ref.t) * length(d) / (4 * eps * scale * (1 + 1 / sinGraze));
                worst = std::max(worst, err);
                badT += err > 1;
            }
        }
        CHECK(wrongMiss == 0);
        CHECK(wrongHit == 0);
        CHECK(badT == 0);
        CHECK(hits > 5000);
        std::printf("sphere %-5s worst t error %.3f of the bound\n", cs.name, worst);
    }
    // tMax is exclusive; a sphere behind the origin is a miss.
    float t = -1;
    CHECK(intersectSphere(Vec3(0, 0, 5), Vec3(0, 0, -1), Vec3(0), 1, INFINITY, t));
    CHECK(t == Approx(4));
    CHECK(!intersectSphere(Vec3(0, 0, 5), Vec3(0, 0, -1), Vec3(0), 1, 4, t));
    CHECK(!intersectSphere(Vec3(0, 0, 5), Vec3(0, 0, 1), Vec3(0), 1, INFINITY, t));
    CHECK(intersectSphere(Vec3(0, 0, 0.5f), Vec3(0, 0, 1), Vec3(0), 1, INFINITY, t));
    CHECK(t == Approx(0.5));
}

TEST_CASE("BVH build time for 1M random triangles", "[.perf][bvh]") {
    Rng rng(3);
    std::vector<Aabb> boxes(1000000);
    for (Aabb& b : boxes) {
        Vec3 c = rng.inCube(100);
        float s = rng.logUni(0.01f, 1.f);
        b = Aabb();
        for (int k = 0; k < 3; ++k) b.grow(c + rng.inCube(s));
    }
    auto t0 = std::chrono::steady_clock::now();
    Bvh bvh = buildBvh(boxes);
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("buildBvh: 1M triangles in %.3f s, %zu nodes, depth %d, SAH cost %.2f\n", secs,
                bvh.nodes.size(), bvh.depth, bvh.sahCost);
    CHECK(bvh.primRefs.size() == boxes.size());
}
