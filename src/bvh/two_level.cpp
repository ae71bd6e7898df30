// Two-level BVH on the host: bottom BVHs per mesh in object space, the top BVH over instances, and
// the reference closest-hit and any-hit walks (two_level.h).
#include "bvh/two_level.h"

#include "bvh/host_intersect.h"

namespace clrt {
namespace {

// The bottom level of one mesh: a box per triangle in object space (a non-finite one never widens a
// node, and its triangle is never hit: the watertight test rejects it).
Bvh buildBottom(const TwoLevelMesh& mesh) {
    const std::vector<Vec3>& p = *mesh.positions;
    const std::vector<int>& idx = *mesh.indices;
    std::vector<Aabb> boxes(idx.size() / 3);
    for (size_t t = 0; t < boxes.size(); ++t)
        for (int k = 0; k < 3; ++k) boxes[t].grow(p[size_t(idx[3 * t + size_t(k)])]);
    BvhBuildOptions opts;
    opts.traversalCost = 2;  // as the flattened device BVH (flatten_geometry.cpp, buildDeviceBvh)
    return buildBvh(boxes, opts);
}

// The world box of an instance: the 8 corners of its bottom root mapped to world space, swept by its
// motion over the shutter.
Aabb instanceBox(const Bvh& bottom, const TwoLevelInstance& inst) {
    Aabb box;
    if (bottom.primRefs.empty()) return box;
    const BvhNode& root = bottom.nodes[0];
    for (int c = 0; c < 8; ++c) {
        Vec3 corner((c & 1) ? root.boundsMax.x : root.boundsMin.x, (c & 2) ? root.boundsMax.y : root.boundsMin.y,
                    (c & 4) ? root.boundsMax.z : root.boundsMin.z);
        Vec3 w = inst.objectToWorld.transformPoint(corner);
        box.grow(w);
        box.grow(w + inst.motion);
    }
    return box;
}

// The ray of instance `inst` in its object space at shutter time `time`.
void toObject(const TwoLevelInstance& inst, const Vec3& org, const Vec3& dir, float time, Vec3& orgObj, Vec3& dirObj) {
    orgObj = inst.worldToObject.transformPoint(org - inst.motion * time);
    dirObj = inst.worldToObject.transformVector(dir);
}

// Walks the top level; at each instance walks its bottom level in object space. test(instance,
// triangle, t, b1, b2) is called for every triangle hit closer than tMax (which it lowers); it
// returns true to stop the walk.
template <class F>
bool walkTwoLevel(const TwoLevelBvh& bvh, const std::vector<TwoLevelMesh>& meshes, const Vec3& org, const Vec3& dir,
                  float& tMax, float time, F&& test) {
    return detail::walkBvh(bvh.top, org, dir, tMax, [&](int instRef, float& tMaxTop) {
        const TwoLevelInstance& inst = bvh.instances[size_t(instRef)];
        const TwoLevelMesh& mesh = meshes[size_t(inst.mesh)];
        Vec3 o, d;
        toObject(inst, org, dir, time, o, d);
        return detail::walkBvh(bvh.bottom[size_t(inst.mesh)], o, d, tMaxTop, [&](int tri, float& tm) {
            const std::vector<Vec3>& p = *mesh.positions;
            const int* ix = &(*mesh.indices)[3 * size_t(tri)];
            float t, b1, b2;
            if (!intersectTriangleWatertight(o, d, p[size_t(ix[0])], p[size_t(ix[1])], p[size_t(ix[2])], tm, t, b1, b2))
                return false;
            tm = t;
            return test(instRef, tri, t, b1, b2);
        });
    });
}

}  // namespace

TwoLevelBvh buildTwoLevelBvh(const std::vector<TwoLevelMesh>& meshes, std::vector<TwoLevelInstance> instances,
                             std::vector<int>* skipped) {
    TwoLevelBvh out;
    out.bottom.resize(meshes.size());
    std::vector<bool> used(meshes.size(), false);
    for (size_t i = 0; i < instances.size(); ++i) {
        TwoLevelInstance& inst = instances[i];
        if (!inst.objectToWorld.inverse(inst.worldToObject)) {
            if (skipped) skipped->push_back(int(i));
            continue;
        }
        used.at(size_t(inst.mesh)) = true;
        out.instances.push_back(inst);
    }
    for (size_t m = 0; m < meshes.size(); ++m)
        if (used[m]) out.bottom[m] = buildBottom(meshes[m]);
    std::vector<Aabb> boxes;
    boxes.reserve(out.instances.size());
    for (const TwoLevelInstance& inst : out.instances) boxes.push_back(instanceBox(out.bottom[size_t(inst.mesh)], inst));
    out.top = buildBvh(boxes);
    return out;
}

TwoLevelHit closestHitTwoLevel(const TwoLevelBvh& bvh, const std::vector<TwoLevelMesh>& meshes, const Vec3& org,
                               const Vec3& dir, float tMax, float time) {
    TwoLevelHit hit;
    walkTwoLevel(bvh, meshes, org, dir, tMax, time, [&](int inst, int tri, float t, float b1, float b2) {
        hit = {inst, tri, t, b1, b2};
        return false;
    });
    return hit;
}

bool anyHitTwoLevel(const TwoLevelBvh& bvh, const std::vector<TwoLevelMesh>& meshes, const Vec3& org, const Vec3& dir,
                    float tMax, float time) {
    return walkTwoLevel(bvh, meshes, org, dir, tMax, time, [](int, int, float, float, float) { return true; });
}

}  // namespace clrt
