// Two-level BVH on the host (docs/architecture.md, "Instancing"): one bottom-level BVH per mesh over
// its object-space triangles, shared by every instance of the mesh, and a top-level BVH over the
// instances (object-to-world and world-to-object maps, a MotionBlur translation, the world box of
// the bottom root swept over the shutter). This is the structure and its plain C++ reference walk
// (closest hit, any hit), against which flattening is checked (tests/test_instancing.cpp) and the
// device traversal is to be; the device does not read it yet. Reads no scene element: its inputs
// are the positions and index triples of Scene::meshes and each instance's transform and motion.
#pragma once
#include <vector>

#include "bvh/bvh.h"
#include "util/math.h"

namespace clrt {

// A mesh as the bottom level reads it (Scene::meshes' MeshData: positions, 3 indices per triangle).
struct TwoLevelMesh {
    const std::vector<Vec3>* positions = nullptr;
    const std::vector<int>* indices = nullptr;
};

struct TwoLevelInstance {
    int mesh = 0;          // into TwoLevelBvh::bottom
    Mat4 objectToWorld;    // as Shape::transform
    Mat4 worldToObject;    // its inverse
    Vec3 motion;           // world-space translation over the shutter [0, 1] (MotionBlur)
};

struct TwoLevelBvh {
    std::vector<Bvh> bottom;                 // per mesh; primRefs index its triangles (index triple / 3)
    std::vector<TwoLevelInstance> instances; // primRefs of `top` index these
    Bvh top;
};

// Builds the bottom level once per mesh (meshes no instance uses are left empty) and the top level
// over the instances with invertible transforms (others are left out and reported in `skipped`).
TwoLevelBvh buildTwoLevelBvh(const std::vector<TwoLevelMesh>& meshes, std::vector<TwoLevelInstance> instances,
                             std::vector<int>* skipped = nullptr);

// A closest hit of the reference walk: the instance, the triangle of its mesh, t (the world ray's
// parameter) and the barycentrics of the triangle's second and third corners.
struct TwoLevelHit {
    int instance = -1;
    int triangle = -1;
    float t = 0, b1 = 0, b2 = 0;
};

// The closest hit with 0 < t < tMax of the ray at shutter time `time` (instance -1: none). At an
// instance the ray is taken into its object space: origin worldToObject·(org − time·motion),
// direction worldToObject·dir, not renormalised, so that t means the same in both spaces.
TwoLevelHit closestHitTwoLevel(const TwoLevelBvh& bvh, const std::vector<TwoLevelMesh>& meshes, const Vec3& org,
                               const Vec3& dir, float tMax, float time = 0);
// Whether anything is hit with 0 < t < tMax (shadow rays).
bool anyHitTwoLevel(const TwoLevelBvh& bvh, const std::vector<TwoLevelMesh>& meshes, const Vec3& org, const Vec3& dir,
                    float tMax, float time = 0);

}  // namespace clrt
