// src/scene/: scene files to the scene model (XML and JSON nodes, one walker, PLY reader, transforms).
// The scene model: what a CENG795 scene file says, resolved (ids -> indices, transformation strings
// -> matrices, PLY files -> vertex arrays) but not yet flattened for the device. Produced by the scene
// loader (scene_loader.h) from XML or JSON; consumed by src/flatten/. Nothing here knows OpenCL (the enums are those of
// shared/device_types.h, plain C shared with the kernels).
//
// Conventions: all indices are 0-based indices into the vectors of Scene; colours are linear
// (degamma already applied by the loader); angles are in degrees as in the file unless named *Rad.
#pragma once
#include <string>
#include <vector>

#include "shared/device_types.h"  // the enums (one per concept, shared with the kernels)
#include "shared/tonemap_settings.h"  // TonemapSettings: one camera Tonemap block
#include "util/math.h"

namespace clrt {

// Limits applied alike to the scene file and the command line (a larger scene value is capped with a
// warning naming the file; a larger --spp is a usage error). Documented in README and `render --help`.
constexpr int kMaxSamplesPerPixel = 1 << 20;  // 1,048,576 samples per pixel
constexpr int kMaxRecursionDepth = 256;       // bounces after the camera ray

struct Camera {
    int id = 0;
    // Orthonormal camera frame in world space, already corrected for handedness:
    // u = right, v = up, w = -gaze (the camera looks along -w).
    Vec3 position, u, v, w;
    // Image plane at distance nearDistance along -w: left right bottom top.
    float left = -1, right = 1, bottom = -1, top = 1;
    float nearDistance = 1;
    float focusDistance = 0;  // > 0 with apertureSize > 0: thin lens
    float apertureSize = 0;
    // What camera rays see between the eye (or lens) and the image plane, dev CLRT_NEAR_*: by default only
    // triangles' front faces, as the course's references show (hw3 cornellbox_boxes_dynamic hides the wall it
    // looks through from behind, hw1 spheres shows the floor it looks down on); clrt render --ray-origin eye
    // (everything) or plane (nothing) overrides it (docs/scene-format.md, conventions).
    int nearMode = CLRT_NEAR_FRONT;
    int width = 0, height = 0;
    int numSamples = 1;
    std::string imageName;
    std::vector<TonemapSettings> tonemaps;  // its Tonemap blocks
    int pathMode = 0;  // 0: classic ray tracing; <Renderer>PathTracing: dev CLRT_PATH_* bits (CLRT_PATH_ON set)
    int maxRecursionDepth = -1;  // 2025 <MaxRecursionDepth> in <Camera>: overrides Scene's; -1: Scene's
    int minRecursionDepth = 0;   // 2025 <MinRecursionDepth> in <Camera>: Russian roulette from this depth on (SceneParams.rrMinDepth)
    int splittingFactor = 1;     // 2025 <SplittingFactor> in <Camera>: paths per camera sample (SceneParams.split)
};

struct Material {
    int id = 0;
    dev::MaterialKind type = dev::MATERIAL_BLINN_PHONG;
    Vec3 ambient, diffuse, specular, mirror;
    float phongExponent = 1;
    float refractionIndex = 1;
    float absorptionIndex = 0;  // conductor k
    Vec3 absorptionCoefficient; // dielectric Beer's law, per unit distance (<Transparency> T adds -ln T)
    float roughness = 0;
    int brdf = -1;              // index into Scene::brdfs (BRDF="id"), -1: classic Blinn-Phong shading
};

// A <BRDFs> entry (course hw6): the reflection model a material names with BRDF="id".
struct Brdf {
    int id = 0;
    dev::BrdfKind type = dev::BRDF_ORIGINAL_BLINN_PHONG;
    float exponent = 1;
    bool normalized = false;    // Modified(Blinn)Phong normalized="true"
    bool kdFresnel = false;     // TorranceSparrow kdfresnel="true": diffuse times (1 - F)
};

struct Texture {
    int id = 0;
    dev::TextureKind type = dev::TEXTURE_IMAGE;
    int imageIndex = -1;            // into Scene::imagePaths (Image textures)
    dev::DecalKind decalMode = dev::DECAL_REPLACE_KD;
    dev::InterpKind interpolation = dev::INTERP_NEAREST;  // the course's default (hw4 normal maps without <Interpolation>)
    float normalizer = 255;         // Image: texel / normalizer (loader sets 1 for EXR when absent)
    bool normalizerGiven = false;
    float bumpFactor = 1;
    bool degamma = false;           // degamma="true" on the TextureMap: texels are gamma-encoded
    // Procedural (Perlin, Checkerboard)
    std::string noiseConversion = "linear";  // linear | absval
    float noiseScale = 1;
    int numOctaves = 1;             // Perlin: NumOctaves (2025), the fractal sum's number of terms
    Vec3 blackColor{0, 0, 0}, whiteColor{1, 1, 1};
    float scale = 1, offset = 0;
};

struct Light {
    int id = 0;
    dev::LightKind type = dev::LIGHT_POINT;
    Vec3 position;
    Vec3 intensity;       // Point, Spot: intensity; Area, Directional: radiance
    Vec3 direction;       // Directional, Spot; Area: normal
    float size = 1;       // Area: side length
    float coverageAngle = 0, falloffAngle = 0;  // Spot, full angles in degrees
    int imageIndex = -1;  // Environment
    dev::EnvMappingKind mapping = dev::ENV_LATLONG;
    dev::EnvStrategy envStrategy = dev::ENV_STRATEGY_MIS;  // sampler= (or <Sampler>)
    Mat4 envToWorld;      // Environment: the map's frame in world space, a rotation (<Transformations>, 2025)
    int shapeIndex = -1;  // LightMesh, LightSphere: the emitting shape (into Scene::shapes); intensity = Radiance
};

// A triangle mesh in its own object space (before its transformation).
struct MeshData {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;    // per vertex, empty if none given
    std::vector<Vec2> uvs;        // per vertex, empty if none
    std::vector<int> indices;     // 3 per triangle, 0-based into positions
};

// One placed shape. Meshes and instances share MeshData by index; spheres carry their own data.
enum class ShapeType { Mesh, Sphere, Plane };

// Smooth shading's face-normal weights at a vertex (vertex_normals.h): Area, each face's cross product as it
// is (twice its area); Unweighted, each face's unit normal.
enum class VertexNormalWeighting { Area, Unweighted };

struct Shape {
    int id = 0;
    ShapeType type = ShapeType::Mesh;
    int meshIndex = -1;           // Mesh: into Scene::meshes (instances share it)
    Vec3 center;                  // Sphere: object-space centre; Plane: a point on it
    Vec3 normal;                  // Plane: object-space normal (unnormalised as given)
    float radius = 1;             // Sphere
    int materialIndex = 0;        // into Scene::materials
    std::vector<int> textureIndices;  // into Scene::textures
    Mat4 transform;               // object -> world
    Vec3 motion;                  // <MotionBlur>: world-space translation over the shutter interval [0, 1]
                                  // (at time t the object is at transform, then moved by t·motion)
    bool smooth = false;          // smooth shading: interpolate vertex normals
    std::string source;           // for messages, e.g. "Mesh id=3"
    int lightIndex = -1;          // LightMesh, LightSphere: its light (into Scene::lights), else -1
};

struct Scene {
    std::string path;              // the scene file
    Vec3 backgroundColor{0, 0, 0};
    int maxRecursionDepth = 6;
    float shadowRayEpsilon = 1e-3f;  // ShadowRayEpsilon (the course's default when absent)
    // The classic renderer's rays in air skip triangles seen from behind, as the course's 2025 renderer does:
    // set for scenes in the 2025 JSON form (loadScene), clrt render --backface-culling overrides it
    // (docs/scene-format.md, conventions).
    bool backfaceCulling = false;
    // How smooth shading averages face normals at a vertex without given normals (vertex_normals.h): by area,
    // as the course's references since 2022 at least (2022 XML and 2025 JSON); clrt render --vertex-normals
    // unweighted gives the 2020 references' rule (docs/scene-format.md, conventions).
    VertexNormalWeighting vertexNormals = VertexNormalWeighting::Area;
    Vec3 ambientLight{0, 0, 0};
    std::vector<Camera> cameras;
    std::vector<Light> lights;     // all but ambient
    std::vector<Material> materials;
    std::vector<Brdf> brdfs;
    std::vector<std::string> imagePaths;  // absolute or relative to the working dir, resolved by the loader
    std::vector<std::string> plyPaths;    // every PLY file read, resolved as imagePaths (outputs must not overwrite inputs)
    std::vector<Texture> textures;
    std::vector<MeshData> meshes;
    std::vector<Shape> shapes;
};

// Environment-light sampling strategy by name (uniform | cosine | importance | mis); false if unknown.
bool parseEnvStrategy(const std::string& name, dev::EnvStrategy& out);
// Sets the env strategy of every environment light (clrt render --env-sampling), before flattening.
void overrideEnvStrategy(Scene& scene, dev::EnvStrategy strategy);

}  // namespace clrt
