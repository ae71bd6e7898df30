// The scene walker's one interface, shared by the element readers of src/scene/read_*.cpp (internal to
// src/scene/; the rest of the program calls loadScene, scene_loader.h). The walker interprets a <Scene>
// SceneNode tree (xml_node.cpp or json_node.cpp) into the scene model (scene.h): scene_walker.cpp walks
// the children of <Scene> through a table of element readers, one row per element:
//   {"Cameras", readCameras, ...}: the rows are read in table order (every data dependency points
//   upwards: Transformations, VertexData, TexCoordData, BRDFs, Materials, Textures before the Cameras,
//   Lights and Objects that name them), each element's occurrences in document order.
// Each element family lives in one file, which says which elements it reads:
//   read_settings.cpp    BackgroundColor ShadowRayEpsilon IntersectionTestEpsilon MaxRecursionDepth
//                        ZeroBasedIndexing
//   read_transforms.cpp  Transformations (Translation Scaling Rotation Composite)
//   read_vertex_data.cpp VertexData TexCoordData
//   read_materials.cpp   BRDFs, Materials (Material)
//   read_textures.cpp    Textures (Images/Image, TextureMap)
//   read_cameras.cpp     Cameras (Camera, its Tonemap, Renderer, RendererParams)
//   read_lights.cpp      Lights (AmbientLight and the light types of shared/type_tables.h)
//   read_objects.cpp     Objects (Mesh MeshInstance Triangle Sphere Plane LightMesh LightSphere)
// Nested elements are read the same way: a family file keeps its own table (e.g. the Lights' readers
// by light type, the Objects' readers by element name).
//
// The shared reading helpers below turn a node's text and attributes into checked values. Errors:
// clrt::Error "<location>: <what>", location from SceneNode::location() ("file.xml:12:5" or
// "file.json: Scene.Cameras.Camera[1]"). Every number must be finite and within float range (1e39 is an
// error, not an infinity), every integer within int range.
#pragma once
#include <cstdint>
#include <initializer_list>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "scene/scene.h"
#include "scene/scene_node.h"
#include "scene/transforms.h"

namespace clrt::walker {

// ---- Text and messages (scene_walker.cpp) ----------------------------------------------------------
std::string lower(std::string s);
std::string trim(const std::string& s);
[[noreturn]] void fail(const SceneNode& n, const std::string& msg);  // throws "<n's location>: msg"
std::string describe(const SceneNode& n);  // how messages name an element: "Mesh id=3" or "Camera"

// ---- Values of a node's text (scene_walker.cpp) ----------------------------------------------------
std::vector<double> numbers(const SceneNode& n);                // all numbers, each finite, float range
std::vector<double> numbers(const SceneNode& n, size_t count);  // exactly `count` numbers
double toInteger(const SceneNode& n, double v);                 // v, checked to be an int
// A non-negative count, values over `limit` capped to it with a warning naming the file.
int cappedInteger(const SceneNode& n, int limit);
float number(const SceneNode& n);
int integer(const SceneNode& n);
std::vector<int> integers(const SceneNode& n);
Vec3 vec3(const SceneNode& n);
// normalize(v), also when |v|² overflows or underflows a float; 0 for a zero vector.
Vec3 unit(const Vec3& v);
// s (an attribute or text of n) as true|1|yes or false|0|no; `what` names it in the message.
bool boolean(const SceneNode& n, const std::string& s, const std::string& what);

// ---- Children, attributes, ids (scene_walker.cpp) --------------------------------------------------
SceneNodePtr need(const SceneNode& parent, const std::string& name);  // the child, or an error
int intAttribute(const SceneNode& n, const std::string& attr, int dflt);
int requiredId(const SceneNode& n);  // the id attribute, which must be there

struct Walker;

// One row of a table of element readers: the element's name and the function that reads one
// occurrence of it.
using ElementReadFn = void (*)(Walker& w, const SceneNode& n);
struct ElementReader {
    const char* name;
    ElementReadFn read;
    bool firstOnly = false;  // true: only the first occurrence is read (a setting), others ignored
};

// The walk's state: the scene being built and what later elements look up.
struct Walker {
    Scene scene;
    std::string dir;  // scene file's directory ("" = working dir)
    bool zeroBased = false;
    TransformTable transforms;
    std::vector<Vec3> vertices;
    std::vector<Vec2> texcoords;
    std::map<int, int> materialIds, imageIds, textureIds, brdfIds;  // file id -> index in scene
    std::set<std::string> warnedUnknown;
    std::unordered_map<std::string, int> plyMeshes;  // resolved ply path -> Scene::meshes index

    // A path of the scene file, relative to its directory, as the working directory sees it.
    std::string resolve(const std::string& rel) const;
    // Warns once per (parent, element) name about children of n that are not in `known`.
    void checkChildren(const SceneNode& n, std::initializer_list<const char*> known);
    void checkChildren(const SceneNode& n, const std::vector<std::string>& known);
    // Reads the children of n with `table` (unknown children warned about): the rows in table order,
    // each row's occurrences in document order.
    void readInTableOrder(const SceneNode& n, const std::vector<ElementReader>& table);
    // A binaryFile (course hw6 text): a little-endian int32 count of records (vertices, texture
    // coordinates or faces), then exactly that many records of `perRecord` little-endian 4-byte
    // words. Returns the words after the count; the size must match the count.
    std::vector<uint32_t> binaryWords(const SceneNode& n, const std::string& file, const char* records,
                                      size_t perRecord) const;
};

// ---- The readers of <Scene>'s children (the rows of sceneElements() in scene_walker.cpp) ------------
void readBackgroundColor(Walker& w, const SceneNode& n);      // read_settings.cpp
void readIntersectionEpsilon(Walker& w, const SceneNode& n);  // read_settings.cpp
void readShadowRayEpsilon(Walker& w, const SceneNode& n);     // read_settings.cpp
void readMaxRecursionDepth(Walker& w, const SceneNode& n);    // read_settings.cpp
void readZeroBasedIndexing(Walker& w, const SceneNode& n);    // read_settings.cpp
void readTransformations(Walker& w, const SceneNode& n);      // read_transforms.cpp
void readVertexData(Walker& w, const SceneNode& n);           // read_vertex_data.cpp
void readTexCoordData(Walker& w, const SceneNode& n);         // read_vertex_data.cpp
void readBrdfs(Walker& w, const SceneNode& n);                // read_materials.cpp
void readMaterials(Walker& w, const SceneNode& n);            // read_materials.cpp
void readTextures(Walker& w, const SceneNode& n);             // read_textures.cpp
void readCameras(Walker& w, const SceneNode& n);              // read_cameras.cpp
void readLights(Walker& w, const SceneNode& n);               // read_lights.cpp
void readObjects(Walker& w, const SceneNode& n);              // read_objects.cpp

// ---- Look-ups that more than one family makes ---------------------------------------------------------
// The owner's <Transformations> string ("t1 s2 r1") composed into one matrix (identity without one):
// objects, cameras and lights (read_transforms.cpp).
Mat4 transformOf(const Walker& w, const SceneNode& owner);
// The Scene::imagePaths index of the Image whose id is idNode's text (read_textures.cpp).
int imageRef(const Walker& w, const SceneNode& owner, const SceneNode& idNode);
// A vertex index as written (1-based unless ZeroBasedIndexing) plus offset -> 0-based, checked
// against the VertexData read so far (read_vertex_data.cpp).
int vertexIndex(const Walker& w, const SceneNode& n, const std::string& who, long raw, long offset);

}  // namespace clrt::walker
