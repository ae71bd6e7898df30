// The intersection kernels (cl_kernels/intersect.cl) against the plain C++ reference
// (src/bvh/host_intersect.h) on PoCL: closest hits (distance, primitive and barycentrics) and
// shadow-ray any-hits over random scenes of triangles and spheres, BVH-traversed on both sides, plus
// two infinite planes; and the same with moving primitives (MotionBlur) at given shutter times, the
// kernels built with CLRT_HAS_MOTION_BLUR and the host moving each primitive by time·motion; and rays that
// skip back faces closer than a bound (Ray.direction.w = -bound under CLRT_HAS_BACKFACE_CULLING: the course's
// culling and the camera's near segment), the host skipping triangles seen from behind (d·n > 0) before it.
#include <catch.hpp>

#include <random>

#include "bvh/bvh.h"
#include "bvh/bvh8.h"
#include "bvh/host_intersect.h"
#include "cl/check.h"
#include "cl/kernel_args.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

struct RandomScene {
    std::vector<dev::Triangle> tris;
    std::vector<dev::Sphere> spheres;
    std::vector<Vec3> sphereCenter;
    std::vector<float> sphereRadius;
    std::vector<Vec3> motion;  // per primitive reference (triangles, then spheres)
    Bvh bvh;
};

// Boxes swept over the shutter (as flatten_geometry.cpp builds them): both ends of the motion.
Aabb swept(Aabb b, const Vec3& m) {
    Aabb end = b;
    end.min = end.min + m;
    end.max = end.max + m;
    b.grow(end);
    return b;
}

// moving: every primitive but every fourth gets a random translation over the shutter, stored as
// the device reads it (Triangle v0.w v1.w v2.w, Sphere.motion), its BVH box swept over it.
RandomScene makeScene(uint32_t seed, int numTris, int numSpheres, bool moving = false) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> pos(-10, 10), size(0.05f, 3.0f), unit(-1, 1);
    RandomScene s;
    std::vector<Aabb> boxes;
    auto nextMotion = [&](int i) {
        Vec3 m = Vec3(unit(rng), unit(rng), unit(rng)) * 4.0f;
        return moving && i % 4 != 0 ? m : Vec3(0, 0, 0);
    };
    for (int i = 0; i < numTris; ++i) {
        Vec3 c(pos(rng), pos(rng), pos(rng));
        float sz = size(rng);
        Vec3 p[3];
        for (Vec3& v : p) v = c + Vec3(unit(rng), unit(rng), unit(rng)) * sz;
        if (i % 17 == 0) p[2] = p[1];  // some degenerate ones
        Vec3 m = nextMotion(i);
        s.motion.push_back(m);
        s.tris.push_back({{p[0].x, p[0].y, p[0].z, m.x}, {p[1].x, p[1].y, p[1].z, m.y}, {p[2].x, p[2].y, p[2].z, m.z}});
        Aabb b;
        for (Vec3& v : p) b.grow(v);
        boxes.push_back(swept(b, m));
    }
    for (int i = 0; i < numSpheres; ++i) {
        Vec3 c(pos(rng), pos(rng), pos(rng));
        float r = size(rng) * 0.5f;
        dev::Sphere sp{};
        sp.centerRadius = {c.x, c.y, c.z, r};
        for (int k = 0; k < 3; ++k) {
            sp.worldToObject[k] = {k == 0 ? 1.f : 0.f, k == 1 ? 1.f : 0.f, k == 2 ? 1.f : 0.f, 0};
            sp.objectToWorld[k] = sp.worldToObject[k];
        }
        Vec3 m = nextMotion(i);
        sp.motion = {m.x, m.y, m.z, 0};
        s.motion.push_back(m);
        s.spheres.push_back(sp);
        s.sphereCenter.push_back(c);
        s.sphereRadius.push_back(r);
        Aabb b;
        b.grow(c - Vec3(r));
        b.grow(c + Vec3(r));
        boxes.push_back(swept(b, m));
    }
    s.bvh = buildBvh(boxes);
    return s;
}

// Shutter time of ray i: 0 and 1 (the ends of the motion), else spread over [0, 1).
float rayTime(int i) { return i % 7 == 0 ? 0.0f : i % 7 == 1 ? 1.0f : float((i * 2654435761u) % 1000u) / 1000.0f; }

// Runs both kernels of `program` over random rays in scene s (each ray at rayTime(i) when timed)
// and compares them with the host: the primitive, t and barycentrics of the closest hit, and
// whether the shadow ray is occluded. The host moves each primitive by time·motion.
void compareWithHost(const cl::Program& program, const RandomScene& s, bool timed, bool culling = false) {
    DeviceContext& dc = testContext();
    KernelArgs closest(program, "intersect_closest");
    KernelArgs shadow(program, "intersect_shadow");
    const int numTris = int(s.tris.size());
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> pos(-15, 15), unit(-1, 1);
    const int numRays = 20000;
    std::vector<dev::Ray> rays(numRays);
    std::vector<dev::ShadowRay> shadows(numRays);
    std::vector<float> cullBefore(numRays, 0.0f);  // back faces closer than this are skipped
    for (int i = 0; i < numRays; ++i) {
        Vec3 o(pos(rng), pos(rng), pos(rng));
        Vec3 d = normalize(Vec3(unit(rng), unit(rng), unit(rng)));
        if (i % 10 == 0) d = Vec3(0, 0, i % 20 == 0 ? 1.f : -1.f);  // axis-aligned: zero components
        float tMax = (i % 3 == 0) ? 5.0f : INFINITY;
        float time = timed ? rayTime(i) : 0.0f;
        rays[i] = {{o.x, o.y, o.z, time}, {d.x, d.y, d.z, tMax}};
        if (culling && i % 2 == 1) {  // every back face (the course's culling), or those before a bound
            tMax = INFINITY;
            cullBefore[size_t(i)] = i % 6 == 1 ? INFINITY : 20.0f * float((i * 2654435761u) % 1000u) / 1000.0f;
            rays[i].direction.w = -cullBefore[size_t(i)];
        }
        shadows[i] = {{o.x, o.y, o.z, tMax}, {d.x, d.y, d.z, time}, {1, 1, 1, 0}};
    }
    cl::Context& ctx = dc.context();
    Bvh8 b8 = collapseBvh8(s.bvh);
    setLeafTriangles(b8, s.tris, numTris);
    cl::Buffer rayBuf = readOnlyBuffer(rays);
    cl::Buffer hitBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, sizeof(dev::Hit) * numRays));
    cl::Buffer shadowBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                                             sizeof(dev::ShadowRay) * numRays, shadows.data()));
    // Two infinite planes, outside the BVH, with references after the triangles and spheres.
    std::vector<dev::Plane> planes(2);
    planes[0].point = {0, -12, 0, 0}; planes[0].normal = {0, 1, 0, 0};
    Vec3 n1 = normalize(Vec3(1, 0.5f, -0.25f));
    planes[1].point = {14, 0, 0, 0}; planes[1].normal = {n1.x, n1.y, n1.z, 0};
    const int firstPlaneRef = numTris + int(s.spheres.size());
    dev::SceneParams sp{};
    sp.numTriangles = numTris;
    sp.numSpheres = int(s.spheres.size());
    sp.numPlanes = 2;
    const IntersectScene scene =
        intersectScene(sp, numRays, b8.nodes, b8.leaves, s.tris, s.spheres, planes, std::vector<dev::Instance>{});
    // hitInstances: unused without instances
    scene.bind(closest).set("rays", rayBuf).set("hits", hitBuf).set("hitInstances", scene.queueCount);
    scene.bind(shadow).set("raysPerPath", 1).set("shadows", shadowBuf);
    cl::CommandQueue& q = dc.queue();
    CL_CPP(q.enqueueNDRangeKernel(closest.ready(), cl::NullRange, cl::NDRange(roundUp(numRays, 64)), cl::NDRange(64)));
    CL_CPP(q.enqueueNDRangeKernel(shadow.ready(), cl::NullRange, cl::NDRange(roundUp(numRays, 64)), cl::NDRange(64)));
    std::vector<dev::Hit> hits(numRays);
    CL_CPP(q.enqueueReadBuffer(hitBuf, CL_TRUE, 0, sizeof(dev::Hit) * numRays, hits.data()));
    CL_CPP(q.enqueueReadBuffer(shadowBuf, CL_TRUE, 0, sizeof(dev::ShadowRay) * numRays, shadows.data()));

    int culled = 0;  // triangle hits the host skipped as back faces
    int hitCount = 0, movingHits = 0, primMismatch = 0, tMismatch = 0, baryMismatch = 0, occlusionMismatch = 0;
    for (int i = 0; i < numRays; ++i) {
        Vec3 o(rays[i].origin.x, rays[i].origin.y, rays[i].origin.z);
        Vec3 d(rays[i].direction.x, rays[i].direction.y, rays[i].direction.z);
        float tMax = cullBefore[size_t(i)] > 0.0f ? INFINITY : rays[i].direction.w;
        const float time = rays[i].origin.w;
        int prim = -1;
        float tBest = tMax, bary1 = 0, bary2 = 0;
        traverseBvh(s.bvh, o, d, tBest, [&](int ref, float& tm) {
            float t, b1 = 0, b2 = 0;
            const Vec3 m = s.motion[size_t(ref)] * time;  // the primitive at this ray's time
            const dev::Triangle* tri = ref < numTris ? &s.tris[size_t(ref)] : nullptr;
            bool h = tri ? intersectTriangleWatertight(o, d, Vec3(tri->v0.x, tri->v0.y, tri->v0.z) + m,
                                                       Vec3(tri->v1.x, tri->v1.y, tri->v1.z) + m,
                                                       Vec3(tri->v2.x, tri->v2.y, tri->v2.z) + m, tm, t, b1, b2)
                         : intersectSphere(o, d, s.sphereCenter[ref - numTris] + m, s.sphereRadius[ref - numTris], tm, t);
            if (h && tri && t < cullBefore[size_t(i)]) {  // seen from behind: along the geometric normal
                const Vec3 e1(tri->v1.x - tri->v0.x, tri->v1.y - tri->v0.y, tri->v1.z - tri->v0.z);
                const Vec3 e2(tri->v2.x - tri->v0.x, tri->v2.y - tri->v0.y, tri->v2.z - tri->v0.z);
                if (dot(d, cross(e1, e2)) > 0.0f) { ++culled; h = false; }
            }
            if (h) { tm = t; prim = ref; bary1 = b1; bary2 = b2; }
        });
        for (int k = 0; k < 2; ++k) {  // host reference for the planes
            Vec3 pp(planes[k].point.x, planes[k].point.y, planes[k].point.z);
            Vec3 pn(planes[k].normal.x, planes[k].normal.y, planes[k].normal.z);
            float denom = dot(pn, d);
            if (denom == 0) continue;
            float t = dot(pp - o, pn) / denom;
            if (t > 0 && t < tBest) { tBest = t; prim = firstPlaneRef + k; }
        }
        const dev::Hit& h = hits[i];
        hitCount += prim >= 0;
        bool devHit = h.prim >= 0;
        if (devHit != (prim >= 0)) { ++primMismatch; continue; }
        if (prim < 0) continue;
        if (h.prim != prim) {
            // Two primitives at (almost) the same distance may be ordered differently by float noise.
            if (std::fabs(h.t - tBest) > 1e-4f * std::max(1.0f, tBest)) ++primMismatch;
            continue;
        }
        // Moving primitives: the device moves the ray instead of the primitive (a few ulps apart).
        const bool moved = prim < numTris + int(s.spheres.size()) && s.motion[size_t(prim)] != Vec3(0, 0, 0);
        movingHits += moved;
        if (std::fabs(h.t - tBest) > (moved ? 1e-4f : 1e-5f) * std::max(1.0f, tBest)) ++tMismatch;
        if (prim < numTris && (std::fabs(h.u - bary1) > 1e-3f || std::fabs(h.v - bary2) > 1e-3f)) ++baryMismatch;
        bool occluded = shadows[i].contribution.x == 0;
        if (!occluded) ++occlusionMismatch;  // the ray hit something before tMax: must be occluded
    }
    // Rays the host says miss must not be occluded on the device.
    for (int i = 0; i < numRays; ++i)  // (a shadow ray sees back faces: only rays that cull none)
        if (hits[i].prim < 0 && shadows[i].contribution.x == 0 && cullBefore[size_t(i)] == 0.0f) ++occlusionMismatch;
    INFO("rays with hits: " << hitCount << " of " << numRays << ", on moving primitives: " << movingHits
                            << ", back faces skipped: " << culled);
    if (culling) CHECK(culled > numRays / 20);
    CHECK(hitCount > numRays / 10);
    if (timed) CHECK(movingHits > numRays / 20);
    CHECK(primMismatch == 0);
    CHECK(tMismatch == 0);
    CHECK(baryMismatch == 0);
    CHECK(occlusionMismatch == 0);
}

}  // namespace

TEST_CASE("intersection kernels match the host reference on random scenes", "[cl][intersect]") {
    cl::Program program = buildProgramFromSources(testContext(), loadKernelSources(KernelProgram::Intersect), {});
    compareWithHost(program, makeScene(1234, 3000, 200), false);
}

TEST_CASE("moving primitives (MotionBlur): kernels match the host at given shutter times", "[cl][intersect][motion]") {
    cl::Program program = buildProgramFromSources(testContext(), loadKernelSources(KernelProgram::Intersect),
                                                  {"-DCLRT_HAS_MOTION_BLUR=1"});
    compareWithHost(program, makeScene(4321, 3000, 200, true), true);
}

TEST_CASE("rays that skip back faces closer than a bound: kernels match the host", "[cl][intersect][orientation]") {
    cl::Program program = buildProgramFromSources(testContext(), loadKernelSources(KernelProgram::Intersect),
                                                  {"-DCLRT_HAS_BACKFACE_CULLING=1"});
    compareWithHost(program, makeScene(2468, 3000, 200), false, true);
}
