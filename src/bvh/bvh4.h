// Collapse of the binary SAH tree (bvh.h) into the 4-wide nodes the device traverses
// (dev::Bvh4Node in shared/device_types.h): each 4-wide node takes a binary node's children and keeps
// opening its largest-area interior child until it has four (Wald et al. 2008, "Getting rid of
// packets"; Embree's BVH4 is built the same way). Leaves and primRefs are the binary tree's own.
#pragma once
#include <vector>

#include "bvh/bvh.h"
#include "shared/device_types.h"

namespace clrt {

struct Bvh4 {
    std::vector<dev::Bvh4Node> nodes;  // nodes[0] is the root; never empty
    int maxStack = 0;  // most entries the device's near-first traversal can have on its stack
    int depth = 0;     // node levels on the longest root-to-leaf path
};

// Always succeeds for a tree from buildBvh (maxStack <= CLRT_BVH4_STACK_SIZE); throws
// std::logic_error for a hand-made tree that breaks that bound.
Bvh4 collapseBvh4(const Bvh& bvh);

}  // namespace clrt
