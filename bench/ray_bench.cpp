// ray_bench — the same rays traced by clrt's intersection kernels and by Embree 3 (a baseline nobody
// here wrote), both on this machine's CPU. For a scene it generates, on the host:
//   camera rays   one per pixel centre of the first camera (the camera kernel's formula);
//   shadow rays   from each camera-ray hit towards the first point/spot/area light (or straight up);
//   diffuse rays  cosine-distributed around each hit's normal (fixed seed);
// then times clrt's intersect_closest / intersect_shadow kernels on the chosen OpenCL device and
// Embree's single-ray API (rtcIntersect1 / rtcOccluded1) on N threads, and prints Mrays/s, the ratio
// clrt/Embree, and how often the two agree on hit/miss (and on the primitive hit).
//
// usage: ray_bench SCENE [--runs 5] [--device SPEC] [--threads 2] [--dump FILE] [--embree-config STR] [--embree-robust]
//                  [--instancing flatten|two-level|auto]   (clrt's layout; Embree always gets the flattened scene;
//                  with two-level the "prim" agreement column compares different numberings: read the hit column)
//   --threads T: Embree's thread count, and the whole process (so the OpenCL runtime's workers too) is
//   pinned to the first T CPUs it may run on; PoCL is also told T workers (POCL_MAX_PTHREAD_COUNT,
//   unless already set). Without --threads, Embree gets 2 threads and nothing is pinned.
//   --dump FILE: also writes clrt's closest hits (t, prim, u, v of every camera and diffuse ray) and
//   shadow results, as raw bytes, so that two kernel versions can be compared hit by hit (cmp).
//   --embree-config STR: appended to Embree's device configuration, e.g. "verbose=2": Embree then prints
//   the BVH and intersector it picked (on this machine BVH8<triangle4>, BVH8Triangle4Intersector1Moeller)
//   and its tree's statistics (nodes, fill, SAH cost); the "clrt BVH" line gives clrt's tree's SAH cost counted
//   the same way (sahEmbreeTerms).
//   --embree-robust: Embree's scene with RTC_SCENE_FLAG_ROBUST ("robust traversal, no optimizations that
//   reduce arithmetic accuracy ... rays shooting through edges of neighboring primitives"): Embree's mode
//   for what clrt always does (watertight triangles). Its default mode tests triangles by Moeller-Trumbore.
#include <embree3/rtcore.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bvh/bvh8.h"
#include "cl/check.h"
#include "cl/devices.h"
#include "cl/kernel_args.h"
#include "cl/program.h"
#include "cl/scene_buffers.h"
#include "flatten/device_scene.h"
#include "scene/scene_loader.h"
#include "util/error.h"

using namespace clrt;

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// Host copy of Ray_OffsetOrigin (cl_kernels/common.cl).
Vec3 offsetOrigin(Vec3 p, Vec3 n) {
    auto one = [](float p, float n) {
        int of = int(256.0f * n);
        int bits;
        std::memcpy(&bits, &p, 4);
        bits += p < 0 ? -of : of;
        float pi;
        std::memcpy(&pi, &bits, 4);
        return std::fabs(p) < 1.0f / 32.0f ? p + n / 65536.0f : pi;
    };
    return {one(p.x, n.x), one(p.y, n.y), one(p.z, n.z)};
}

// Restricts this process to the first n CPUs of its affinity mask (before any OpenCL or Embree
// thread starts), so that both sides of the comparison run on the same n cores.
void pinToCpus(int n) {
    cpu_set_t cur, want;
    CPU_ZERO(&want);
    if (sched_getaffinity(0, sizeof(cur), &cur) != 0) return;
    for (int c = 0, k = 0; c < CPU_SETSIZE && k < n; ++c)
        if (CPU_ISSET(c, &cur)) { CPU_SET(c, &want); ++k; }
    if (sched_setaffinity(0, sizeof(want), &want) != 0) std::fprintf(stderr, "note: could not pin to %d CPUs\n", n);
    setenv("POCL_MAX_PTHREAD_COUNT", std::to_string(n).c_str(), 0);
}

struct RaySet {
    std::string name;
    std::vector<dev::Ray> rays;
};

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Options {
    std::string scenePath, deviceSpec = "cpu", dumpPath, embreeConfig;
    bool embreeRobust = false;
    Instancing instancing = Instancing::Flatten;  // --instancing: how clrt stores instanced meshes
    int runs = 5, threads = 2;
    bool threadsGiven = false;
};

Options parseArgs(int argc, char** argv) {
    Options o;
    o.scenePath = argv[1];
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--embree-robust") { o.embreeRobust = true; continue; }
        if (i + 1 >= argc) throw Error(a + ": expects a value (or is not an option)");
        const std::string v = argv[++i];
        if (a == "--runs") o.runs = std::max(1, std::atoi(v.c_str()));
        else if (a == "--device") o.deviceSpec = v;
        else if (a == "--threads") o.threads = std::max(1, std::atoi(v.c_str())), o.threadsGiven = true;
        else if (a == "--dump") o.dumpPath = v;
        else if (a == "--embree-config") o.embreeConfig = v;
        else if (a == "--instancing") {
            if (v != "flatten" && v != "two-level" && v != "auto") throw Error("--instancing: flatten, two-level or auto");
            o.instancing = v == "flatten" ? Instancing::Flatten : v == "two-level" ? Instancing::TwoLevel : Instancing::Auto;
        } else throw Error(a + ": unknown option");
    }
    return o;
}

// Embree's side: the scene's world-space triangles in one Embree scene, traced with the single-ray
// API on `threads` threads.
class EmbreeTracer {
public:
    EmbreeTracer(const DeviceScene& ds, int threads, const std::string& config, bool robust) : threads_(threads) {
        const int numTris = ds.params.numTriangles;
        dev_ = rtcNewDevice(("threads=" + std::to_string(threads) + (config.empty() ? "" : "," + config)).c_str());
        scene_ = rtcNewScene(dev_);
        if (robust) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
        RTCGeometry geom = rtcNewGeometry(dev_, RTC_GEOMETRY_TYPE_TRIANGLE);
        float* vb = (float*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                    size_t(numTris) * 3);
        unsigned* ib = (unsigned*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                          3 * sizeof(unsigned), size_t(numTris));
        for (int t = 0; t < numTris; ++t) {
            const dev::Triangle& tr = ds.triangles[t];
            const dev::float4* v[3] = {&tr.v0, &tr.v1, &tr.v2};
            for (int k = 0; k < 3; ++k) {
                vb[(size_t(t) * 3 + k) * 3 + 0] = v[k]->x;
                vb[(size_t(t) * 3 + k) * 3 + 1] = v[k]->y;
                vb[(size_t(t) * 3 + k) * 3 + 2] = v[k]->z;
                ib[size_t(t) * 3 + k] = unsigned(t * 3 + k);
            }
        }
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        auto tb = std::chrono::steady_clock::now();
        rtcCommitScene(scene_);
        buildSeconds = secondsSince(tb);
    }
    ~EmbreeTracer() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(dev_);
    }
    EmbreeTracer(const EmbreeTracer&) = delete;
    EmbreeTracer& operator=(const EmbreeTracer&) = delete;

    // prim[i]: the primitive ray i hits (closest), or 1 if it is occluded (shadow); -1 for a miss.
    void trace(const std::vector<dev::Ray>& rays, bool shadow, std::vector<int>& prim) const {
        prim.assign(rays.size(), -1);
        std::atomic<size_t> next{0};
        auto work = [&]() {
            for (;;) {
                size_t b = next.fetch_add(1024);
                if (b >= rays.size()) break;
                size_t e = std::min(rays.size(), b + 1024);
                for (size_t i = b; i < e; ++i) prim[i] = traceOne(rays[i], shadow);
            }
        };
        std::vector<std::thread> ts;
        for (int t = 0; t < threads_; ++t) ts.emplace_back(work);
        for (auto& t : ts) t.join();
    }

    double buildSeconds = 0;

private:
    int traceOne(const dev::Ray& r, bool shadow) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh;
        rh.ray.org_x = r.origin.x; rh.ray.org_y = r.origin.y; rh.ray.org_z = r.origin.z;
        rh.ray.dir_x = r.direction.x; rh.ray.dir_y = r.direction.y; rh.ray.dir_z = r.direction.z;
        rh.ray.tnear = 0; rh.ray.tfar = r.direction.w; rh.ray.mask = ~0u; rh.ray.flags = 0; rh.ray.time = 0;
        if (shadow) {
            rtcOccluded1(scene_, &ctx, &rh.ray);
            return rh.ray.tfar < 0 ? 1 : -1;
        }
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &ctx, &rh);
        return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : int(rh.hit.primID);
    }

    int threads_;
    RTCDevice dev_;
    RTCScene scene_;
};

// clrt's side: the intersection program and the scene arrays on one OpenCL device, planes left
// out (Embree has none).
class ClrtTracer {
public:
    ClrtTracer(const DeviceScene& ds, const std::string& deviceSpec, FILE* dump)
        : di_(selectDevices(deviceSpec).front()), dc_(di_), dump_(dump),
          // The scene arrays as the renderer uploads them (huge-page host memory on CPU devices,
          // cl/scene_buffers.h); the uploader owns that memory, so it lives as long as the buffers.
          sceneUpload_(dc_.context(), (di_.type & CL_DEVICE_TYPE_CPU) != 0) {
        prog_ = buildProgram(dc_, KernelProgram::Intersect, ds.features.defines());
        kClosest_ = KernelArgs(prog_, "intersect_closest");
        kShadow_ = KernelArgs(prog_, "intersect_shadow");
        // Kept as members: a kernel argument does not keep its buffer alive.
        scene_ = {sceneUpload_.upload(ds.bvh8.nodes), sceneUpload_.upload(ds.bvh8.leaves),
                  sceneUpload_.upload(ds.triangles), sceneUpload_.upload(ds.spheres)};
        scene_.push_back(sceneUpload_.upload(ds.planes));
        scene_.push_back(sceneUpload_.upload(ds.instances));
        if (ds.params.numPlanes > 0) std::fprintf(stderr, "note: planes are ignored by this benchmark\n");
        dev::SceneParams sp = ds.params;
        sp.numPlanes = 0;  // planes left out (Embree has none)
        for (KernelArgs* k : {&kClosest_, &kShadow_})
            k->set("scene", sp).set("nodes", scene_[0]).set("leaves", scene_[1]).set("tris", scene_[2])
                .set("spheres", scene_[3]).set("planes", scene_[4]).set("instances", scene_[5]);
    }
    const DeviceInfo& device() const { return di_; }

    // As EmbreeTracer::trace; returns the kernel's time (seconds). --dump: appends the results.
    double trace(const std::vector<dev::Ray>& rays, bool shadow, std::vector<int>& prim) {
        prim.assign(rays.size(), -1);
        const size_t local = std::getenv("CLRT_LOCAL_SIZE") ? size_t(std::atoi(std::getenv("CLRT_LOCAL_SIZE"))) : 64;
        const size_t global = roundUp(rays.size(), local);
        std::vector<int> queueLength{int(rays.size())};  // the kernels read the queue length on the device
        cl::Buffer cb = upload(queueLength);
        return shadow ? traceShadow(rays, cb, global, local, prim) : traceClosest(rays, cb, global, local, prim);
    }

private:
    template <class V> cl::Buffer upload(V& v) {
        using T = typename V::value_type;
        return CL_CPP(cl::Buffer(dc_.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * v.size(), v.data()));
    }
    // Runs kernel k once over the global range; its time in seconds.
    double timeKernel(KernelArgs& k, size_t global, size_t local) {
        cl::CommandQueue& q = dc_.queue();
        CL_CPP(q.finish());
        auto t0 = std::chrono::steady_clock::now();
        CL_CPP(q.enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(global), cl::NDRange(local)));
        CL_CPP(q.finish());
        return secondsSince(t0);
    }
    double traceClosest(const std::vector<dev::Ray>& rays, cl::Buffer& cb, size_t global, size_t local,
                        std::vector<int>& prim) {
        cl::Buffer rb = upload(const_cast<std::vector<dev::Ray>&>(rays));
        cl::Buffer hb = CL_CPP(cl::Buffer(dc_.context(), CL_MEM_READ_WRITE, sizeof(dev::Hit) * rays.size()));
        cl::Buffer ib = CL_CPP(cl::Buffer(dc_.context(), CL_MEM_READ_WRITE, sizeof(int) * rays.size()));
        kClosest_.set("rays", rb).set("hits", hb).set("hitInstances", ib).set("queueCount", cb);
        double s = timeKernel(kClosest_, global, local);
        std::vector<dev::Hit> hits(rays.size());
        CL_CPP(dc_.queue().enqueueReadBuffer(hb, CL_TRUE, 0, sizeof(dev::Hit) * hits.size(), hits.data()));
        for (size_t i = 0; i < hits.size(); ++i) prim[i] = hits[i].prim;
        if (dump_) std::fwrite(hits.data(), sizeof(dev::Hit), hits.size(), dump_);
        return s;
    }
    double traceShadow(const std::vector<dev::Ray>& rays, cl::Buffer& cb, size_t global, size_t local,
                       std::vector<int>& prim) {
        std::vector<dev::ShadowRay> sr(rays.size());
        for (size_t i = 0; i < rays.size(); ++i) {
            sr[i].origin = rays[i].origin;
            sr[i].origin.w = rays[i].direction.w;
            sr[i].direction = rays[i].direction;
            sr[i].contribution = {1, 1, 1, 0};
        }
        cl::Buffer sb = upload(sr);
        kShadow_.set("shadows", sb).set("queueCount", cb).set("raysPerPath", 1);
        double s = timeKernel(kShadow_, global, local);
        CL_CPP(dc_.queue().enqueueReadBuffer(sb, CL_TRUE, 0, sizeof(dev::ShadowRay) * sr.size(), sr.data()));
        for (size_t i = 0; i < sr.size(); ++i) prim[i] = sr[i].contribution.x == 0 ? 1 : -1;
        if (dump_) std::fwrite(sr.data(), sizeof(dev::ShadowRay), sr.size(), dump_);
        return s;
    }

    DeviceInfo di_;
    DeviceContext dc_;
    FILE* dump_;
    SceneBufferUploader sceneUpload_;
    std::vector<cl::Buffer> scene_;  // nodes, leaves, triangles, spheres, planes
    cl::Program prog_;
    KernelArgs kClosest_, kShadow_;
};

// One ray per pixel centre of `cam` (the camera kernel's formula).
RaySet cameraRays(const Camera& cam) {
    dev::CameraParams cp = makeCameraParams(cam);
    RaySet camera{"camera", {}};
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            float su = (x + 0.5f) / cam.width, sv = (y + 0.5f) / cam.height;
            float uc = cp.nearPlane.x + (cp.nearPlane.y - cp.nearPlane.x) * su;
            float vc = cp.nearPlane.w - (cp.nearPlane.w - cp.nearPlane.z) * sv;
            Vec3 d = normalize(cam.u * uc + cam.v * vc - cam.w * cam.nearDistance);
            camera.rays.push_back({{cam.position.x, cam.position.y, cam.position.z, 0}, {d.x, d.y, d.z, INFINITY}});
        }
    return camera;
}

// Where shadow rays go: the first point, spot or area light, else a point high above the scene.
Vec3 shadowTarget(const DeviceScene& ds) {
    for (const dev::Light& l : ds.lights)
        if (l.kind == dev::LIGHT_POINT || l.kind == dev::LIGHT_SPOT || l.kind == dev::LIGHT_AREA)
            return Vec3(l.position.x, l.position.y, l.position.z);
    const Aabb& world = ds.bvh.bounds;
    return Vec3(world.centroid().x, world.max.y + length(world.max - world.min), world.centroid().z);
}

// From each camera-ray hit (camPrim: the triangle it hit): a shadow ray towards lightPos and a
// cosine-distributed diffuse ray around the triangle's normal (fixed seed).
void secondaryRays(const DeviceScene& ds, const RaySet& camera, const std::vector<int>& camPrim, Vec3 lightPos,
                   RaySet& shadow, RaySet& diffuse) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(0, 1);
    for (size_t i = 0; i < camera.rays.size(); ++i) {
        int p = camPrim[i];
        if (p < 0 || p >= ds.params.numTriangles) continue;
        const dev::Triangle& tr = ds.triangles[p];
        Vec3 v0(tr.v0.x, tr.v0.y, tr.v0.z), v1(tr.v1.x, tr.v1.y, tr.v1.z), v2(tr.v2.x, tr.v2.y, tr.v2.z);
        Vec3 o(camera.rays[i].origin.x, camera.rays[i].origin.y, camera.rays[i].origin.z);
        Vec3 d(camera.rays[i].direction.x, camera.rays[i].direction.y, camera.rays[i].direction.z);
        Vec3 n = normalize(cross(v1 - v0, v2 - v0));
        if (dot(n, d) > 0) n = -n;
        // Hit point: intersect the triangle's plane (good enough for generating rays).
        float t = dot(v0 - o, n) / dot(d, n);
        Vec3 ph = offsetOrigin(o + d * t, n);
        Vec3 toL = lightPos - ph;
        float dist = length(toL);
        Vec3 l = toL / dist;
        shadow.rays.push_back({{ph.x, ph.y, ph.z, 0}, {l.x, l.y, l.z, dist * 0.9999f}});
        Vec3 a = std::fabs(n.x) > 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
        Vec3 tu = normalize(cross(a, n)), tv = cross(n, tu);
        float r1 = U(rng), r2 = U(rng), r = std::sqrt(r1), phi = 2 * float(M_PI) * r2;
        Vec3 dd = normalize(tu * (r * std::cos(phi)) + tv * (r * std::sin(phi)) + n * std::sqrt(std::max(0.f, 1 - r1)));
        diffuse.rays.push_back({{ph.x, ph.y, ph.z, 0}, {dd.x, dd.y, dd.z, INFINITY}});
    }
}

// The tree's SAH cost as Embree's statistics (--embree-config verbose=2) report its own: each node's box
// area and each leaf's box area times its blocks of four, over the root's area (traversal and block test
// costing 1 each). Returns {nodes' part, leaves' part}; a root box dominated by one huge primitive (the
// Audi TT's ground) makes both trees' figures that primitive's.
std::pair<double, double> sahEmbreeTerms(const Bvh8& t) {
    auto halfArea = [](double dx, double dy, double dz) { return dx < 0 || dy < 0 || dz < 0 ? 0.0 : dx * dy + dy * dz + dz * dx; };
    auto laneArea = [&](const dev::Bvh8Node& n, int i) {
        return halfArea(double(lanePlane(n, 1, i)) - lanePlane(n, 0, i), double(lanePlane(n, 3, i)) - lanePlane(n, 2, i),
                        double(lanePlane(n, 5, i)) - lanePlane(n, 4, i));
    };
    if (t.nodes.size() == 0) return {0, 0};
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < kBvhWidth; ++i)
        if (laneEntry(t.nodes[0], i) != CLRT_INVALID)
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], double(lanePlane(t.nodes[0], 2 * a, i)));
                hi[a] = std::max(hi[a], double(lanePlane(t.nodes[0], 2 * a + 1, i)));
            }
    const double root = halfArea(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    double nodes = 1, leaves = 0;  // the root node: area 1
    for (const dev::Bvh8Node& n : t.nodes)
        for (int i = 0; i < kBvhWidth; ++i) {
            const int e = laneEntry(n, i);
            if (e >= 0) nodes += laneArea(n, i) / root;
            else if (isLeafEntry(e)) leaves += laneArea(n, i) / root * double((leafCount(e) + 3) / 4);
        }
    return {nodes, leaves};
}

// Traces `set` `runs` times on both sides and prints one table row: median Mrays/s, their ratio,
// and how often the two agree on hit/miss and on the primitive hit.
void compareRaySet(const RaySet& set, bool isShadow, int runs, ClrtTracer& clrt, const EmbreeTracer& embree) {
    std::vector<double> tc, te;
    std::vector<int> pc, pe;
    for (int r = 0; r < runs; ++r) {
        tc.push_back(clrt.trace(set.rays, isShadow, pc));
        auto t0 = std::chrono::steady_clock::now();
        embree.trace(set.rays, isShadow, pe);
        te.push_back(secondsSince(t0));
    }
    size_t hitAgree = 0, primAgree = 0;
    for (size_t i = 0; i < pc.size(); ++i) {
        hitAgree += (pc[i] >= 0) == (pe[i] >= 0);
        primAgree += pc[i] == pe[i];
    }
    double n = double(set.rays.size());
    double mc = n / median(tc) * 1e-6, me = n / median(te) * 1e-6;
    std::printf("%-8s %10zu %12.2f %12.2f %8.2f %9.3f%% %9.3f%%\n", set.name.c_str(), set.rays.size(), mc, me, mc / me,
                100.0 * hitAgree / std::max(1.0, n), 100.0 * primAgree / std::max(1.0, n));
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) {
            std::fprintf(stderr, "usage: ray_bench SCENE [--runs N] [--device SPEC] [--threads T]\n");
            return 1;
        }
        const Options opt = parseArgs(argc, argv);
        if (opt.threadsGiven) pinToCpus(opt.threads);
        FILE* dump = opt.dumpPath.empty() ? nullptr : std::fopen(opt.dumpPath.c_str(), "wb");
        if (!opt.dumpPath.empty() && !dump) throw Error("cannot write " + opt.dumpPath);
        Scene scene = loadScene(opt.scenePath);
        // Embree and the ray sets always see the flattened scene; clrt traverses its own layout (--instancing).
        FlattenOptions flat;
        flat.instancing = Instancing::Flatten;
        DeviceScene ds = flattenScene(scene, flat);
        FlattenOptions own;
        own.instancing = opt.instancing;
        DeviceScene dsClrt = opt.instancing == Instancing::Flatten ? DeviceScene{} : flattenScene(scene, own);
        if (ds.params.numSpheres > 0) std::fprintf(stderr, "note: spheres are ignored by this benchmark\n");
        EmbreeTracer embree(ds, opt.threads, opt.embreeConfig, opt.embreeRobust);
        ClrtTracer clrt(opt.instancing == Instancing::Flatten ? ds : dsClrt, opt.deviceSpec, dump);

        RaySet camera = cameraRays(scene.cameras.at(0));
        std::vector<int> camPrim;
        clrt.trace(camera.rays, false, camPrim);  // also warms up the kernel
        if (opt.instancing != Instancing::Flatten) embree.trace(camera.rays, false, camPrim);  // ds's numbering
        RaySet shadow{"shadow", {}}, diffuse{"diffuse", {}};
        secondaryRays(ds, camera, camPrim, shadowTarget(ds), shadow, diffuse);

        std::printf("scene %s: %d triangles; clrt device: %s; Embree %d threads (BVH build %.3f s)%s\n",
                    opt.scenePath.c_str(), ds.params.numTriangles, clrt.device().name.c_str(), opt.threads,
                    embree.buildSeconds, opt.threadsGiven ? "; process pinned to that many CPUs" : "");
        const auto sah = sahEmbreeTerms(ds.bvh8);
        std::printf("clrt BVH: %zu 8-wide nodes, %zu leaf blocks (%.2f primitives per block); SAH as Embree counts it "
                    "%.3f (nodes %.3f, leaves %.3f)\n", ds.bvh8.nodes.size(), ds.bvh8.leaves.size(),
                    double(ds.bvh.primitives) / double(std::max<size_t>(1, ds.bvh8.leaves.size())), sah.first + sah.second,
                    sah.first, sah.second);
        std::printf("%-8s %10s %12s %12s %8s %10s %10s\n", "rays", "count", "clrt Mray/s", "embree Mray/s", "ratio",
                    "hit agree", "prim agree");
        for (const RaySet* set : {&camera, &shadow, &diffuse}) compareRaySet(*set, set == &shadow, opt.runs, clrt, embree);
        std::printf("(medians of %d runs)\n", opt.runs);
        if (dump) std::fclose(dump);
        return 0;
    } catch (const Error& e) {
        std::fprintf(stderr, "ray_bench: error: %s\n", e.what());
        return int(e.code());
    }
}
