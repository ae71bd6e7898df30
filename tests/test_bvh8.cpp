// Tests for the binary -> 8-wide BVH collapse (src/bvh/bvh8.cpp) and the device's 8-wide traversal
// (Bvh_Traverse in cl_kernels/intersect.cl): structure of the collapsed tree (every primitive in
// exactly one leaf lane, lanes inside their parent, empty lanes never hit), the traversal stack bound
// the host computes (a host replica of the kernel's traversal never exceeds it; the kernel compiled
// with exactly that stack finds what brute force finds on a deep tree built to fill its stack), and
// the limits of the leaf packing, and the device's four-wide leaf blocks against brute force on degenerate
// inputs (empty, one triangle, a coplanar grid hit through shared edges and vertices, huge coordinates).
#include <catch.hpp>

#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "bvh/bvh.h"
#include "bvh/bvh8.h"
#include "bvh/host_intersect.h"
#include "bvh_test_inputs.h"
#include "cl/check.h"
#include "cl/kernel_args.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

using Tri = std::array<Vec3, 3>;

std::vector<Aabb> triBoxes(const std::vector<Tri>& tris) {
    std::vector<Aabb> boxes;
    for (const Tri& t : tris) {
        Aabb b;
        for (const Vec3& v : t) b.grow(v);
        boxes.push_back(b);
    }
    return boxes;
}

int lane(const dev::int4& v, int i) { return (&v.x)[i]; }

// Lane i's box in node nd (bvh8.h's lanePlane).
Aabb laneBox(const dev::Bvh8Node& nd, int i) {
    Aabb box;
    box.min = Vec3(lanePlane(nd, 0, i), lanePlane(nd, 2, i), lanePlane(nd, 4, i));
    box.max = Vec3(lanePlane(nd, 1, i), lanePlane(nd, 3, i), lanePlane(nd, 5, i));
    return box;
}

// Walks the 8-wide tree from the root: every node reached once, every leaf block owned by one leaf
// lane, every primitive in exactly one leaf lane's blocks (and lanes past a leaf's end empty), every lane's box inside the box its parent lane gave, empty lanes marked
// and last, the other lanes ordered by area, largest first (the order shadow rays visit them in).
void checkStructure8(const Bvh& bin, const Bvh8& b8, const std::vector<Aabb>& boxes) {
    const int n = int(bin.primRefs.size());
    std::vector<int> covered(size_t(n), 0), reached(b8.nodes.size(), 0), blockUse(b8.leaves.size(), 0);
    int badBox = 0, badEmpty = 0, badChild = 0, badOrder = 0, maxLevel = 0;
    struct Item { int node, level; Aabb box; };
    Aabb all;
    all.min = Vec3(-INFINITY); all.max = Vec3(INFINITY);
    std::vector<Item> stack{{0, 1, all}};
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        REQUIRE(it.node >= 0);
        REQUIRE(it.node < int(b8.nodes.size()));
        reached[size_t(it.node)]++;
        maxLevel = std::max(maxLevel, it.level);
        const dev::Bvh8Node& nd = b8.nodes[size_t(it.node)];
        double lastArea = INFINITY;
        bool seenEmpty = false;
        for (int i = 0; i < kBvhWidth; ++i) {
            const int entry = laneEntry(nd, i);
            const bool leaf = isLeafEntry(entry);
            const int child = leaf ? leafFirstBlock(entry) : entry, count = leaf ? leafCount(entry) : 0;
            const Aabb box = laneBox(nd, i);
            if (entry != CLRT_INVALID) {
                const double dx = double(box.max.x) - box.min.x, dy = double(box.max.y) - box.min.y,
                             dz = double(box.max.z) - box.min.z;
                double area = dx >= 0 && dy >= 0 && dz >= 0 ? dx * dy + dy * dz + dz * dx : 0;
                if (!(area >= 0)) area = 0;
                badOrder += seenEmpty || area > lastArea;
                lastArea = area;
            }
            seenEmpty = seenEmpty || entry == CLRT_INVALID;
            if (entry == CLRT_INVALID) {
                badEmpty += !(box.min.x == INFINITY && box.max.x == -INFINITY && box.min.y == INFINITY &&
                              box.max.y == -INFINITY && box.min.z == INFINITY && box.max.z == -INFINITY);
                continue;
            }
            if (entry < 0 && !leaf) { ++badChild; continue; }  // an instance's form, in a tree without them
            const bool valid = box.valid();
            if (valid && it.box.valid() &&
                !(it.box.min.x <= box.min.x && it.box.min.y <= box.min.y && it.box.min.z <= box.min.z &&
                  box.max.x <= it.box.max.x && box.max.y <= it.box.max.y && box.max.z <= it.box.max.z))
                ++badBox;
            if (count > 0) {
                const int blocks = (count + 3) / 4;
                if (child < 0 || child + blocks > int(b8.leaves.size())) { ++badChild; continue; }
                for (int k = 0; k < 4 * blocks; ++k) {
                    const int ref = lane(b8.leaves[size_t(child + k / 4)].prim, k % 4);
                    if (k % 4 == 0) blockUse[size_t(child + k / 4)]++;
                    if (k >= count) { badEmpty += ref != CLRT_INVALID; continue; }
                    if (ref < 0 || ref >= n) { ++badChild; continue; }
                    covered[size_t(ref)]++;
                    const Aabb& pb = boxes[size_t(ref)];
                    if (pb.valid() && isFinite(pb.min) && isFinite(pb.max) &&
                        !(box.min.x <= pb.min.x && box.min.y <= pb.min.y && box.min.z <= pb.min.z &&
                          pb.max.x <= box.max.x && pb.max.y <= box.max.y && pb.max.z <= box.max.z))
                        ++badBox;
                }
            } else {
                if (child <= it.node) { ++badChild; continue; }  // children after parents
                stack.push_back({child, it.level + 1, box});
            }
        }
    }
    int wrongCover = 0, wrongReach = 0;
    for (int c : covered) wrongCover += (c != 1);
    for (int r : reached) wrongReach += (r != 1);
    for (int u : blockUse) wrongReach += (u != 1);  // every leaf block belongs to exactly one leaf lane
    CHECK(wrongCover == 0);
    CHECK(wrongReach == 0);
    CHECK(badBox == 0);
    CHECK(badEmpty == 0);
    CHECK(badChild == 0);
    CHECK(badOrder == 0);
    CHECK(maxLevel == b8.depth);
    CHECK(b8.depth <= bin.depth);
    CHECK(b8.maxStack <= CLRT_BVH8_STACK_SIZE);
    // Collapsing opens about one binary level in two.
    if (n > 1000) CHECK(b8.nodes.size() < bin.nodes.size() / 2);
}

// Host replica of the kernel's traversal (same near/far plane choice, fmin/fmax NaN handling, sorted
// pushes, culling on pop). Returns the closest primitive (-1: none) and the deepest stack it used.
struct Trace8 { int prim = -1; float t = INFINITY; int maxSp = 0; };
Trace8 traverse8(const Bvh& bin, const Bvh8& b8, const std::vector<Tri>& tris, Vec3 o, Vec3 d, float tMax) {
    Trace8 r;
    Vec3 inv(1 / d.x, 1 / d.y, 1 / d.z);
    std::vector<std::pair<float, int>> stack;
    int entry = 0;
    for (;;) {
        if (entry >= 0) {
            const dev::Bvh8Node& nd = b8.nodes[size_t(entry)];
            std::vector<std::pair<float, int>> hits;
            for (int i = 0; i < kBvhWidth; ++i) {
                const float lo[3] = {lanePlane(nd, 0, i), lanePlane(nd, 2, i), lanePlane(nd, 4, i)};
                const float hi[3] = {lanePlane(nd, 1, i), lanePlane(nd, 3, i), lanePlane(nd, 5, i)};
                float tEnter = 0, tExit = INFINITY;
                for (int a = 0; a < 3; ++a) {
                    const bool neg = std::signbit(inv[a]);
                    float tn = ((neg ? hi[a] : lo[a]) - o[a]) * inv[a];
                    float tf = ((neg ? lo[a] : hi[a]) - o[a]) * inv[a];
                    tEnter = std::fmax(tEnter, tn);
                    tExit = std::fmin(tExit, tf);
                }
                tExit = std::fmin(tExit * 1.0000004f, tMax * 1.0000004f);  // CLRT_SLAB_WIDEN, both
                if (!(tEnter <= tExit)) continue;
                hits.push_back({std::fmin(tEnter, FLT_MAX), laneEntry(nd, i)});
            }
            if (!hits.empty()) {
                std::stable_sort(hits.begin(), hits.end(),
                                 [](auto& a, auto& b) { return a.first < b.first; });
                for (size_t k = hits.size() - 1; k >= 1; --k) stack.push_back(hits[k]);
                r.maxSp = std::max(r.maxSp, int(stack.size()));
                entry = hits[0].second;
                continue;
            }
        } else {
            const int first = (~entry) >> 4, count = (~entry) & 15;
            for (int k = 0; k < count; ++k) {
                const int p = lane(b8.leaves[size_t(first + k / 4)].prim, k % 4);
                float t, b1, b2;
                if (intersectTriangleWatertight(o, d, tris[size_t(p)][0], tris[size_t(p)][1], tris[size_t(p)][2],
                                                tMax, t, b1, b2)) {
                    tMax = t;
                    r.prim = p;
                    r.t = t;
                }
            }
        }
        bool next = false;
        while (!stack.empty()) {
            auto e = stack.back();
            stack.pop_back();
            if (e.first <= tMax * 1.0000004f) { entry = e.second; next = true; break; }
        }
        if (!next) return r;
    }
}

// A stack of big triangles, each twice the size of the one below, all over the z axis: a ray from
// near the origin going up passes through every box, so the traversal pushes at every level.
// The closest triangle along (o, d) by testing every one (the reference the traversals are held to);
// -1 when none is hit, its distance in *tBest (INFINITY then).
int bruteClosest(const std::vector<Tri>& tris, Vec3 o, Vec3 d, float* tBest) {
    int best = -1;
    *tBest = INFINITY;
    for (size_t k = 0; k < tris.size(); ++k) {
        float tt, b1, b2;
        if (intersectTriangleWatertight(o, d, tris[k][0], tris[k][1], tris[k][2], *tBest, tt, b1, b2)) {
            *tBest = tt;
            best = int(k);
        }
    }
    return best;
}

std::vector<Tri> towerScene(int levels) {
    std::vector<Tri> tris;
    for (int i = -levels / 2; i < levels - levels / 2; ++i) {
        const float s = std::ldexp(1.f, i);
        tris.push_back({Vec3(-3 * s, -3 * s, s), Vec3(3 * s, -3 * s, s * 1.25f), Vec3(0, 3 * s, s * 1.5f)});
    }
    return tris;
}

}  // namespace

TEST_CASE("BVH8 of an empty and of a one-primitive input", "[bvh8]") {
    Bvh8 empty = collapseBvh8(buildBvh(std::vector<Aabb>{}));
    REQUIRE(empty.nodes.size() == 1);
    for (int i = 0; i < kBvhWidth; ++i) {
        CHECK(laneEntry(empty.nodes[0], i) == CLRT_INVALID);
        CHECK(lanePlane(empty.nodes[0], 0, i) == INFINITY);
        CHECK(lanePlane(empty.nodes[0], 5, i) == -INFINITY);
    }
    CHECK(empty.maxStack == 0);

    Aabb a;
    a.grow(Vec3(1, 2, 3));
    a.grow(Vec3(2, 3, 4));
    Bvh one = buildBvh({a});
    Bvh8 one8 = collapseBvh8(one);
    REQUIRE(one8.nodes.size() == 1);
    CHECK(laneEntry(one8.nodes[0], 0) == leafEntry(0, 1));
    CHECK(lanePlane(one8.nodes[0], 2, 0) == 2.f);  // minY
    CHECK(lanePlane(one8.nodes[0], 5, 0) == 4.f);  // maxZ
    for (int i = 1; i < kBvhWidth; ++i) CHECK(laneEntry(one8.nodes[0], i) == CLRT_INVALID);
    CHECK(one8.maxStack == 0);
}

TEST_CASE("BVH8 structure on random, degenerate and deep trees", "[bvh8]") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> pos(-10, 10), unit(-1, 1);
    SECTION("random triangles, leaves of 1, 4 and 15") {
        std::vector<Tri> tris;
        for (int i = 0; i < 20000; ++i) {
            Vec3 c(pos(rng), pos(rng), pos(rng));
            float s = std::exp(unit(rng) * 3);
            tris.push_back({c, c + Vec3(unit(rng), unit(rng), unit(rng)) * s, c + Vec3(unit(rng), unit(rng), unit(rng)) * s});
        }
        for (int leaf : {1, 4, 15}) {
            BvhBuildOptions o;
            o.maxLeafSize = leaf;
            auto boxes = triBoxes(tris);
            Bvh bin = buildBvh(boxes, o);
            Bvh8 b8 = collapseBvh8(bin);
            INFO("maxLeafSize " << leaf);
            checkStructure8(bin, b8, boxes);
        }
    }
    SECTION("identical and non-finite boxes") {
        std::vector<Aabb> boxes(5000);
        for (size_t i = 0; i < boxes.size(); ++i) {
            boxes[i].grow(Vec3(1, 1, 1));
            boxes[i].grow(Vec3(2, 2, 1));
            if (i % 7 == 0) boxes[i].min.x = NAN;
        }
        Bvh bin = buildBvh(boxes);
        checkStructure8(bin, collapseBvh8(bin), boxes);
    }
    SECTION("the builder's deepest trees stay within the default stack") {
        // Exponentially spaced primitives (bvh_test_inputs.h): the binary builder's depth cap is what keeps
        // this chain finite (see test_bvh.cpp); the collapsed tree's stack need must still fit.
        const std::vector<Aabb> boxes = exponentialBoxes();
        BvhBuildOptions o;
        o.maxLeafSize = 1;
        Bvh bin = buildBvh(boxes, o);
        Bvh8 b8 = collapseBvh8(bin);
        checkStructure8(bin, b8, boxes);
        std::printf("exponential input: binary depth %d, 8-wide depth %d, stack need %d (default %d)\n", bin.depth,
                    b8.depth, b8.maxStack, CLRT_BVH8_STACK_SIZE);
    }
}

TEST_CASE("BVH8 near the leaves: the nodes of least area, not the largest box opened first", "[bvh8]") {
    // Unit boxes in a row, one per leaf: the binary tree is balanced (SAH splits in the middle). Opening the
    // largest box first gives 16 boxes a root over 8 pairs and 8 nodes of two lanes (9 nodes); the least area
    // takes one half as a node of 8 leaves, and the other in 7 lanes (4 leaves, 2 leaves, a pair's node): 3.
    for (int n : {16, 32, 64}) {
        std::vector<Aabb> boxes(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) {
            boxes[size_t(i)].grow(Vec3(2.0f * float(i), 0, 0));
            boxes[size_t(i)].grow(Vec3(2.0f * float(i) + 1, 1, 1));
        }
        BvhBuildOptions o;
        o.maxLeafSize = 1;
        Bvh bin = buildBvh(boxes, o);
        Bvh8 b8 = collapseBvh8(bin);
        INFO(n << " boxes");
        checkStructure8(bin, b8, boxes);
        const size_t fewest = size_t(n - 1 + 6) / 7;  // each node adds at most 7 lanes to the root's one
        std::printf("%d boxes in a row: %zu 8-wide nodes (fewest possible %zu)\n", n, b8.nodes.size(), fewest);
        CHECK(b8.nodes.size() == fewest);  // the greedy opening: 9, 9 and 9
    }
}

// Walks two 8-wide trees from their roots in lane order: the same boxes (bit for bit), counts and leaf
// primitives at every node, wherever each tree keeps its nodes and blocks. Returns the nodes compared.
size_t sameTree8(const Bvh8& a, int na, const Bvh8& b, int nb) {
    const dev::Bvh8Node &x = a.nodes[size_t(na)], &y = b.nodes[size_t(nb)];
    REQUIRE(std::memcmp(&x.planes, &y.planes, sizeof x.planes) == 0);
    size_t compared = 1;
    for (int i = 0; i < kBvhWidth; ++i) {
        const int ex = laneEntry(x, i), ey = laneEntry(y, i);
        REQUIRE((ex == CLRT_INVALID) == (ey == CLRT_INVALID));
        if (ex == CLRT_INVALID) continue;
        REQUIRE(isLeafEntry(ex) == isLeafEntry(ey));
        if (!isLeafEntry(ex)) {
            compared += sameTree8(a, ex, b, ey);
            continue;
        }
        const int count = leafCount(ex), cx = leafFirstBlock(ex), cy = leafFirstBlock(ey);
        REQUIRE(count == leafCount(ey));
        for (int k = 0; k < (count + 3) / 4; ++k)
            REQUIRE(std::memcmp(&a.leaves[size_t(cx + k)].prim, &b.leaves[size_t(cy + k)].prim, sizeof(dev::int4)) == 0);
    }
    return compared;
}

TEST_CASE("BVH8 of a big tree, split over threads or in one pass: the same tree", "[bvh8]") {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> pos(-10, 10), unit(-1, 1);
    std::vector<Tri> tris;
    for (int i = 0; i < 60000; ++i) {
        Vec3 c(pos(rng), pos(rng), pos(rng));
        tris.push_back({c, c + Vec3(unit(rng), unit(rng), unit(rng)) * 0.3f, c + Vec3(unit(rng), unit(rng), unit(rng)) * 0.3f});
    }
    const auto boxes = triBoxes(tris);
    const Bvh bin = buildBvh(boxes);
    const Bvh8 onePass = collapseBvh8(bin, SIZE_MAX);
    for (size_t split : {size_t(1), size_t(1000), kCollapseSplitNodes}) {
        INFO("splitNodes " << split);
        const Bvh8 b8 = collapseBvh8(bin, split);
        checkStructure8(bin, b8, boxes);
        REQUIRE(b8.nodes.size() == onePass.nodes.size());
        REQUIRE(b8.leaves.size() == onePass.leaves.size());
        CHECK(sameTree8(b8, 0, onePass, 0) == onePass.nodes.size());
        CHECK(b8.maxStack == onePass.maxStack);
        CHECK(b8.depth == onePass.depth);
        if (split < bin.nodes.size())  // split: laid out otherwise (top first), else byte for byte the same
            CHECK(std::memcmp(b8.nodes.data(), onePass.nodes.data(), b8.nodes.size() * sizeof(dev::Bvh8Node)) != 0);
        else
            CHECK(std::memcmp(b8.nodes.data(), onePass.nodes.data(), b8.nodes.size() * sizeof(dev::Bvh8Node)) == 0);
    }
}

TEST_CASE("BVH8 appended after another tree equals its own collapse moved by the arrays before it", "[bvh8]") {
    // appendBvh8 (the two-level BVH's bottom levels, flatten_instances.cpp) writes a tree into arrays
    // that already hold one: node for node it must be collapseBvh8's, interior children moved by the
    // nodes before it, leaf children by the blocks before it, primitives by primOffset.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> pos(-10, 10), unit(-1, 1);
    auto soup = [&](int n) {
        std::vector<Tri> tris;
        for (int i = 0; i < n; ++i) {
            Vec3 c(pos(rng), pos(rng), pos(rng));
            tris.push_back({c, c + Vec3(unit(rng), unit(rng), unit(rng)), c + Vec3(unit(rng), unit(rng), unit(rng))});
        }
        return triBoxes(tris);
    };
    const std::vector<Aabb> first = soup(3000), second = soup(5000);
    Bvh8 into = collapseBvh8(buildBvh(first));
    const Bvh8 before = into;
    const Bvh8 alone = collapseBvh8(buildBvh(second));
    const int primOffset = 3000;
    int stack = -1;
    const int root = appendBvh8(buildBvh(second), primOffset, into, &stack);
    REQUIRE(root == int(before.nodes.size()));
    CHECK(stack == alone.maxStack);
    CHECK((into.maxStack == before.maxStack && into.depth == before.depth));
    REQUIRE(into.nodes.size() == before.nodes.size() + alone.nodes.size());
    REQUIRE(into.leaves.size() == before.leaves.size() + alone.leaves.size());
    for (size_t n = 0; n < before.nodes.size(); ++n) CHECK(std::memcmp(&into.nodes[n], &before.nodes[n], sizeof(dev::Bvh8Node)) == 0);
    for (size_t l = 0; l < before.leaves.size(); ++l) CHECK(std::memcmp(&into.leaves[l], &before.leaves[l], sizeof(dev::LeafBlock)) == 0);
    int mismatches = 0;
    for (size_t n = 0; n < alone.nodes.size(); ++n) {
        dev::Bvh8Node want = alone.nodes[n];
        for (int i = 0; i < kBvhWidth; ++i) {
            int& e = laneEntry(want, i);
            if (isLeafEntry(e)) e = leafEntry(leafFirstBlock(e) + int(before.leaves.size()), leafCount(e));
            else if (e != CLRT_INVALID) e += root;
        }
        mismatches += std::memcmp(&into.nodes[size_t(root) + n], &want, sizeof want) != 0;
    }
    for (size_t l = 0; l < alone.leaves.size(); ++l) {
        dev::LeafBlock want = alone.leaves[l];
        int* prim = &want.prim.x;
        for (int i = 0; i < 4; ++i)
            if (prim[i] >= 0) prim[i] += primOffset;
        mismatches += std::memcmp(&into.leaves[before.leaves.size() + l], &want, sizeof want) != 0;
    }
    CHECK(mismatches == 0);
    // An empty tree appends one empty node and no block.
    const size_t nodes = into.nodes.size(), leaves = into.leaves.size();
    CHECK(appendBvh8(buildBvh(std::vector<Aabb>{}), 0, into) == int(nodes));
    CHECK(into.nodes.size() == nodes + 1);
    CHECK(into.leaves.size() == leaves);
    CHECK(laneEntry(into.nodes.back(), 0) == CLRT_INVALID);
}

TEST_CASE("BVH8 leaf packing limits are enforced", "[bvh8]") {
    Bvh bin;
    BvhNode leaf{};
    leaf.boundsMin = {0, 0, 0, 0};
    leaf.boundsMax = {1, 1, 1, 0};
    leaf.first = 0;
    leaf.count = CLRT_BVH_MAX_LEAF + 1;
    bin.nodes.push_back(leaf);
    bin.primRefs.assign(size_t(leaf.count), 0);
    CHECK_THROWS_AS(collapseBvh8(bin), std::logic_error);
    // The builder never makes such a leaf, whatever it is asked for.
    std::vector<Aabb> boxes(100);
    for (Aabb& b : boxes) { b.grow(Vec3(0)); b.grow(Vec3(1)); }
    BvhBuildOptions o;
    o.maxLeafSize = 64;
    CHECK_NOTHROW(collapseBvh8(buildBvh(boxes, o)));
}

TEST_CASE("BVH8 traversal stack: the host bound holds, and the kernel with exactly that stack is exact",
          "[bvh8][cl]") {
    std::vector<Tri> tris = towerScene(60);
    BvhBuildOptions o;
    o.maxLeafSize = 1;
    Bvh bin = buildBvh(triBoxes(tris), o);
    Bvh8 b8 = collapseBvh8(bin);
    checkStructure8(bin, b8, triBoxes(tris));

    std::mt19937 rng(3);
    std::uniform_real_distribution<float> unit(-1, 1);
    const int numRays = 4096;
    std::vector<dev::Ray> rays(numRays);
    std::vector<Vec3> org(numRays), dir(numRays);
    int maxSp = 0, hostMismatch = 0;
    for (int i = 0; i < numRays; ++i) {
        // Mostly up the tower from near the origin (every level's boxes hit), some from far away.
        org[i] = i % 4 ? Vec3(unit(rng), unit(rng), unit(rng)) * 1e-6f : Vec3(unit(rng), unit(rng), unit(rng)) * 1e6f;
        dir[i] = i % 4 ? normalize(Vec3(unit(rng) * 0.3f, unit(rng) * 0.3f, 1)) : normalize(-org[i]);
        rays[size_t(i)] = {{org[i].x, org[i].y, org[i].z, 0}, {dir[i].x, dir[i].y, dir[i].z, INFINITY}};
        Trace8 t = traverse8(bin, b8, tris, org[i], dir[i], INFINITY);
        maxSp = std::max(maxSp, t.maxSp);
        float tBest;
        const int best = bruteClosest(tris, org[i], dir[i], &tBest);
        // Compared by distance: from 1e6 away, tiny triangles of the tower tie at one float t.
        hostMismatch += ((t.prim < 0) != (best < 0)) || (best >= 0 && t.t != tBest);
    }
    std::printf("tower: 8-wide depth %d, stack need %d, deepest stack used by the host replica %d\n", b8.depth,
                b8.maxStack, maxSp);
    CHECK(hostMismatch == 0);
    CHECK(maxSp <= b8.maxStack);
    CHECK(maxSp >= b8.maxStack / 2);  // the scene does exercise the stack

    DeviceContext& dc = testContext();
    auto sources = loadKernelSources(KernelProgram::Intersect);
    cl::Program program = buildProgramFromSources(
        dc, sources, {"-DCLRT_BVH8_STACK_SIZE=" + std::to_string(b8.maxStack)});
    KernelArgs closest(program, "intersect_closest");
    std::vector<dev::Triangle> devTris;
    for (const Tri& t : tris) {
        devTris.push_back({{t[0].x, t[0].y, t[0].z, 0}, {t[1].x, t[1].y, t[1].z, 0}, {t[2].x, t[2].y, t[2].z, 0}});
    }
    // Leaf prim values index devTris directly (the renderer reorders triangles; here there is no need).
    setLeafTriangles(b8, devTris, int(devTris.size()));
    dev::SceneParams sp{};
    sp.numTriangles = int(tris.size());  // no spheres, no planes
    const IntersectScene scene = intersectScene(sp, numRays, b8.nodes, b8.leaves, devTris, std::vector<dev::Sphere>{},
                                                std::vector<dev::Plane>{}, std::vector<dev::Instance>{});
    cl::Buffer rb = readOnlyBuffer(rays);
    cl::Buffer hb = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, sizeof(dev::Hit) * numRays));
    scene.bind(closest).set("rays", rb).set("hits", hb).set("hitInstances", scene.queueCount);  // unused without instances
    CL_CPP(dc.queue().enqueueNDRangeKernel(closest.ready(), cl::NullRange, cl::NDRange(roundUp(size_t(numRays), 64)),
                                           cl::NDRange(64)));
    std::vector<dev::Hit> hits(numRays);
    CL_CPP(dc.queue().enqueueReadBuffer(hb, CL_TRUE, 0, sizeof(dev::Hit) * numRays, hits.data()));
    int devMismatch = 0, hitRays = 0;
    for (int i = 0; i < numRays; ++i) {
        // Only the rays up the tower: those fired from 1e6 away at 0.01-wide triangles are decided by
        // rounding, and the device's and host's triangle tests round differently (about 1% differ).
        if (i % 4 == 0) continue;
        Trace8 t = traverse8(bin, b8, tris, org[i], dir[i], INFINITY);
        const dev::Hit& h = hits[size_t(i)];
        devMismatch += ((h.prim < 0) != (t.prim < 0)) || (t.prim >= 0 && std::fabs(h.t - t.t) > 1e-6f * t.t);
        hitRays += t.prim >= 0;
    }
    CHECK(hitRays > numRays / 2);  // of the 3/4 compared
    CHECK(devMismatch == 0);
}

namespace {

// The device kernels' (intersect.cl) closest hits and shadow results (occluded: 1) for rays (org, dir)
// on the tree b8 over tris (its leaf blocks filled here).
struct DeviceTrace {
    std::vector<dev::Hit> hits;
    std::vector<int> occluded;
};
DeviceTrace traceOnDevice(Bvh8 b8, const std::vector<Tri>& tris, const std::vector<Vec3>& org, const std::vector<Vec3>& dir) {
    std::vector<dev::Triangle> devTris;
    for (const Tri& t : tris)
        devTris.push_back({{t[0].x, t[0].y, t[0].z, 0}, {t[1].x, t[1].y, t[1].z, 0}, {t[2].x, t[2].y, t[2].z, 0}});
    setLeafTriangles(b8, devTris, int(devTris.size()));
    const int n = int(org.size());
    std::vector<dev::Ray> rays(static_cast<size_t>(n));
    std::vector<dev::ShadowRay> shadows(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        rays[size_t(i)] = {{org[i].x, org[i].y, org[i].z, 0}, {dir[i].x, dir[i].y, dir[i].z, INFINITY}};
        shadows[size_t(i)] = {{org[i].x, org[i].y, org[i].z, INFINITY}, {dir[i].x, dir[i].y, dir[i].z, 0}, {1, 1, 1, 0}};
    }
    DeviceContext& dc = testContext();
    static cl::Program program = buildProgramFromSources(dc, loadKernelSources(KernelProgram::Intersect), {});
    KernelArgs closest(program, "intersect_closest"), shadow(program, "intersect_shadow");
    cl::Context& ctx = dc.context();
    dev::SceneParams sp{};
    sp.numTriangles = int(tris.size());
    const IntersectScene scene = intersectScene(sp, n, b8.nodes, b8.leaves, devTris, std::vector<dev::Sphere>{},
                                                std::vector<dev::Plane>{}, std::vector<dev::Instance>{});
    cl::Buffer rb = readOnlyBuffer(rays);
    cl::Buffer hb = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(dev::Hit) * size_t(n)));
    cl::Buffer shb = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof(dev::ShadowRay) * size_t(n),
                                       shadows.data()));
    // hitInstances: unused without instances
    scene.bind(closest).set("rays", rb).set("hits", hb).set("hitInstances", scene.queueCount);
    scene.bind(shadow).set("raysPerPath", 1).set("shadows", shb);
    const cl::NDRange global(roundUp(size_t(n), 64)), local(64);
    CL_CPP(dc.queue().enqueueNDRangeKernel(closest.ready(), cl::NullRange, global, local));
    CL_CPP(dc.queue().enqueueNDRangeKernel(shadow.ready(), cl::NullRange, global, local));
    DeviceTrace r;
    r.hits.resize(static_cast<size_t>(n));
    CL_CPP(dc.queue().enqueueReadBuffer(hb, CL_TRUE, 0, sizeof(dev::Hit) * r.hits.size(), r.hits.data()));
    CL_CPP(dc.queue().enqueueReadBuffer(shb, CL_TRUE, 0, sizeof(dev::ShadowRay) * shadows.size(), shadows.data()));
    for (const dev::ShadowRay& s : shadows) r.occluded.push_back(s.contribution.x == 0);
    return r;
}

// Closest hits and shadow results of the device kernels (intersect.cl) on a BVH over tris built with
// leaves of at most maxLeaf primitives (so leaves of several LeafBlock blocks when maxLeaf > 4), compared
// with brute force over the host's watertight test. Returns the number of mismatches; *hitsOut: rays hit.
int deviceVsBruteForce(const std::vector<Tri>& tris, const std::vector<Vec3>& org, const std::vector<Vec3>& dir,
                       int maxLeaf, int* hitsOut) {
    BvhBuildOptions o;
    o.maxLeafSize = maxLeaf;
    o.traversalCost = 8;  // leaves as full as maxLeaf allows: every lane of a block, several blocks
    Bvh bin = buildBvh(triBoxes(tris), o);
    Bvh8 b8 = collapseBvh8(bin);
    // Nearly full blocks (all four lanes used in most) in every non-trivial case with leaves of 4 or more.
    if (maxLeaf >= 4 && tris.size() > 64) CHECK(double(tris.size()) / double(b8.leaves.size()) > 2.9);
    const DeviceTrace dt = traceOnDevice(b8, tris, org, dir);
    const int n = int(org.size());
    int mismatch = 0, hitRays = 0;
    for (int i = 0; i < n; ++i) {
        float tBest;
        const int best = bruteClosest(tris, org[i], dir[i], &tBest);
        const dev::Hit& h = dt.hits[size_t(i)];
        const bool occluded = dt.occluded[size_t(i)];
        mismatch += ((h.prim < 0) != (best < 0)) || (best >= 0 && std::fabs(h.t - tBest) > 1e-6f * tBest) ||
                    (occluded != (best >= 0));
        hitRays += best >= 0;
    }
    *hitsOut = hitRays;
    return mismatch;
}

}  // namespace

TEST_CASE("BVH8 leaf blocks on the device: empty, one triangle, coplanar grid, huge coordinates",
          "[bvh8][cl]") {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> unit(-1, 1);
    std::vector<Vec3> org, dir;
    auto raysAt = [&](float scale, float height) {  // down at the z = 0 plane, some slanted, some grazing
        org.clear();
        dir.clear();
        for (int i = 0; i < 3000; ++i) {
            org.push_back(Vec3(unit(rng) * scale, unit(rng) * scale, height));
            Vec3 d = i % 3 == 0 ? Vec3(0, 0, -1) : Vec3(unit(rng), unit(rng), -1.0f - 0.5f * unit(rng));
            if (i % 50 == 0) d = Vec3(unit(rng), unit(rng), 0);  // parallel to the plane: never a hit
            dir.push_back(normalize(d));
        }
    };
    int hits = 0;
    SECTION("empty scene: every ray misses") {
        raysAt(1, 1);
        CHECK(deviceVsBruteForce({}, org, dir, 4, &hits) == 0);
        CHECK(hits == 0);
    }
    SECTION("one triangle") {
        raysAt(1, 1);
        std::vector<Tri> one{{Vec3(-0.5f, -0.5f, 0), Vec3(0.5f, -0.5f, 0), Vec3(0, 0.5f, 0)}};
        CHECK(deviceVsBruteForce(one, org, dir, 4, &hits) == 0);
        CHECK(hits > 100);
    }
    // A 32 x 32 grid of squares, two triangles each, all in z = 0: rays aimed at shared edges and
    // vertices must neither slip through nor disagree; leaves of 4 (one block), 7 and 15 (several).
    std::vector<Tri> grid;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            Vec3 a(x / 16.f - 1, y / 16.f - 1, 0), b = a + Vec3(1 / 16.f, 0, 0), c = a + Vec3(0, 1 / 16.f, 0),
                 d = a + Vec3(1 / 16.f, 1 / 16.f, 0);
            grid.push_back({a, b, d});
            grid.push_back({a, d, c});
        }
    SECTION("coplanar grid") {
        raysAt(0.9f, 1);
        for (int i = 0; i < 300; ++i) {  // exactly through grid vertices and edges
            org.push_back(Vec3(std::round(unit(rng) * 14) / 16.f, (i % 2 ? std::round(unit(rng) * 14) : unit(rng) * 14) / 16.f, 1));
            dir.push_back(Vec3(0, 0, -1));
        }
        for (int leaf : {4, 7, 15}) {
            INFO("maxLeafSize " << leaf);
            CHECK(deviceVsBruteForce(grid, org, dir, leaf, &hits) == 0);
            CHECK(hits > int(org.size()) / 2);
        }
    }
    SECTION("huge coordinates") {
        // At 1e12 the rays hit; at 1e18 the test's T (a product of three coordinate differences)
        // overflows to inf and every hit is refused, by both the host and the device: agreement only.
        for (float scale : {1e12f, 1e18f}) {
            std::vector<Tri> huge = grid;
            for (Tri& t : huge)
                for (Vec3& v : t) v = v * scale;
            raysAt(0.9f * scale, scale);
            INFO("scale " << scale);
            CHECK(deviceVsBruteForce(huge, org, dir, 4, &hits) == 0);
            if (scale < 1e15f) CHECK(hits > int(org.size()) / 2);
        }
    }
}

// The traversal's node paths on inputs that stress them, against brute force: nodes with every child
// hit (sorted pushes for closest hits, lane-order pushes for any hit; leaves of 1 make deep trees of
// full nodes), and rays lying exactly in the planes of box faces (0 * inf = NaN in the slab test, which
// must leave the slab unbounded, so no box in whose face a ray lies is culled).
TEST_CASE("BVH8 traversal on the device: a triangle soup with full nodes, rays in box faces", "[bvh8][cl]") {
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> unit(-1, 1);
    int hits = 0;
    SECTION("triangle soup: overlapping boxes, many hit children per node") {
        std::vector<Tri> soup;
        for (int i = 0; i < 3000; ++i) {
            const Vec3 c(unit(rng) * 4, unit(rng) * 4, unit(rng) * 4);
            Tri t;
            for (Vec3& v : t) v = c + Vec3(unit(rng), unit(rng), unit(rng)) * 0.6f;
            soup.push_back(t);
        }
        std::vector<Vec3> org, dir;
        for (int i = 0; i < 3000; ++i) {  // from inside the soup, and from outside aimed at it
            const Vec3 o = Vec3(unit(rng), unit(rng), unit(rng)) * (i % 2 ? 3.f : 20.f);
            org.push_back(o);
            dir.push_back(normalize(i % 2 ? Vec3(unit(rng), unit(rng), unit(rng)) : Vec3(unit(rng), unit(rng), unit(rng)) - o));
        }
        for (int leaf : {1, 4, 15}) {
            INFO("maxLeafSize " << leaf);
            CHECK(deviceVsBruteForce(soup, org, dir, leaf, &hits) == 0);
            CHECK(hits > int(org.size()) / 2);
        }
    }
    SECTION("rays in the planes of box faces and along box edges") {
        // A ray lying in a face plane of a box (a zero direction component, the origin's component on
        // the face: 0 * inf = NaN in the slab test) can meet what the box holds only on the boundary of
        // a triangle, where the reference's edge ownership and the kernel's inclusive test differ on a
        // mesh's outline. So the kernel is held to itself: the same tree with every box unbounded (no
        // culling: every leaf tested) must give the same closest distance and shadow result.
        // Closed unit cubes (12 triangles each) at even lattice points, some left out: every box face
        // lies on an integer plane; rays along an axis with the other two coordinates integers (along
        // cube edges, through corners) or one of them k + 1/2 (across faces, in face planes).
        std::vector<Tri> cubes;
        for (int z = 0; z < 4; ++z)
            for (int y = 0; y < 4; ++y)
                for (int x = 0; x < 4; ++x) {
                    if ((x + y + z) % 3 == 0) continue;
                    const Vec3 p(float(2 * x), float(2 * y), float(2 * z));
                    const Vec3 v[8] = {p, p + Vec3(1, 0, 0), p + Vec3(0, 1, 0), p + Vec3(1, 1, 0),
                                       p + Vec3(0, 0, 1), p + Vec3(1, 0, 1), p + Vec3(0, 1, 1), p + Vec3(1, 1, 1)};
                    const int face[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
                    for (const auto& q : face) {
                        cubes.push_back({v[q[0]], v[q[1]], v[q[2]]});
                        cubes.push_back({v[q[0]], v[q[2]], v[q[3]]});
                    }
                }
        std::vector<Vec3> org, dir;
        std::uniform_int_distribution<int> cell(0, 8), axis(0, 2), coin(0, 1);
        for (int i = 0; i < 3000; ++i) {
            const int a = axis(rng), u = (a + 1) % 3, v = (a + 2) % 3;
            Vec3 o, d(0, 0, 0);
            o[u] = float(cell(rng)) + (i % 3 == 1 ? 0.5f : 0.f);
            o[v] = float(cell(rng)) + (i % 3 == 2 ? 0.5f : 0.f);
            const bool outside = i % 2;
            o[a] = outside ? -3.f : float(cell(rng)) + 0.25f;  // outside every box, or anywhere along the axis
            d[a] = outside || coin(rng) ? 1.f : -1.f;
            org.push_back(o);
            dir.push_back(d);
        }
        for (int leaf : {1, 4}) {
            INFO("maxLeafSize " << leaf);
            BvhBuildOptions o;
            o.maxLeafSize = leaf;
            Bvh8 b8 = collapseBvh8(buildBvh(triBoxes(cubes), o));
            Bvh8 open = b8;
            for (dev::Bvh8Node& nd : open.nodes)
                for (int i = 0; i < kBvhWidth; ++i) {
                    if (laneEntry(nd, i) == CLRT_INVALID) continue;
                    for (int p = 0; p < 6; ++p) lanePlane(nd, p, i) = p % 2 ? INFINITY : -INFINITY;
                }
            const DeviceTrace culled = traceOnDevice(b8, cubes, org, dir), all = traceOnDevice(open, cubes, org, dir);
            int differ = 0, hit = 0, inFace = 0;
            for (size_t i = 0; i < org.size(); ++i) {
                const dev::Hit &h = culled.hits[i], &g = all.hits[i];
                differ += ((h.prim < 0) != (g.prim < 0)) || (g.prim >= 0 && h.t != g.t) || culled.occluded[i] != all.occluded[i];
                hit += g.prim >= 0;
                bool inPlane = false;  // a zero direction component with an integer origin component
                for (int a = 0; a < 3; ++a) inPlane = inPlane || (dir[i][a] == 0 && org[i][a] == std::floor(org[i][a]));
                inFace += g.prim >= 0 && inPlane;
            }
            CHECK(differ == 0);
            CHECK(hit > int(org.size()) / 4);
            CHECK(inFace > int(org.size()) / 8);  // rays in box faces that hit something
        }
    }
}
