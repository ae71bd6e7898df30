// Binned SAH BVH builder. Works on a compact copy of the primitive boxes (32-byte items that are
// partitioned in place), writes BvhNode depth-first (left child = parent + 1), and caps the tree
// depth so the device traversal stack (CLRT_BVH_STACK_SIZE) can never overflow: a node whose SAH
// split would leave a child too deep for a median-split subtree gets a median split instead.
// Costs are evaluated in double so huge scenes cannot overflow to inf or NaN.
// A node takes two passes over its items: binning, on all three axes at once (4-wide SIMD: an
// item is two vectors), and the partition, which also gathers each child's bounds and centroid
// bounds, so no node rescans its items for them. The SAH sweep visits only nonempty bins.
// On several threads, big nodes are split as tasks of their own and smaller subtrees built whole
// by any thread, while the calling thread assembles the tree depth-first, so the result is
// identical for any thread count.
#include "bvh/bvh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <system_error>
#include <thread>

#include "bvh/simd4.h"
#include "util/parallel.h"

namespace clrt {
namespace {
using namespace simd4;

constexpr int kMaxBins = 64;

// One primitive as the builder sees it (bvh.h): lo and hi load as one vector each, prim riding in the
// fourth lane of lo (pad, in that of hi, stays 0).
using Item = BvhItem;
static_assert(sizeof(Item) == 32, "an item is two 16-byte vectors");

// An item in registers: c = lo + hi is twice its centroid (fourth lane 0: prim is masked off
// before the add, so no stray bits become a denormal).
struct ItemV {
    F4 lo, hi, c;
    explicit ItemV(const Item& it) : lo(load4(it.lo)), hi(load4(it.hi)), c(xyz(lo) + hi) {}
};

struct Box {
    F4 lo = f4(1e30f), hi = f4(-1e30f);
    void grow(F4 l, F4 h) { lo = min4(lo, l); hi = max4(hi, h); }
    void grow(const Box& b) { grow(b.lo, b.hi); }
    // SAH metric: half surface area, or the half perimeter when the node itself is flat in two
    // axes (a segment or a point), so splits inside degenerate nodes can still be compared.
    // 0 for an empty (inverted) box.
    double metric(bool perimeter) const {
        double d[3];
        if (!extent(lo, hi, d)) return 0;
        return perimeter ? d[0] + d[1] + d[2] : d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    }
};

// A node's item range with its bounds and centroid bounds (bounds of lo + hi).
struct Range {
    int begin, end;
    Box bounds, cbounds;
};

// Bounds and centroid bounds of items [begin, end), by a pass over them.
Range scan(const Item* items, int begin, int end) {
    Range r{begin, end, {}, {}};
    for (int i = begin; i < end; ++i) {
        ItemV v(items[i]);
        r.bounds.grow(v.lo, v.hi);
        r.cbounds.grow(v.c, v.c);
    }
    return r;
}

struct Bin {
    Box box;
    int count = 0;
};

inline int ceilLog2(int n) {
    int l = 0;
    while ((1LL << l) < n) ++l;
    return l;
}

class Builder {
public:
    Builder(const BvhBuildOptions& o, Item* items) : opts_(o), items_(items) {
        numBins_ = std::max(2, std::min(kMaxBins, o.bins));
        maxLeaf_ = std::min(CLRT_BVH_MAX_LEAF, std::max(1, o.maxLeafSize));  // the device packs leaves in 4 bits
    }

    // Levels on the longest root-to-leaf path (root alone = 1); the builder keeps it <= kMaxLevels.
    static constexpr int kMaxLevels = CLRT_BVH_STACK_SIZE - 8;
    int depth = 0;

    // Makes the node of r: a leaf (false), or an interior node whose children are left and right,
    // its `first` still to be set.
    bool makeNode(const Range& r, int level, BvhNode& node, Range& left, Range& right) {
        depth = std::max(depth, level);
        float lo[4], hi[4];
        store(r.bounds.lo, lo);
        store(r.bounds.hi, hi);
        node.boundsMin = {lo[0], lo[1], lo[2], 0.f};
        node.boundsMax = {hi[0], hi[1], hi[2], 0.f};
        node.pad0 = 0;
        const int n = r.end - r.begin;
        const int axis = n > 1 ? split(r, level, left, right) : -1;
        node.first = axis < 0 ? r.begin : 0;
        node.count = axis < 0 ? n : 0;
        node.axis = std::max(axis, 0);
        return axis >= 0;
    }

    // Appends the subtree of r to nodes, depth-first.
    template <class Nodes>  // BvhNodes, or a task's std::vector (bvh.h)
    void build(const Range& r, int level, Nodes& nodes) {
        const size_t idx = nodes.size();
        nodes.emplace_back();
        Range left, right;
        if (!makeNode(r, level, nodes[idx], left, right)) return;
        build(left, level + 1, nodes);
        nodes[idx].first = int(nodes.size());
        build(right, level + 1, nodes);
    }

private:
    // Bin of an item on each axis from c = lo + hi: int((c - lo) * scale) clamped to
    // [0, bins - 1] (clamping before truncating gives the same; NaN lands in bin 0).
    struct Binner {
        F4 lo, scale, maxBin;
        void binsOf(F4 c, int out[4]) const { truncate(min4(max4((c - lo) * scale, f4(0.f)), maxBin), out); }
    };

    // The best SAH split found so far: after bin `bin` on `axis` (-1: none), and its cost.
    struct SplitChoice {
        int axis = -1, bin = -1;
        double cost = INFINITY;
    };

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
            scale[a] = ext > 0 ? float(numBins_) / ext : 0.f;
            usable[a] = ext > 0 && std::isfinite(scale[a]);
        }
        const Binner binner{r.cbounds.lo, f4(scale[0], scale[1], scale[2]), f4(float(numBins_ - 1))};
        SplitChoice best;
        if (n == 2)
            best = splitOfTwo(r, binner, usable, perimeter);
        else if (usable[0] || usable[1] || usable[2])
            best = binnedSplit(r, binner, usable, perimeter);

        // ---- leaf or split?
        const double leafCost = nodeMetric * n;
        const double splitCost = nodeMetric * opts_.traversalCost + best.cost;
        if (n <= maxLeaf_ && !(best.axis >= 0 && splitCost < leafCost)) return -1;

        if (best.axis >= 0) {
            partition(r, binner, best.axis, best.bin, left, right);
            int nl = left.end - left.begin, nr = right.end - right.begin;
            // Both children must still fit under the depth cap with median splits below them.
            if (nl > 0 && nr > 0 && level + 1 + ceilLog2(std::max(nl, nr)) <= kMaxLevels) return best.axis;
        }
        return medianSplit(r, clo, chi, left, right);
    }

    // Two items (over a third of the nodes): each usable axis where they fall in different bins
    // offers the one split that parts them, at the same cost; the first such axis wins.
    SplitChoice splitOfTwo(const Range& r, const Binner& binner, const bool usable[3], bool perimeter) const {
        SplitChoice best;
        const ItemV v0(items_[r.begin]), v1(items_[r.begin + 1]);
        int b0[4], b1[4];
        binner.binsOf(v0.c, b0);
        binner.binsOf(v1.c, b1);
        for (int a = 0; a < 3 && best.axis < 0; ++a) {
            if (!usable[a] || b0[a] == b1[a]) continue;
            Box x, y;
            x.grow(v0.lo, v0.hi);
            y.grow(v1.lo, v1.hi);
            best.cost = x.metric(perimeter) + y.metric(perimeter);
            best.axis = a;
            best.bin = std::min(b0[a], b1[a]);
        }
        return best;
    }

    // Bins r's items on all three axes (unusable axes are binned too, and ignored), then sweeps
    // the usable ones for the cheapest split. A big node bins its items alternately into two sets of
    // bins, merged before the sweep: neighbouring items often fall in the same bins, and one set would
    // make each update wait for the last one's store.
    SplitChoice binnedSplit(const Range& r, const Binner& binner, const bool usable[3], bool perimeter) {
        auto binItem = [&](Bin (*bins)[kMaxBins], const Item& item) {
            ItemV v(item);
            int b[4];
            binner.binsOf(v.c, b);
            for (int a = 0; a < 3; ++a) {
                bins[a][b[a]].box.grow(v.lo, v.hi);
                bins[a][b[a]].count++;
            }
        };
        int i = r.begin;
        if (r.end - r.begin >= kTwoSetsMin) {
            for (; i + 1 < r.end; i += 2) {
                binItem(bins_, items_[i]);
                binItem(bins2_, items_[i + 1]);
            }
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < numBins_; ++k) {
                    Bin& from = bins2_[a][k];
                    if (from.count == 0) continue;
                    bins_[a][k].box.grow(from.box);
                    bins_[a][k].count += from.count;
                    from = Bin();
                }
        }
        for (; i < r.end; ++i) binItem(bins_, items_[i]);
        SplitChoice best;
        for (int a = 0; a < 3; ++a) sweepAxis(a, usable[a], perimeter, best);
        return best;
    }

    // Sweep: cost of splitting after bin i = sum of child metric * count. An empty bin changes
    // neither side, so its split costs what the one before it does and never wins: only the
    // nonempty bins are swept (a small node has few), and then emptied again.
    void sweepAxis(int a, bool usable, bool perimeter, SplitChoice& best) {
        Bin* bins = bins_[a];
        int used[kMaxBins], m = 0;  // the nonempty bins, in order
        for (int i = 0; i < numBins_; i += 4) {  // by fours (bins past numBins_ stay empty)
            if ((bins[i].count | bins[i + 1].count | bins[i + 2].count | bins[i + 3].count) == 0) continue;
            for (int k = i; k < i + 4; ++k) {
                used[m] = k;
                m += bins[k].count != 0;
            }
        }
        double rightCost[kMaxBins];  // [k]: cost of bins used[k], used[k + 1], ...
        Box acc;
        int cnt = 0;
        for (int k = m - 1; k > 0 && usable; --k) {
            acc.grow(bins[used[k]].box);
            cnt += bins[used[k]].count;
            rightCost[k] = acc.metric(perimeter) * cnt;
        }
        acc = Box();
        cnt = 0;
        for (int k = 0; k < m - 1 && usable; ++k) {
            acc.grow(bins[used[k]].box);
            cnt += bins[used[k]].count;
            double cost = acc.metric(perimeter) * cnt + rightCost[k + 1];
            if (cost < best.cost) { best.cost = cost; best.axis = a; best.bin = used[k]; }
        }
        for (int k = 0; k < m; ++k) bins[used[k]] = Bin();
    }

    // Fallback: object median along the widest centroid axis (any order if all coincide).
    int medianSplit(const Range& r, const float clo[4], const float chi[4], Range& left, Range& right) {
        int a = 0;
        for (int k = 1; k < 3; ++k)
            if (chi[k] - clo[k] > chi[a] - clo[a]) a = k;
        const int mid = r.begin + (r.end - r.begin) / 2;
        auto c2 = [a](const Item& it) { return it.lo[a] + it.hi[a]; };
        std::nth_element(items_ + r.begin, items_ + mid, items_ + r.end,
                         [&](const Item& x, const Item& y) { return c2(x) < c2(y); });
        left = scan(items_, r.begin, mid);
        right = scan(items_, mid, r.end);
        return a;
    }

    // Partitions r's items in place so that those in bins <= bin on axis come first (in the same
    // order as std::partition), growing each side's bounds and centroid bounds as they are sorted.
    void partition(const Range& r, const Binner& binner, int axis, int bin, Range& left, Range& right) {
        Item* items = items_;
        Box lb, lc, rb, rc;  // bounds and centroid bounds of each side
        int i = r.begin, j = r.end;
        for (;;) {
            for (; i < j; ++i) {
                ItemV v(items[i]);
                int b[4];
                binner.binsOf(v.c, b);
                if (b[axis] > bin) break;
                lb.grow(v.lo, v.hi);
                lc.grow(v.c, v.c);
            }
            for (; i < j; --j) {
                ItemV v(items[j - 1]);
                int b[4];
                binner.binsOf(v.c, b);
                if (b[axis] <= bin) break;
                rb.grow(v.lo, v.hi);
                rc.grow(v.c, v.c);
            }
            if (i == j) break;
            std::swap(items[i], items[j - 1]);
        }
        left = Range{r.begin, i, lb, lc};
        right = Range{i, r.end, rb, rc};
    }

    const BvhBuildOptions& opts_;
    Item* items_;
    int numBins_ = 16;
    int maxLeaf_ = 4;
    static constexpr int kTwoSetsMin = 256;  // nodes of this many items bin into two sets (binnedSplit)
    Bin bins_[3][kMaxBins];   // per axis; all empty between nodes
    Bin bins2_[3][kMaxBins];  // the second set; all empty between nodes
};

// The SAH cost of a tree, summed node by node in order: node area relative to the root's, times
// the node's primitives (leaf) or the traversal cost (interior).
struct SahSum {
    double rootArea, traversalCost, cost = 0;
    static double area(const BvhNode& nd) {
        double dx = double(nd.boundsMax.x) - nd.boundsMin.x, dy = double(nd.boundsMax.y) - nd.boundsMin.y,
               dz = double(nd.boundsMax.z) - nd.boundsMin.z;
        return dx >= 0 && dy >= 0 && dz >= 0 ? dx * dy + dy * dz + dz * dx : 0;
    }
    SahSum(const Box& root, float traversal) : rootArea(root.metric(false)), traversalCost(traversal) {}
    void add(const BvhNode& nd) {
        double rel = rootArea > 0 ? area(nd) / rootArea : 1.0;
        cost += rel * (nd.count > 0 ? double(nd.count) : traversalCost);
    }
};

// A node range for some thread to build. A big one (more than the task size) is only split: its
// node is made and its children become tasks. A smaller one is built whole: straight into place
// by the thread that assembles the tree, or by another into an array of its own, copied later.
struct Task {
    Range range;
    int level;
    uint64_t path;  // its turns from the root (1 = right), the first one in the top bit
    bool taken = false, done = false;
    BvhNode node{};              // split: its node
    int left = -1, right = -1;   // split: its children's tasks (none: it made a leaf)
    std::vector<BvhNode> nodes;  // built whole apart: its subtree (plain heap memory: many, short-lived)
    int depth = 0;
    Task(const Range& r, int lvl, uint64_t p) : range(r), level(lvl), path(p) {}
};

// The build on several threads. The calling thread assembles the tree in bvh.nodes depth-first,
// left to right, running each task it comes to that nobody took yet; the other threads take tasks
// from the right end. So most of the caller's work lands in place at once, the two ends meet
// somewhere in the middle, and the tree is the same whoever built which part.
class ParallelBuild {
public:
    ParallelBuild(const BvhBuildOptions& opts, Item* items, int threads, Bvh& bvh)
        : opts_(opts), items_(items), threads_(threads), bvh_(bvh) {}

    // Fills bvh (nodes, primRefs, depth, sahCost); primRefs is already sized.
    void run(const Range& root) {
        taskSize_ = std::max(kTaskMin, (root.end - root.begin) / (8 * threads_));  // ~8 per thread
        sah_ = SahSum(root.bounds, opts_.traversalCost);
        const int rootTask = push(root, 1, 0);
        std::vector<std::thread> workers;
        for (int i = 1; i < threads_; ++i) {
            try {
                workers.emplace_back([this] {
                    while (runNext(nullptr)) {}
                });
            } catch (const std::system_error&) {  // fewer threads to be had: fine
                break;
            }
        }
        place(rootTask);
        for (std::thread& w : workers) w.join();
        bvh_.sahCost = float(sah_.cost);
    }

private:
    static constexpr int kTaskMin = 4096;  // no smaller tasks (unless the tree is)

    bool whole(const Task& t) const { return t.range.end - t.range.begin <= taskSize_; }

    int push(const Range& r, int level, uint64_t path) {
        std::lock_guard<std::mutex> lock(m_);
        tasks_.emplace_back(r, level, path);
        waiting_.push_back(int(tasks_.size()) - 1);
        cv_.notify_all();
        return int(tasks_.size()) - 1;
    }

    // Task k if nobody has taken it yet (this thread then runs it and completes it), else null.
    Task* claim(int k) {
        std::lock_guard<std::mutex> lock(m_);
        Task& t = tasks_[size_t(k)];
        if (t.taken) return nullptr;
        waiting_.erase(std::find(waiting_.begin(), waiting_.end(), k));
        t.taken = true;
        ++running_;
        return &t;
    }

    void complete(Task& t) {
        std::lock_guard<std::mutex> lock(m_);
        t.done = true;
        --running_;
        cv_.notify_all();
    }

    // Takes a waiting task and runs it apart: the rightmost, or with `until` (the assembling
    // thread, while another builds that task) the leftmost. False, running nothing, once `until`
    // is done, or without it once no task waits and none runs (so none can come).
    bool runNext(const Task* until) {
        Task* t;
        {
            std::unique_lock<std::mutex> lock(m_);
            for (;;) {
                if (until ? until->done : waiting_.empty() && running_ == 0) return false;
                if (!waiting_.empty()) break;
                cv_.wait(lock);
            }
            auto lefter = [&](int a, int b) { return tasks_[size_t(a)].path < tasks_[size_t(b)].path; };
            auto pick = until ? std::min_element(waiting_.begin(), waiting_.end(), lefter)
                              : std::max_element(waiting_.begin(), waiting_.end(), lefter);
            t = &tasks_[size_t(*pick)];
            waiting_.erase(pick);
            t->taken = true;
            ++running_;
        }
        runTask(*t);
        complete(*t);
        return true;
    }

    void runTask(Task& t) {
        Builder b(opts_, items_);
        Range left, right;
        if (whole(t)) {
            t.nodes.reserve(size_t(2) * (t.range.end - t.range.begin));
            b.build(t.range, t.level, t.nodes);
        } else if (b.makeNode(t.range, t.level, t.node, left, right)) {
            const uint64_t right1 = uint64_t(1) << (64 - t.level);  // levels stay below 64
            t.left = push(left, t.level + 1, t.path);
            t.right = push(right, t.level + 1, t.path | right1);
        }
        t.depth = b.depth;
        if (t.left < 0) setPrimRefs(t.range);
    }

    void setPrimRefs(const Range& r) {
        for (int i = r.begin; i < r.end; ++i) bvh_.primRefs[size_t(i)] = items_[i].prim;
    }

    void append(const BvhNode& nd) {
        bvh_.nodes.push_back(nd);
        sah_.add(nd);
    }

    // Puts the subtree of task k in place: at the end of bvh.nodes, depth-first.
    void place(int k) {
        Task* t = claim(k);
        if (t && whole(*t)) {  // nobody took it: built right here, in place
            Builder b(opts_, items_);
            const size_t first = bvh_.nodes.size();
            b.build(t->range, t->level, bvh_.nodes);
            for (size_t i = first; i < bvh_.nodes.size(); ++i) sah_.add(bvh_.nodes[i]);
            setPrimRefs(t->range);
            bvh_.depth = std::max(bvh_.depth, b.depth);
            complete(*t);
            return;
        }
        if (t) {  // a split nobody took
            runTask(*t);
            complete(*t);
        } else {  // another thread has it: help with other tasks until it is done
            {
                std::lock_guard<std::mutex> lock(m_);
                t = &tasks_[size_t(k)];
            }
            while (runNext(t)) {}
        }
        bvh_.depth = std::max(bvh_.depth, t->depth);
        if (t->left >= 0) {
            const size_t idx = bvh_.nodes.size();
            append(t->node);
            place(t->left);
            bvh_.nodes[idx].first = int(bvh_.nodes.size());
            place(t->right);
        } else if (!whole(*t)) {  // a big node made a leaf: cannot happen, but would be fine
            append(t->node);
        } else {
            const int offset = int(bvh_.nodes.size());
            for (BvhNode nd : t->nodes) {
                if (nd.count == 0) nd.first += offset;
                append(nd);
            }
            std::vector<BvhNode>().swap(t->nodes);
        }
    }

    const BvhBuildOptions& opts_;
    Item* items_;
    int threads_;
    Bvh& bvh_;
    int taskSize_ = 0;
    SahSum sah_{Box(), 1.f};
    std::mutex m_;
    std::condition_variable cv_;
    std::deque<Task> tasks_;    // a deque: a push never moves a task another thread is using
    std::vector<int> waiting_;  // tasks nobody has taken yet
    int running_ = 0;           // tasks taken and not done
};

constexpr int kParallelMin = 65536;  // smaller inputs are built on the calling thread alone
constexpr int kChunk = 65536;        // items per chunk of the initial copy

}  // namespace

Bvh buildBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& opts) {
    BvhItems items;
    items.resize(primBounds.size());
    parallelFor((primBounds.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
        const size_t end = std::min(primBounds.size(), (chunk + 1) * kChunk);
        for (size_t i = chunk * kChunk; i < end; ++i) items[i] = bvhItem(primBounds[i]);
    }, size_t(opts.maxThreads));
    return buildBvh(std::move(items), opts);
}

Bvh buildBvh(BvhItems&& itemStore, const BvhBuildOptions& opts) {
    Bvh bvh;
    const int n = int(itemStore.size());
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
    int threads = opts.maxThreads > 0 ? opts.maxThreads : int(std::thread::hardware_concurrency());
    if (threads < 1 || n < kParallelMin) threads = 1;

    // A pass over the items in chunks (in parallel) that numbers them and gathers each chunk's bounds;
    // merged in order they give the root's bounds bit for bit as one pass would. Boxes with NaN/inf or
    // min > max become empty items (centroid 0); they are still referenced once, in some leaf, and never
    // widen any node's bounds.
    Item* items = itemStore.data();
    const int chunks = (n + kChunk - 1) / kChunk;
    std::vector<Range> chunkBounds(static_cast<size_t>(chunks));
    parallelFor(size_t(chunks), [&](size_t chunk) {
        const int c = int(chunk);
        const int begin = c * kChunk, end = std::min(n, begin + kChunk);
        Box bounds, cbounds;
        for (int i = begin; i < end; ++i) {
            Item& it = items[i];
            const Vec3 lo(it.lo[0], it.lo[1], it.lo[2]), hi(it.hi[0], it.hi[1], it.hi[2]);
            const bool ok = isFinite(lo) && isFinite(hi) && lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z;
            if (!ok) it = Item{{1e30f, 1e30f, 1e30f}, 0, {-1e30f, -1e30f, -1e30f}, 0};
            it.prim = i;
            it.pad = 0;
            ItemV v(it);
            bounds.grow(v.lo, v.hi);
            cbounds.grow(v.c, v.c);
        }
        chunkBounds[size_t(c)] = Range{begin, end, bounds, cbounds};
    }, size_t(threads));
    Range root{0, n, {}, {}};
    for (const Range& r : chunkBounds) {
        root.bounds.grow(r.bounds);
        root.cbounds.grow(r.cbounds);
    }

    bvh.nodes.reserve(size_t(2) * n);
    bvh.primRefs.resize(size_t(n));
    if (threads == 1) {
        Builder builder(opts, items);
        builder.build(root, 1, bvh.nodes);
        bvh.depth = builder.depth;
        SahSum sah(root.bounds, opts.traversalCost);
        for (const BvhNode& nd : bvh.nodes) sah.add(nd);
        bvh.sahCost = float(sah.cost);
        for (int i = 0; i < n; ++i) bvh.primRefs[size_t(i)] = items[i].prim;
    } else {
        ParallelBuild(opts, items, threads, bvh).run(root);
    }
    BvhItems().swap(itemStore);  // freed before the caller's next arrays (util/huge_pages.h, HugeRecycling)
    return bvh;
}

BvhSummary summarizeBvh(const Bvh& bvh) {
    BvhSummary s;
    if (!bvh.nodes.empty() && !bvh.primRefs.empty()) {
        const BvhNode& root = bvh.nodes[0];
        s.bounds.min = Vec3(root.boundsMin.x, root.boundsMin.y, root.boundsMin.z);
        s.bounds.max = Vec3(root.boundsMax.x, root.boundsMax.y, root.boundsMax.z);
    }
    s.sahCost = bvh.sahCost;
    s.depth = bvh.depth;
    s.nodes = bvh.nodes.size();
    s.primitives = bvh.primRefs.size();
    return s;
}

}  // namespace clrt
