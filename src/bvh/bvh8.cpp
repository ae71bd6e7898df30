// Binary -> 8-wide BVH collapse (see bvh8.h). The top of the tree opens the largest box first; subtrees of
// at most kCollapseOptimalSpan binary nodes take the lanes that give their 8-wide nodes the least total area
// (Region). Nodes are written depth-first, parent before children; a big tree's top first, then its
// subtrees, each depth-first (SplitCollapse).
#include "bvh/bvh8.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "util/parallel.h"

namespace clrt {
namespace {

double halfArea(const BvhNode& n) {
    double dx = double(n.boundsMax.x) - n.boundsMin.x, dy = double(n.boundsMax.y) - n.boundsMin.y,
           dz = double(n.boundsMax.z) - n.boundsMin.z;
    if (!(dx >= 0 && dy >= 0 && dz >= 0)) return 0;
    return dx * dy + dy * dz + dz * dx;
}

// The tree's leaf blocks' primitives: each binary leaf's primRefs, four to a block (the blocks are
// made afterwards, makeLeaves).
using BlockPrims = HostArray<dev::int4>;

// A subtree collapsed by least area: its root's binary index and, for each of its binary nodes x,
// cost[x - root][i - 1], the least total box area of the 8-wide nodes that x's subtree makes when it
// takes at most i lanes of its parent (i = 1: x's own node and those below it). The leaves do not
// count: each binary leaf is one lane however the tree is cut. cost null: the top, largest box first.
using LaneCosts = std::array<float, kBvhWidth>;
struct Region {
    int root = -1;
    const LaneCosts* cost = nullptr;
    const LaneCosts& at(int x) const { return cost[x - root]; }
};

// Writes 8-wide nodes at fixed places: node i at out[i] (i counts in the whole nodes array), leaf block
// j's primitives at blocks[j], from nextNode and nextBlock on. countOf tells how many of each emit uses.
struct Collapser {
    const Bvh& bin;
    dev::Bvh8Node* out;
    dev::int4* blocks;
    int nextNode = 0, nextBlock = 0;
    int depth = 0;

    struct Counts {
        size_t nodes = 0, blocks = 0;
    };

    // Binary nodes in b's subtree (depth-first layout: it ends at its rightmost leaf).
    size_t span(int b) const {
        int e = b;
        while (bin.nodes[size_t(e)].count == 0) e = bin.nodes[size_t(e)].first;
        return size_t(e) + 1 - size_t(b);
    }

    // Region's cost table of b's subtree (span n), children before parents (dynamic programming, Ylitie, Karras
    // & Laine 2017, "Efficient incoherent ray traversal on GPUs through compressed wide BVHs", section 3.1).
    void regionCosts(int b, size_t n, std::vector<LaneCosts>& cost) const {
        cost.resize(n);
        for (size_t x = n; x-- > 0;) {
            const BvhNode& nx = bin.nodes[size_t(b) + x];
            if (nx.count > 0) {
                cost[x].fill(0.0f);
                continue;
            }
            const LaneCosts& l = cost[x + 1];
            const LaneCosts& r = cost[size_t(nx.first - b)];
            float split[kBvhWidth + 1];  // split[j]: the two children's subtrees in at most j lanes
            for (int j = 2; j <= kBvhWidth; ++j) {
                split[j] = INFINITY;
                for (int q = 1; q < j; ++q) split[j] = std::min(split[j], l[size_t(q - 1)] + r[size_t(j - q - 1)]);
            }
            const double a = halfArea(nx);
            cost[x][0] = float(a >= 0 ? a : 0) + split[kBvhWidth];
            for (int i = 2; i <= kBvhWidth; ++i) cost[x][size_t(i - 1)] = std::min(cost[x][size_t(i - 2)], split[i]);
        }
    }

    // The lanes region.cost chose for b's subtree in at most i lanes (ties: fewer lanes, then more on the left).
    void regionLanes(const Region& region, int b, int i, int lanes[kBvhWidth], int& k) const {
        const LaneCosts& c = region.at(b);
        while (i > 1 && c[size_t(i - 1)] == c[size_t(i - 2)]) --i;  // a leaf's costs are all equal: i = 1
        if (i == 1) lanes[k++] = b;
        else regionSplit(region, b, i, lanes, k);
    }
    void regionSplit(const Region& region, int b, int j, int lanes[kBvhWidth], int& k) const {
        const int left = b + 1, right = bin.nodes[size_t(b)].first;
        const LaneCosts &l = region.at(left), &r = region.at(right);
        int bestQ = 1;
        float best = INFINITY;
        for (int q = 1; q < j; ++q)
            if (l[size_t(q - 1)] + r[size_t(j - q - 1)] < best) {
                best = l[size_t(q - 1)] + r[size_t(j - q - 1)];
                bestQ = q;
            }
        regionLanes(region, left, bestQ, lanes, k);
        regionLanes(region, right, j - bestQ, lanes, k);
    }

    // The binary nodes that become the lanes of the 8-wide node made for binary node b: a leaf root
    // alone; in a region, the lanes of least area (regionSplit); above, b's children, opening the interior
    // lane with the largest area until there are eight, which brings big occluders up. Then ordered by
    // area, largest first. Returns how many. The order is what shadow rays (any hit)
    // visit in: a ray is likelier to meet an occluder in a bigger box, and finding one ends the ray
    // (veachAjar's shadow rays 1.48x faster, docs/studies/2026-12-06-classic-lanes-children.md); closest-hit
    // rays sort the lanes by entry distance, which only ties leave in lane order.
    int lanesOf(int b, int lanes[kBvhWidth], const Region& region = {}) const {
        int k = 0;
        const BvhNode& nb = bin.nodes[size_t(b)];
        if (nb.count > 0) {
            lanes[k++] = b;  // a leaf root: one lane
            return k;
        }
        if (region.cost) {
            regionSplit(region, b, kBvhWidth, lanes, k);
            sortByArea(lanes, k);
            return k;
        }
        lanes[k++] = b + 1;
        lanes[k++] = nb.first;
        while (k < kBvhWidth) {
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
        sortByArea(lanes, k);
        return k;
    }

    // Orders lanes by their boxes' area, largest first (stable: equal areas keep their order).
    void sortByArea(int lanes[kBvhWidth], int k) const {
        double area[kBvhWidth];
        for (int i = 0; i < k; ++i) {
            const double a = halfArea(bin.nodes[size_t(lanes[i])]);
            area[i] = a >= 0 ? a : 0;  // NaN (inf * 0 on a huge flat box): last, and a strict weak order
        }
        for (int i = 1; i < k; ++i)  // insertion sort
            for (int j = i; j > 0 && area[j] > area[j - 1]; --j) {
                std::swap(area[j], area[j - 1]);
                std::swap(lanes[j], lanes[j - 1]);
            }
    }

    // The region b's node is collapsed in: `outer` if there is one, else b's own if its subtree is small
    // enough (its cost table then in `table`), else none (the top).
    Region regionFor(int b, const Region& outer, std::vector<LaneCosts>& table) const {
        if (outer.cost || bin.nodes[size_t(b)].count > 0) return outer;
        const size_t n = span(b);
        if (n > kCollapseOptimalSpan) return outer;
        regionCosts(b, n, table);
        return Region{b, table.data()};
    }

    // The 8-wide nodes and leaf blocks emit(b) writes (the same choices, nothing written).
    Counts countOf(int b, const Region& outer = {}) const {
        std::vector<LaneCosts> table;
        const Region region = regionFor(b, outer, table);
        int lanes[kBvhWidth];
        const int k = lanesOf(b, lanes, region);
        Counts n;
        n.nodes = 1;
        for (int i = 0; i < k; ++i) {
            const BvhNode& c = bin.nodes[size_t(lanes[i])];
            if (c.count > 0) {
                n.blocks += size_t(c.count + 3) / 4;
            } else {
                const Counts sub = countOf(lanes[i], region);
                n.nodes += sub.nodes;
                n.blocks += sub.blocks;
            }
        }
        return n;
    }

    // Writes the blocks of binary leaf c (its primRefs, four to a block); returns the first block.
    int emitLeaf(const BvhNode& c) {
        // The traversal packs a leaf into one stack entry: ~(first << 4 | count).
        if (c.count > CLRT_BVH_MAX_LEAF)
            throw std::logic_error("collapseBvh8: leaf of " + std::to_string(c.count) + " primitives");
        if (c.first > CLRT_BVH_MAX_PRIMS - c.count)
            throw std::runtime_error("scene has more than " + std::to_string(CLRT_BVH_MAX_PRIMS) +
                                     " primitives (the BVH's limit)");
        const int firstBlock = nextBlock;
        for (int k = 0; k < c.count; k += 4) {
            int* prim = &blocks[size_t(nextBlock++)].x;
            for (int i = 0; i < 4; ++i)
                prim[i] = k + i < c.count ? bin.primRefs[size_t(c.first + k + i)] : CLRT_INVALID;
        }
        return firstBlock;
    }

    // Lane i of node: the box of binary node c (empty: c null) and its stack entry.
    static void setLane(dev::Bvh8Node& node, int i, const BvhNode* c, int entry) {
        for (int a = 0; a < 3; ++a) {
            lanePlane(node, 2 * a, i) = c ? (&c->boundsMin.x)[a] : INFINITY;
            lanePlane(node, 2 * a + 1, i) = c ? (&c->boundsMax.x)[a] : -INFINITY;
        }
        laneEntry(node, i) = entry;
    }

    // Writes the 8-wide node for binary node b and its subtree, depth-first; returns {index, stack
    // need}. Stack need of a subtree: the most entries its traversal pushes, from an empty stack (a
    // node with k hit children pushes k - 1 and goes on into one of them).
    std::pair<int, int> emit(int b, int level, const Region& outer = {}) {
        depth = std::max(depth, level);
        const int idx = nextNode++;
        std::vector<LaneCosts> table;
        const Region region = regionFor(b, outer, table);
        int lanes[kBvhWidth];
        const int k = lanesOf(b, lanes, region);
        dev::Bvh8Node node{};
        int need = 0;
        for (int i = 0; i < kBvhWidth; ++i) {
            const BvhNode* c = i < k ? &bin.nodes[size_t(lanes[i])] : nullptr;
            if (!c) {
                setLane(node, i, nullptr, CLRT_INVALID);
            } else if (c->count > 0) {
                setLane(node, i, c, leafEntry(emitLeaf(*c), c->count));
            } else {
                const auto sub = emit(lanes[i], level + 1, region);
                setLane(node, i, c, sub.first);
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

// The collapse of a big tree on all threads. Its top (8-wide nodes over binary subtrees of more than
// taskSpan binary nodes) is planned on this thread; the subtrees under it are counted, then written, in
// parallel, each at the place its counts give: the top's nodes first (in pre-order), then each subtree's
// (in pre-order), subtrees in the order the top meets them; leaf blocks alike (the top's own leaves
// first). The same 8-wide nodes as one depth-first pass, laid out by the tree alone (never by the
// thread count), parents before children.
class SplitCollapse {
public:
    SplitCollapse(const Bvh& bin, size_t taskSpan) : bin_(bin), taskSpan_(taskSpan), c_{bin, nullptr, nullptr} {}

    // Appends the tree's nodes to `nodes` (spareNodes more reserved) and fills `blocks`; *maxStack, *depth.
    void run(HostArray<dev::Bvh8Node>& nodes, BlockPrims& blocks, size_t spareNodes, int* maxStack, int* depth) {
        plan(0, 1);
        std::vector<Collapser::Counts> counts(tasks_.size());
        parallelFor(tasks_.size(), [&](size_t t) { counts[t] = c_.countOf(tasks_[t].binary); });
        const size_t base = nodes.size();
        size_t nodeEnd = base + tops_.size(), blockEnd = topBlocks_;
        for (size_t t = 0; t < tasks_.size(); ++t) {
            tasks_[t].node = int(nodeEnd);
            tasks_[t].block = int(blockEnd);
            nodeEnd += counts[t].nodes;
            blockEnd += counts[t].blocks;
        }
        reserveMore(nodes, nodeEnd - base + spareNodes);
        nodes.resize(nodeEnd);
        blocks.resize(blockEnd);
        parallelFor(tasks_.size(), [&](size_t t) {
            Collapser c{bin_, nodes.data(), blocks.data(), tasks_[t].node, tasks_[t].block};
            tasks_[t].need = c.emit(tasks_[t].binary, tasks_[t].level).second;
            tasks_[t].depth = c.depth;
        });
        *maxStack = writeTop(nodes, blocks, base);
        *depth = 0;
        for (const Top& top : tops_) *depth = std::max(*depth, top.level);
        for (const Task& t : tasks_) *depth = std::max(*depth, t.depth);
    }

private:
    enum Kind { kLeaf, kTop, kTask };
    struct Top {
        int binary, level, k;
        int lanes[kBvhWidth];
        Kind kind[kBvhWidth];
        int ref[kBvhWidth];  // kTop: index in tops_; kTask: index in tasks_
    };
    struct Task {
        int binary, level;
        int node = 0, block = 0, need = 0, depth = 0;
    };

    // Plans the top node made for binary node b (in pre-order); returns its index in tops_.
    int plan(int b, int level) {
        const int t = int(tops_.size());
        tops_.push_back(Top{b, level, 0, {}, {}, {}});
        int lanes[kBvhWidth];
        const int k = c_.lanesOf(b, lanes);
        tops_[size_t(t)].k = k;
        for (int i = 0; i < k; ++i) {
            tops_[size_t(t)].lanes[i] = lanes[i];
            const BvhNode& c = bin_.nodes[size_t(lanes[i])];
            Kind kind = kLeaf;
            int ref = -1;
            if (c.count > 0) {
                topBlocks_ += size_t(c.count + 3) / 4;
            } else if (c_.span(lanes[i]) > taskSpan_) {
                kind = kTop;
                ref = plan(lanes[i], level + 1);
            } else {
                kind = kTask;
                ref = int(tasks_.size());
                tasks_.push_back(Task{lanes[i], level + 1});
            }
            tops_[size_t(t)].kind[i] = kind;
            tops_[size_t(t)].ref[i] = ref;
        }
        return t;
    }

    // Writes the top's nodes (at base on) and its own leaves' blocks (from 0); returns the root's
    // stack need. Children come after their parents in tops_, so a backward pass has their needs.
    int writeTop(HostArray<dev::Bvh8Node>& nodes, BlockPrims& blocks, size_t base) {
        Collapser c{bin_, nodes.data(), blocks.data(), 0, 0};
        std::vector<int> need(tops_.size(), 0);
        std::vector<int> leafBlock(kBvhWidth * tops_.size(), 0);
        for (size_t t = 0; t < tops_.size(); ++t)  // blocks in pre-order
            for (int i = 0; i < tops_[t].k; ++i)
                if (tops_[t].kind[i] == kLeaf) leafBlock[kBvhWidth * t + size_t(i)] = c.emitLeaf(bin_.nodes[size_t(tops_[t].lanes[i])]);
        for (size_t t = tops_.size(); t-- > 0;) {
            const Top& top = tops_[t];
            dev::Bvh8Node node{};
            int lanesNeed = 0;
            for (int i = 0; i < kBvhWidth; ++i) {
                const BvhNode* b = i < top.k ? &bin_.nodes[size_t(top.lanes[i])] : nullptr;
                if (!b) { Collapser::setLane(node, i, nullptr, CLRT_INVALID); continue; }
                if (top.kind[i] == kLeaf) {
                    Collapser::setLane(node, i, b, leafEntry(leafBlock[kBvhWidth * t + size_t(i)], b->count));
                    continue;
                }
                const bool isTop = top.kind[i] == kTop;
                const int child = isTop ? int(base) + top.ref[i] : tasks_[size_t(top.ref[i])].node;
                lanesNeed = std::max(lanesNeed, isTop ? need[size_t(top.ref[i])] : tasks_[size_t(top.ref[i])].need);
                Collapser::setLane(node, i, b, child);
            }
            need[t] = lanesNeed + (top.k - 1);
            nodes[base + t] = node;
        }
        return need[0];
    }

    const Bvh& bin_;
    size_t taskSpan_;
    Collapser c_;  // for lanesOf and countOf (writes nothing)
    std::vector<Top> tops_;
    std::vector<Task> tasks_;
    size_t topBlocks_ = 0;
};

// The 8-wide nodes of `bvh` appended to `nodes` (child indices of interior lanes are indices of
// `nodes`, leaf lanes index blocks), and its leaf blocks' primitives into blocks; *maxStack and
// *depth its figures. A tree of splitNodes binary nodes or more is collapsed by SplitCollapse.
// False for an empty tree (then one empty node is appended).
bool collapseNodes(const Bvh& bvh, HostArray<dev::Bvh8Node>& nodes, BlockPrims& blocks, int* maxStack, int* depth,
                   size_t spareNodes, size_t splitNodes) {
    if (bvh.primRefs.empty() || bvh.nodes.empty()) {
        dev::Bvh8Node empty{};
        for (int i = 0; i < kBvhWidth; ++i) Collapser::setLane(empty, i, nullptr, CLRT_INVALID);
        nodes.push_back(empty);
        *maxStack = 0;
        *depth = 1;
        return false;
    }
    if (bvh.nodes.size() >= splitNodes) {
        SplitCollapse(bvh, std::max<size_t>(bvh.nodes.size() / 64, 1)).run(nodes, blocks, spareNodes, maxStack, depth);
    } else {
        Collapser c{bvh, nullptr, nullptr};
        const Collapser::Counts n = c.countOf(0);  // sized exactly, so a recycled block fits (util/huge_pages.h)
        reserveMore(nodes, n.nodes + spareNodes);
        const size_t base = nodes.size();
        nodes.resize(base + n.nodes);
        blocks.resize(n.blocks);
        c.out = nodes.data();
        c.blocks = blocks.data();
        c.nextNode = int(base);
        *maxStack = c.emit(0, 1).second;
        *depth = c.depth;
    }
    if (*maxStack > CLRT_BVH8_STACK_SIZE)
        throw std::logic_error("collapseBvh8: traversal stack need " + std::to_string(*maxStack) +
                               " exceeds CLRT_BVH8_STACK_SIZE");
    return true;
}

constexpr size_t kBlocksPerTask = 16384;  // leaf blocks per parallelFor item (2.5 MB)

// The leaf blocks from their primitives, moved by primOffset, appended to `leaves` (vertices zero
// until setLeafTriangles). Written on all threads: most of the time is the kernel zeroing the fresh
// pages each thread touches first (resize leaves them unwritten, util/huge_pages.h).
void makeLeaves(const BlockPrims& blockPrims, int primOffset, HostArray<dev::LeafBlock>& leaves) {
    reserveMore(leaves, blockPrims.size());
    const size_t first = leaves.size(), count = blockPrims.size();
    leaves.resize(first + count);
    parallelFor((count + kBlocksPerTask - 1) / kBlocksPerTask, [&](size_t task) {
        const size_t end = std::min(count, (task + 1) * kBlocksPerTask);
        for (size_t b = task * kBlocksPerTask; b < end; ++b) {
            dev::LeafBlock block{};
            block.prim = blockPrims[b];
            int* prim = &block.prim.x;
            for (int i = 0; i < 4; ++i)
                if (prim[i] >= 0) prim[i] += primOffset;
            leaves[first + b] = block;
        }
    });
}

}  // namespace

Bvh8 collapseBvh8(const Bvh& bvh, size_t splitNodes) {
    Bvh8 r;
    BlockPrims blockPrims;
    if (collapseNodes(bvh, r.nodes, blockPrims, &r.maxStack, &r.depth, 0, splitNodes)) makeLeaves(blockPrims, 0, r.leaves);
    return r;
}

Bvh8 collapseBvh8(Bvh&& bvh) {
    Bvh8 r;
    BlockPrims blockPrims;
    const bool any = collapseNodes(bvh, r.nodes, blockPrims, &r.maxStack, &r.depth, 0, kCollapseSplitNodes);
    bvh = Bvh{};  // freed before the leaf blocks are allocated
    if (any) makeLeaves(blockPrims, 0, r.leaves);
    return r;
}

int appendBvh8(Bvh&& bvh, int primOffset, Bvh8& into, int* maxStack, size_t spareNodes) {
    const size_t root = into.nodes.size(), leafOffset = into.leaves.size();
    BlockPrims blockPrims;
    int stack = 0, depth = 0;
    const bool any = collapseNodes(bvh, into.nodes, blockPrims, &stack, &depth, spareNodes, kCollapseSplitNodes);
    bvh = Bvh{};  // freed before the leaf blocks are allocated
    if (leafOffset + blockPrims.size() > size_t(CLRT_BVH_MAX_PRIMS))
        throw std::runtime_error("scene has more than " + std::to_string(CLRT_BVH_MAX_PRIMS) +
                                 " leaf blocks (the BVH's limit)");
    for (size_t n = root; n < into.nodes.size(); ++n) {
        int* entry = &into.nodes[n].entry[0].x;
        for (int i = 0; i < kBvhWidth; ++i)
            if (entry[i] < 0 && entry[i] != CLRT_INVALID) {  // a leaf: ~(firstBlock << 4 | count)
                const int packed = ~entry[i];
                entry[i] = leafEntry((packed >> 4) + int(leafOffset), packed & 15);
            }
    }
    if (any) makeLeaves(blockPrims, primOffset, into.leaves);
    if (maxStack) *maxStack = stack;
    return int(root);
}

void setLeafTriangles(Bvh8& b8, const dev::Triangle* tris, int numTriangles, size_t firstLeaf) {
    const size_t count = b8.leaves.size() - std::min(firstLeaf, b8.leaves.size());
    parallelFor((count + kBlocksPerTask - 1) / kBlocksPerTask, [&](size_t task) {
        const size_t end = firstLeaf + std::min(count, (task + 1) * kBlocksPerTask);
        for (size_t l = firstLeaf + task * kBlocksPerTask; l < end; ++l) {
            dev::LeafBlock& block = b8.leaves[l];
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
