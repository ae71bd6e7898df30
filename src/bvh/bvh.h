// src/bvh/: the bounding volume hierarchy (binned-SAH build, 8-wide collapse for the device, host reference traversal).
// Bounding volume hierarchy over world-space primitives: binned SAH build on the host into binary
// nodes (BvhNode, depth-first, left child next to its parent). The device reads it collapsed to
// 8-wide nodes (bvh8.h); the binary tree is also what the plain C++ reference traversal in tests walks.
#pragma once
#include <vector>

#include "shared/device_types.h"
#include "util/huge_pages.h"
#include "util/math.h"

namespace clrt {

struct Aabb {
    Vec3 min{1e30f, 1e30f, 1e30f};
    Vec3 max{-1e30f, -1e30f, -1e30f};
    void grow(const Vec3& p) { min = vmin(min, p); max = vmax(max, p); }
    void grow(const Aabb& b) { min = vmin(min, b.min); max = vmax(max, b.max); }
    Vec3 centroid() const { return (min + max) * 0.5f; }
    float surfaceArea() const {
        Vec3 d = max - min;
        if (d.x < 0 || d.y < 0 || d.z < 0) return 0;
        return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
    bool valid() const { return min.x <= max.x && min.y <= max.y && min.z <= max.z; }
};

// A binary node. Leaf: count > 0 and first = first index into primRefs. Interior: count == 0,
// first = index of the right child (the left child is the next node).
struct BvhNode {
    dev::float4 boundsMin;  // xyz; w unused
    dev::float4 boundsMax;  // xyz; w unused
    int first;
    int count;
    int axis;  // interior: split axis (0,1,2)
    int pad0;
};

struct BvhBuildOptions {
    int bins = 16;            // SAH bins per axis
    int maxLeafSize = 4;      // leaves never hold more (coincident centroids: median split); <= 15
    float traversalCost = 1;  // SAH cost of an interior node relative to one primitive test
    int maxThreads = 0;       // threads for inputs of 65536 primitives or more; 0 = all hardware
                              // threads. The tree does not depend on it.
};

using BvhNodes = HostArray<BvhNode>;

struct Bvh {
    BvhNodes nodes;                   // nodes[0] is the root
    std::vector<int> primRefs;        // leaf ranges index this; values index the input boxes
    float sahCost = 0;                // SAH cost of the tree (root area normalised)
    int depth = 0;                    // levels on the longest root-to-leaf path (root alone = 1);
                                      // always <= CLRT_BVH_STACK_SIZE - 8
};

// What a caller keeps of a binary tree once it has been collapsed for the device (bvh8.h): its
// figures for -v and benches, not its nodes (~30 B per primitive, freed; flatten_geometry.cpp).
struct BvhSummary {
    Aabb bounds;             // the root's box (inverted when there are no primitives)
    float sahCost = 0;
    int depth = 0;
    size_t nodes = 0, primitives = 0;  // binary nodes, primRefs
};
BvhSummary summarizeBvh(const Bvh& bvh);

// One primitive as the builder takes it: its box and, in the fourth lane of lo, its reference. The
// builder partitions these 32-byte items in place, so a caller that writes them (flattening does, one
// per triangle as it stores the triangle) hands them over and no other copy of the boxes is made.
struct alignas(16) BvhItem {
    float lo[3];
    int prim;  // set by buildBvh: the item's index
    float hi[3];
    int pad;   // set by buildBvh: 0
};
using BvhItems = HostArray<BvhItem>;
inline BvhItem bvhItem(const Aabb& b) { return BvhItem{{b.min.x, b.min.y, b.min.z}, 0, {b.max.x, b.max.y, b.max.z}, 0}; }

// Builds over the given primitive boxes (one per primitive; index = primitive reference).
// Empty input gives a single node with count 0 and inverted bounds and no primRefs: callers must
// not traverse it (check primRefs.empty()). Boxes that are non-finite or inverted are still
// referenced once but never widen a node. Leaves hold at most maxLeafSize primitives.
Bvh buildBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& opts = {});
// The same over items (item i: primitive i's box), which the build consumes and frees: the same tree.
Bvh buildBvh(BvhItems&& items, const BvhBuildOptions& opts = {});

}  // namespace clrt
