// Mesh instances (<MeshInstance baseMeshId resetTransform>): instances of instances compose their
// transformations (the base's composed one first, then the instance's own; resetTransform keeps only
// the instance's own), take their own or else their base's material, textures and shading mode, and
// move by their own MotionBlur only. Parsing (transforms, inheritance, a base defined later, the Mesh
// an id names before an instance, cycles and ambiguous ids named in the error), and a render of
// nested, rotated, scaled and moving instances against the same scene written out as plain Meshes
// with the composed transformation strings (bit for bit). The hw2 grass field against its reference.
// Two-level through the binary: --part + merge, progressive passes, two PoCL devices and MPI ranks
// give what one process gives (bit for bit), and what flattening gives (>= 60 dB).
// The host two-level BVH (bvh/two_level.h: one bottom BVH per mesh, rays taken to object space at the
// instance) against brute force over the world-space triangles that flattening makes.
#include <catch.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <regex>
#include <unistd.h>

#include "bvh/host_intersect.h"
#include "bvh/two_level.h"
#include "cl/check.h"
#include "cl/kernel_args.h"
#include "cl/program.h"
#include "flatten/device_scene.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// A camera looking down −z at a floor with a small pyramid mesh (id 1) and the given objects.
std::string instanceScene(const std::string& objects) {
    return R"(<Scene><BackgroundColor>10 20 30</BackgroundColor><MaxRecursionDepth>2</MaxRecursionDepth>
<Cameras><Camera id="1"><Position>0 3 6</Position><Gaze>0 -0.45 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-0.6 0.6 -0.45 0.45</NearPlane><NearDistance>1</NearDistance>
<ImageResolution>64 48</ImageResolution><ImageName>i.exr</ImageName></Camera></Cameras>
<Lights><AmbientLight>20 20 20</AmbientLight>
<PointLight id="1"><Position>2 6 4</Position><Intensity>4000 4000 4000</Intensity></PointLight></Lights>
<Materials>
<Material id="1"><AmbientReflectance>0.1 0.1 0.1</AmbientReflectance><DiffuseReflectance>0.8 0.7 0.6</DiffuseReflectance>
<SpecularReflectance>0.3 0.3 0.3</SpecularReflectance><PhongExponent>20</PhongExponent></Material>
<Material id="2"><AmbientReflectance>0.1 0.1 0.1</AmbientReflectance><DiffuseReflectance>0.2 0.5 0.9</DiffuseReflectance>
<SpecularReflectance>0.5 0.5 0.5</SpecularReflectance><PhongExponent>50</PhongExponent>
<MirrorReflectance>0.3 0.3 0.3</MirrorReflectance></Material>
</Materials>
<Transformations>
<Translation id="1">1.5 0 -1</Translation><Translation id="2">-2 0.2 -2</Translation>
<Translation id="3">0 0.5 1</Translation>
<Rotation id="1">30 0 1 0</Rotation><Rotation id="2">-50 1 0.3 0</Rotation>
<Scaling id="1">0.6 1.2 0.8</Scaling><Scaling id="2">1.5 1.5 1.5</Scaling>
</Transformations>
<VertexData>-0.5 0 -0.5  0.5 0 -0.5  0.5 0 0.5  -0.5 0 0.5  0 1 0
-20 0 -20  20 0 -20  20 0 20  -20 0 20</VertexData>
<Objects>
<Mesh id="100"><Material>1</Material><Faces>6 8 7  6 9 8</Faces></Mesh>
)" + objects + "</Objects></Scene>";
}

// Nested instances: 2 (rotated) of mesh 1 (scaled), 3 (moving) of 2, 4 (scaled, standing still) of 3,
// 5 (resetTransform, smooth) of 4, 6 of 7, which is defined after it.
const char* kNested = R"(
<Mesh id="1"><Material>1</Material><Transformations>s1</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<MeshInstance id="2" baseMeshId="1"><Material>2</Material><Transformations>r1</Transformations></MeshInstance>
<MeshInstance id="3" baseMeshId="2"><Transformations>t1</Transformations><MotionBlur>0.4 0 0.2</MotionBlur></MeshInstance>
<MeshInstance id="4" baseMeshId="3"><Transformations>s2</Transformations></MeshInstance>
<MeshInstance id="5" baseMeshId="4" resetTransform="true" shadingMode="smooth"><Material>1</Material><Transformations>t2</Transformations></MeshInstance>
<MeshInstance id="6" baseMeshId="7"><Transformations>t3</Transformations></MeshInstance>
<MeshInstance id="7" baseMeshId="1"><Transformations>r2</Transformations></MeshInstance>
)";

// kNested written out: each shape a Mesh with the whole transformation string, its material and motion.
const char* kNestedAsMeshes = R"(
<Mesh id="1"><Material>1</Material><Transformations>s1</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<Mesh id="2"><Material>2</Material><Transformations>s1 r1</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<Mesh id="3"><Material>2</Material><Transformations>s1 r1 t1</Transformations><MotionBlur>0.4 0 0.2</MotionBlur><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<Mesh id="4"><Material>2</Material><Transformations>s1 r1 t1 s2</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<Mesh id="5" shadingMode="smooth"><Material>1</Material><Transformations>t2</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<Mesh id="6"><Material>1</Material><Transformations>s1 r2 t3</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
<Mesh id="7"><Material>1</Material><Transformations>s1 r2</Transformations><Faces>1 2 5  2 3 5  3 4 5  4 1 5</Faces></Mesh>
)";

Scene loadText(TempDir& dir, const std::string& name, const std::string& xml) {
    const std::string path = dir.file(name);
    writeFileBytes(path, xml);
    return loadScene(path);
}

std::string loadError(TempDir& dir, const std::string& name, const std::string& xml) {
    try {
        loadText(dir, name, xml);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

bool nearVec(const Vec3& a, const Vec3& b) { return length(a - b) <= 1e-5f; }

}  // namespace

TEST_CASE("instancing: instances of instances compose transforms; material, motion and shading", "[instancing][scene]") {
    TempDir dir;
    Scene s = loadText(dir, "nested.xml", instanceScene(kNested));
    Scene m = loadText(dir, "meshes.xml", instanceScene(kNestedAsMeshes));
    REQUIRE(s.shapes.size() == 8);
    REQUIRE(m.shapes.size() == 8);
    CHECK(s.meshes.size() == 2);  // the floor and the pyramid, shared by every instance
    const Vec3 probes[] = {Vec3(0.3f, 0.7f, -0.2f), Vec3(1, 2, 3), Vec3(-0.5f, 0, 0.5f)};
    for (size_t i = 1; i < s.shapes.size(); ++i) {
        INFO(s.shapes[i].source);
        for (const Vec3& p : probes)
            CHECK(nearVec(s.shapes[i].transform.transformPoint(p), m.shapes[i].transform.transformPoint(p)));
        CHECK(s.shapes[i].materialIndex == m.shapes[i].materialIndex);
        CHECK(s.shapes[i].motion == m.shapes[i].motion);
        CHECK(s.shapes[i].smooth == m.shapes[i].smooth);
        CHECK(s.shapes[i].meshIndex == s.shapes[1].meshIndex);
    }
    // By hand: instance 4 = s2 · t1 · r1 · s1; instance 5 (reset) = t2 only.
    const Vec3 p(0.5f, 0, 0.5f);  // s1 -> (0.3, 0, 0.4); r1 (30° about y) -> (0.3c+0.4s, 0, -0.3s+0.4c)
    const float c = std::cos(float(M_PI) / 6), sn = std::sin(float(M_PI) / 6);
    const Vec3 r(0.3f * c + 0.4f * sn, 0, -0.3f * sn + 0.4f * c);
    CHECK(nearVec(s.shapes[4].transform.transformPoint(p), (r + Vec3(1.5f, 0, -1)) * 1.5f));
    CHECK(nearVec(s.shapes[5].transform.transformPoint(p), p + Vec3(-2, 0.2f, -2)));
    CHECK(s.shapes[3].motion == Vec3(0.4f, 0, 0.2f));
    CHECK(s.shapes[4].motion == Vec3(0, 0, 0));  // its base moves; it moves by its own MotionBlur only
    CHECK(s.shapes[4].materialIndex == s.shapes[2].materialIndex);  // inherited through 3 from 2
    CHECK(s.shapes[6].source.find("MeshInstance id=6") == 0);
}

TEST_CASE("instancing: a Mesh id is named before an instance id; cycles and ambiguous ids are errors", "[instancing][scene]") {
    TempDir dir;
    const std::string mesh =
        R"(<Mesh id="1"><Material>1</Material><Faces>1 2 5</Faces></Mesh>)";
    SECTION("a Mesh and a MeshInstance share id 1: baseMeshId 1 is the Mesh") {
        Scene s = loadText(dir, "shared_id.xml", instanceScene(mesh + R"(
<MeshInstance id="1" baseMeshId="1"><Transformations>t1</Transformations></MeshInstance>
<MeshInstance id="2" baseMeshId="1"><Transformations>t3</Transformations></MeshInstance>)"));
        REQUIRE(s.shapes.size() == 4);
        CHECK(nearVec(s.shapes[3].transform.transformPoint(Vec3(0, 0, 0)), Vec3(0, 0.5f, 1)));
    }
    SECTION("a cycle of three") {
        std::string e = loadError(dir, "cycle.xml", instanceScene(mesh + R"(
<MeshInstance id="4" baseMeshId="5"/><MeshInstance id="5" baseMeshId="6"/><MeshInstance id="6" baseMeshId="4"/>)"));
        INFO(e);
        CHECK(e.find("cycle") != std::string::npos);
        CHECK(e.find("4 -> 5 -> 6 -> 4") != std::string::npos);
    }
    SECTION("an instance of itself") {
        std::string e = loadError(dir, "self.xml", instanceScene(mesh + R"(<MeshInstance id="7" baseMeshId="7"/>)"));
        INFO(e);
        CHECK(e.find("7 -> 7") != std::string::npos);
    }
    SECTION("a cycle reached from an instance outside it names the cycle only") {
        std::string e = loadError(dir, "tail.xml", instanceScene(mesh + R"(
<MeshInstance id="3" baseMeshId="8"/><MeshInstance id="8" baseMeshId="9"/><MeshInstance id="9" baseMeshId="8"/>)"));
        INFO(e);
        CHECK(e.find("8 -> 9 -> 8") != std::string::npos);
        CHECK(e.find("3 -> ") == std::string::npos);
    }
    SECTION("two instances with the id a third names") {
        std::string e = loadError(dir, "dup.xml", instanceScene(mesh + R"(
<MeshInstance id="2" baseMeshId="1"/><MeshInstance id="2" baseMeshId="1"/><MeshInstance id="3" baseMeshId="2"/>)"));
        INFO(e);
        CHECK(e.find("MeshInstance 2") != std::string::npos);
    }
    SECTION("an undefined base") {
        std::string e = loadError(dir, "undef.xml", instanceScene(mesh + R"(<MeshInstance id="2" baseMeshId="42"/>)"));
        CHECK(e.find("undefined Mesh 42") != std::string::npos);
    }
}

TEST_CASE("instancing: nested, rotated, scaled and moving instances render as the same meshes written out", "[instancing][render]") {
    TempDir dir;
    Scene s = loadText(dir, "nested.xml", instanceScene(kNested));
    Scene m = loadText(dir, "meshes.xml", instanceScene(kNestedAsMeshes));
    ImageRGB a = renderCamera(s, s.cameras.at(0), 4, 3);
    ImageRGB b = renderCamera(m, m.cameras.at(0), 4, 3);
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
    // The instances are there: the picture differs from the floor alone.
    Scene floorOnly = loadText(dir, "floor.xml", instanceScene(""));
    ImageRGB f = renderCamera(floorOnly, floorOnly.cameras.at(0), 4, 3);
    CHECK(std::memcmp(a.pixels.data(), f.pixels.data(), a.pixels.size() * sizeof(float)) != 0);
}

// The same scene and camera through the device's two-level BVH and flattened (RenderSettings as
// renderCamera's).
static ImageRGB renderInstancing(const Scene& scene, Instancing mode, int spp, uint32_t seed, int* numInstances) {
    FlattenOptions opts;
    opts.instancing = mode;
    DeviceScene ds = flattenScene(scene, opts);
    *numInstances = ds.params.numInstances;
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = spp;
    rs.seed = seed;
    RenderCounters c;
    return r.render(scene.cameras.at(0), rs, c);
}

TEST_CASE("instancing: the device's two-level BVH renders what flattening renders", "[instancing][render]") {
    TempDir dir;
    // kNested plus a mirrored instance (negative scale: the winding reverses) and a smooth one.
    const std::string mirrored = R"(<MeshInstance id="8" baseMeshId="1"><Transformations>s3 t3</Transformations></MeshInstance>
<MeshInstance id="9" baseMeshId="2" shadingMode="smooth"><Transformations>t2 s2</Transformations></MeshInstance>)";
    std::string xml = instanceScene(std::string(kNested) + mirrored);
    xml.replace(xml.find("</Transformations>"), 0, "<Scaling id=\"3\">-1 1 1</Scaling>");
    Scene s = loadText(dir, "nested.xml", xml);
    int flatInstances = -1, twoLevelInstances = -1;
    ImageRGB flat = quantize(renderInstancing(s, Instancing::Flatten, 4, 3, &flatInstances));
    ImageRGB twoLevel = quantize(renderInstancing(s, Instancing::TwoLevel, 4, 3, &twoLevelInstances));
    CHECK(flatInstances == 0);
    CHECK(twoLevelInstances == 10);  // every mesh shape: the floor, mesh 1 and its 8 instances
    // Object-space intersection rounds differently from world space: not bit for bit.
    const double db = psnr8(flat, twoLevel);
    INFO("two-level against flattened: " << db << " dB");
    CHECK(db >= 60.0);
}

TEST_CASE("instancing: hw2 grass_desert (instances of instances) matches the course's PNG, flattened and two-level", "[instancing][render][shared][one-implementation]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    const std::string dir = sharedDir() + "/scenes/hw2/grass/";
    Scene scene = loadScene(dir + "grass_desert.xml");
    ImageRGB img = renderCamera(scene, scene.cameras.at(0), 1);
    ImageRGB ref = readImage(dir + "_reference_outputs/grass_desert.png");
    REQUIRE(img.width == ref.width);
    REQUIRE(img.height == ref.height);
    const double p = psnr8(quantize(img, true), ref);
    WARN("grass_desert: PSNR " << p << " dB (truncated)");
    // 50.80 dB measured (29.97 dB while back-facing hits of the blades were shaded with the normal turned
    // toward the viewer: the blades are thin open geometry, lit through from the stored side; shade.cl,
    // Shade_OrientsNormalToRay). The other readings of the hw2 text scored below 29.5 dB under that old
    // rule: resetTransform dropping only the base's own transforms 27.95 dB, every instance an instance
    // of the Mesh 28.13 dB.
    CHECK(p >= 50.0);
    // The same through the device's two-level BVH (every mesh kept once): 51.01 dB measured.
    int instances = 0;
    const ImageRGB twoLevel = renderInstancing(scene, Instancing::TwoLevel, 1, 0, &instances);
    CHECK(instances > 0);
    const double p2 = psnr8(quantize(twoLevel, true), ref);
    WARN("grass_desert two-level: PSNR " << p2 << " dB (truncated)");
    CHECK(p2 >= 50.0);
}

// instancedShapes under auto (flatten_instances.cpp; the bounds are measured in
// docs/studies/2026-12-04-instancing-threshold.md). Counts only: the meshes hold index triples, no
// geometry.
TEST_CASE("instancing: auto keeps a mesh once from 2^20 triangles as seen, and every instanced mesh from 2^23 in all", "[instancing][scene]") {
    auto addMesh = [](Scene& s, size_t triangles, int placements, int light = -1) {
        s.meshes.emplace_back();
        s.meshes.back().indices.assign(3 * triangles, 0);
        for (int k = 0; k < placements; ++k) {
            Shape sh;
            sh.type = ShapeType::Mesh;
            sh.meshIndex = int(s.meshes.size()) - 1;
            sh.lightIndex = light;
            s.shapes.push_back(sh);
        }
    };
    auto count = [](const std::vector<bool>& v) { return std::count(v.begin(), v.end(), true); };
    Scene s;
    addMesh(s, size_t(1) << 19, 2);        // 2^20 as seen: two-level
    addMesh(s, (size_t(1) << 19) - 1, 2);  // just under: flattened
    addMesh(s, size_t(1) << 21, 1);        // placed once: flattened
    addMesh(s, size_t(1) << 20, 2, 0);     // an object light: flattened
    std::vector<bool> autoShapes = instancedShapes(s, Instancing::Auto);
    CHECK(autoShapes == std::vector<bool>{true, true, false, false, false, false, false});
    CHECK(count(instancedShapes(s, Instancing::Flatten)) == 0);
    CHECK(count(instancedShapes(s, Instancing::TwoLevel)) == 5);  // every mesh shape but the light's
    // Many meshes, each under 2^20 as seen: 2^16 triangles placed 15 times (983,040 each).
    Scene many;
    for (int m = 0; m < 8; ++m) addMesh(many, size_t(1) << 16, 15);
    CHECK(count(instancedShapes(many, Instancing::Auto)) == 0);  // 7.9M as seen in all: flattened
    addMesh(many, size_t(1) << 16, 15);
    addMesh(many, 100, 1);                                          // placed once: stays flattened
    CHECK(count(instancedShapes(many, Instancing::Auto)) == 9 * 15);  // 8.8M >= 2^23: all kept once
}

namespace {

// Every mesh shape of `scene` as the two-level BVH reads it: the meshes, one instance per shape.
void twoLevelInputs(const Scene& scene, std::vector<TwoLevelMesh>& meshes, std::vector<TwoLevelInstance>& insts) {
    for (const MeshData& m : scene.meshes) meshes.push_back({&m.positions, &m.indices});
    for (const Shape& s : scene.shapes) {
        if (s.type != ShapeType::Mesh) continue;
        TwoLevelInstance in;
        in.mesh = s.meshIndex;
        in.objectToWorld = s.transform;
        in.motion = s.motion;
        insts.push_back(in);
    }
}

// Brute force over the world-space triangles of every mesh shape (as flattening places them), each
// at its position at shutter time `time`: the closest (t, shape, triangle).
TwoLevelHit bruteForce(const Scene& scene, const Vec3& org, const Vec3& dir, float time) {
    TwoLevelHit best;
    float tMax = INFINITY;
    int inst = -1;
    for (const Shape& s : scene.shapes) {
        if (s.type != ShapeType::Mesh) continue;
        ++inst;
        const MeshData& m = scene.meshes[size_t(s.meshIndex)];
        const Vec3 o = org - s.motion * time;
        for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
            Vec3 p[3];
            for (int k = 0; k < 3; ++k) p[k] = s.transform.transformPoint(m.positions[size_t(m.indices[t + size_t(k)])]);
            float th, b1, b2;
            if (intersectTriangleWatertight(o, dir, p[0], p[1], p[2], tMax, th, b1, b2)) {
                tMax = th;
                best = {inst, int(t / 3), th, b1, b2};
            }
        }
    }
    return best;
}

}  // namespace

TEST_CASE("instancing: the host two-level BVH finds the hits of the flattened triangles", "[instancing][bvh]") {
    TempDir dir;
    Scene s = loadText(dir, "nested.xml", instanceScene(kNested));
    std::vector<TwoLevelMesh> meshes;
    std::vector<TwoLevelInstance> insts;
    twoLevelInputs(s, meshes, insts);
    std::vector<int> skipped;
    TwoLevelBvh bvh = buildTwoLevelBvh(meshes, insts, &skipped);
    CHECK(skipped.empty());
    REQUIRE(bvh.instances.size() == 8);
    REQUIRE(bvh.bottom.size() == 2);  // the floor and the pyramid: one bottom BVH each
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    const int n = 20000;
    int hits = 0, sameHit = 0, tClose = 0, anyAgrees = 0;
    for (int i = 0; i < n; ++i) {
        const Vec3 org(-3 + 6 * u(rng), 0.1f + 4 * u(rng), -3 + 7 * u(rng));
        const Vec3 target(-2.5f + 5 * u(rng), -0.2f + 2 * u(rng), -3 + 4 * u(rng));
        const Vec3 d = normalize(target - org);
        const float time = u(rng);
        const TwoLevelHit ref = bruteForce(s, org, d, time);
        const TwoLevelHit got = closestHitTwoLevel(bvh, meshes, org, d, INFINITY, time);
        hits += ref.instance >= 0;
        sameHit += ref.instance == got.instance && ref.triangle == got.triangle;
        tClose += ref.instance < 0 ? got.instance < 0 : std::fabs(got.t - ref.t) <= 1e-4f * ref.t;
        anyAgrees += anyHitTwoLevel(bvh, meshes, org, d, INFINITY, time) == (got.instance >= 0);
    }
    INFO(hits << " hits of " << n << " rays; same instance and triangle " << sameHit << ", t within 1e-4 " << tClose);
    CHECK(hits > n / 2);
    CHECK(anyAgrees == n);
    // Object-space tests round differently from world-space ones: a ray within a few ULPs of an edge may
    // take the neighbouring triangle, never another surface.
    CHECK(sameHit >= n - n / 500);
    CHECK(tClose >= n - n / 1000);
}

namespace {

Vec3 rowsApply(const dev::float4 rows[3], const dev::float4& p) {
    return Vec3(rows[0].x * p.x + rows[0].y * p.y + rows[0].z * p.z + rows[0].w,
                rows[1].x * p.x + rows[1].y * p.y + rows[1].z * p.z + rows[1].w,
                rows[2].x * p.x + rows[2].y * p.y + rows[2].z * p.z + rows[2].w);
}

// The device's closest hits (intersect_closest of the intersection program, this scene's defines) with
// the Instance of each (hitInstances, CLRT_INVALID for a world-space primitive).
void deviceClosestTwoLevel(const DeviceScene& ds, const std::vector<dev::Ray>& rays, std::vector<dev::Hit>& hits,
                           std::vector<int>& instances) {
    DeviceContext& dc = testContext();
    cl::Context& ctx = dc.context();
    cl::Program program = buildProgram(dc, KernelProgram::Intersect, ds.features.defines());
    KernelArgs k(program, "intersect_closest");
    const int n = int(rays.size());
    dev::SceneParams sp = ds.params;
    sp.numPlanes = 0;
    const IntersectScene scene = intersectScene(sp, n, ds.bvh8.nodes, ds.bvh8.leaves, ds.triangles, ds.spheres,
                                                std::vector<dev::Plane>{}, ds.instances);
    cl::Buffer rb = readOnlyBuffer(rays);
    cl::Buffer hb = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(dev::Hit) * rays.size()));
    cl::Buffer hib = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(int) * rays.size()));
    scene.bind(k).set("rays", rb).set("hits", hb).set("hitInstances", hib);
    CL_CPP(dc.queue().enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(roundUp(size_t(n), 64)), cl::NDRange(64)));
    hits.resize(rays.size());
    instances.resize(rays.size());
    CL_CPP(dc.queue().enqueueReadBuffer(hb, CL_TRUE, 0, sizeof(dev::Hit) * hits.size(), hits.data()));
    CL_CPP(dc.queue().enqueueReadBuffer(hib, CL_TRUE, 0, sizeof(int) * instances.size(), instances.data()));
}

}  // namespace

// The device's two-level traversal against the brute force: each hit's triangle, placed at rest by the
// Instance the kernel reports beside the Hit (hitInstances), is the triangle the brute force hits.
TEST_CASE("instancing: the device's two-level traversal reports the instance and triangle hit", "[instancing][bvh][intersect]") {
    TempDir dir;
    Scene s = loadText(dir, "nested.xml", instanceScene(kNested));
    FlattenOptions opts;
    opts.instancing = Instancing::TwoLevel;
    DeviceScene ds = flattenScene(s, opts);
    REQUIRE(ds.params.numInstances == 8);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    const int n = 20000;
    std::vector<dev::Ray> rays;
    std::vector<float> times;
    for (int i = 0; i < n; ++i) {
        const Vec3 org(-3 + 6 * u(rng), 0.1f + 4 * u(rng), -3 + 7 * u(rng));
        const Vec3 target(-2.5f + 5 * u(rng), -0.2f + 2 * u(rng), -3 + 4 * u(rng));
        const Vec3 d = normalize(target - org);
        times.push_back(u(rng));
        rays.push_back({{org.x, org.y, org.z, times.back()}, {d.x, d.y, d.z, INFINITY}});
    }
    std::vector<dev::Hit> hits;
    std::vector<int> hitInstances;
    deviceClosestTwoLevel(ds, rays, hits, hitInstances);
    int refHits = 0, instanced = 0, sameTriangle = 0, tClose = 0;
    for (int i = 0; i < n; ++i) {
        const Vec3 org(rays[i].origin.x, rays[i].origin.y, rays[i].origin.z);
        const Vec3 d(rays[i].direction.x, rays[i].direction.y, rays[i].direction.z);
        const TwoLevelHit ref = bruteForce(s, org, d, times[size_t(i)]);
        const dev::Hit& h = hits[size_t(i)];
        refHits += ref.instance >= 0;
        if (ref.instance < 0 || h.prim < 0) {
            sameTriangle += (ref.instance < 0) == (h.prim < 0);
            tClose += (ref.instance < 0) == (h.prim < 0);
            continue;
        }
        // The brute force's triangle at rest, in world space.
        const Shape* shape = nullptr;
        int meshShape = -1;
        for (const Shape& sh : s.shapes) if (sh.type == ShapeType::Mesh && ++meshShape == ref.instance) shape = &sh;
        REQUIRE(shape);
        const MeshData& mesh = s.meshes[size_t(shape->meshIndex)];
        Vec3 refCentroid(0, 0, 0);
        for (int c = 0; c < 3; ++c)
            refCentroid = refCentroid + shape->transform.transformPoint(mesh.positions[size_t(mesh.indices[size_t(ref.triangle) * 3 + size_t(c)])]) * (1.0f / 3);
        // The device's, through the Instance it reports.
        const dev::Triangle& tri = ds.triangles[size_t(h.prim)];
        const int inst = hitInstances[size_t(i)];
        instanced += inst >= 0;
        Vec3 centroid(0, 0, 0);
        for (const dev::float4* v : {&tri.v0, &tri.v1, &tri.v2})
            centroid = centroid + (inst >= 0 ? rowsApply(ds.instances[size_t(inst)].objectToWorld, *v) : Vec3(v->x, v->y, v->z)) * (1.0f / 3);
        sameTriangle += length(centroid - refCentroid) <= 1e-4f;
        tClose += std::fabs(h.t - ref.t) <= 1e-4f * ref.t;
    }
    INFO(refHits << " hits of " << n << " rays (" << instanced << " in instances); same triangle " << sameTriangle
                 << ", t within 1e-4 " << tClose);
    CHECK(refHits > n / 2);
    CHECK(instanced > refHits / 4);  // the instances are hit, not only the floor
    // As the host test: a ray within a few ULPs of an edge may take the neighbouring triangle.
    CHECK(sameTriangle >= n - n / 500);
    CHECK(tClose >= n - n / 1000);
}

namespace {

// Work per camera ray of the host walks (binary BVHs: the device's 8-wide trees visit fewer nodes, but
// enter the same instances): triangle tests of the flattened walk; instances entered and triangle
// tests of the two-level walk (walkTwoLevel's order, counted).
struct WalkWork {
    double flatTests = 0, twoEntries = 0, twoTests = 0;
};
WalkWork countWalkWork(const Bvh& flat, const std::vector<Vec3>& world, const TwoLevelBvh& two,
                       const std::vector<TwoLevelMesh>& meshes, const Vec3& org, const std::vector<Vec3>& dirs) {
    WalkWork w;
    for (const Vec3& d : dirs) {
        float tMax = INFINITY;
        traverseBvh(flat, org, d, tMax, [&](int tri, float& tm) {
            ++w.flatTests;
            float t, b1, b2;
            const size_t k = 3 * size_t(tri);
            if (intersectTriangleWatertight(org, d, world[k], world[k + 1], world[k + 2], tm, t, b1, b2)) tm = t;
        });
        tMax = INFINITY;
        detail::walkBvh(two.top, org, d, tMax, [&](int instRef, float& tMaxTop) {
            ++w.twoEntries;
            const TwoLevelInstance& inst = two.instances[size_t(instRef)];
            const std::vector<Vec3>& p = *meshes[size_t(inst.mesh)].positions;
            const std::vector<int>& ix = *meshes[size_t(inst.mesh)].indices;
            const Vec3 o = inst.worldToObject.transformPoint(org), dObj = inst.worldToObject.transformVector(d);
            return detail::walkBvh(two.bottom[size_t(inst.mesh)], o, dObj, tMaxTop, [&](int tri, float& tm) {
                ++w.twoTests;
                float t, b1, b2;
                const size_t k = 3 * size_t(tri);
                if (intersectTriangleWatertight(o, dObj, p[size_t(ix[k])], p[size_t(ix[k + 1])], p[size_t(ix[k + 2])], tm, t, b1, b2))
                    tm = t;
                return false;
            });
        });
    }
    const double n = double(std::max<size_t>(1, dirs.size()));
    for (double* v : {&w.flatTests, &w.twoEntries, &w.twoTests}) *v /= n;
    return w;
}

}  // namespace

// Not a timed test (hidden: run with "[.instancing-bench]" and CLRT_BENCH_SCENE=scene.xml): the host
// cost of flattening a scene's meshes into one BVH against the two-level BVH: build seconds, bytes
// of the structures the device would hold, and host closest-hit walks per second on camera rays.
TEST_CASE("instancing: flattened against two-level on the host (bench)", "[.instancing-bench]") {
    const char* path = std::getenv("CLRT_BENCH_SCENE");
    if (!path) { WARN("set CLRT_BENCH_SCENE"); return; }
    Scene s = loadScene(path);
    using clock = std::chrono::steady_clock;
    auto secs = [](clock::time_point t0) { return std::chrono::duration<double>(clock::now() - t0).count(); };
    // Flattened: world-space triangles (48 B + 96 B of shading each, as dev::Triangle and the TriangleShading of before session 16).
    auto t0 = clock::now();
    std::vector<Vec3> world;
    std::vector<Aabb> boxes;
    for (const Shape& sh : s.shapes) {
        if (sh.type != ShapeType::Mesh) continue;
        const MeshData& m = s.meshes[size_t(sh.meshIndex)];
        for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
            Aabb b;
            for (int k = 0; k < 3; ++k) {
                world.push_back(sh.transform.transformPoint(m.positions[size_t(m.indices[t + size_t(k)])]));
                b.grow(world.back());
            }
            boxes.push_back(b);
        }
    }
    BvhBuildOptions opts;
    opts.traversalCost = 2;
    Bvh flat = buildBvh(boxes, opts);
    const double flatBuild = secs(t0);
    const double flatBytes = double(boxes.size()) * (48 + 96) + double(flat.nodes.size()) * sizeof(BvhNode);
    // Two-level.
    t0 = clock::now();
    std::vector<TwoLevelMesh> meshes;
    std::vector<TwoLevelInstance> insts;
    twoLevelInputs(s, meshes, insts);
    TwoLevelBvh two = buildTwoLevelBvh(meshes, insts);
    const double twoBuild = secs(t0);
    double twoBytes = double(two.instances.size()) * (2 * 48 + 16 + 16) + double(two.top.nodes.size()) * sizeof(BvhNode);
    for (size_t m = 0; m < two.bottom.size(); ++m)
        if (!two.bottom[m].primRefs.empty())
            twoBytes += double(s.meshes[m].indices.size() / 3) * (48 + 96) + double(two.bottom[m].nodes.size()) * sizeof(BvhNode);
    // Camera rays of the first camera, host walks.
    const Camera& cam = s.cameras.at(0);
    const int w = 160, h = 90;
    std::vector<Vec3> dirs;
    const Vec3 org = cam.position;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float px = cam.left + (cam.right - cam.left) * (x + 0.5f) / w;
            const float py = cam.top - (cam.top - cam.bottom) * (y + 0.5f) / h;
            dirs.push_back(normalize(cam.u * px + cam.v * py - cam.w * cam.nearDistance));
        }
    t0 = clock::now();
    int flatHits = 0;
    for (const Vec3& d : dirs) {
        float tMax = INFINITY;
        bool hit = false;
        traverseBvh(flat, org, d, tMax, [&](int tri, float& tm) {
            float t, b1, b2;
            if (intersectTriangleWatertight(org, d, world[3 * size_t(tri)], world[3 * size_t(tri) + 1],
                                            world[3 * size_t(tri) + 2], tm, t, b1, b2)) { tm = t; hit = true; }
        });
        flatHits += hit;
    }
    const double flatRays = double(dirs.size()) / secs(t0);
    t0 = clock::now();
    int twoHits = 0;
    for (const Vec3& d : dirs) twoHits += closestHitTwoLevel(two, meshes, org, d, INFINITY).instance >= 0;
    const double twoRays = double(dirs.size()) / secs(t0);
    WARN(path << ": " << boxes.size() << " triangles as seen, " << two.instances.size() << " instances\n"
              << "  flattened: build " << flatBuild << " s, " << flatBytes / 1e6 << " MB, " << flatRays / 1e3
              << " k host rays/s (" << flatHits << " hits)\n"
              << "  two-level: build " << twoBuild << " s, " << twoBytes / 1e6 << " MB, " << twoRays / 1e3
              << " k host rays/s (" << twoHits << " hits)");
    CHECK(flatHits == twoHits);
    const WalkWork work = countWalkWork(flat, world, two, meshes, org, dirs);
    WARN("per camera ray: flattened " << work.flatTests << " triangle tests; two-level " << work.twoEntries
                                      << " instances entered, " << work.twoTests << " triangle tests");
}

// ---- Everything else still works with instances (issue 30): the nested scene (with the mirrored and
// smooth instances, and instance 3 moving: motion blur) through the clrt binary, two-level against
// flattened and against itself split over parts, devices and MPI ranks. 64x48, 4 spp: each case
// renders in well under a second; the process starts and kernel builds are most of its time.
namespace {

// The scene of "the device's two-level BVH renders what flattening renders" (writes i.exr) as dir/nested.xml.
std::string writeNestedScene(const TempDir& dir) {
    const std::string mirrored = R"(<MeshInstance id="8" baseMeshId="1"><Transformations>s3 t3</Transformations></MeshInstance>
<MeshInstance id="9" baseMeshId="2" shadingMode="smooth"><Transformations>t2 s2</Transformations></MeshInstance>)";
    std::string xml = instanceScene(std::string(kNested) + mirrored);
    xml.replace(xml.find("</Transformations>"), 0, "<Scaling id=\"3\">-1 1 1</Scaling>");
    writeFileBytes(dir.file("nested.xml"), xml);
    return dir.file("nested.xml");
}

// Runs `env clrt args` in dir (stdout and stderr together in the result's log).
CliResult runIn(const TempDir& dir, const std::string& env, const std::string& args) {
    const std::string log = dir.file("log.txt");
    const std::string cmd = "cd " + dir.path.string() + " && " + env + " " + CLRT_BINARY + " " + args + " >" + log + " 2>&1";
    const int rc = std::system(cmd.c_str());
    return cliResult(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFileBytes(log));
}

// Renders the scene into dir/<out>/i.exr with `extra` options (seed 3); returns the image. The kernel
// flags (-v) say that the kernels were built with instances exactly when `extra` asks for two-level.
ImageRGB renderCli(const TempDir& dir, const std::string& scene, const std::string& out, const std::string& extra,
                   const std::string& env = "") {
    std::filesystem::create_directories(dir.file(out));
    CliResult r = runIn(dir, env, "render " + scene + " -o " + out + " -v --seed 3" + extra);
    INFO(r.log);
    REQUIRE(r.rc == 0);
    CHECK((r.log.find("-DCLRT_HAS_INSTANCES=1") != std::string::npos) == (extra.find("two-level") != std::string::npos));
    return readImage(dir.file(out + "/i.exr"));
}

// On this scene two-level pixels have so far been bit-identical to flattened ones on PoCL; object-space
// intersection may round differently elsewhere, so the bound is the deterministic one, 60 dB.
void checkTwoLevelNearFlat(const ImageRGB& twoLevel, const ImageRGB& flat) {
    REQUIRE(twoLevel.pixels.size() == flat.pixels.size());
    const double db = psnr8(quantize(flat), quantize(twoLevel));
    INFO("two-level against flattened: " << db << " dB");
    CHECK(db >= 60.0);
}

}  // namespace

TEST_CASE("instancing: --part 1/3..3/3 + clrt merge of a two-level render equal its one-process render", "[instancing][cli]") {
    TempDir dir;
    const std::string scene = writeNestedScene(dir), dev = deviceArg();
    const std::string two = " --spp 4 --instancing two-level --tile-pixels 256" + dev;  // 12 tiles of 256 pixels
    const ImageRGB one = renderCli(dir, scene, "one", two);
    checkTwoLevelNearFlat(one, renderCli(dir, scene, "flat", " --spp 4 --instancing flatten" + dev));
    std::filesystem::create_directories(dir.file("parts"));
    std::string parts;
    for (int k = 1; k <= 3; ++k) {
        CliResult r = runIn(dir, "", "render " + scene + " -o parts --seed 3 --part " + std::to_string(k) + "/3" + two);
        INFO(r.log);
        REQUIRE(r.rc == 0);
        parts += " parts/i.exr.part" + std::to_string(k) + "of3.exr";
    }
    std::filesystem::create_directories(dir.file("merged"));
    CliResult m = runIn(dir, "", "merge" + parts + " -o merged" + dev);
    INFO(m.log);
    REQUIRE(m.rc == 0);
    CHECK(readImage(dir.file("merged/i.exr")).pixels == one.pixels);
}

TEST_CASE("instancing: --time-limit 0 (progressive passes) two-level against flattened", "[instancing][cli][progressive]") {
    TempDir dir;
    const std::string scene = writeNestedScene(dir);
    const std::string prog = " --time-limit 0" + deviceArg();  // one pair of passes: a deterministic spp
    const ImageRGB two = renderCli(dir, scene, "two", " --instancing two-level" + prog);
    const std::string twoLog = readFileBytes(dir.file("log.txt"));
    const ImageRGB flat = renderCli(dir, scene, "flat", " --instancing flatten" + prog);
    const std::string flatLog = readFileBytes(dir.file("log.txt"));
    std::smatch a, b;
    const std::regex stop("stopped \\(time limit\\) at (\\d+) spp");
    REQUIRE((std::regex_search(twoLog, a, stop) && std::regex_search(flatLog, b, stop)));
    CHECK(a[1] == b[1]);
    checkTwoLevelNearFlat(two, flat);
}

TEST_CASE("instancing: two PoCL devices render the two-level scene as one device does", "[instancing][multidevice]") {
    TempDir dir;
    const std::string scene = writeNestedScene(dir);
    const std::string env = "POCL_DEVICES='pthread pthread'";
    CliResult list = runIn(dir, env, "devices");
    std::vector<std::string> pocl;
    const std::regex line("\\[(\\d+)\\][^\\n]*\\(platform: Portable Computing Language\\)");
    for (auto it = std::sregex_iterator(list.log.begin(), list.log.end(), line); it != std::sregex_iterator(); ++it)
        pocl.push_back((*it)[1]);
    INFO(list.log);
    REQUIRE(pocl.size() == 2);
    const std::string two = " --spp 4 --instancing two-level --tile-pixels 256";
    const ImageRGB one = renderCli(dir, scene, "one", two + " --device " + pocl[0], env);
    const ImageRGB both = renderCli(dir, scene, "both", two + " --device " + pocl[0] + "," + pocl[1], env);
    CHECK(both.pixels == one.pixels);
    checkTwoLevelNearFlat(both, renderCli(dir, scene, "flat", " --spp 4 --instancing flatten --device " + pocl[0], env));
}

TEST_CASE("instancing: mpirun -np 2 renders the two-level scene as one process does", "[instancing][mpi]") {
    const std::string exe = CLRT_MPIEXEC;
    if (exe.empty() || access(exe.c_str(), X_OK) != 0) {
        WARN("clrt built without MPI, or mpirun not found: skipped");
        return;
    }
    // As test_dist.cpp's mpirun3: local launch, no single-copy transport, hwloc without OpenCL.
    const std::string mpi = "env OMPI_MCA_plm=isolated OMPI_MCA_btl_vader_single_copy_mechanism=none HWLOC_COMPONENTS=-opencl " +
                            exe + " --oversubscribe --allow-run-as-root -np 2";
    TempDir dir;
    const std::string scene = writeNestedScene(dir);
    const std::string two = " --spp 4 --instancing two-level --tile-pixels 256" + deviceArg();
    const ImageRGB one = renderCli(dir, scene, "one", two);
    const ImageRGB ranks = renderCli(dir, scene, "mpi", two, mpi);
    CHECK(ranks.pixels == one.pixels);
}
