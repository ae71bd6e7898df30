// Collapse of the binary SAH tree (bvh.h) into the 8-wide nodes the device traverses
// (dev::Bvh8Node in shared/device_types.h): each 8-wide node takes a binary node's children and keeps
// opening its largest-area interior child until it has eight (Wald et al. 2008, "Getting rid of
// packets"; Embree builds its BVH8 the same way), its lanes ordered by area, largest first (the order
// shadow rays visit them in). A leaf's primitives (the binary tree's own leaves,
// in primRefs order) are copied into blocks of four (dev::LeafBlock) with their triangles' vertices
// as struct of arrays, so the device tests a leaf's triangles four at a time.
#pragma once
#include <vector>

#include "bvh/bvh.h"
#include "shared/device_types.h"
#include "util/huge_pages.h"

namespace clrt {

constexpr int kBvhWidth = 8;  // lanes of a dev::Bvh8Node

// Host views of a Bvh8Node's lane i: plane p of its box (0 minX, 1 maxX, 2 minY, 3 maxY, 4 minZ, 5 maxZ) and
// its entry (device_types.h: node index, leaf, instance or CLRT_INVALID).
inline float& lanePlane(dev::Bvh8Node& n, int p, int i) { return (&n.planes[0].x)[8 * p + i]; }
inline float lanePlane(const dev::Bvh8Node& n, int p, int i) { return (&n.planes[0].x)[8 * p + i]; }
inline int& laneEntry(dev::Bvh8Node& n, int i) { return (&n.entry[0].x)[i]; }
inline int laneEntry(const dev::Bvh8Node& n, int i) { return (&n.entry[0].x)[i]; }
// A leaf lane's entry, ~(firstBlock << 4 | count) with count 1..CLRT_BVH_MAX_LEAF, and its parts.
inline int leafEntry(int firstBlock, int count) { return ~((firstBlock << 4) | count); }
inline bool isLeafEntry(int entry) { return entry < 0 && ((~entry) & 15) != 0; }
inline int leafFirstBlock(int entry) { return (~entry) >> 4; }
inline int leafCount(int entry) { return (~entry) & 15; }

struct Bvh8 {
    HostArray<dev::Bvh8Node> nodes;  // nodes[0] is the root; never empty
    HostArray<dev::LeafBlock> leaves;  // the leaves' primitives, four to a block (vertices: setLeafTriangles)
    int maxStack = 0;  // most entries the device's near-first traversal can have on its stack
    int depth = 0;     // node levels on the longest root-to-leaf path
};

// A subtree of at most this many binary nodes is collapsed into the 8-wide nodes of least total box area
// (each node's lanes chosen by dynamic programming over the subtree), which fills the nodes near the
// leaves; above, each node opens its largest box first, which brings big occluders near the root (shadow
// rays stop at the first). Both: docs/studies/2026-12-07-diffuse-rays.md.
constexpr size_t kCollapseOptimalSpan = 512;

// A tree of this many binary nodes or more is collapsed on all threads: its top (nodes over subtrees of
// more than 1/64 of the tree) on one, the subtrees below in parallel, each written where counting it
// says. Nodes are then laid out top first, subtree after subtree (each depth-first), which depends on the
// tree alone: the same nodes, and the same traversal, as one depth-first pass gives.
constexpr size_t kCollapseSplitNodes = size_t(1) << 18;

// Always succeeds for a tree from buildBvh (maxStack <= CLRT_BVH8_STACK_SIZE); throws
// std::logic_error for a hand-made tree that breaks that bound.
// Leaf lanes point at blocks of `leaves` whose prim holds the binary tree's primRefs (in leaf order);
// their vertices are zero until setLeafTriangles. splitNodes: see kCollapseSplitNodes (tests compare
// the split layout with one pass, SIZE_MAX).
Bvh8 collapseBvh8(const Bvh& bvh, size_t splitNodes = kCollapseSplitNodes);
// The same, freeing the binary tree (left empty) before the leaf blocks are allocated, so the two are
// never held together: what flattening does, since nothing reads its binary tree afterwards.
Bvh8 collapseBvh8(Bvh&& bvh);

// collapseBvh8(Bvh&&) appended to `into` after the trees it already holds (the two-level BVH's bottom
// levels, flatten_instances.cpp): the 8-wide nodes are written straight into into.nodes and the leaf
// blocks into into.leaves, child indices pointing into those arrays and primitive references moved by
// primOffset, so neither array is made twice. Returns the root's index in into.nodes, *maxStack its
// traversal stack need (into.maxStack and depth stay the caller's). The binary tree is left empty.
// spareNodes: room for that many more nodes kept past them where into.nodes must grow (the top level,
// appended last, then does not move the bottom levels' nodes).
int appendBvh8(Bvh&& bvh, int primOffset, Bvh8& into, int* maxStack = nullptr, size_t spareNodes = 0);

// Copies each triangle lane's world-space vertices (prim < numTriangles) from tris into its block, for
// the blocks from firstLeaf on.
void setLeafTriangles(Bvh8& b8, const dev::Triangle* tris, int numTriangles, size_t firstLeaf = 0);
template <class Triangles>  // std::vector or HostArray
void setLeafTriangles(Bvh8& b8, const Triangles& tris, int numTriangles, size_t firstLeaf = 0) {
    setLeafTriangles(b8, tris.data(), numTriangles, firstLeaf);
}

}  // namespace clrt
