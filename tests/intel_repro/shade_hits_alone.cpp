// shade_hits_alone.cpp — issue 17's standalone reproducer: runs the render program's shade_hits kernel
// alone, on synthetic hits (8192 paths on random small triangles: a checkerboard-textured diffuse
// material, a mirror and a dielectric with Beer absorption; 5% misses; depths 0..2 with splitDepth 2),
// no scene file, no BVH, and writes its outputs (childValid, the children, the path radiance).
// The program is one that clrt dumped (CLRT_DUMP_PROGRAM=DIR writes DIR/<hash>.cl and .options); it is
// built with exactly the dumped options.
// In issue 17, Intel's OpenCL CPU runtime (2026.22) with its vectoriser gave children unlike PoCL's
// (~1500 of 16384 child slots); with CL_CONFIG_USE_VECTORIZER=False, or with shade_hits'
// vec_type_hint(float4), it agreed. What it shows on today's kernels: docs/quirks.md, INTEL_VEC_HINT.
// The arguments are bound by name through the project's own binder (src/cl/kernel_args.h, KernelArgs and
// CLRT_BIND_GROUP over CLRT_KERNEL_shade_hits of src/shared/kernel_params.h), as src/render/renderer.cpp
// binds them, from the members of ShadeArgs below: a parameter added to the declaration is a compile
// error here (no member of that name), a wrong kind or value size throws. Before binding, the kernel
// of the dumped program is checked against that declaration (argument count, then the names; a runtime
// that reports no names without -cl-kernel-arg-info, as PoCL, gets a second build with it for the
// check alone), so a program from another revision than these sources fails with a message naming the
// first mismatch instead of clSetKernelArg's -51. On stderr it prints the build log's lines about
// shade_hits (Intel's runtime: whether it vectorised the kernel, and how wide) and what it checked.
// Built by scripts/intel_vectorizer_repro.sh, not by CMake:
//   g++ -std=c++17 -O1 -Isrc -DCL_TARGET_OPENCL_VERSION=120 -DCL_HPP_TARGET_OPENCL_VERSION=120
//       -DCL_HPP_MINIMUM_OPENCL_VERSION=120 -DCL_HPP_ENABLE_EXCEPTIONS tests/intel_repro/shade_hits_alone.cpp
//       src/cl/kernel_args.cpp src/cl/check.cpp src/util/error.cpp -lOpenCL
// usage: shade_hits_alone PROGRAM.cl OPTIONS PLATFORM_SUBSTRING OUT.bin
//        shade_hits_alone --compare A.bin B.bin
//   (PROGRAM.cl and OPTIONS: a dumped program and the contents of its .options file; the first device of
//   the first platform whose name contains PLATFORM_SUBSTRING runs it.) --compare prints how many of
//   the 16384 childValid slots differ (and how many the first marks valid) and how many output floats
//   (valid children, radiance) differ by more than 1e-3 relative and in any bit (exit 2 if slots or
//   floats beyond 1e-3 differ).
#include <CL/opencl.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "cl/check.h"
#include "cl/kernel_args.h"
#include "shared/device_types.h"
#include "shared/kernel_params.h"
#include "util/error.h"
using namespace clrt::dev;
static unsigned st = 12345;
static float rnd() { st = st * 1664525u + 1013904223u; return (st >> 8) * (1.0f / 16777216.0f); }
static int compare(const char* fa, const char* fb) {
    auto load = [](const char* f) { std::ifstream in(f, std::ios::binary); return std::vector<char>(std::istreambuf_iterator<char>(in), {}); };
    std::vector<char> a = load(fa), b = load(fb);
    const int N = 8192;
    if (a.size() != b.size() || a.size() < sizeof(int) * 2 * N) { printf("output sizes differ\n"); return 1; }
    const int* va = (const int*)a.data(); const int* vb = (const int*)b.data();
    int dv = 0, nv = 0; for (int i = 0; i < 2 * N; ++i) { dv += va[i] != vb[i]; nv += va[i] != 0; }
    const float* xa = (const float*)a.data() + 2 * N; const float* xb = (const float*)b.data() + 2 * N;
    size_t nf = a.size() / 4 - 2 * N, bad = 0, bits = 0;
    for (size_t i = 0; i < nf; ++i) {
        float x = xa[i], y = xb[i];
        bits += std::memcmp(&x, &y, sizeof x) != 0;
        if (x != y && !(std::isnan(x) && std::isnan(y)) && std::fabs(x - y) > 1e-3f * std::fmax(std::fmax(std::fabs(x), std::fabs(y)), 1e-6f)) ++bad;
    }
    printf("childValid differs in %d of %d slots (%d valid in the first); %zu of %zu output floats differ by more than 1e-3 relative, %zu in any bit\n",
           dv, 2 * N, nv, bad, nf, bits);
    return dv || bad ? 2 : 0;
}

// shade_hits' arguments, each member named as the parameter it is bound to (CLRT_KERNEL_shade_hits).
struct ShadeArgs {
    cl::Buffer queueCount;
    SceneParams scene{};
    CameraParams cam{};
    cl::Buffer paths, rays, hits, hitInstances, tris, triShading, triAttributes, spheres, planes, instances, materials,
        textureSets, textures, images, texels, lights, points, pathRadiance, envDist, nextPaths, nextRays, childValid;
};

// The kernel of the dumped program against the declaration these sources were compiled with: throws
// clrt::Error naming the first mismatch. Returns how many argument names the runtime reported.
static int checkDeclaration(const cl::Kernel& k, const clrt::KernelDecl& decl) {
    std::string declared;
    for (const clrt::ParamDecl& p : decl.params) declared += std::string(declared.empty() ? "" : ", ") + p.name;
    const std::string hint = " (" + declared + "): dump the program with a clrt built from these sources";
    cl_uint n = 0;
    CL_CHECK(clGetKernelInfo(k(), CL_KERNEL_NUM_ARGS, sizeof n, &n, nullptr));
    if (n != decl.params.size())
        throw clrt::Error("the program's " + std::string(decl.name) + " takes " + std::to_string(n) +
                              " arguments; src/shared/kernel_params.h declares " + std::to_string(decl.params.size()) + hint,
                          clrt::ExitCode::Device);
    int named = 0;
    for (cl_uint i = 0; i < n; ++i) {
        char name[256] = {0};
        if (clGetKernelArgInfo(k(), i, CL_KERNEL_ARG_NAME, sizeof name, name, nullptr) != CL_SUCCESS) continue;
        ++named;
        if (std::strcmp(name, decl.params[i].name) != 0)
            throw clrt::Error("the program's " + std::string(decl.name) + " argument " + std::to_string(i) + " is " +
                                  name + "; src/shared/kernel_params.h declares " + decl.params[i].name + " there" + hint,
                              clrt::ExitCode::Device);
    }
    return named;
}

static void buildOrExit(cl::Program& program, const cl::Device& dev, const std::string& options) {
    try {
        program.build(std::vector<cl::Device>{dev}, options.c_str());
    } catch (const cl::Error& e) {
        fprintf(stderr, "build %d\n%s\n", e.err(), program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(dev).c_str());
        exit(1);
    }
}

static int run(char** argv) {
    std::ifstream in(argv[1]);
    if (!in) { fprintf(stderr, "shade_hits_alone: cannot read %s\n", argv[1]); return 1; }
    std::stringstream ss; ss << in.rdbuf(); std::string src = ss.str();
    std::string options = argv[2];
    while (!options.empty() && (options.back() == '\n' || options.back() == '\r')) options.pop_back();
    std::vector<cl::Platform> platforms; cl::Platform::get(&platforms); cl::Platform pl;
    for (cl::Platform& p : platforms) if (!pl() && p.getInfo<CL_PLATFORM_NAME>().find(argv[3]) != std::string::npos) pl = p;
    if (!pl()) { fprintf(stderr, "no OpenCL platform named *%s*\n", argv[3]); return 1; }
    std::vector<cl::Device> devices; pl.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    cl::Device dev = devices.at(0);
    cl::Context ctx(dev); cl::CommandQueue q(ctx, dev);
    // Built with exactly the dumped options, as clrt built it.
    cl::Program program(ctx, src);
    buildOrExit(program, dev, options);
    {  // what the compiler says about shade_hits (Intel's runtime: whether it vectorised it, and how wide)
        std::istringstream log(program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(dev));
        for (std::string line; std::getline(log, line);)
            if (line.find("shade_hits") != std::string::npos) fprintf(stderr, "shade_hits_alone: build log: %s\n", line.c_str());
    }
    clrt::KernelArgs k(program, "shade_hits");
    cl_uint nargs = cl_uint(k.decl().params.size());
    const char* names = "checked";
    if (checkDeclaration(k.kernel(), k.decl()) == 0) {
        // This runtime reports no names without -cl-kernel-arg-info (PoCL): a second build with it, for
        // the check only (the launch uses the program above).
        cl::Program withInfo(ctx, src);
        buildOrExit(withInfo, dev, options + " -cl-kernel-arg-info");
        if (checkDeclaration(CL_CPP(cl::Kernel(withInfo, "shade_hits")), k.decl()) == 0) names = "not reported";
        else names = "checked (-cl-kernel-arg-info build)";
    }
    fprintf(stderr, "shade_hits_alone: %s: %s; shade_hits' %u arguments as src/shared/kernel_params.h declares (names %s)\n",
            argv[3], pl.getInfo<CL_PLATFORM_NAME>().c_str(), nargs, names);
    const int N = 8192;
    std::vector<PathState> paths(N); std::vector<Ray> rays(N); std::vector<Hit> hits(N);
    std::vector<Triangle> tris(N); std::vector<TriangleShading> sh(N); std::vector<float> attr(size_t(N) * 15);
    for (int i = 0; i < N; ++i) {
        float cx = rnd() * 4 - 2, cy = rnd() * 4 - 2, cz = -3 - rnd() * 2;
        float v[3][3];
        for (int a = 0; a < 3; ++a) { v[a][0] = cx + rnd() * 0.2f - 0.1f; v[a][1] = cy + rnd() * 0.2f - 0.1f; v[a][2] = cz + rnd() * 0.2f - 0.1f; }
        tris[i].v0 = {v[0][0], v[0][1], v[0][2], 0}; tris[i].v1 = {v[1][0], v[1][1], v[1][2], 0}; tris[i].v2 = {v[2][0], v[2][1], v[2][2], 0};
        float e1[3], e2[3], n[3];
        for (int a = 0; a < 3; ++a) { e1[a] = v[1][a] - v[0][a]; e2[a] = v[2][a] - v[0][a]; }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1]; n[1] = e1[2] * e2[0] - e1[0] * e2[2]; n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        float l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]); for (int a = 0; a < 3; ++a) n[a] /= l;
        float4 nn[3];
        for (int a = 0; a < 3; ++a) nn[a] = {n[0] + 0.1f * (rnd() - 0.5f), n[1] + 0.1f * (rnd() - 0.5f), n[2] + 0.1f * (rnd() - 0.5f), 0};
        float* corner = &attr[size_t(i) * 15];  // normals, then uvs (TriangleShading.attributes)
        for (int a = 0; a < 3; ++a) { corner[3 * a] = nn[a].x; corner[3 * a + 1] = nn[a].y; corner[3 * a + 2] = nn[a].z; }
        for (int a = 9; a < 15; ++a) corner[a] = rnd();
        sh[i].attributes = CLRT_TRI_NORMALS | CLRT_TRI_UVS | unsigned(i * 15);
        float u = rnd(); sh[i].material = u < 0.3f ? 0 : u < 0.45f ? 1 : 2;
        sh[i].textureSet = (sh[i].material == 0 && rnd() < 0.7f) ? 0 : -1;
        sh[i].light = -1;
        float b1 = 0.2f + 0.3f * rnd(), b2 = 0.2f + 0.3f * rnd(), b0 = 1 - b1 - b2;
        float h[3]; for (int a = 0; a < 3; ++a) h[a] = b0 * v[0][a] + b1 * v[1][a] + b2 * v[2][a];
        float o[3] = {0.1f * rnd(), 0.1f * rnd(), 0.0f};
        float d[3] = {h[0] - o[0], h[1] - o[1], h[2] - o[2]}; float dl = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        rays[i].origin = {o[0], o[1], o[2], 0}; rays[i].direction = {d[0] / dl, d[1] / dl, d[2] / dl, INFINITY};
        hits[i].t = dl; hits[i].prim = rnd() < 0.05f ? -1 : i; hits[i].u = b1; hits[i].v = b2;
        paths[i].throughput = {1, 1, 1, 0}; paths[i].pixel = i / 2; paths[i].sample = i & 1; paths[i].depth = int(rnd() * 3); paths[i].pathId = 1;
    }
    std::vector<Material> mats(3); memset(mats.data(), 0, sizeof(Material) * 3);
    for (auto& m : mats) { m.brdf = -1; m.phongExponent = 10; m.diffuse = {0.5f, 0.5f, 0.5f, 0}; m.ambient = {0.1f, 0.1f, 0.1f, 0}; }
    mats[1].kind = MATERIAL_MIRROR; mats[1].mirror = {0.4f, 0.4f, 0.4f, 0};
    mats[2].kind = MATERIAL_DIELECTRIC; mats[2].refractionIndex = 1.3f; mats[2].absorption = {0.1f, 0, 0.1f, 0}; mats[2].diffuse = {0, 0, 0, 0};
    TextureSet ts{}; ts.texture[0] = 0; ts.texture[1] = ts.texture[2] = ts.texture[3] = -1;
    ts.worldToObject[0] = {1, 0, 0, 0}; ts.worldToObject[1] = {0, 1, 0, 0}; ts.worldToObject[2] = {0, 0, 1, 0};
    TextureMap tm{}; tm.kind = TEXTURE_CHECKERBOARD; tm.decal = DECAL_REPLACE_KD; tm.image = -1; tm.blackColor = {0.1f, 0.1f, 0.1f, 0}; tm.whiteColor = {0.9f, 0.9f, 0.9f, 0}; tm.scale = 3; tm.offset = 0.01f; tm.normalizer = 255;
    ImageInfo img{0, 1, 1, 0}; float4 texel{1, 1, 1, 1}; Light light{}; float envd = 0; Sphere sph{}; Plane pla{};
    SceneParams sc{}; sc.numTriangles = N; sc.numSpheres = 0; sc.numPlanes = 0; sc.numLights = 1; sc.maxDepth = 8; sc.backgroundTexture = -1; sc.envLight = -1; sc.seed = 7; sc.splitDepth = 2; sc.envImage = -1;
    sc.background = {0.2f, 0.3f, 0.4f, 0}; sc.ambient = {0.1f, 0.1f, 0.1f, 0};
    CameraParams cam{}; cam.width = N / 2; cam.height = 1; cam.spp = 2;
    auto ro = [&](size_t bytes, const void* data) { return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, (void*)data)); };
    auto rw = [&](size_t bytes) { cl::Buffer m = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE, bytes));
        std::vector<unsigned char> z(bytes, 0xAB); CL_CPP(q.enqueueWriteBuffer(m, CL_TRUE, 0, bytes, z.data())); return m; };
    // hitInstances: every hit on a world-space primitive (read only when the program has CLRT_HAS_INSTANCES).
    std::vector<int> hitInst(N, CLRT_INVALID); Instance inst{}; int count = N;
    ShadeArgs a;
    a.queueCount = ro(sizeof count, &count); a.scene = sc; a.cam = cam;
    a.paths = ro(sizeof(PathState) * N, paths.data()); a.rays = ro(sizeof(Ray) * N, rays.data()); a.hits = ro(sizeof(Hit) * N, hits.data());
    a.hitInstances = ro(sizeof(int) * N, hitInst.data());
    a.tris = ro(sizeof(Triangle) * N, tris.data()); a.triShading = ro(sizeof(TriangleShading) * N, sh.data()); a.triAttributes = ro(sizeof(float) * attr.size(), attr.data());
    a.spheres = ro(sizeof sph, &sph); a.planes = ro(sizeof pla, &pla); a.instances = ro(sizeof inst, &inst);
    a.materials = ro(sizeof(Material) * 3, mats.data()); a.textureSets = ro(sizeof ts, &ts); a.textures = ro(sizeof tm, &tm); a.images = ro(sizeof img, &img); a.texels = ro(sizeof texel, &texel);
    a.lights = ro(sizeof light, &light); a.envDist = ro(sizeof envd, &envd);
    a.points = rw(sizeof(ShadingPoint) * N); a.pathRadiance = rw(sizeof(float4) * N); a.nextPaths = rw(sizeof(PathState) * 2 * N); a.nextRays = rw(sizeof(Ray) * 2 * N); a.childValid = rw(sizeof(int) * 2 * N);
    CLRT_BIND_GROUP(k, CLRT_KERNEL_shade_hits, a);
    CL_CPP(q.enqueueNDRangeKernel(k.ready(), cl::NullRange, cl::NDRange(N), cl::NDRange(64)));
    CL_CPP(q.finish());
    std::vector<int> valid(2 * N); std::vector<PathState> np2(2 * N); std::vector<Ray> nr(2 * N); std::vector<ShadingPoint> pts(N); std::vector<float4> rad(N);
    CL_CPP(q.enqueueReadBuffer(a.childValid, CL_TRUE, 0, sizeof(int) * 2 * N, valid.data()));
    CL_CPP(q.enqueueReadBuffer(a.nextPaths, CL_TRUE, 0, sizeof(PathState) * 2 * N, np2.data()));
    CL_CPP(q.enqueueReadBuffer(a.nextRays, CL_TRUE, 0, sizeof(Ray) * 2 * N, nr.data()));
    CL_CPP(q.enqueueReadBuffer(a.points, CL_TRUE, 0, sizeof(ShadingPoint) * N, pts.data()));
    CL_CPP(q.enqueueReadBuffer(a.pathRadiance, CL_TRUE, 0, sizeof(float4) * N, rad.data()));
    // only the valid children count
    for (int i = 0; i < 2 * N; ++i) if (!valid[i]) { memset(&np2[i], 0, sizeof(PathState)); memset(&nr[i], 0, sizeof(Ray)); }
    FILE* o = fopen(argv[4], "wb");
    if (!o) { fprintf(stderr, "shade_hits_alone: cannot write %s\n", argv[4]); return 1; }
    fwrite(valid.data(), sizeof(int), 2 * N, o); fwrite(np2.data(), sizeof(PathState), 2 * N, o); fwrite(nr.data(), sizeof(Ray), 2 * N, o);
    fwrite(rad.data(), sizeof(float4), N, o); fclose(o);
    return 0;
}

int main(int argc, char** argv) {
    if (argc == 4 && !strcmp(argv[1], "--compare")) return compare(argv[2], argv[3]);
    if (argc != 5) { fprintf(stderr, "usage: shade_hits_alone PROGRAM.cl OPTIONS PLATFORM OUT.bin | --compare A B\n"); return 1; }
    try {
        return run(argv);
    } catch (const clrt::Error& e) {
        fprintf(stderr, "shade_hits_alone: %s\n", e.what());
    } catch (const cl::Error& e) {
        fprintf(stderr, "shade_hits_alone: OpenCL error %s (%d) in %s\n", clrt::clErrorName(e.err()), e.err(), e.what());
    }
    return 1;
}
