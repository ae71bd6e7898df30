// flatten_geometry.cpp — planes, spheres and mesh triangles in world space (meshes on all hardware
// threads), then the BVH over triangles and spheres with the triangles stored in leaf order (see
// flatten.h). Triangles keep flat or smooth normals (vertex_normals.h) and uvs; spheres their affine maps.
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

#include "flatten/flatten.h"
#include "flatten/vertex_normals.h"
#include "scene/transforms.h"
#include "util/error.h"

namespace clrt {
namespace {

// The triangles of one mesh shape in world space, in index order (degenerate and non-finite ones
// counted and left out). Independent per shape, so shapes are flattened on several threads.
struct MeshTriangles {
    std::vector<dev::Triangle> triangles;
    std::vector<dev::TriangleShading> shading;
    std::vector<Aabb> boxes;
    size_t degenerate = 0, nonFinite = 0;
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

void flattenMesh(const Scene& scene, const Shape& s, int texSet, MeshTriangles& out) {
    const MeshData& mesh = scene.meshes.at(s.meshIndex);
    // Corners (a, b, c) of triangle t; a mirrored mesh takes them as (a, c, b).
    const int kB = mirrorsOrientation(s.transform) ? 2 : 1, kC = 3 - kB;
    out.triangles.reserve(mesh.indices.size() / 3);
    out.shading.reserve(mesh.indices.size() / 3);
    out.boxes.reserve(mesh.indices.size() / 3);
    std::vector<Vec3> pw(mesh.positions.size());
    for (size_t v = 0; v < pw.size(); ++v) pw[v] = s.transform.transformPoint(mesh.positions[v]);
    // Smooth shading: the object-space vertex normals (vertex_normals.h) carried to world space by the
    // inverse transpose; (0, 0, 0) where a vertex has none (the face normal is used there).
    std::vector<Vec3> nw;
    if (s.smooth) {
        nw = objectVertexNormals(mesh);
        Mat4 inv;
        const Mat4 invT = s.transform.inverse(inv) ? inv.transposed() : Mat4::identity();
        for (Vec3& n : nw)
            if (n != Vec3(0, 0, 0)) n = normalize(invT.transformVector(n));
    }
    bool hasUv = mesh.uvs.size() == mesh.positions.size();
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        int a = mesh.indices[t], b = mesh.indices[t + kB], c = mesh.indices[t + kC];
        const Vec3 &p0 = pw[a], &p1 = pw[b], &p2 = pw[c];
        if (!isFinite(p0) || !isFinite(p1) || !isFinite(p2)) { ++out.nonFinite; continue; }
        Vec3 n = cross(p1 - p0, p2 - p0);
        float len = length(n);
        if (p0 == p1 || p1 == p2 || p0 == p2 || !(len > 0) || !std::isfinite(len)) {
            ++out.degenerate;
            continue;
        }
        n = n / len;
        // w of the three vertices: the motion's x, y, z (0, 0, 0 for a static mesh).
        dev::Triangle tri{toFloat4(p0, s.motion.x), toFloat4(p1, s.motion.y), toFloat4(p2, s.motion.z)};
        dev::TriangleShading sh{};
        auto normalAt = [&](int v) { return (s.smooth && nw[v] != Vec3(0, 0, 0) && isFinite(nw[v])) ? nw[v] : n; };
        sh.n0 = toFloat4(normalAt(a));
        sh.n1 = toFloat4(normalAt(b));
        sh.n2 = toFloat4(normalAt(c));
        if (hasUv) {
            sh.uv01 = {mesh.uvs[a].x, mesh.uvs[a].y, mesh.uvs[b].x, mesh.uvs[b].y};
            sh.uv2 = {mesh.uvs[c].x, mesh.uvs[c].y, 0, 0};
        }
        sh.material = s.materialIndex;
        sh.textureSet = texSet;
        sh.light = s.lightIndex;  // LightMesh: its light, else CLRT_INVALID (-1)
        Aabb box;
        box.grow(p0); box.grow(p1); box.grow(p2);
        out.triangles.push_back(tri);
        out.shading.push_back(sh);
        out.boxes.push_back(sweptBox(box, s.motion));
    }
}


void storeRows(dev::float4 rows[3], const Mat4& m) {
    for (int r = 0; r < 3; ++r)
        rows[r] = {float(m.m[r][0]), float(m.m[r][1]), float(m.m[r][2]), float(m.m[r][3])};
}

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

// Meshes on all hardware threads (each job writes only its own result), then concatenated in shape
// order: the same arrays as a sequential loop. Appends the triangles' boxes to `boxes`; warns about
// and counts (ds.skippedTriangles) degenerate and non-finite triangles.
void flattenMeshes(const Scene& scene, const std::vector<MeshJob>& meshJobs, DeviceScene& ds, std::vector<Aabb>& boxes) {
    std::vector<MeshTriangles> results(meshJobs.size());
    std::atomic<size_t> next{0};
    const size_t threads = std::min<size_t>(meshJobs.size(), std::max(1u, std::thread::hardware_concurrency()));
    std::vector<std::exception_ptr> errors(std::max<size_t>(threads, 1));
    auto worker = [&](size_t t) {
        try {
            for (size_t j; (j = next++) < meshJobs.size();)
                flattenMesh(scene, *meshJobs[j].first, meshJobs[j].second, results[j]);
        } catch (...) {
            errors[t] = std::current_exception();
            next = meshJobs.size();  // the others stop too
        }
    };
    std::vector<std::thread> pool;
    try {
        for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker, t);
    } catch (const std::system_error&) {  // no thread to be had: the others (and this one) do it
    }
    worker(0);
    for (std::thread& t : pool) t.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
    size_t nanSkipped = 0;
    for (MeshTriangles& r : results) {
        ds.triangles.insert(ds.triangles.end(), r.triangles.begin(), r.triangles.end());
        ds.triangleShading.insert(ds.triangleShading.end(), r.shading.begin(), r.shading.end());
        boxes.insert(boxes.end(), r.boxes.begin(), r.boxes.end());
        ds.skippedTriangles += r.degenerate;
        nanSkipped += r.nonFinite;
    }
    if (ds.skippedTriangles) warn(scene.path + ": skipped " + std::to_string(ds.skippedTriangles) + " degenerate triangles");
    if (nanSkipped) warn(scene.path + ": skipped " + std::to_string(nanSkipped) + " triangles with NaN/Inf vertices");
    ds.skippedTriangles += nanSkipped;
}

// The BVH over `boxes` (triangles, then spheres); the triangles are stored in leaf order so a leaf's
// triangles are contiguous in memory, then the tree is collapsed to 4-wide nodes with the leaves'
// triangles copied into their struct-of-arrays blocks.
void buildDeviceBvh(const std::vector<Aabb>& boxes, DeviceScene& ds) {
    auto tb = std::chrono::steady_clock::now();
    // The device tests a leaf's triangles four at a time (Bvh4Leaf), so a leaf of up to four costs
    // about what one triangle test did: a node is costed as two triangle tests, which gives fuller
    // leaves (Audi TT: 2.1 -> 3.0 primitives per block) and fewer nodes (86k -> 61k).
    BvhBuildOptions opts;
    opts.traversalCost = 2;
    ds.bvh = buildBvh(boxes, opts);
    const int numTris = int(ds.triangles.size());
    std::vector<dev::Triangle> tris(ds.triangles.size());
    std::vector<dev::TriangleShading> shading(ds.triangleShading.size());
    int next = 0;
    for (int& ref : ds.bvh.primRefs) {
        if (ref >= numTris) continue;  // spheres keep their indices
        tris[size_t(next)] = ds.triangles[size_t(ref)];
        shading[size_t(next)] = ds.triangleShading[size_t(ref)];
        ref = next++;
    }
    ds.triangles.swap(tris);
    ds.triangleShading.swap(shading);
    ds.bvh4 = collapseBvh4(ds.bvh);
    setLeafTriangles(ds.bvh4, ds.triangles, numTris);
    ds.features.bvhStack = std::max(1, ds.bvh4.maxStack);
    ds.bvhSeconds = secondsSince(tb);
}

}  // namespace

bool mirrorsOrientation(const Mat4& m) { return linearDeterminant(m) < 0; }

void flattenGeometry(const Scene& scene, DeviceScene& ds) {
    std::vector<Aabb> boxes, sphereBoxes;
    size_t total = 0;
    for (const Shape& s : scene.shapes)
        if (s.type == ShapeType::Mesh) total += scene.meshes.at(s.meshIndex).indices.size() / 3;
    ds.triangles.reserve(total);
    ds.triangleShading.reserve(total);
    boxes.reserve(total + scene.shapes.size());
    std::vector<MeshJob> meshJobs;
    for (const Shape& s : scene.shapes) {
        int texSet = flattenTextureSet(scene, s, ds);  // for every shape, in shape order
        if (s.type == ShapeType::Plane) flattenPlane(s, texSet, ds);
        else if (s.type == ShapeType::Sphere) flattenSphere(s, texSet, ds, sphereBoxes);
        else meshJobs.push_back({&s, texSet});
    }
    flattenMeshes(scene, meshJobs, ds, boxes);
    ds.features.spheres = !ds.spheres.empty();
    for (const Shape& s : scene.shapes)
        if (s.type != ShapeType::Plane && s.motion != Vec3(0, 0, 0)) ds.features.motionBlur = true;
    const int numTriangles = int(boxes.size());
    boxes.insert(boxes.end(), sphereBoxes.begin(), sphereBoxes.end());
    buildDeviceBvh(boxes, ds);
    // Never an empty buffer (the counts below stay those of the scene, except planes: see Plane).
    if (ds.triangles.empty()) { ds.triangles.push_back(dev::Triangle{}); ds.triangleShading.push_back(dev::TriangleShading{}); }
    if (ds.spheres.empty()) ds.spheres.push_back(dev::Sphere{});
    if (ds.planes.empty()) ds.planes.push_back(dev::Plane{});  // a zero normal: never hit, counted in numPlanes
    if (ds.textureSets.empty()) ds.textureSets.push_back(dev::TextureSet{{-1, -1, -1, -1}, {}});
    ds.params.numTriangles = numTriangles;
    ds.params.numSpheres = int(sphereBoxes.size());
    ds.params.numPlanes = int(ds.planes.size());
}

}  // namespace clrt
