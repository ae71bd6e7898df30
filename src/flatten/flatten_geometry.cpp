// flatten_geometry.cpp — planes, spheres and mesh triangles in world space (meshes on all hardware
// threads), then the BVH over triangles and spheres with the triangles stored in leaf order (see
// flatten.h). Triangles keep smooth normals (vertex_normals.h) and uvs in triAttributes, only where their
// mesh has them (TriangleShading.attributes; a flat triangle's normal is recomputed by the kernel from
// its vertices, flattenTriangles and triangleCorners use the same formula); spheres their affine maps.
// A mesh whose transformation mirrors (det < 0) has its winding reversed, as the course does, so its
// geometric normal is the object-space one carried by the inverse transpose (see mirrorsOrientation).
// Moving shapes (MotionBlur) keep their rest position; their motion rides in Triangle.v*.w and
// Sphere.motion, and their BVH boxes are swept over the shutter interval (sweptBox).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <system_error>
#include <thread>
#include <utility>

#include "flatten/flatten.h"
#include "flatten/vertex_normals.h"
#include "scene/transforms.h"
#include "util/error.h"
#include "util/parallel.h"

namespace clrt {

uint32_t meshAttributeFlags(const Scene& scene, const Shape& s) {
    const MeshData& mesh = scene.meshes.at(s.meshIndex);
    return (s.smooth ? CLRT_TRI_NORMALS : 0u) | (mesh.uvs.size() == mesh.positions.size() ? CLRT_TRI_UVS : 0u);
}

size_t attributeFloats(uint32_t flags) {
    return ((flags & CLRT_TRI_NORMALS) ? CLRT_TRI_NORMAL_FLOATS : 0) + ((flags & CLRT_TRI_UVS) ? CLRT_TRI_UV_FLOATS : 0);
}

// The attributes word of a triangle whose corner data starts at `offset` floats into triAttributes
// (0 for a triangle with none); throws when the offset does not fit below the flags.
uint32_t attributeWord(uint32_t flags, size_t offset) {
    if (!flags) return 0;
    if (offset > CLRT_TRI_OFFSET_MASK) throw Error("scene too large: more triangle normals and uvs than TriangleShading.attributes can address");
    return flags | uint32_t(offset);
}

namespace {

// A triangle's face normal cross(p1 - p0, p2 - p0) / its length, and that length in *len. The kernels'
// Triangle_FaceNormal (cl_kernels/intersect.cl) repeats these operations in this order, so a flat
// triangle's normal recomputed on the device equals this one bit for bit.
Vec3 faceNormal(const Vec3& p0, const Vec3& p1, const Vec3& p2, float* len) {
    const Vec3 n = cross(p1 - p0, p2 - p0);
    *len = length(n);
    return n / *len;
}

}  // namespace

// Where a run of triangles is written: slots of the scene's arrays (triangles, their
// shading and boxes; their corner attributes from `attributes`, which is triAttributes[attributeBase]),
// and what was left out (degenerate and non-finite triangles, counted).
struct TriangleSlots {
    dev::Triangle* triangles;
    dev::TriangleShading* shading;
    BvhItem* boxes;  // each kept triangle's box (swept over the shutter), for the BVH
    float* attributes;
    size_t attributeBase;
    size_t kept = 0, degenerate = 0, nonFinite = 0;
};
// A mesh shape's vertices in world space, and its smooth normals: what its triangles are made from.
struct MeshVertices {
    std::vector<Vec3> pw, nw;
    int kB = 1, kC = 2;  // corners (a, b, c) of a triangle; a mirrored mesh takes them as (a, c, b)
};

// The box a primitive sweeps over the shutter interval: moved by t·motion, t in [0, 1], it stays
// inside the union of its boxes at both ends (the motion is a straight translation).
Aabb sweptBox(const Aabb& rest, const Vec3& motion) {
    Aabb box = rest;
    if (motion == Vec3(0, 0, 0)) return box;
    box.grow(rest.min + motion);
    box.grow(rest.max + motion);
    return box;
}

void meshVertices(const Scene& scene, const Shape& s, MeshVertices& out) {
    const MeshData& mesh = scene.meshes.at(s.meshIndex);
    const int kB = mirrorsOrientation(s.transform) ? 2 : 1, kC = 3 - kB;
    out.kB = kB;
    out.kC = kC;
    std::vector<Vec3>& pw = out.pw;
    pw.resize(mesh.positions.size());
    for (size_t v = 0; v < pw.size(); ++v) pw[v] = s.transform.transformPoint(mesh.positions[v]);
    // Smooth shading: the object-space vertex normals (vertex_normals.h) carried to world space by the
    // inverse transpose; (0, 0, 0) where a vertex has none (the face normal is used there).
    std::vector<Vec3>& nw = out.nw;
    if (s.smooth) {
        nw = objectVertexNormals(mesh, scene.vertexNormals);
        Mat4 inv;
        const Mat4 invT = s.transform.inverse(inv) ? inv.transposed() : Mat4::identity();
        for (Vec3& n : nw)
            if (n != Vec3(0, 0, 0)) n = normalize(invT.transformVector(n));
    }
}

// Triangles [tBegin, tEnd) of a mesh shape in world space, in index order, into `out` (degenerate
// and non-finite ones counted and left out). Independent per range, so a mesh is flattened on several
// threads.
void flattenTriangles(const Scene& scene, const Shape& s, int texSet, const MeshVertices& mv, size_t tBegin,
                      size_t tEnd, TriangleSlots& out) {
    const MeshData& mesh = scene.meshes.at(s.meshIndex);
    const std::vector<Vec3>&pw = mv.pw, &nw = mv.nw;
    const int kB = mv.kB, kC = mv.kC;
    const uint32_t flags = meshAttributeFlags(scene, s);
    const size_t floats = attributeFloats(flags);
    for (size_t t = 3 * tBegin; t < 3 * tEnd; t += 3) {
        int a = mesh.indices[t], b = mesh.indices[t + kB], c = mesh.indices[t + kC];
        const Vec3 &p0 = pw[a], &p1 = pw[b], &p2 = pw[c];
        if (!isFinite(p0) || !isFinite(p1) || !isFinite(p2)) { ++out.nonFinite; continue; }
        float len;
        const Vec3 n = faceNormal(p0, p1, p2, &len);  // what the device recomputes without CLRT_TRI_NORMALS
        if (p0 == p1 || p1 == p2 || p0 == p2 || !(len > 0) || !std::isfinite(len)) {
            ++out.degenerate;
            continue;
        }
        // w of the three vertices: the motion's x, y, z (0, 0, 0 for a static mesh).
        dev::Triangle tri{toFloat4(p0, s.motion.x), toFloat4(p1, s.motion.y), toFloat4(p2, s.motion.z)};
        dev::TriangleShading sh{};
        float* corner = out.attributes + out.kept * floats;
        if (flags & CLRT_TRI_NORMALS) {  // a corner without a vertex normal takes the face normal
            auto normalAt = [&](int v) { return (nw[v] != Vec3(0, 0, 0) && isFinite(nw[v])) ? nw[v] : n; };
            for (int v : {a, b, c}) {
                const Vec3 nv = normalAt(v);
                *corner++ = nv.x; *corner++ = nv.y; *corner++ = nv.z;
            }
        }
        if (flags & CLRT_TRI_UVS)
            for (int v : {a, b, c}) { *corner++ = mesh.uvs[v].x; *corner++ = mesh.uvs[v].y; }
        sh.attributes = attributeWord(flags, out.attributeBase + out.kept * floats);
        sh.material = s.materialIndex;
        sh.textureSet = texSet;
        sh.light = s.lightIndex;  // LightMesh: its light, else CLRT_INVALID (-1)
        Aabb box;
        box.grow(p0); box.grow(p1); box.grow(p2);
        out.triangles[out.kept] = tri;
        out.shading[out.kept] = sh;
        out.boxes[out.kept] = bvhItem(sweptBox(box, s.motion));
        ++out.kept;
    }
}


namespace {

// Puts a[i] = a[src[i]] and b[i] = b[src[i]] (the values before the call) for every i < src.size(), in
// place: each cycle of the permutation is followed once, with one element of each array held aside,
// so no copy of either array is made (src is spent: every entry ends as -1).
template <class A, class B>
void gatherInPlace(A* a, B* b, std::vector<int>& src) {
    for (size_t start = 0; start < src.size(); ++start) {
        if (src[start] < 0) continue;  // moved in an earlier cycle
        const A heldA = a[start];
        const B heldB = b[start];
        size_t j = start;
        for (;;) {
            const size_t k = size_t(src[j]);
            src[j] = -1;
            if (k == start) { a[j] = heldA; b[j] = heldB; break; }
            a[j] = a[k];
            b[j] = b[k];
            j = k;
        }
    }
}

}  // namespace

void putInLeafOrder(Bvh& bvh, dev::Triangle* tris, dev::TriangleShading* shading, int numTriangles) {
    std::vector<int> src;  // leaf-order slot -> the triangle's slot now; spheres keep their indices
    src.reserve(size_t(numTriangles));
    for (int& ref : bvh.primRefs) {
        if (ref >= numTriangles) continue;
        src.push_back(ref);
        ref = int(src.size()) - 1;
    }
    gatherInPlace(tris, shading, src);
}

void storeRows(dev::float4 rows[3], const Mat4& m) {
    for (int r = 0; r < 3; ++r)
        rows[r] = {float(m.m[r][0]), float(m.m[r][1]), float(m.m[r][2]), float(m.m[r][3])};
}

namespace {

// False (warned) when the plane is degenerate.
bool flattenPlane(const Shape& s, int texSet, DeviceScene& ds) {
    Mat4 inv;
    Vec3 n = s.transform.inverse(inv) ? normalize(inv.transposed().transformVector(s.normal)) : Vec3(0, 0, 0);
    Vec3 p = s.transform.transformPoint(s.center);
    if (!(length(n) > 0) || !isFinite(n) || !isFinite(p)) {
        warn(s.source + ": singular transform or bad normal; plane skipped");
        return false;
    }
    dev::Plane pl{};
    pl.point = toFloat4(p);
    pl.normal = toFloat4(n);
    pl.material = s.materialIndex;
    pl.textureSet = texSet;
    ds.planes.push_back(pl);
    return true;
}

// Appends the sphere and its world-space box; false (warned) when it is degenerate.
bool flattenSphere(const Shape& s, int texSet, DeviceScene& ds, std::vector<Aabb>& sphereBoxes) {
    dev::Sphere sp{};
    sp.centerRadius = toFloat4(s.center, s.radius);
    Mat4 inv;
    if (!s.transform.inverse(inv) || !(s.radius > 0) || !isFinite(s.center)) {
        warn(s.source + ": singular transform or bad radius; sphere skipped");
        return false;
    }
    storeRows(sp.objectToWorld, s.transform);
    storeRows(sp.worldToObject, inv);
    sp.material = s.materialIndex;
    sp.textureSet = texSet;
    sp.motion = toFloat4(s.motion);
    sp.light = s.lightIndex;  // LightSphere: its light, else CLRT_INVALID (-1)
    Aabb box;
    for (int c = 0; c < 8; ++c) {
        Vec3 corner(s.center.x + ((c & 1) ? s.radius : -s.radius), s.center.y + ((c & 2) ? s.radius : -s.radius),
                    s.center.z + ((c & 4) ? s.radius : -s.radius));
        box.grow(s.transform.transformPoint(corner));
    }
    ds.spheres.push_back(sp);
    sphereBoxes.push_back(sweptBox(box, s.motion));
    return true;
}

using MeshJob = std::pair<const Shape*, int>;  // (shape, texture set)

}  // namespace

constexpr size_t kTrianglesPerTask = 16384;  // a big mesh is cut into runs of this many for the threads

// Meshes on all hardware threads, written straight into their place in ds.triangles,
// ds.triangleShading and `boxes` (each task its own run of slots; small meshes one task each, a big
// one cut into runs after its vertices are transformed), then the runs are closed up over the
// triangles left out: the same arrays as a sequential loop (flatten.h).
std::pair<size_t, size_t> flattenMeshes(const Scene& scene, const std::vector<MeshJob>& meshJobs, DeviceScene& ds,
                                        BvhItems& boxes) {
    struct Task {
        size_t job, tBegin, tEnd, slot;  // triangles [tBegin, tEnd) of job, written from slot
        size_t attributeSlot, floats;    // their corner attributes from there, `floats` per triangle
        TriangleSlots out;
    };
    std::vector<Task> tasks;
    std::vector<size_t> smallJobs, bigJobs;
    const size_t base = ds.triangles.size(), boxBase = boxes.size(), attributeBase = ds.triangleAttributes.size();
    size_t slot = 0, attributeSlot = 0;
    for (size_t j = 0; j < meshJobs.size(); ++j) {
        const size_t n = scene.meshes.at(meshJobs[j].first->meshIndex).indices.size() / 3;
        const size_t floats = attributeFloats(meshAttributeFlags(scene, *meshJobs[j].first));
        if (n <= kTrianglesPerTask) {
            smallJobs.push_back(j);
            tasks.push_back({j, 0, n, slot, attributeSlot, floats, {}});
        } else {
            bigJobs.push_back(j);
            for (size_t t = 0; t < n; t += kTrianglesPerTask)
                tasks.push_back({j, t, std::min(n, t + kTrianglesPerTask), slot + t, attributeSlot + t * floats, floats, {}});
        }
        slot += n;
        attributeSlot += n * floats;
    }
    ds.triangles.resize(base + slot);
    ds.triangleShading.resize(base + slot);
    ds.triangleAttributes.resize(attributeBase + attributeSlot);
    boxes.resize(boxBase + slot);
    auto run = [&](Task& k, const MeshVertices& mv) {
        k.out = TriangleSlots{ds.triangles.data() + base + k.slot, ds.triangleShading.data() + base + k.slot,
                              boxes.data() + boxBase + k.slot, ds.triangleAttributes.data() + attributeBase + k.attributeSlot,
                              attributeBase + k.attributeSlot};
        flattenTriangles(scene, *meshJobs[k.job].first, meshJobs[k.job].second, mv, k.tBegin, k.tEnd, k.out);
    };
    std::vector<size_t> taskOfJob(meshJobs.size());
    for (size_t i = tasks.size(); i-- > 0;) taskOfJob[tasks[i].job] = i;  // each job's first task
    parallelFor(smallJobs.size(), [&](size_t k) {
        MeshVertices mv;
        meshVertices(scene, *meshJobs[smallJobs[k]].first, mv);
        run(tasks[taskOfJob[smallJobs[k]]], mv);
    });
    for (size_t j : bigJobs) {
        MeshVertices mv;
        meshVertices(scene, *meshJobs[j].first, mv);
        size_t first = taskOfJob[j], count = 0;
        while (first + count < tasks.size() && tasks[first + count].job == j) ++count;
        parallelFor(count, [&](size_t k) { run(tasks[first + k], mv); });
    }
    // Close up: each run's kept triangles (and their corner attributes, whose offsets follow) move down
    // to follow the previous run's.
    size_t to = 0, attributeTo = 0, degenerate = 0, nanSkipped = 0;
    for (Task& k : tasks) {
        if (to != k.slot)
            for (size_t i = 0; i < k.out.kept; ++i) {
                ds.triangles[base + to + i] = ds.triangles[base + k.slot + i];
                ds.triangleShading[base + to + i] = ds.triangleShading[base + k.slot + i];
                boxes[boxBase + to + i] = boxes[boxBase + k.slot + i];
            }
        if (attributeTo != k.attributeSlot && k.floats) {
            std::copy(ds.triangleAttributes.begin() + std::ptrdiff_t(attributeBase + k.attributeSlot),
                      ds.triangleAttributes.begin() + std::ptrdiff_t(attributeBase + k.attributeSlot + k.out.kept * k.floats),
                      ds.triangleAttributes.begin() + std::ptrdiff_t(attributeBase + attributeTo));
            for (size_t i = 0; i < k.out.kept; ++i) {
                uint32_t& word = ds.triangleShading[base + to + i].attributes;
                word = (word & ~CLRT_TRI_OFFSET_MASK) | uint32_t(attributeBase + attributeTo + i * k.floats);
            }
        }
        to += k.out.kept;
        attributeTo += k.out.kept * k.floats;
        degenerate += k.out.degenerate;
        nanSkipped += k.out.nonFinite;
    }
    ds.triangles.resize(base + to);
    ds.triangleShading.resize(base + to);
    ds.triangleAttributes.resize(attributeBase + attributeTo);
    boxes.resize(boxBase + to);
    ds.skippedTriangles += degenerate + nanSkipped;
    return {degenerate, nanSkipped};
}

namespace {

// The BVH over `boxes` (triangles, then spheres); with leafOrder the triangles are stored in leaf order
// so a leaf's triangles are contiguous in memory (FlattenOptions::leafOrderTriangles), then the tree is
// collapsed to 8-wide nodes with the leaves' triangles copied into their struct-of-arrays blocks. The
// boxes are released once the tree is built, the triangles and their shading are put in leaf order in
// place (no copies), and the binary tree is freed once its 8-wide nodes are made, before the leaf
// blocks (only its figures stay: ds.bvh), so the binary tree and the leaf blocks are never held together.
void buildDeviceBvh(BvhItems&& boxes, DeviceScene& ds, bool leafOrder) {
    auto tb = std::chrono::steady_clock::now();
    // The device tests a leaf's triangles four at a time (LeafBlock), so a leaf of up to four costs
    // about what one triangle test did: a node is costed as two triangle tests, which gives fuller
    // leaves (Audi TT: 2.1 -> 3.0 primitives per block) and fewer nodes (86k -> 61k).
    BvhBuildOptions opts;
    opts.traversalCost = 2;
    Bvh bvh = buildBvh(std::move(boxes), opts);  // consumes the boxes
    const int numTris = int(ds.triangles.size());
    if (leafOrder) putInLeafOrder(bvh, ds.triangles.data(), ds.triangleShading.data(), numTris);
    ds.bvh = summarizeBvh(bvh);
    ds.bvh8 = collapseBvh8(std::move(bvh));  // frees the binary tree before making the leaf blocks
    setLeafTriangles(ds.bvh8, ds.triangles, numTris);
    ds.features.bvhStack = std::max(1, ds.bvh8.maxStack);
    ds.bvhSeconds = secondsSince(tb);
}

}  // namespace

TriangleCorners triangleCorners(const DeviceScene& ds, size_t t) {
    const dev::Triangle& tri = ds.triangles.at(t);
    const uint32_t word = ds.triangleShading.at(t).attributes;
    const float* corner = ds.triangleAttributes.data() + (word & CLRT_TRI_OFFSET_MASK);
    TriangleCorners c{};
    for (int k = 0; k < 3; ++k) {
        if (word & CLRT_TRI_NORMALS) {
            c.normal[k] = Vec3(corner[3 * k], corner[3 * k + 1], corner[3 * k + 2]);
        } else {  // as flattenTriangles computes it (and Triangle_FaceNormal)
            float len;
            c.normal[k] = faceNormal(Vec3(tri.v0.x, tri.v0.y, tri.v0.z), Vec3(tri.v1.x, tri.v1.y, tri.v1.z),
                                     Vec3(tri.v2.x, tri.v2.y, tri.v2.z), &len);
        }
    }
    if (word & CLRT_TRI_NORMALS) corner += CLRT_TRI_NORMAL_FLOATS;
    if (word & CLRT_TRI_UVS)
        for (int k = 0; k < 3; ++k) { c.uv[k][0] = corner[2 * k]; c.uv[k][1] = corner[2 * k + 1]; }
    return c;
}

bool mirrorsOrientation(const Mat4& m) { return linearDeterminant(m) < 0; }

void flattenGeometry(const Scene& scene, DeviceScene& ds, const FlattenOptions& opts) {
    BvhItems boxes;  // the BVH's items: one per triangle, written as it is stored, then the spheres
    std::vector<Aabb> sphereBoxes;
    const std::vector<bool> instanced = instancedShapes(scene, opts.instancing);
    size_t total = 0, floats = 0;
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (scene.shapes[i].type == ShapeType::Mesh && !instanced[i]) {
            const size_t n = scene.meshes.at(scene.shapes[i].meshIndex).indices.size() / 3;
            total += n;
            floats += n * attributeFloats(meshAttributeFlags(scene, scene.shapes[i]));
        }
    size_t bottomFloats = 0;
    const size_t bottomTotal = bottomLevelTriangles(scene, instanced, &bottomFloats);  // appended by flattenInstances
    ds.triangles.reserve(total + bottomTotal);
    ds.triangleShading.reserve(total + bottomTotal);
    ds.triangleAttributes.reserve(floats + bottomFloats);
    boxes.reserve(total + scene.shapes.size());
    std::vector<MeshJob> meshJobs, instanceJobs;
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const Shape& s = scene.shapes[i];
        int texSet = flattenTextureSet(scene, s, ds);  // for every shape, in shape order
        if (s.type == ShapeType::Plane) flattenPlane(s, texSet, ds);
        else if (s.type == ShapeType::Sphere) flattenSphere(s, texSet, ds, sphereBoxes);
        else (instanced[i] ? instanceJobs : meshJobs).push_back({&s, texSet});
    }
    const auto skipped = flattenMeshes(scene, meshJobs, ds, boxes);
    if (skipped.first) warn(scene.path + ": skipped " + std::to_string(skipped.first) + " degenerate triangles");
    if (skipped.second) warn(scene.path + ": skipped " + std::to_string(skipped.second) + " triangles with NaN/Inf vertices");
    ds.features.spheres = !ds.spheres.empty();
    for (const Shape& s : scene.shapes)
        if (s.type != ShapeType::Plane && s.motion != Vec3(0, 0, 0)) ds.features.motionBlur = true;
    const int numTriangles = int(boxes.size());
    for (const Aabb& b : sphereBoxes) boxes.push_back(bvhItem(b));
    buildDeviceBvh(std::move(boxes), ds, opts.leafOrderTriangles);
    ds.params.numTriangles = numTriangles;
    if (!instanceJobs.empty()) flattenInstances(scene, instanceJobs, numTriangles, ds, opts.leafOrderTriangles);
    // Never an empty buffer (the counts below stay those of the scene, except planes: see Plane).
    if (ds.triangles.empty()) { ds.triangles.push_back(dev::Triangle{}); ds.triangleShading.push_back(dev::TriangleShading{}); }
    if (ds.triangleAttributes.empty()) ds.triangleAttributes.push_back(0.0f);
    if (ds.spheres.empty()) ds.spheres.push_back(dev::Sphere{});
    if (ds.planes.empty()) ds.planes.push_back(dev::Plane{});  // a zero normal: never hit, counted in numPlanes
    if (ds.textureSets.empty()) ds.textureSets.push_back(dev::TextureSet{{-1, -1, -1, -1}, {}});
    ds.params.numSpheres = int(sphereBoxes.size());
    ds.params.numPlanes = int(ds.planes.size());
}

}  // namespace clrt
