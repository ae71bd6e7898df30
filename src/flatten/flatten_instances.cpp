// flatten_instances.cpp — meshes kept once for all their instances (the two-level BVH of
// docs/architecture.md, "Instancing"): which mesh shapes go two-level (instancedShapes), each such
// mesh's triangles in object space under its own bottom-level BVH, and a top-level BVH over the shapes
// as dev::Instance records (transform, inverse, material, texture set, MotionBlur translation), all
// appended to the arrays of the world BVH that flattenGeometry built. Reads Mesh/MeshInstance shapes
// (Scene::shapes of type Mesh: meshIndex, transform, motion, smooth, material) and Scene::meshes.
#include <algorithm>
#include <map>
#include <set>

#include "flatten/flatten.h"
#include "scene/transforms.h"
#include "util/error.h"

namespace clrt {
namespace {

// Auto: a mesh goes two-level when it is placed at least twice and its placements together hold at
// least kTwoLevelMinTriangles; and every mesh placed at least twice does when such meshes together hold
// at least kTwoLevelSceneTriangles as seen (many meshes, each under the first bound: flattened, ~4 GB
// of host memory at ~500 B a triangle). Constants, not the machine's memory: every machine (--part,
// MPI ranks) stores a scene alike. docs/studies/2026-12-04-instancing-threshold.md has the measurements.
constexpr size_t kTwoLevelMinTriangles = size_t(1) << 20;
constexpr size_t kTwoLevelSceneTriangles = size_t(1) << 23;

// What an instance needs of its bottom-level tree, once that is in ds's arrays.
struct BottomLevel {
    Aabb box;              // object-space box of the mesh
    int rootNode = 0;      // nodes index
    size_t triangles = 0;  // stored (none: the mesh has no triangle to hit, its shapes are left out)
};

// The key of a bottom level: shapes of one mesh may shade it differently (flat or smooth normals).
std::pair<int, bool> bottomKey(const Shape& s) { return {s.meshIndex, s.smooth}; }

// The mesh of shape s in object space (identity transform, no motion; material, texture set and light
// belong to the instance) appended to ds: its triangles and their shading written in place after
// ds's (room reserved by flattenGeometry) on all threads (flattenMeshes), its BVH built over their
// boxes, with leafOrder the triangles put in leaf order in place, the binary tree freed before its
// leaf blocks are appended to ds.bvh8 (as the world tree, flatten_geometry.cpp's buildDeviceBvh).
// *maxStack: its traversal stack need; spareNodes: room kept for the top level's nodes (appendBvh8).
// Its build and collapse count as BVH time (ds.bvhSeconds).
BottomLevel appendBottomLevel(const Scene& scene, const Shape& s, DeviceScene& ds, bool leafOrder, size_t spareNodes,
                              int* maxStack) {
    Shape objectSpace = s;
    objectSpace.transform = Mat4::identity();
    objectSpace.motion = Vec3(0, 0, 0);
    objectSpace.materialIndex = CLRT_INVALID;
    objectSpace.lightIndex = CLRT_INVALID;
    const size_t base = ds.triangles.size();
    BvhItems boxes;
    flattenMeshes(scene, {{&objectSpace, CLRT_INVALID}}, ds, boxes);  // corner attributes after those stored
    BottomLevel b;
    b.triangles = boxes.size();
    if (b.triangles == 0) return b;
    const auto tb = std::chrono::steady_clock::now();
    BvhBuildOptions opts;
    opts.traversalCost = 2;  // as the world BVH's (flatten_geometry.cpp, buildDeviceBvh)
    Bvh bvh = buildBvh(std::move(boxes), opts);  // consumes the boxes
    b.box = summarizeBvh(bvh).bounds;  // the root's box: the union of the triangles' (all finite)
    if (leafOrder) putInLeafOrder(bvh, ds.triangles.data() + base, ds.triangleShading.data() + base, int(b.triangles));
    const size_t firstLeaf = ds.bvh8.leaves.size();
    b.rootNode = appendBvh8(std::move(bvh), int(base), ds.bvh8, maxStack, spareNodes);
    setLeafTriangles(ds.bvh8, ds.triangles, int(ds.triangles.size()), firstLeaf);
    ds.bvhSeconds += secondsSince(tb);
    return b;
}

// Shape s as an instance of the bottom level b; false (warned) for a transform without inverse.
bool makeInstance(const Shape& s, int texSet, const BottomLevel& b, dev::Instance& inst, Aabb& worldBox) {
    Mat4 inv;
    if (!s.transform.inverse(inv)) {
        warn(s.source + ": singular transform; mesh skipped");
        return false;
    }
    inst = dev::Instance{};
    storeRows(inst.objectToWorld, s.transform);
    storeRows(inst.worldToObject, inv);
    inst.motion = toFloat4(s.motion);
    inst.rootNode = b.rootNode;
    inst.material = s.materialIndex;
    inst.textureSet = texSet;
    inst.mirrored = mirrorsOrientation(s.transform) ? 1 : 0;
    Aabb box;
    for (int c = 0; c < 8; ++c)
        box.grow(s.transform.transformPoint(Vec3((c & 1) ? b.box.max.x : b.box.min.x, (c & 2) ? b.box.max.y : b.box.min.y,
                                                 (c & 4) ? b.box.max.z : b.box.min.z)));
    worldBox = sweptBox(box, s.motion);
    return true;
}

// The top-level tree over the instances' world boxes, appended to ds.bvh8: each leaf lane becomes
// the instance it holds (entry ~((instance + 1) << 4), as intersect.cl's Entry_Instance reads it).
// Returns its root's index; *maxStack its traversal stack need.
int appendTopLevel(const std::vector<Aabb>& boxes, DeviceScene& ds, int* maxStack) {
    BvhBuildOptions opts;
    opts.traversalCost = 2;
    opts.maxLeafSize = 1;  // one instance per leaf: entering it replaces the ray
    Bvh top = buildBvh(boxes, opts);
    Bvh8 b8 = collapseBvh8(top);
    const int nodeOffset = int(ds.bvh8.nodes.size());
    ds.bvh8.nodes.reserve(ds.bvh8.nodes.size() + b8.nodes.size());  // room kept by the bottom levels
    for (dev::Bvh8Node n : b8.nodes) {
        for (int i = 0; i < kBvhWidth; ++i) {
            int& entry = laneEntry(n, i);
            if (entry == CLRT_INVALID) continue;
            if (isLeafEntry(entry)) {
                const int instance = b8.leaves[size_t(leafFirstBlock(entry))].prim.x;
                entry = ~((instance + 1) << 4);
            } else {
                entry += nodeOffset;
            }
        }
        ds.bvh8.nodes.push_back(n);
    }
    *maxStack = b8.maxStack;
    return nodeOffset;
}

}  // namespace

std::vector<bool> instancedShapes(const Scene& scene, Instancing mode) {
    std::vector<bool> out(scene.shapes.size(), false);
    if (mode == Instancing::Flatten) return out;
    std::map<int, size_t> placements;  // mesh index -> shapes that place it
    auto eligible = [](const Shape& s) { return s.type == ShapeType::Mesh && s.lightIndex < 0; };
    for (const Shape& s : scene.shapes)
        if (eligible(s)) ++placements[s.meshIndex];
    auto triangles = [&](int mesh) { return scene.meshes.at(size_t(mesh)).indices.size() / 3; };
    size_t placedSeveralTimes = 0;  // triangles as seen of the meshes placed at least twice
    for (const auto& mk : placements)
        if (mk.second >= 2) placedSeveralTimes += mk.second * triangles(mk.first);
    const bool wholeScene = placedSeveralTimes >= kTwoLevelSceneTriangles;
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const Shape& s = scene.shapes[i];
        if (!eligible(s)) continue;
        const size_t k = placements[s.meshIndex];
        out[i] = mode == Instancing::TwoLevel || (k >= 2 && (wholeScene || k * triangles(s.meshIndex) >= kTwoLevelMinTriangles));
    }
    return out;
}

size_t bottomLevelTriangles(const Scene& scene, const std::vector<bool>& instanced, size_t* attributeFloatsOut) {
    std::set<std::pair<int, bool>> keys;
    size_t total = 0, floats = 0;
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (instanced[i] && keys.insert(bottomKey(scene.shapes[i])).second) {
            const size_t n = scene.meshes.at(size_t(scene.shapes[i].meshIndex)).indices.size() / 3;
            total += n;
            floats += n * attributeFloats(meshAttributeFlags(scene, scene.shapes[i]));
        }
    if (attributeFloatsOut) *attributeFloatsOut = floats;
    return total;
}

void flattenInstances(const Scene& scene, const std::vector<std::pair<const Shape*, int>>& jobs, int numWorldTriangles,
                      DeviceScene& ds, bool leafOrder) {
    const int numWorldLeaves = int(ds.bvh8.leaves.size());
    const int worldStack = std::max(1, ds.bvh8.maxStack);
    std::map<std::pair<int, bool>, BottomLevel> bottoms;
    int bottomStack = 0;
    for (const auto& job : jobs) {
        if (bottoms.count(bottomKey(*job.first))) continue;
        int stack = 0;
        // The top level's 8-wide nodes: at most one per instance (each has two children or more).
        bottoms[bottomKey(*job.first)] = appendBottomLevel(scene, *job.first, ds, leafOrder, jobs.size() + 1, &stack);
        bottomStack = std::max(bottomStack, stack);
    }
    // The world tree's sphere references follow every triangle.
    const int added = int(ds.triangles.size()) - numWorldTriangles;
    for (int l = 0; l < numWorldLeaves; ++l)
        for (int i = 0; i < 4; ++i) {
            int& prim = (&ds.bvh8.leaves[size_t(l)].prim.x)[i];
            if (prim >= numWorldTriangles) prim += added;
        }
    std::vector<Aabb> boxes;
    for (const auto& job : jobs) {
        const BottomLevel& b = bottoms.at(bottomKey(*job.first));
        dev::Instance inst;
        Aabb box;
        if (b.triangles == 0 || !makeInstance(*job.first, job.second, b, inst, box)) continue;
        ds.instances.push_back(inst);
        boxes.push_back(box);
    }
    ds.params.numTriangles = int(ds.triangles.size());
    if (ds.instances.empty()) return;
    int topStack = 0;
    ds.params.instanceRoot = appendTopLevel(boxes, ds, &topStack);
    ds.params.numInstances = int(ds.instances.size());
    ds.features.instances = true;
    // The top root waits under the world traversal; an instance's tree above the top's entries.
    ds.features.bvhStack = std::max(1 + worldStack, 1 + topStack + bottomStack);
}

}  // namespace clrt
