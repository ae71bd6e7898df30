// Collapse of the binary SAH tree (bvh.h) into the 4-wide nodes the device traverses
// (dev::Bvh4Node in shared/device_types.h): each 4-wide node takes a binary node's children and keeps
// opening its largest-area interior child until it has four (Wald et al. 2008, "Getting rid of
// packets"; Embree's BVH4 is built the same way), its lanes ordered by area, largest first (the order
// shadow rays visit them in). A leaf's primitives (the binary tree's own leaves,
// in primRefs order) are copied into blocks of four (dev::Bvh4Leaf) with their triangles' vertices
// as struct of arrays, so the device tests a leaf's triangles four at a time.
#pragma once
#include <vector>

#include "bvh/bvh.h"
#include "shared/device_types.h"
#include "util/huge_pages.h"

namespace clrt {

struct Bvh4 {
    HostArray<dev::Bvh4Node> nodes;  // nodes[0] is the root; never empty
    HostArray<dev::Bvh4Leaf> leaves;  // the leaves' primitives, four to a block (vertices: setLeafTriangles)
    int maxStack = 0;  // most entries the device's near-first traversal can have on its stack
    int depth = 0;     // node levels on the longest root-to-leaf path
};

// A tree of this many binary nodes or more is collapsed on all threads: its top (nodes over subtrees of
// more than 1/64 of the tree) on one, the subtrees below in parallel, each written where counting it
// says. Nodes are then laid out top first, subtree after subtree (each depth-first), which depends on the
// tree alone: the same nodes, and the same traversal, as one depth-first pass gives.
constexpr size_t kCollapseSplitNodes = size_t(1) << 18;

// Always succeeds for a tree from buildBvh (maxStack <= CLRT_BVH4_STACK_SIZE); throws
// std::logic_error for a hand-made tree that breaks that bound.
// Leaf lanes point at blocks of `leaves` whose prim holds the binary tree's primRefs (in leaf order);
// their vertices are zero until setLeafTriangles. splitNodes: see kCollapseSplitNodes (tests compare
// the split layout with one pass, SIZE_MAX).
Bvh4 collapseBvh4(const Bvh& bvh, size_t splitNodes = kCollapseSplitNodes);
// The same, freeing the binary tree (left empty) before the leaf blocks are allocated, so the two are
// never held together: what flattening does, since nothing reads its binary tree afterwards.
Bvh4 collapseBvh4(Bvh&& bvh);

// collapseBvh4(Bvh&&) appended to `into` after the trees it already holds (the two-level BVH's bottom
// levels, flatten_instances.cpp): the 4-wide nodes are written straight into into.nodes and the leaf
// blocks into into.leaves, child indices pointing into those arrays and primitive references moved by
// primOffset, so neither array is made twice. Returns the root's index in into.nodes, *maxStack its
// traversal stack need (into.maxStack and depth stay the caller's). The binary tree is left empty.
// spareNodes: room for that many more nodes kept past them where into.nodes must grow (the top level,
// appended last, then does not move the bottom levels' nodes).
int appendBvh4(Bvh&& bvh, int primOffset, Bvh4& into, int* maxStack = nullptr, size_t spareNodes = 0);

// Copies each triangle lane's world-space vertices (prim < numTriangles) from tris into its block, for
// the blocks from firstLeaf on.
void setLeafTriangles(Bvh4& b4, const dev::Triangle* tris, int numTriangles, size_t firstLeaf = 0);
template <class Triangles>  // std::vector or HostArray
void setLeafTriangles(Bvh4& b4, const Triangles& tris, int numTriangles, size_t firstLeaf = 0) {
    setLeafTriangles(b4, tris.data(), numTriangles, firstLeaf);
}

}  // namespace clrt
