// embree_watertight — is Embree 3 watertight? The closed triangulated spheres and rays of clrt's device test
// "robust: watertight triangles on the device, ..." (tests/watertight_sphere.h: 100,000 rays from inside each
// sphere, many aimed exactly at its vertices and edges) traced by Embree's single-ray API in its default
// mode and with RTC_SCENE_FLAG_ROBUST (the mode ray_bench --embree-robust compares against); prints how
// many rays escape each sphere. clrt's test requires 0 of them (its watertight triangle test, Woop et al.).
// usage: embree_watertight
#include <embree3/rtcore.h>

#include <cmath>
#include <cstdio>

#include "watertight_sphere.h"

using namespace clrt;

namespace {

// Rays of the case that hit nothing (escape the closed sphere) in an Embree scene with `flags`.
size_t escapes(RTCDevice dev, const test::WatertightCase& wc, RTCSceneFlags flags) {
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneFlags(scene, flags);
    RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* vb = (float*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                wc.vertices.size());
    unsigned* ib = (unsigned*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                      3 * sizeof(unsigned), wc.indices.size() / 3);
    for (size_t i = 0; i < wc.vertices.size(); ++i) {
        vb[3 * i] = wc.vertices[i].x; vb[3 * i + 1] = wc.vertices[i].y; vb[3 * i + 2] = wc.vertices[i].z;
    }
    for (size_t i = 0; i < wc.indices.size(); ++i) ib[i] = unsigned(wc.indices[i]);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    size_t n = 0;
    for (const dev::Ray& r : wc.rays) {
        RTCRayHit rh{};
        rh.ray.org_x = r.origin.x; rh.ray.org_y = r.origin.y; rh.ray.org_z = r.origin.z;
        rh.ray.dir_x = r.direction.x; rh.ray.dir_y = r.direction.y; rh.ray.dir_z = r.direction.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &ctx, &rh);
        n += rh.hit.geomID == RTC_INVALID_GEOMETRY_ID;
    }
    rtcReleaseScene(scene);
    return n;
}

}  // namespace

int main() {
    RTCDevice dev = rtcNewDevice("threads=1");
    std::printf("%-30s %6s %7s %15s %14s\n", "sphere centre", "radius", "rays", "escape: default", "robust");
    for (const Vec3 centre : {Vec3(0, 0, 0), Vec3(0.37f, -0.21f, 0.05f), Vec3(1000.25f, -1000.5f, 1000.125f)}) {
        const float radius = centre.x > 100 ? 10.0f : 1.0f;
        const test::WatertightCase wc = test::watertightSphere(centre, radius);
        char name[64];
        std::snprintf(name, sizeof name, "(%g, %g, %g)", centre.x, centre.y, centre.z);
        std::printf("%-30s %6g %7zu %15zu %14zu\n", name, radius, wc.rays.size(),
                    escapes(dev, wc, RTC_SCENE_FLAG_NONE), escapes(dev, wc, RTC_SCENE_FLAG_ROBUST));
    }
    rtcReleaseDevice(dev);
    return 0;
}
