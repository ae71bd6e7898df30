// src/flatten/: scene model + BVH -> DeviceScene, the flat arrays the kernels read (materials, textures, geometry, lights, environment maps).
// Flattening: Scene (the model) + BVH -> DeviceScene, the flat arrays of shared structs the kernels
// read, plus the feature set of this scene (which -D flags its program needs). Images referenced by
// textures and environment lights are loaded here into one float4 texel atlas.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bvh/bvh.h"
#include "bvh/bvh8.h"
#include "scene/scene.h"
#include "shared/device_types.h"

namespace clrt {

// Which types and features a scene uses: its program is compiled with the matching -D flags only.
// The flags of lights, materials and BRDFs come from their tables (src/shared/type_tables.h).
struct FeatureSet {
    uint32_t lightKinds = 0;     // bit k set: the scene has a light of dev::LightKind k
    uint32_t materialKinds = 0;  // bit k set: the scene has a material of dev::MaterialKind k
    uint32_t brdfKinds = 0;      // bit k set: a material uses a BRDF of dev::BrdfKind k
    bool textures = false;
    bool normalMaps = false;  // a shape uses a replace_normal texture
    bool bumpMaps = false;    // a shape uses a bump_normal texture
    bool mipMaps = false;     // a trilinear image texture (mip chain, ray cones: CLRT_HAS_MIPMAPS)
    bool spheres = false;
    bool motionBlur = false;        // a mesh, triangle or sphere has a MotionBlur translation
    bool pathTracing = false;       // a camera has <Renderer>PathTracing (cl_kernels/path.cl)
    bool instances = false;         // a two-level BVH (dev::Instance; flatten_instances.cpp)
    bool zsobol = false;            // not the scene's: clrt render --sampler zsobol (ZSobol_2D, common.cl)
    bool correlatedSampler = false; // not the scene's: clrt render --sampler correlated (Sampler_Light2D, common.cl)
    bool meshLightsByArea = false;  // not the scene's: clrt render --mesh-light-sampling area (object_lights.cl)
    bool envRotation = false;       // an environment light's map is turned by its <Transformations> (lights.cl)
    bool backfaceCulling = false;   // classic rays skip back faces (Scene::backfaceCulling; intersect.cl Ray_Closest)
    bool lanes = false;             // the scene is of render_lanes' family (lanesFamily below; cl_kernels/lanes.cl)
    int bvhStack = 0;  // traversal stack entries the scene's BVH needs (0: the header's default)
    void add(dev::LightKind k) { lightKinds |= 1u << k; }
    void add(dev::MaterialKind k) { materialKinds |= 1u << k; }
    void add(dev::BrdfKind k) { brdfKinds |= 1u << k; }
    bool has(dev::BrdfKind k) const { return (brdfKinds >> k) & 1u; }
    bool has(dev::LightKind k) const { return (lightKinds >> k) & 1u; }
    bool has(dev::MaterialKind k) const { return (materialKinds >> k) & 1u; }
    bool bounces() const;  // a material that spawns reflection/refraction children
    std::vector<std::string> defines() const;  // e.g. {"-DCLRT_HAS_POINT_LIGHT=1", ...}
    // Every feature on: the unspecialised program (clrt render --all-features).
    static FeatureSet all() {
        FeatureSet f;
        f.lightKinds = f.materialKinds = f.brdfKinds = ~0u;
        f.textures = f.normalMaps = f.bumpMaps = f.mipMaps = f.spheres = f.motionBlur = f.pathTracing = f.instances = f.zsobol = f.envRotation =
            f.backfaceCulling = f.correlatedSampler = true;
        return f;
    }
};

struct DeviceScene {
    HostArray<dev::Triangle> triangles;          // in BVH leaf order
    HostArray<dev::TriangleShading> triangleShading;
    HostArray<float> triangleAttributes;  // the triangles' optional vertex normals and uvs (TriangleShading.attributes)
    std::vector<dev::Sphere> spheres;
    std::vector<dev::Instance> instances;         // two-level BVH: instances of meshes kept once (may be empty)
    std::vector<dev::Plane> planes;               // never empty (a dummy when the scene has none)
    std::vector<dev::Material> materials;
    std::vector<dev::TextureSet> textureSets;
    std::vector<dev::TextureMap> textures;
    std::vector<dev::ImageInfo> images;
    HostArray<dev::float4> texels;
    std::vector<dev::Light> lights;
    HostArray<float> envDistribution;  // importance distributions of env lights (env_distribution.h)
    HostArray<dev::float4> lightData;  // object lights' triangles and spheres (layout: device_types.h, Light)
    BvhSummary bvh;  // the binary tree's figures (the tree itself is freed once collapsed into bvh8)
    Bvh8 bvh8;  // what the device traverses
    dev::SceneParams params{};
    FeatureSet features;
    size_t skippedTriangles = 0;
    double bvhSeconds = 0, flattenSeconds = 0;
    double imageSeconds = 0, envDistSeconds = 0;  // parts of flattenSeconds: reading images, env distributions
};

// How meshes with several instances are stored: Auto (two-level where that saves, see
// instancedShapes), Flatten (every triangle in world space, one BVH), TwoLevel (every mesh that is
// not an object light kept once, under its own BVH; for tests and measurements).
enum class Instancing { Auto, Flatten, TwoLevel };
struct FlattenOptions {
    Instancing instancing = Instancing::Auto;
    // Called once, as soon as the feature set (the kernel -D flags, BVH stack included) is final: after
    // the BVH, before the lights and their environment distributions, so that clrt render compiles
    // the program on another thread while the rest is flattened. The DeviceScene's features equal it.
    std::function<void(const FeatureSet&)> onFeaturesKnown;
    // Renumber the triangles (and their shading records) into BVH leaf order, so that rays hitting
    // neighbouring leaves read neighbouring records (a GPU coalesces such reads). The leaf blocks name
    // each triangle by index, so the images are the same either way. clrt render turns it off when
    // every device is a CPU device: there it measured no faster and its random-access pass costs
    // ~0.2 us per triangle of setup (docs/architecture.md, pipeline step 3).
    bool leafOrderTriangles = true;
};

DeviceScene flattenScene(const Scene& scene, const FlattenOptions& opts = {});
// Which shapes go two-level under `mode` (their mesh kept once under its own BVH), per shape index.
std::vector<bool> instancedShapes(const Scene& scene, Instancing mode);

// Half4 texels (ImageInfo.format TEXELS_HALF4): the n texels src[0..n) packed two to a float4, each
// channel (alpha included) a half of the same value; false, and nothing written, unless every value is
// a half exactly (a finite float with at most 11 significant bits in the half's range, or 0).
bool packHalf4Exact(const dev::float4* src, size_t n, std::vector<dev::float4>& packed);
// The texels of device image `image` as float4 (half4 images unpacked: the values the device reads).
std::vector<dev::float4> imageTexels(const DeviceScene& ds, int image);

// Camera frame and image plane for the kernels, and numSamples.
// Whether a flattened scene is of the lanes kernel's family (cl_kernels/lanes.cl, render_lanes): a
// path-traced camera, or classic cameras with an environment light (their children, of mirrors, conductors
// and dielectrics, too); no motion blur or mip-maps (every light, material, BRDF, texture and instance is in).
// "" when it is, else the first reason it is not.
std::string lanesFamily(const DeviceScene& ds);

// Why `--pipeline auto` leaves a camera of the lanes' family to render_fused ("" when it takes the lanes): a
// path-traced one when no environment light is sampled by multi-sample MIS (envMis: the render's two
// shadow-ray slots; its pair is made in steps across the lanes) and no surface is shaded in lanes (no
// untextured one with kd or ks > 0: its BRDF in lanes, cl_kernels/lanes_brdf.cl; textured surfaces are made
// per lane; docs/architecture.md "Paths in lanes"); a
// classic one (classic) when no environment light is sampled by multi-sample MIS, the one step it takes in lanes.
std::string lanesNoGain(const DeviceScene& ds, bool classic = false, bool envMis = false);
// What a path's throughput gains, in expectation, at a bounce off material m, from its untextured diffuse
// part and its specular child: π·kd for classic materials and the BRDFs that take kd without 1/π (the
// course's un-normalized models), kd for the normalized ones and TorranceSparrow; plus the mirror
// reflectance (mirror, conductor: an upper bound) or 1 (dielectric). The glossy ks lobe is not counted.
float pathAlbedoBound(const dev::Material& m);
// The index of the material, among those some primitive uses, with the largest pathAlbedoBound above 1,
// or -1. A closed scene of such surfaces gains energy at every bounce: a path tracer without a depth cap
// (RussianRoulette) does not converge there (clrt render warns).
int energyGainingMaterial(const DeviceScene& ds);

dev::CameraParams makeCameraParams(const Camera& cam);
// Sets spp (at least 1).
void setSamplesPerPixel(dev::CameraParams& c, int spp);

inline dev::float4 toFloat4(const Vec3& v, float w = 0) { return {v.x, v.y, v.z, w}; }

}  // namespace clrt
