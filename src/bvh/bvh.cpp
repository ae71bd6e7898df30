// Binned SAH BVH builder. Works on a compact copy of the primitive boxes (32-byte items that are
// partitioned in place), writes BvhNode depth-first (left child = parent + 1) as it recurses,
// and caps the tree depth so the device traversal stack (CLRT_BVH_STACK_SIZE) can never overflow:
// a node whose SAH split would leave a child too deep for a median-split subtree gets a median
// split instead. Costs are evaluated in double so huge scenes cannot overflow to inf or NaN.
// Large subtrees are built on separate threads (right child into its own node array, appended
// afterwards with its indices shifted), so the result is identical for any thread count.
#include "bvh/bvh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <system_error>
#include <thread>

namespace clrt {
namespace {

constexpr int kMaxBins = 64;

// One primitive as the builder sees it. c2 (= lo + hi, twice the centroid) is derived on the fly.
struct Item {
    float lo[3];
    float hi[3];
    int prim;
    int pad;
};

struct Box {
    float lo[3] = {1e30f, 1e30f, 1e30f};
    float hi[3] = {-1e30f, -1e30f, -1e30f};
    void grow(const float* l, const float* h) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], l[a]);
            hi[a] = std::max(hi[a], h[a]);
        }
    }
    void grow(const Box& b) { grow(b.lo, b.hi); }
    bool empty() const { return !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]); }
    // SAH metric: half surface area, or the half perimeter when the node itself is flat in two
    // axes (a segment or a point), so splits inside degenerate nodes can still be compared.
    double metric(bool perimeter) const {
        if (empty()) return 0;
        double dx = double(hi[0]) - lo[0], dy = double(hi[1]) - lo[1], dz = double(hi[2]) - lo[2];
        return perimeter ? dx + dy + dz : dx * dy + dy * dz + dz * dx;
    }
};

struct Bin {
    Box box;
    int count = 0;
};

inline float c2(const Item& it, int axis) { return it.lo[axis] + it.hi[axis]; }

inline int ceilLog2(int n) {
    int l = 0;
    while ((1LL << l) < n) ++l;
    return l;
}

class Builder {
public:
    Builder(const BvhBuildOptions& o, std::vector<Item>& items, std::vector<BvhNode>& nodes)
        : opts_(o), items_(items), nodes_(nodes) {
        bins_ = std::max(2, std::min(kMaxBins, o.bins));
        maxLeaf_ = std::min(CLRT_BVH4_MAX_LEAF, std::max(1, o.maxLeafSize));  // the device packs leaves in 4 bits
    }

    // Levels on the longest root-to-leaf path (root alone = 1); the builder keeps it <= kMaxLevels.
    static constexpr int kMaxLevels = CLRT_BVH_STACK_SIZE - 8;
    static constexpr int kParallelMin = 65536;  // smaller subtrees are not worth a thread
    int depth = 0;

    // threads: how many threads this subtree may use (including the calling one).
    void build(int begin, int end, int level, int threads = 1) {
        depth = std::max(depth, level);
        const int n = end - begin;
        const int idx = int(nodes_.size());
        nodes_.emplace_back();

        Box bounds, cbounds;  // cbounds holds lo + hi (twice the centroid)
        for (int i = begin; i < end; ++i) {
            const Item& it = items_[i];
            bounds.grow(it.lo, it.hi);
            float c[3] = {c2(it, 0), c2(it, 1), c2(it, 2)};
            cbounds.grow(c, c);
        }
        writeBounds(idx, bounds);

        int axis = -1, mid = -1;
        if (n > 1) chooseSplit(begin, end, level, bounds, cbounds, axis, mid);
        if (axis < 0) {  // leaf
            nodes_[idx].first = begin;
            nodes_[idx].count = n;
            nodes_[idx].axis = 0;
            return;
        }
        nodes_[idx].count = 0;
        nodes_[idx].axis = axis;
        if (threads > 1 && n >= kParallelMin) {
            // Right subtree on a new thread into its own array; left subtree here.
            std::vector<BvhNode> rightNodes;
            rightNodes.reserve(size_t(2) * (end - mid));
            Builder right(opts_, items_, rightNodes);
            int rt = threads / 2;
            std::thread worker;
            try {
                worker = std::thread([&] { right.build(mid, end, level + 1, rt); });
            } catch (const std::system_error&) {  // no thread to be had: do it here
                right.build(mid, end, level + 1, 1);
            }
            build(begin, mid, level + 1, threads - rt);
            if (worker.joinable()) worker.join();
            const int offset = int(nodes_.size());
            for (BvhNode nd : rightNodes) {
                if (nd.count == 0) nd.first += offset;
                nodes_.push_back(nd);
            }
            nodes_[idx].first = offset;
            depth = std::max(depth, right.depth);
            return;
        }
        build(begin, mid, level + 1, threads);
        nodes_[idx].first = int(nodes_.size());
        build(mid, end, level + 1, threads);
    }

private:
    // Picks a split for items [begin, end); returns axis = -1 for a leaf. On return items are
    // partitioned so that [begin, mid) is the left child.
    void chooseSplit(int begin, int end, int level, const Box& bounds, const Box& cbounds, int& axis,
                     int& mid) {
        const int n = end - begin;
        const bool perimeter = bounds.metric(false) <= 0;
        const double nodeMetric = bounds.metric(perimeter);

        // ---- binning over the centroid bounds, all three axes at once
        float scale[3];
        bool usable[3];
        for (int a = 0; a < 3; ++a) {
            float ext = cbounds.hi[a] - cbounds.lo[a];
            scale[a] = ext > 0 ? float(bins_) / ext : 0.f;
            usable[a] = ext > 0 && std::isfinite(scale[a]);
        }
        int bestAxis = -1, bestBin = -1;
        double bestCost = INFINITY;
        if (usable[0] || usable[1] || usable[2]) {
            Bin bins[3][kMaxBins];
            for (int i = begin; i < end; ++i) {
                const Item& it = items_[i];
                for (int a = 0; a < 3; ++a) {
                    if (!usable[a]) continue;
                    Bin& b = bins[a][binOf(it, a, cbounds.lo[a], scale[a])];
                    b.box.grow(it.lo, it.hi);
                    b.count++;
                }
            }
            // Sweep: cost of splitting after bin i = sum of child metric * count.
            double rightCost[kMaxBins];
            for (int a = 0; a < 3; ++a) {
                if (!usable[a]) continue;
                Box acc;
                int cnt = 0;
                for (int i = bins_ - 1; i > 0; --i) {
                    acc.grow(bins[a][i].box);
                    cnt += bins[a][i].count;
                    rightCost[i] = cnt ? acc.metric(perimeter) * cnt : -1;
                }
                acc = Box();
                cnt = 0;
                for (int i = 0; i < bins_ - 1; ++i) {
                    acc.grow(bins[a][i].box);
                    cnt += bins[a][i].count;
                    if (cnt == 0 || rightCost[i + 1] < 0) continue;
                    double cost = acc.metric(perimeter) * cnt + rightCost[i + 1];
                    if (cost < bestCost) { bestCost = cost; bestAxis = a; bestBin = i; }
                }
            }
        }

        // ---- leaf or split?
        const double leafCost = nodeMetric * n;
        const double splitCost = nodeMetric * opts_.traversalCost + bestCost;
        if (n <= maxLeaf_ && !(bestAxis >= 0 && splitCost < leafCost)) return;

        if (bestAxis >= 0) {
            Item* first = items_.data() + begin;
            const float lo = cbounds.lo[bestAxis], sc = scale[bestAxis];
            Item* m = std::partition(first, first + n, [&](const Item& it) {
                return binOf(it, bestAxis, lo, sc) <= bestBin;
            });
            int nl = int(m - first), nr = n - nl;
            // Both children must still fit under the depth cap with median splits below them.
            if (nl > 0 && nr > 0 && level + 1 + ceilLog2(std::max(nl, nr)) <= kMaxLevels) {
                axis = bestAxis;
                mid = begin + nl;
                return;
            }
        }
        // ---- fallback: object median along the widest centroid axis (any order if all coincide)
        int a = 0;
        for (int k = 1; k < 3; ++k)
            if (cbounds.hi[k] - cbounds.lo[k] > cbounds.hi[a] - cbounds.lo[a]) a = k;
        mid = begin + n / 2;
        std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                         [a](const Item& x, const Item& y) { return c2(x, a) < c2(y, a); });
        axis = a;
    }

    int binOf(const Item& it, int a, float lo, float scale) const {
        int b = int((c2(it, a) - lo) * scale);
        return std::min(bins_ - 1, std::max(0, b));
    }

    void writeBounds(int idx, const Box& b) {
        BvhNode& nd = nodes_[idx];
        nd.boundsMin = {b.lo[0], b.lo[1], b.lo[2], 0.f};
        nd.boundsMax = {b.hi[0], b.hi[1], b.hi[2], 0.f};
        nd.pad0 = 0;
    }

    const BvhBuildOptions& opts_;
    std::vector<Item>& items_;
    std::vector<BvhNode>& nodes_;
    int bins_ = 16;
    int maxLeaf_ = 4;
};

double nodeArea(const BvhNode& nd) {
    Box b;
    std::memcpy(b.lo, &nd.boundsMin, sizeof b.lo);
    std::memcpy(b.hi, &nd.boundsMax, sizeof b.hi);
    return b.metric(false);
}

}  // namespace

Bvh buildBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& opts) {
    Bvh bvh;
    const int n = int(primBounds.size());
    if (n == 0) {
        // Single empty node with inverted bounds; callers must not traverse (primRefs is empty).
        BvhNode root{};
        root.boundsMin = {1e30f, 1e30f, 1e30f, 0.f};
        root.boundsMax = {-1e30f, -1e30f, -1e30f, 0.f};
        root.first = 0;
        root.count = 0;
        bvh.nodes.push_back(root);
        bvh.depth = 1;
        return bvh;
    }

    // Boxes with NaN/inf or min > max become empty items (centroid 0); they are still referenced
    // once, in some leaf, and never widen any node's bounds.
    std::vector<Item> items(n);
    for (int i = 0; i < n; ++i) {
        const Aabb& b = primBounds[i];
        Item& it = items[i];
        it.prim = i;
        it.pad = 0;
        if (isFinite(b.min) && isFinite(b.max) && b.valid()) {
            for (int a = 0; a < 3; ++a) { it.lo[a] = b.min[a]; it.hi[a] = b.max[a]; }
        } else {
            for (int a = 0; a < 3; ++a) { it.lo[a] = 1e30f; it.hi[a] = -1e30f; }
        }
    }

    bvh.nodes.reserve(size_t(2) * n);
    Builder builder(opts, items, bvh.nodes);
    int threads = opts.maxThreads > 0 ? opts.maxThreads : int(std::thread::hardware_concurrency());
    builder.build(0, n, 1, std::max(1, threads));
    bvh.depth = builder.depth;

    bvh.primRefs.resize(n);
    for (int i = 0; i < n; ++i) bvh.primRefs[i] = items[i].prim;

    double rootArea = nodeArea(bvh.nodes[0]);
    double cost = 0;
    for (const BvhNode& nd : bvh.nodes) {
        double rel = rootArea > 0 ? nodeArea(nd) / rootArea : 1.0;
        cost += rel * (nd.count > 0 ? double(nd.count) : double(opts.traversalCost));
    }
    bvh.sahCost = float(cost);
    return bvh;
}

}  // namespace clrt
