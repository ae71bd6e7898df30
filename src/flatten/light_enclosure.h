// light_enclosure.h — whether a LightMesh's triangles hide their inner sides from every point outside them.
// A LightMesh emits from both faces of each triangle (the course's AreaLight rule), yet where its triangles bound
// a closed convex volume, a point outside sees only their outer sides: the inner side of a triangle lies behind
// the outer sides of the others. The course's light boxes (hw6 cornellbox_jaroslav_*: five faces of a box whose
// open side lies flat on the ceiling) are such volumes once the ceiling is counted. The sampler then gives the
// hidden triangles no samples (object_lights.cl MeshLight_Weights): without this, a third of the hw6 box's light
// samples went to triangles their shadow rays could never reach (docs/studies/2026-12-06-enclosed-lights.md).
// Reads: the light's world-space triangles, and the scene's meshes and planes (materials, motion) that may close
// its opening.
#pragma once
#include <vector>

#include "scene/scene.h"

namespace clrt {

struct MeshLightEnclosure {
    bool enclosed = false;  // the triangles bound a closed convex volume (see below)
    Vec3 inside;            // a point strictly inside it (the mean of the distinct vertices)
};

// Meshes of more triangles than this are not examined (the device picks by weight only up to 16 triangles:
// object_lights.cl CLRT_MESHLIGHT_PICK_MAX).
constexpr size_t kEnclosureMaxTriangles = 64;

// The light's triangles (world space, 3 vertices each, as written to lightData) are enclosed when:
//  - the volume is convex: every vertex lies on the inner side of every triangle's plane, within a tolerance of
//    1e-5 of the light's size, and the mean of the vertices strictly inside each (a flat mesh never is);
//  - it is closed: each edge (vertices matched exactly) is shared by two triangles, but for edges that form planar
//    loops (openings), each lying in a plane of the volume and covered by opaque, unmoving scene geometry in that
//    plane: triangles of other meshes (not instanced ones) or a Plane. Opaque: any material but a dielectric;
//  - the light's own material is no dielectric and its shape does not move.
// lightShape: the light's index into scene.shapes (left out of the covering geometry).
MeshLightEnclosure findMeshLightEnclosure(const Scene& scene, int lightShape, const std::vector<Vec3>& triangles);

// The same for each light of a scene in turn: the scene's shapes' world boxes are made once, on the first
// opening to cover, and each opening reads only the triangles of shapes whose box reaches it, 2^24 of them at
// most for the scene (so many light boxes under one huge mesh do not read it once each).
class MeshLightEnclosures {
public:
    explicit MeshLightEnclosures(const Scene& scene) : scene_(scene) {}
    MeshLightEnclosure find(int lightShape, const std::vector<Vec3>& triangles);

    struct Box {
        double lo[3], hi[3];
    };

private:
    const Scene& scene_;
    std::vector<Box> shapeBoxes_;  // world boxes of scene_.shapes (planes: everything), once made
    // Covering triangles left to read for the whole scene (a fixed count, not a time: the same lights are
    // enclosed on every machine); an opening whose candidates exceed it is taken as open.
    size_t budget_ = size_t(1) << 24;
    const std::vector<Box>& shapeBoxes();
};

}  // namespace clrt
