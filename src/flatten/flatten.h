// flatten.h — the parts of flattenScene() (flatten_scene.cpp), one per domain and file:
//   flatten_materials.cpp    materials
//   flatten_textures.cpp     the texel atlas (ImageAtlas), texture maps, per-shape texture sets
//   flatten_geometry.cpp     planes, spheres, meshes (on all hardware threads), the BVH, leaf order
//   flatten_lights.cpp       lights (one case per light type)
//   flatten_environment.cpp  environment lights: map, env strategy, importance distribution, miss radiance
// Each appends to a DeviceScene and marks the features it finds. The driver calls them in the order
// above: images enter the atlas in order of first use (textures, then environment maps).
#pragma once
#include <chrono>
#include <map>
#include <vector>

#include "flatten/device_scene.h"

namespace clrt {

double secondsSince(std::chrono::steady_clock::time_point t0);

// The texel atlas: each scene image that is used is read once, on first use, into ds.texels (float4
// texels) with its ImageInfo in ds.images; environment maps may add a half4 copy (useEnvironment),
// trilinear textures a mip chain (useMipChain).
class ImageAtlas {
public:
    ImageAtlas(const Scene& scene, DeviceScene& ds) : scene_(scene), ds_(ds) {}
    int use(int sceneImage);  // the device image index of scene image `sceneImage`
    // A TextureMap's image with degamma="true": a copy of use(sceneImage) decoded with gamma 2.2 in the
    // image's own range r (255 for 8-bit images, 1 for HDR ones): c -> r·(c/r)^2.2, texel by texel
    // (before any filtering). Read once per scene image, whichever maps share it.
    int useDegamma(int sceneImage);
    // The device image an environment map is read from: a half4 copy of use(sceneImage) when every
    // value is a half exactly (the same lookups, half the cache footprint), else use(sceneImage).
    int useEnvironment(int sceneImage);
    // A trilinear texture's images: level 0 (the texels of use(sceneImage)) and its box-filtered
    // levels (mip_pyramid.h) at consecutive device images from the returned one; *levels their count.
    int useMipChain(int sceneImage, int* levels, bool degamma = false);
    bool isHdr(int deviceImage) const { return hdr_.at(size_t(deviceImage)); }

private:
    const Scene& scene_;
    DeviceScene& ds_;
    std::map<int, int> slot_;  // scene image index -> device image index
    std::map<int, int> envSlot_;  // scene image index -> device image of useEnvironment
    std::map<int, int> degammaSlot_;  // scene image index -> device image of useDegamma
    std::map<std::pair<int, bool>, std::pair<int, int>> mipSlot_;  // (scene image, degamma) -> (first image, levels)
    std::vector<bool> hdr_;    // per device image (other images, e.g. flattenTextures' dummy, may follow)
    void setHdr(int deviceImage, bool hdr) {
        if (hdr_.size() <= size_t(deviceImage)) hdr_.resize(size_t(deviceImage) + 1, false);
        hdr_[size_t(deviceImage)] = hdr;
    }
};

void flattenMaterials(const Scene& scene, DeviceScene& ds);
// Texture maps (and the background texture); images through `atlas`.
void flattenTextures(const Scene& scene, DeviceScene& ds, ImageAtlas& atlas);
// The texture set of shape `s` (appended to ds.textureSets), or CLRT_INVALID when it has none.
int flattenTextureSet(const Scene& scene, const Shape& s, DeviceScene& ds);
// Planes, spheres and mesh triangles, then the BVH over triangles and spheres with the triangles
// stored in leaf order; meshes that instancedShapes(scene, instancing) picks go to flattenInstances.
// Sets the primitive counts of ds.params.
void flattenGeometry(const Scene& scene, DeviceScene& ds, const FlattenOptions& opts = {});
// Whether the transformation's linear part has a negative determinant (a mirror): the world-space
// cross product of a triangle's edges then points against the transformed object-space normal, so
// flattenGeometry (and the LightMesh sampling data, flatten_lights.cpp) take its corners as (a, c, b).
bool mirrorsOrientation(const Mat4& m);
void flattenLights(const Scene& scene, DeviceScene& ds, ImageAtlas& atlas);

// ---- shared by flatten_geometry.cpp and flatten_instances.cpp ----
// The mesh shapes of `jobs` (shape, texture set) on all hardware threads, appended to ds.triangles,
// ds.triangleShading, ds.triangleAttributes and `boxes` in job and index order (what one thread writing
// them in turn would give); degenerate and non-finite triangles left out, counted in ds.skippedTriangles
// and returned as {degenerate, non-finite}.
std::pair<size_t, size_t> flattenMeshes(const Scene& scene, const std::vector<std::pair<const Shape*, int>>& jobs,
                                        DeviceScene& ds, BvhItems& boxes);
// Puts the triangles [0, numTriangles) of tris and shading in the leaf order of `bvh` (built over their
// boxes, then maybe others: references from numTriangles on, spheres, keep their indices) in place, no
// copy of either array made, and makes bvh's triangle references those new positions. The shading
// records carry their attribute offsets, so triAttributes stays where it is.
void putInLeafOrder(Bvh& bvh, dev::Triangle* tris, dev::TriangleShading* shading, int numTriangles);
// The TriangleShading.attributes flags of a mesh shape's triangles (CLRT_TRI_NORMALS when smooth,
// CLRT_TRI_UVS when its mesh has a uv per vertex) and the floats of triAttributes each such triangle takes.
uint32_t meshAttributeFlags(const Scene& scene, const Shape& s);
size_t attributeFloats(uint32_t flags);
// Stored triangle t's corners as shading reads them (cl_kernels/shade.cl, HitTriangle_Load): its vertex
// normals (stored, or its face normal thrice) and uvs (stored, or (0, 0)), in the triangle's own space
// (world; object space for a two-level mesh's). For host references and tests.
struct TriangleCorners {
    Vec3 normal[3];
    float uv[3][2];
};
TriangleCorners triangleCorners(const DeviceScene& ds, size_t t);
// The box a primitive sweeps over the shutter interval: moved by t·motion, t in [0, 1], it stays
// inside the union of its boxes at both ends (the motion is a straight translation).
Aabb sweptBox(const Aabb& rest, const Vec3& motion);
void storeRows(dev::float4 rows[3], const Mat4& m);  // the first three rows of an affine map
// The meshes of `jobs` (shape, texture set), each stored once in object space under its own bottom-level
// BVH, and the top-level BVH over the shapes as instances; appended to ds's arrays after the world
// BVH's (whose sphere references move past the appended triangles). Sets numTriangles, numInstances,
// instanceRoot and the traversal's stack need. numWorldTriangles: the world BVH's triangles.
// The triangles the bottom levels of the shapes marked in `instanced` (instancedShapes) will store at
// most: each (mesh, flat or smooth) once; *attributeFloats their triAttributes floats. flattenGeometry
// reserves them, so no array grows by copying.
size_t bottomLevelTriangles(const Scene& scene, const std::vector<bool>& instanced, size_t* attributeFloats = nullptr);
// leafOrder: each bottom level's triangles renumbered into its leaf order (FlattenOptions::leafOrderTriangles).
void flattenInstances(const Scene& scene, const std::vector<std::pair<const Shape*, int>>& jobs, int numWorldTriangles,
                      DeviceScene& ds, bool leafOrder = true);
// The device fields of environment light `l` (index `lightIndex`), its importance distribution, and
// the first environment light's SceneParams fields (envLight, envScale, envImage, envMapping).
void flattenEnvironmentLight(const Scene& scene, const Light& l, int lightIndex, dev::Light& d, DeviceScene& ds,
                             ImageAtlas& atlas);
// Whether `l` is an environment light whose map its <Transformations> turn (CLRT_HAS_ENV_ROTATION).
bool isEnvironmentTurned(const Light& l);

}  // namespace clrt
