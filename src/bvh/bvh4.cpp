// Binary -> 4-wide BVH collapse (see bvh4.h). Nodes are written depth-first, parent before children.
#include "bvh/bvh4.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "util/parallel.h"

namespace clrt {
namespace {

double halfArea(const BvhNode& n) {
    double dx = double(n.boundsMax.x) - n.boundsMin.x, dy = double(n.boundsMax.y) - n.boundsMin.y,
           dz = double(n.boundsMax.z) - n.boundsMin.z;
    if (!(dx >= 0 && dy >= 0 && dz >= 0)) return 0;
    return dx * dy + dy * dz + dz * dx;
}

struct Collapser {
    const Bvh& bin;
    HostArray<dev::Bvh4Node>& out;
    std::vector<dev::int4>& blockPrims;  // each leaf block's primitives (the blocks are made afterwards)
    int depth = 0;

    // Appends the blocks of binary leaf c (its primRefs, four to a block); returns the first block.
    int emitLeaf(const BvhNode& c) {
        const int firstBlock = int(blockPrims.size());
        for (int k = 0; k < c.count; k += 4) {
            dev::int4 prims;
            int* prim = &prims.x;
            for (int i = 0; i < 4; ++i)
                prim[i] = k + i < c.count ? bin.primRefs[size_t(c.first + k + i)] : CLRT_INVALID;
            blockPrims.push_back(prims);
        }
        return firstBlock;
    }

    // The binary nodes that become the lanes of the 4-wide node made for binary node b: a leaf root
    // alone, else b's children, opening the interior lane with the largest area until there are four.
    // Returns how many.
    int lanesOf(int b, int lanes[4]) const {
        int k = 0;
        const BvhNode& nb = bin.nodes[size_t(b)];
        if (nb.count > 0) {
            lanes[k++] = b;  // a leaf root: one lane
            return k;
        }
        lanes[k++] = b + 1;
        lanes[k++] = nb.first;
        while (k < 4) {
            int best = -1;
            double bestArea = -1;
            for (int i = 0; i < k; ++i) {
                const BvhNode& c = bin.nodes[size_t(lanes[i])];
                if (c.count > 0) continue;
                const double area = halfArea(c);
                if (area > bestArea) { bestArea = area; best = i; }
            }
            if (best < 0) break;
            const int c = lanes[best];
            lanes[best] = c + 1;
            lanes[k++] = bin.nodes[size_t(c)].first;
        }
        return k;
    }

    // The 4-wide nodes emit(b) writes (the same choices, nothing written): so `out` is sized exactly.
    size_t countNodes(int b) const {
        int lanes[4];
        const int k = lanesOf(b, lanes);
        size_t n = 1;
        for (int i = 0; i < k; ++i)
            if (bin.nodes[size_t(lanes[i])].count == 0) n += countNodes(lanes[i]);
        return n;
    }

    // Writes the 4-wide node for binary node b and its subtree; returns {index, stack need}.
    // Stack need of a subtree: the most entries its traversal pushes, from an empty stack (a node
    // with k hit children pushes k - 1 and goes on into one of them).
    std::pair<int, int> emit(int b, int level) {
        depth = std::max(depth, level);
        const int idx = int(out.size());
        out.emplace_back();
        int lanes[4];
        const int k = lanesOf(b, lanes);
        dev::Bvh4Node node;
        float* mn[3] = {&node.minX.x, &node.minY.x, &node.minZ.x};
        float* mx[3] = {&node.maxX.x, &node.maxY.x, &node.maxZ.x};
        int* child = &node.child.x;
        int* count = &node.count.x;
        int need = 0;
        for (int i = 0; i < 4; ++i) {
            if (i >= k) {
                for (int a = 0; a < 3; ++a) { mn[a][i] = INFINITY; mx[a][i] = -INFINITY; }
                child[i] = CLRT_INVALID;
                count[i] = 0;
                continue;
            }
            const BvhNode& c = bin.nodes[size_t(lanes[i])];
            const float* lo = &c.boundsMin.x;
            const float* hi = &c.boundsMax.x;
            for (int a = 0; a < 3; ++a) { mn[a][i] = lo[a]; mx[a][i] = hi[a]; }
            if (c.count > 0) {
                // The traversal packs a leaf into one stack entry: ~(first << 4 | count).
                if (c.count > CLRT_BVH4_MAX_LEAF)
                    throw std::logic_error("collapseBvh4: leaf of " + std::to_string(c.count) + " primitives");
                if (c.first > CLRT_BVH4_MAX_PRIMS - c.count)
                    throw std::runtime_error("scene has more than " + std::to_string(CLRT_BVH4_MAX_PRIMS) +
                                             " primitives (the BVH's limit)");
                child[i] = emitLeaf(c);
                count[i] = c.count;
            } else {
                auto sub = emit(lanes[i], level + 1);
                child[i] = sub.first;
                count[i] = 0;
                need = std::max(need, sub.second);
            }
        }
        out[size_t(idx)] = node;
        return {idx, need + (k - 1)};
    }
};

// Makes room for `more` elements past a's end: exactly when a holds nothing yet (one tree: no unused
// tail), else at least half again (bottom levels appended one after another: amortised copies). A
// HostArray's pages past the end are never touched, so unused capacity costs no resident memory.
template <class T>
void reserveMore(HostArray<T>& a, size_t more) {
    const size_t need = a.size() + more;
    if (need > a.capacity()) a.reserve(a.empty() ? need : std::max(need, a.capacity() + a.capacity() / 2));
}

// The 4-wide nodes of `bvh` appended to `nodes` (child indices of interior lanes are indices of
// `nodes`, leaf lanes index blockPrims), and its leaf blocks' primitives into blockPrims; *maxStack and
// *depth its figures. False for an empty tree (then one empty node is appended).
bool collapseNodes(const Bvh& bvh, HostArray<dev::Bvh4Node>& nodes, std::vector<dev::int4>& blockPrims, int* maxStack,
                   int* depth, size_t spareNodes = 0) {
    if (bvh.primRefs.empty() || bvh.nodes.empty()) {
        dev::Bvh4Node empty;
        empty.minX = empty.minY = empty.minZ = {INFINITY, INFINITY, INFINITY, INFINITY};
        empty.maxX = empty.maxY = empty.maxZ = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
        empty.child = {CLRT_INVALID, CLRT_INVALID, CLRT_INVALID, CLRT_INVALID};
        empty.count = {0, 0, 0, 0};
        nodes.push_back(empty);
        *maxStack = 0;
        *depth = 1;
        return false;
    }
    Collapser c{bvh, nodes, blockPrims};
    reserveMore(nodes, c.countNodes(0) + spareNodes);  // exactly, so a recycled block fits (util/huge_pages.h)
    size_t blocks = 0;  // exactly: each binary leaf's primitives, four to a block (no growth, no copies)
    for (const BvhNode& n : bvh.nodes)
        if (n.count > 0) blocks += size_t(n.count + 3) / 4;
    blockPrims.reserve(blocks);
    *maxStack = c.emit(0, 1).second;
    *depth = c.depth;
    if (*maxStack > CLRT_BVH4_STACK_SIZE)
        throw std::logic_error("collapseBvh4: traversal stack need " + std::to_string(*maxStack) +
                               " exceeds CLRT_BVH4_STACK_SIZE");
    return true;
}

constexpr size_t kBlocksPerTask = 16384;  // leaf blocks per parallelFor item (2.5 MB)

// The leaf blocks from their primitives, moved by primOffset, appended to `leaves` (vertices zero
// until setLeafTriangles). Written on all threads: most of the time is the kernel zeroing the fresh
// pages each thread touches first (resize leaves them unwritten, util/huge_pages.h).
void makeLeaves(const std::vector<dev::int4>& blockPrims, int primOffset, HostArray<dev::Bvh4Leaf>& leaves) {
    reserveMore(leaves, blockPrims.size());
    const size_t first = leaves.size(), count = blockPrims.size();
    leaves.resize(first + count);
    parallelFor((count + kBlocksPerTask - 1) / kBlocksPerTask, [&](size_t task) {
        const size_t end = std::min(count, (task + 1) * kBlocksPerTask);
        for (size_t b = task * kBlocksPerTask; b < end; ++b) {
            dev::Bvh4Leaf block{};
            block.prim = blockPrims[b];
            int* prim = &block.prim.x;
            for (int i = 0; i < 4; ++i)
                if (prim[i] >= 0) prim[i] += primOffset;
            leaves[first + b] = block;
        }
    });
}

}  // namespace

Bvh4 collapseBvh4(const Bvh& bvh) {
    Bvh4 r;
    std::vector<dev::int4> blockPrims;
    if (collapseNodes(bvh, r.nodes, blockPrims, &r.maxStack, &r.depth)) makeLeaves(blockPrims, 0, r.leaves);
    return r;
}

Bvh4 collapseBvh4(Bvh&& bvh) {
    Bvh4 r;
    std::vector<dev::int4> blockPrims;
    const bool any = collapseNodes(bvh, r.nodes, blockPrims, &r.maxStack, &r.depth);
    bvh = Bvh{};  // freed before the leaf blocks are allocated
    if (any) makeLeaves(blockPrims, 0, r.leaves);
    return r;
}

int appendBvh4(Bvh&& bvh, int primOffset, Bvh4& into, int* maxStack, size_t spareNodes) {
    const size_t root = into.nodes.size(), leafOffset = into.leaves.size();
    std::vector<dev::int4> blockPrims;
    int stack = 0, depth = 0;
    const bool any = collapseNodes(bvh, into.nodes, blockPrims, &stack, &depth, spareNodes);
    bvh = Bvh{};  // freed before the leaf blocks are allocated
    for (size_t n = root; n < into.nodes.size(); ++n) {
        dev::Bvh4Node& node = into.nodes[n];
        int* child = &node.child.x;
        const int* count = &node.count.x;
        for (int i = 0; i < 4; ++i)
            if (child[i] != CLRT_INVALID && count[i] > 0) child[i] += int(leafOffset);
    }
    if (any) makeLeaves(blockPrims, primOffset, into.leaves);
    if (maxStack) *maxStack = stack;
    return int(root);
}

void setLeafTriangles(Bvh4& b4, const dev::Triangle* tris, int numTriangles, size_t firstLeaf) {
    const size_t count = b4.leaves.size() - std::min(firstLeaf, b4.leaves.size());
    parallelFor((count + kBlocksPerTask - 1) / kBlocksPerTask, [&](size_t task) {
        const size_t end = firstLeaf + std::min(count, (task + 1) * kBlocksPerTask);
        for (size_t l = firstLeaf + task * kBlocksPerTask; l < end; ++l) {
            dev::Bvh4Leaf& block = b4.leaves[l];
            const int* prim = &block.prim.x;
            for (int i = 0; i < 4; ++i) {
                if (prim[i] < 0 || prim[i] >= numTriangles) continue;
                const dev::Triangle& t = tris[size_t(prim[i])];
                const dev::float4* v[3] = {&t.v0, &t.v1, &t.v2};
                for (int k = 0; k < 3; ++k) {
                    (&block.vertex[3 * k + 0].x)[i] = v[k]->x;
                    (&block.vertex[3 * k + 1].x)[i] = v[k]->y;
                    (&block.vertex[3 * k + 2].x)[i] = v[k]->z;
                }
            }
        }
    });
}

}  // namespace clrt
