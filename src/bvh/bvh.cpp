// Binned SAH BVH builder. Works on a compact copy of the primitive boxes (32-byte items that are
// partitioned in place), writes BvhNode depth-first (left child = parent + 1) as it recurses,
// and caps the tree depth so the device traversal stack (CLRT_BVH_STACK_SIZE) can never overflow:
// a node whose SAH split would leave a child too deep for a median-split subtree gets a median
// split instead. Costs are evaluated in double so huge scenes cannot overflow to inf or NaN.
// Each node reads its items twice: one pass bins them on all three axes at once (4-wide SIMD: an
// item is two vectors), and the partition pass gathers both children's bounds and centroid bounds
// on the way, so a child never rescans its items for them.
// Large subtrees are built on separate threads (right child into its own node array, appended
// afterwards with its indices shifted), so the result is identical for any thread count.
#include "bvh/bvh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <system_error>
#include <thread>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define CLRT_BVH_SSE 1
#endif

namespace clrt {
namespace {

constexpr int kMaxBins = 64;

// ---- four floats (x, y, z and a fourth lane kept at 0): one SSE register where there is SSE,
// else plain floats with the same results.
#ifdef CLRT_BVH_SSE
struct F4 {
    __m128 v;
};
inline F4 f4(float x, float y, float z) { return {_mm_set_ps(0.f, z, y, x)}; }
inline F4 f4(float s) { return {_mm_set_ps(0.f, s, s, s)}; }
inline F4 load3(const float* p) {  // p[0..2], 16-byte aligned; the fourth lane reads as 0
    return {_mm_and_ps(_mm_load_ps(p), _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)))};
}
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4 min4(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }  // a < b ? a : b per lane
inline F4 max4(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }  // a > b ? a : b per lane
inline void store(F4 a, float out[4]) { _mm_storeu_ps(out, a.v); }
inline void truncate(F4 a, int out[4]) { _mm_storeu_si128((__m128i*)out, _mm_cvttps_epi32(a.v)); }
#else
struct F4 {
    float v[4];
};
inline F4 f4(float x, float y, float z) { return {{x, y, z, 0.f}}; }
inline F4 f4(float s) { return {{s, s, s, 0.f}}; }
inline F4 load3(const float* p) { return {{p[0], p[1], p[2], 0.f}}; }
template <class Op>
inline F4 lanes(F4 a, F4 b, Op op) {
    return {{op(a.v[0], b.v[0]), op(a.v[1], b.v[1]), op(a.v[2], b.v[2]), op(a.v[3], b.v[3])}};
}
inline F4 operator+(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x + y; }); }
inline F4 operator-(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x - y; }); }
inline F4 operator*(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x * y; }); }
inline F4 min4(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x < y ? x : y; }); }
inline F4 max4(F4 a, F4 b) { return lanes(a, b, [](float x, float y) { return x > y ? x : y; }); }
inline void store(F4 a, float out[4]) { std::memcpy(out, a.v, sizeof a.v); }
inline void truncate(F4 a, int out[4]) {  // as cvttps2dq: NaN and out of range give INT_MIN
    for (int k = 0; k < 4; ++k) out[k] = std::fabs(a.v[k]) < 2147483648.f ? int(a.v[k]) : INT32_MIN;
}
#endif

// One primitive as the builder sees it: lo and hi load as one vector each; prim rides in lo's
// fourth lane (load3 masks it off). c = lo + hi (twice the centroid) is derived on the fly.
struct alignas(16) Item {
    float lo[3];
    int prim;
    float hi[3];
    int pad;
};

struct Box {
    F4 lo = f4(1e30f), hi = f4(-1e30f);
    void grow(F4 l, F4 h) { lo = min4(lo, l); hi = max4(hi, h); }
    void grow(const Box& b) { grow(b.lo, b.hi); }
    // SAH metric: half surface area, or the half perimeter when the node itself is flat in two
    // axes (a segment or a point), so splits inside degenerate nodes can still be compared.
    // 0 for an empty (inverted) box.
    double metric(bool perimeter) const {
        float l[4], h[4];
        store(lo, l);
        store(hi, h);
        if (!(l[0] <= h[0] && l[1] <= h[1] && l[2] <= h[2])) return 0;
        double dx = double(h[0]) - l[0], dy = double(h[1]) - l[1], dz = double(h[2]) - l[2];
        return perimeter ? dx + dy + dz : dx * dy + dy * dz + dz * dx;
    }
};

// A node's item range with its bounds and centroid bounds (bounds of lo + hi).
struct Range {
    int begin, end;
    Box bounds, cbounds;
};

struct Bin {
    Box box;
    int count;
};

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

    // Bounds and centroid bounds of items [begin, end), by a pass over them.
    Range scan(int begin, int end) const {
        Range r{begin, end, {}, {}};
        for (int i = begin; i < end; ++i) {
            F4 lo = load3(items_[i].lo), hi = load3(items_[i].hi);
            r.bounds.grow(lo, hi);
            r.cbounds.grow(lo + hi, lo + hi);
        }
        return r;
    }

    // threads: how many threads this subtree may use (including the calling one).
    void build(const Range& r, int level, int threads = 1) {
        depth = std::max(depth, level);
        const int n = r.end - r.begin;
        const int idx = int(nodes_.size());
        nodes_.emplace_back();
        writeBounds(idx, r.bounds);

        Range left, right;
        int axis = n > 1 ? split(r, level, left, right) : -1;
        if (axis < 0) {  // leaf
            nodes_[idx].first = r.begin;
            nodes_[idx].count = n;
            nodes_[idx].axis = 0;
            return;
        }
        nodes_[idx].count = 0;
        nodes_[idx].axis = axis;
        if (threads > 1 && n >= kParallelMin) {
            // Right subtree on a new thread into its own array; left subtree here.
            std::vector<BvhNode> rightNodes;
            rightNodes.reserve(size_t(2) * (right.end - right.begin));
            Builder rightBuilder(opts_, items_, rightNodes);
            int rt = threads / 2;
            std::thread worker;
            try {
                worker = std::thread([&] { rightBuilder.build(right, level + 1, rt); });
            } catch (const std::system_error&) {  // no thread to be had: do it here
                rightBuilder.build(right, level + 1, 1);
            }
            build(left, level + 1, threads - rt);
            if (worker.joinable()) worker.join();
            const int offset = int(nodes_.size());
            for (BvhNode nd : rightNodes) {
                if (nd.count == 0) nd.first += offset;
                nodes_.push_back(nd);
            }
            nodes_[idx].first = offset;
            depth = std::max(depth, rightBuilder.depth);
            return;
        }
        build(left, level + 1, threads);
        nodes_[idx].first = int(nodes_.size());
        build(right, level + 1, threads);
    }

private:
    // Picks a split for node r; returns its axis, or -1 for a leaf. On a split, the items are
    // partitioned so that left and right are the children's ranges, boxes included.
    int split(const Range& r, int level, Range& left, Range& right) {
        const int n = r.end - r.begin;
        const bool perimeter = r.bounds.metric(false) <= 0;
        const double nodeMetric = r.bounds.metric(perimeter);

        // ---- binning over the centroid bounds, all three axes at once
        float clo[4], chi[4], scale[4] = {0, 0, 0, 0};
        store(r.cbounds.lo, clo);
        store(r.cbounds.hi, chi);
        bool usable[3];
        for (int a = 0; a < 3; ++a) {
            float ext = chi[a] - clo[a];
            scale[a] = ext > 0 ? float(bins_) / ext : 0.f;
            usable[a] = ext > 0 && std::isfinite(scale[a]);
        }
        const Binner binner{r.cbounds.lo, f4(scale[0], scale[1], scale[2]), f4(float(bins_ - 1))};
        int bestAxis = -1, bestBin = -1;
        double bestCost = INFINITY;
        if (usable[0] || usable[1] || usable[2]) {
            Bin bins[3][kMaxBins];
            for (auto& axisBins : bins)
                for (int i = 0; i < bins_; ++i) axisBins[i] = Bin{Box(), 0};
            for (int i = r.begin; i < r.end; ++i) {
                F4 lo = load3(items_[i].lo), hi = load3(items_[i].hi);
                int b[4];
                binner.binsOf(lo + hi, b);
                for (int a = 0; a < 3; ++a) {  // unusable axes are binned too, and ignored
                    bins[a][b[a]].box.grow(lo, hi);
                    bins[a][b[a]].count++;
                }
            }
            // Sweep: cost of splitting after bin i = sum of child metric * count. An empty bin
            // changes neither side, so its split costs what the one before it does: skipped.
            double rightCost[kMaxBins + 1];
            for (int a = 0; a < 3; ++a) {
                if (!usable[a]) continue;
                Box acc;
                int cnt = 0;
                rightCost[bins_] = -1;
                for (int i = bins_ - 1; i > 0; --i) {
                    if (bins[a][i].count == 0) { rightCost[i] = rightCost[i + 1]; continue; }
                    acc.grow(bins[a][i].box);
                    cnt += bins[a][i].count;
                    rightCost[i] = acc.metric(perimeter) * cnt;
                }
                acc = Box();
                cnt = 0;
                for (int i = 0; i < bins_ - 1; ++i) {
                    if (bins[a][i].count == 0) continue;
                    acc.grow(bins[a][i].box);
                    cnt += bins[a][i].count;
                    if (rightCost[i + 1] < 0) continue;
                    double cost = acc.metric(perimeter) * cnt + rightCost[i + 1];
                    if (cost < bestCost) { bestCost = cost; bestAxis = a; bestBin = i; }
                }
            }
        }

        // ---- leaf or split?
        const double leafCost = nodeMetric * n;
        const double splitCost = nodeMetric * opts_.traversalCost + bestCost;
        if (n <= maxLeaf_ && !(bestAxis >= 0 && splitCost < leafCost)) return -1;

        if (bestAxis >= 0) {
            partition(r, binner, bestAxis, bestBin, left, right);
            int nl = left.end - left.begin, nr = right.end - right.begin;
            // Both children must still fit under the depth cap with median splits below them.
            if (nl > 0 && nr > 0 && level + 1 + ceilLog2(std::max(nl, nr)) <= kMaxLevels) return bestAxis;
        }
        // ---- fallback: object median along the widest centroid axis (any order if all coincide)
        int a = 0;
        for (int k = 1; k < 3; ++k)
            if (chi[k] - clo[k] > chi[a] - clo[a]) a = k;
        const int mid = r.begin + n / 2;
        auto c2 = [a](const Item& it) { return it.lo[a] + it.hi[a]; };
        std::nth_element(items_.begin() + r.begin, items_.begin() + mid, items_.begin() + r.end,
                         [&](const Item& x, const Item& y) { return c2(x) < c2(y); });
        left = scan(r.begin, mid);
        right = scan(mid, r.end);
        return a;
    }

    // Bin of an item on each axis from c = lo + hi: int((c - lo) * scale) clamped to
    // [0, bins - 1] (clamping before truncating gives the same; NaN lands in bin 0).
    struct Binner {
        F4 lo, scale, maxBin;
        void binsOf(F4 c, int out[4]) const { truncate(min4(max4((c - lo) * scale, f4(0.f)), maxBin), out); }
    };

    // Partitions r's items in place so that those in bins <= bin on axis come first (in the same
    // order as std::partition), growing each side's bounds and centroid bounds as they are sorted.
    void partition(const Range& r, const Binner& binner, int axis, int bin, Range& left, Range& right) {
        left = right = Range{r.begin, r.end, {}, {}};
        int i = r.begin, j = r.end;
        for (;;) {
            for (; i < j; ++i) {
                F4 lo = load3(items_[i].lo), hi = load3(items_[i].hi);
                int b[4];
                binner.binsOf(lo + hi, b);
                if (b[axis] > bin) break;
                left.bounds.grow(lo, hi);
                left.cbounds.grow(lo + hi, lo + hi);
            }
            for (; i < j; --j) {
                F4 lo = load3(items_[j - 1].lo), hi = load3(items_[j - 1].hi);
                int b[4];
                binner.binsOf(lo + hi, b);
                if (b[axis] <= bin) break;
                right.bounds.grow(lo, hi);
                right.cbounds.grow(lo + hi, lo + hi);
            }
            if (i == j) break;
            std::swap(items_[i], items_[j - 1]);
        }
        left.end = right.begin = i;
    }

    void writeBounds(int idx, const Box& b) {
        float lo[4], hi[4];
        store(b.lo, lo);
        store(b.hi, hi);
        BvhNode& nd = nodes_[idx];
        nd.boundsMin = {lo[0], lo[1], lo[2], 0.f};
        nd.boundsMax = {hi[0], hi[1], hi[2], 0.f};
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
    b.lo = f4(nd.boundsMin.x, nd.boundsMin.y, nd.boundsMin.z);
    b.hi = f4(nd.boundsMax.x, nd.boundsMax.y, nd.boundsMax.z);
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
    builder.build(builder.scan(0, n), 1, std::max(1, threads));
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
