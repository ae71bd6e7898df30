// Objects: <Objects> and its shapes, each with an optional id, a <Material>, optional <Textures> (ids
// of TextureMaps) and <Transformations> (a string such as "t1 s2 r1", read_transforms.cpp). Reads:
//   Mesh (shadingMode = smooth|flat; <Faces>: inline indices into VertexData, or binaryFile, or
//     plyFile (ply_reader.h); vertexOffset textureOffset), MeshInstance (baseMeshId: a Mesh, else
//     another MeshInstance; resetTransform, shadingMode), Triangle (Indices), Sphere (Center Radius), Plane (Point Normal; JSON 2025 scenes),
//     LightMesh (as Mesh + Radiance) and LightSphere (as Sphere + Radiance): a shape and a light each.
//   Mesh, MeshInstance, Triangle and Sphere take <MotionBlur> (a translation over the shutter); object
//   lights do not (their sampling data are the rest position).
// The Meshes of an <Objects> are read first, so that instances may name a mesh defined after them;
// then every child is placed in document order by its row of objectReaders(). A MeshInstance is
// resolved when first needed (placed, or named by another), so chains may run in any order.
#include <set>
#include <unordered_map>

#include "scene/ply_reader.h"
#include "scene/scene_walker.h"
#include "shared/type_tables.h"
#include "util/error.h"

namespace clrt::walker {
namespace {

// The Meshes of one <Objects>, read before its other children, and its MeshInstances, resolved on
// first use (an instance may name another instance, defined before or after it).
struct ObjectsContext {
    std::map<int, Shape> meshById;  // what MeshInstance baseMeshId names first
    std::map<int, std::vector<std::string>> meshIdLocations;  // Mesh id -> where each Mesh with it is
    std::vector<Shape> meshes;      // in document order
    size_t nextMesh = 0;            // the next one to place
    // Instances are keyed by location(): node wrappers are made afresh by each children() call.
    std::map<int, std::vector<SceneNodePtr>> instanceNodes;  // MeshInstance id -> its elements
    std::map<std::string, Shape> instanceShapes;             // resolved instances by location
    std::vector<std::pair<std::string, int>> resolving;      // (location, id) chain being resolved
};

std::string sourceOf(const SceneNode& n) { return describe(n) + " (" + n.location() + ")"; }

int materialRef(const Walker& w, const SceneNode& owner, const SceneNode& matNode) {
    int id = integer(matNode);
    auto it = w.materialIds.find(id);
    if (it == w.materialIds.end())
        fail(matNode, describe(owner) + " references undefined Material " + std::to_string(id));
    return it->second;
}
std::vector<int> textureRefs(const Walker& w, const SceneNode& owner, const SceneNode& texNode) {
    std::vector<int> out;
    for (int id : integers(texNode)) {
        auto it = w.textureIds.find(id);
        if (it == w.textureIds.end())
            fail(texNode, describe(owner) + " references undefined TextureMap " + std::to_string(id));
        out.push_back(it->second);
    }
    return out;
}
// <MotionBlur>x y z</MotionBlur>: a world-space translation over the shutter interval [0, 1],
// applied after the object's transformations (the object sits at transform, then + time·motion).
Vec3 motionOf(const SceneNode& owner) {
    auto c = owner.child("MotionBlur");
    return c ? vec3(*c) : Vec3(0, 0, 0);
}
bool smoothOf(const SceneNode& n, bool dflt) {
    auto a = n.attribute("shadingMode");
    if (!a) return dflt;
    std::string v = lower(trim(*a));
    if (v == "smooth") return true;
    if (v == "flat") return false;
    fail(n, describe(n) + ": shadingMode='" + *a + "' is not smooth or flat");
}
bool hasImageTexture(const Walker& w, const std::vector<int>& tex) {
    for (int t : tex)
        if (w.scene.textures[size_t(t)].type == dev::TEXTURE_IMAGE) return true;
    return false;
}

// What every shape but MeshInstance reads alike, in this order: id, shadingMode (meshes), Material,
// Textures, Transformations.
Shape baseShape(const Walker& w, const SceneNode& n, ShapeType type, bool shadingMode = false) {
    Shape s;
    s.id = intAttribute(n, "id", 0);
    s.type = type;
    s.source = sourceOf(n);
    if (shadingMode) s.smooth = smoothOf(n, false);
    s.materialIndex = materialRef(w, n, *need(n, "Material"));
    if (auto t = n.child("Textures")) s.textureIndices = textureRefs(w, n, *t);
    s.transform = transformOf(w, n);
    return s;
}

// Texture coordinates of a mesh's own vertices (uvIdx: their TexCoordData index), when they are all
// in range; a warning when an image texture needs them and they are not.
void meshUvs(const Walker& w, const SceneNode& n, const std::string& who, const std::vector<long>& vertUv,
             bool needUv, MeshData& md) {
    if (w.texcoords.empty()) {
        if (needUv) warnOnce(n.location() + ": " + who + " has an image texture but the scene has no TexCoordData");
        return;
    }
    for (long u : vertUv)
        if (u < 0 || u >= long(w.texcoords.size())) {
            if (needUv)
                warnOnce(n.location() + ": " + who + ": texture coordinate index out of range (TexCoordData has " +
                         std::to_string(w.texcoords.size()) + " pairs); the mesh gets no texture coordinates");
            return;
        }
    for (long u : vertUv) md.uvs.push_back(w.texcoords[size_t(u)]);
}

// Compact per-object MeshData from global-vertex triangles. uvIdx: per corner TexCoordData index.
MeshData compactMesh(const Walker& w, const SceneNode& n, const std::string& who, const std::vector<int>& corners,
                     const std::vector<long>& uvIdx, bool needUv) {
    MeshData md;
    std::unordered_map<int, int> local;
    md.indices.reserve(corners.size());
    std::vector<long> vertUv;
    for (size_t k = 0; k < corners.size(); ++k) {
        auto [it, inserted] = local.emplace(corners[k], int(md.positions.size()));
        if (inserted) {
            md.positions.push_back(w.vertices[size_t(corners[k])]);
            vertUv.push_back(uvIdx[k]);
        }
        md.indices.push_back(it->second);
    }
    meshUvs(w, n, who, vertUv, needUv, md);
    return md;
}

// The index triples of <Faces>: its text or its binaryFile.
std::vector<int32_t> faceData(const Walker& w, const SceneNode& faces) {
    if (auto bf = faces.attribute("binaryFile")) {
        auto words = w.binaryWords(faces, *bf, "faces", 3);
        return std::vector<int32_t>(words.begin(), words.end());
    }
    auto v = integers(faces);
    return std::vector<int32_t>(v.begin(), v.end());
}

// <Faces plyFile="...">: the Scene::meshes index of the PLY file's mesh, read once per file.
int plyMesh(Walker& w, const SceneNode& faces, const std::string& who, const std::string& ply, bool needUv) {
    std::string p = w.resolve(ply);
    int index;
    if (auto it = w.plyMeshes.find(p); it != w.plyMeshes.end()) {
        index = it->second;
    } else {
        MeshData md;
        try {
            md = readPly(p);
        } catch (const Error& e) {
            throw Error(faces.location() + ": " + who + ": " + e.what(), e.code());
        }
        index = int(w.scene.meshes.size());
        w.plyMeshes.emplace(p, index);
        w.scene.plyPaths.push_back(p);
        w.scene.meshes.push_back(std::move(md));
    }
    if (needUv && w.scene.meshes[size_t(index)].uvs.empty())
        warnOnce(faces.location() + ": " + who + " has an image texture but PLY '" + ply +
                 "' has no texture coordinates");
    return index;
}

// <Faces> as indices into VertexData (text or binaryFile): the Scene::meshes index of its mesh.
int faceListMesh(Walker& w, const SceneNode& faces, const std::string& who, bool needUv) {
    long vOff = intAttribute(faces, "vertexOffset", 0);
    long tOff = intAttribute(faces, "textureOffset", 0);
    auto idx = faceData(w, faces);
    if (idx.size() % 3 != 0)
        fail(faces, who + ": <Faces> has " + std::to_string(idx.size()) + " indices, not a multiple of 3");
    if (idx.empty()) fail(faces, who + ": <Faces> is empty");
    std::vector<int> corners(idx.size());
    std::vector<long> uv(idx.size());
    long base = w.zeroBased ? 0 : 1;
    for (size_t k = 0; k < idx.size(); ++k) {
        corners[k] = vertexIndex(w, faces, who, idx[k], vOff);
        uv[k] = long(idx[k]) + tOff - base;
    }
    w.scene.meshes.push_back(compactMesh(w, faces, who, corners, uv, needUv));
    return int(w.scene.meshes.size()) - 1;
}

// Mesh and LightMesh (isLight: <Radiance> is read by addObjectLight; no MotionBlur).
Shape readMesh(Walker& w, const SceneNode& n, bool isLight) {
    if (isLight) w.checkChildren(n, {"Material", "Textures", "Transformations", "Faces", "Radiance"});
    else w.checkChildren(n, {"Material", "Textures", "Transformations", "Faces", "MotionBlur"});
    std::string who = describe(n);
    Shape s = baseShape(w, n, ShapeType::Mesh, true);
    s.motion = motionOf(n);
    auto faces = need(n, "Faces");
    bool needUv = hasImageTexture(w, s.textureIndices);
    if (auto ply = faces->attribute("plyFile")) s.meshIndex = plyMesh(w, *faces, who, *ply, needUv);
    else s.meshIndex = faceListMesh(w, *faces, who, needUv);
    return s;
}

void readTriangle(Walker& w, const SceneNode& n, ObjectsContext&) {
    w.checkChildren(n, {"Material", "Textures", "Transformations", "Indices", "MotionBlur"});
    std::string who = describe(n);
    Shape s = baseShape(w, n, ShapeType::Mesh);
    s.motion = motionOf(n);
    auto in = need(n, "Indices");
    auto v = numbers(*in, 3);
    std::vector<int> corners(3);
    std::vector<long> uv(3);
    for (int k = 0; k < 3; ++k) {
        long raw = long(toInteger(*in, v[size_t(k)]));
        corners[size_t(k)] = vertexIndex(w, *in, who, raw, 0);
        uv[size_t(k)] = raw - (w.zeroBased ? 0 : 1);
    }
    s.meshIndex = int(w.scene.meshes.size());
    w.scene.meshes.push_back(compactMesh(w, *in, who, corners, uv, hasImageTexture(w, s.textureIndices)));
    w.scene.shapes.push_back(s);
}

// The VertexData position named by child `child` (a vertex index) of n.
Vec3 vertexAt(const Walker& w, const SceneNode& n, const char* child, const std::string& who) {
    auto c = need(n, child);
    return w.vertices[size_t(vertexIndex(w, *c, who, integer(*c), 0))];
}

// Sphere and LightSphere (isLight: <Radiance> is read by addObjectLight; no MotionBlur).
Shape readSphereShape(Walker& w, const SceneNode& n, bool isLight) {
    if (isLight) w.checkChildren(n, {"Material", "Textures", "Transformations", "Center", "Radius", "Radiance"});
    else w.checkChildren(n, {"Material", "Textures", "Transformations", "Center", "Radius", "MotionBlur"});
    Shape s = baseShape(w, n, ShapeType::Sphere);
    s.motion = motionOf(n);
    std::string who = describe(n);
    s.center = vertexAt(w, n, "Center", who);
    auto rn = need(n, "Radius");
    s.radius = number(*rn);
    if (!(s.radius > 0)) fail(*rn, who + ": Radius must be positive");
    return s;
}

void readSphere(Walker& w, const SceneNode& n, ObjectsContext&) { w.scene.shapes.push_back(readSphereShape(w, n, false)); }

// Plane (2025 JSON scenes): an infinite plane through vertex Point with normal Normal.
void readPlane(Walker& w, const SceneNode& n, ObjectsContext&) {
    w.checkChildren(n, {"Material", "Textures", "Transformations", "Point", "Normal"});
    Shape s = baseShape(w, n, ShapeType::Plane);
    std::string who = describe(n);
    s.center = vertexAt(w, n, "Point", who);
    auto nn = need(n, "Normal");
    auto v = numbers(*nn, 3);
    s.normal = Vec3(float(v[0]), float(v[1]), float(v[2]));
    if (!(length(s.normal) > 0) || !isFinite(s.normal)) fail(*nn, who + ": Normal must be a non-zero vector");
    w.scene.shapes.push_back(s);
}

Shape resolveInstance(Walker& w, const SceneNode& n, ObjectsContext& objects);

// "4 -> 5 -> 4": the ids of a cycle of instances, from where it closes.
std::string idCycle(const std::vector<std::pair<std::string, int>>& chain, const SceneNode& last) {
    std::string out;
    bool in = false;
    for (auto& [where, id] : chain) {
        in = in || where == last.location();
        if (in) out += std::to_string(id) + " -> ";
    }
    return out + std::to_string(intAttribute(last, "id", 0));
}

// What baseMeshId names: a Mesh of this <Objects> if one has that id, else the MeshInstance with that
// id (resolved first: its transforms, material and textures are those it ends up with).
Shape baseOf(Walker& w, const SceneNode& n, ObjectsContext& objects, int baseId) {
    std::string who = describe(n);
    if (auto it = objects.meshById.find(baseId); it != objects.meshById.end()) {
        const std::vector<std::string>& where = objects.meshIdLocations[baseId];
        if (where.size() > 1)
            fail(n, who + " references Mesh " + std::to_string(baseId) + ", which " + std::to_string(where.size()) +
                        " Meshes share as id (" + where.front() + ", " + where[1] + ")");
        return it->second;
    }
    auto inst = objects.instanceNodes.find(baseId);
    if (inst == objects.instanceNodes.end())
        fail(n, who + " references undefined Mesh " + std::to_string(baseId) + " (no Mesh or MeshInstance has that id)");
    if (inst->second.size() > 1)
        fail(n, who + " references MeshInstance " + std::to_string(baseId) + ", which " +
                    std::to_string(inst->second.size()) + " MeshInstances share as id");
    const SceneNode& baseNode = *inst->second.front();
    for (auto& [where, id] : objects.resolving)
        if (where == baseNode.location())
            fail(n, "MeshInstances name each other as baseMeshId in a cycle: " + idCycle(objects.resolving, baseNode));
    return resolveInstance(w, baseNode, objects);
}

// MeshInstance: the geometry of what baseMeshId names (a Mesh, or another MeshInstance's mesh), with
// its own (or the base's) material, textures and shading mode, and its own transformation after the
// base's composed one (or, with resetTransform, instead of it). It moves by its own MotionBlur only.
Shape resolveInstance(Walker& w, const SceneNode& n, ObjectsContext& objects) {
    std::string key = n.location();
    if (auto done = objects.instanceShapes.find(key); done != objects.instanceShapes.end()) return done->second;
    w.checkChildren(n, {"Material", "Textures", "Transformations", "MotionBlur"});
    std::string who = describe(n);
    if (!n.attribute("baseMeshId")) fail(n, who + " has no baseMeshId attribute");
    int baseId = intAttribute(n, "baseMeshId", 0);
    objects.resolving.emplace_back(key, intAttribute(n, "id", 0));
    const Shape base = baseOf(w, n, objects, baseId);
    objects.resolving.pop_back();
    bool reset = false;
    if (auto r = n.attribute("resetTransform")) reset = boolean(n, *r, who + ": resetTransform");
    Shape s = base;
    s.id = intAttribute(n, "id", 0);
    s.source = sourceOf(n);
    s.smooth = smoothOf(n, base.smooth);
    if (auto m = n.child("Material")) s.materialIndex = materialRef(w, n, *m);
    if (auto t = n.child("Textures")) s.textureIndices = textureRefs(w, n, *t);
    Mat4 own = transformOf(w, n);
    s.transform = reset ? own : own * base.transform;
    s.motion = motionOf(n);  // its own motion only: an instance of a moving mesh may stand still
    if (hasImageTexture(w, s.textureIndices) && w.scene.meshes[size_t(s.meshIndex)].uvs.empty())
        warnOnce(n.location() + ": " + who + " has an image texture but its mesh has no texture coordinates");
    objects.instanceShapes.emplace(key, s);
    return s;
}

void readInstance(Walker& w, const SceneNode& n, ObjectsContext& objects) {
    w.scene.shapes.push_back(resolveInstance(w, n, objects));
}

// A Mesh, read ahead by readObjects: placed here, in document order.
void placeMesh(Walker& w, const SceneNode&, ObjectsContext& objects) {
    w.scene.shapes.push_back(objects.meshes[objects.nextMesh++]);
}

// An object light (LightMesh, LightSphere: rows of the light table that are also shapes): the shape
// as a Mesh or Sphere reads it, plus its <Radiance>; the shape and its light point at each other.
void addObjectLight(Walker& w, const SceneNode& n, Shape s, dev::LightKind kind) {
    std::string who = describe(n);
    s.motion = Vec3(0, 0, 0);  // <MotionBlur> is not read for object lights (warned as unknown)
    auto rn = need(n, "Radiance");
    Vec3 radiance = vec3(*rn);
    if (!isFinite(radiance) || radiance.x < 0 || radiance.y < 0 || radiance.z < 0)
        fail(*rn, who + ": Radiance must be three finite non-negative numbers");
    Light light;
    light.id = s.id;
    light.type = kind;
    light.intensity = radiance;
    light.shapeIndex = int(w.scene.shapes.size());
    s.lightIndex = int(w.scene.lights.size());
    w.scene.lights.push_back(light);
    w.scene.shapes.push_back(s);
}
void readLightMesh(Walker& w, const SceneNode& n, ObjectsContext&) {
    addObjectLight(w, n, readMesh(w, n, true), dev::LIGHT_MESH);
}
void readLightSphere(Walker& w, const SceneNode& n, ObjectsContext&) {
    addObjectLight(w, n, readSphereShape(w, n, true), dev::LIGHT_SPHERE);
}

// The children of <Objects> and their readers. Adding a shape: its reader above and one row here.
struct ObjectReader {
    const char* name;
    void (*read)(Walker& w, const SceneNode& n, ObjectsContext& objects);
};
const std::vector<ObjectReader>& objectReaders() {
    static const std::vector<ObjectReader> table = {
        {"Mesh", placeMesh},
        {"MeshInstance", readInstance},
        {"Triangle", readTriangle},
        {"Sphere", readSphere},
        {"Plane", readPlane},
        {typeRow(lightTypes(), dev::LIGHT_MESH).name, readLightMesh},
        {typeRow(lightTypes(), dev::LIGHT_SPHERE).name, readLightSphere},
    };
    return table;
}

// Reads every Mesh of n ahead. Mesh ids only name meshes for MeshInstance's baseMeshId: a repeated one
// warns (edited copies of course scenes repeat them: a student's hw6 box whose ceiling became a second
// Mesh 1), and only an instance that names it is an error (baseOf). Other kinds are not checked
// (shared scenes repeat Sphere ids).
void readMeshesAhead(Walker& w, const SceneNode& n, ObjectsContext& objects) {
    for (auto& c : n.children("Mesh")) {
        if (c->attribute("id")) {
            int v = intAttribute(*c, "id", 0);
            std::vector<std::string>& where = objects.meshIdLocations[v];
            where.push_back(c->location());
            if (where.size() == 2)
                warn(where[1] + ": Mesh id " + std::to_string(v) + " is also the id of the Mesh at " + where[0] +
                     " (allowed while no MeshInstance names it)");
        }
        Shape s = readMesh(w, *c, false);
        objects.meshById.emplace(s.id, s);
        objects.meshes.push_back(s);
    }
    for (auto& c : n.children("MeshInstance"))
        if (c->attribute("id")) objects.instanceNodes[intAttribute(*c, "id", 0)].push_back(c);
}

}  // namespace

void readObjects(Walker& w, const SceneNode& n) {
    std::vector<std::string> known;
    for (const ObjectReader& r : objectReaders()) known.push_back(r.name);
    w.checkChildren(n, known);
    ObjectsContext objects;
    readMeshesAhead(w, n, objects);
    for (auto& c : n.children()) {
        std::string name = c->name();
        for (const ObjectReader& r : objectReaders())
            if (name == r.name) r.read(w, *c, objects);
    }
}

}  // namespace clrt::walker
