// shade_hits_alone.cpp — issue 17's standalone reproducer: runs the render program's shade_hits kernel
// alone, on synthetic hits (8192 paths on random small triangles: a checkerboard-textured diffuse
// material, a mirror and a dielectric with Beer absorption; 5% misses; depths 0..2 with splitDepth 2),
// no scene file, no BVH, and writes its outputs (childValid, the children, the path radiance).
// The program is one that clrt dumped (CLRT_DUMP_PROGRAM=DIR writes DIR/<hash>.cl and .options).
// Intel's OpenCL CPU runtime (2026.22) with its vectoriser gives children unlike PoCL's
// (scripts/intel_vectorizer_repro.sh runs it); with CL_CONFIG_USE_VECTORIZER=False, or with
// shade_hits' vec_type_hint(float4), it agrees.
// Built by scripts/intel_vectorizer_repro.sh (g++ -Isrc ... -lOpenCL), not by CMake.
// It binds shade_hits' arguments by index, in issue 17's parameter list: it runs against a program dumped by
// a build before 6682b8f (queueCount became a buffer there); with later programs clSetKernelArg fails with -51
// (docs/quirks.md, INTEL_VEC_HINT).
// usage: shade_hits_alone PROGRAM.cl OPTIONS PLATFORM_SUBSTRING OUT.bin
//        shade_hits_alone --compare A.bin B.bin
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>
#include "shared/device_types.h"
using namespace clrt::dev;
static unsigned st = 12345;
static float rnd() { st = st * 1664525u + 1013904223u; return (st >> 8) * (1.0f / 16777216.0f); }
#define CK(x) do { cl_int e_ = (x); if (e_) { fprintf(stderr, "%s: %d\n", #x, e_); exit(1); } } while (0)
static int compare(const char* fa, const char* fb) {
    auto load = [](const char* f) { std::ifstream in(f, std::ios::binary); return std::vector<char>(std::istreambuf_iterator<char>(in), {}); };
    std::vector<char> a = load(fa), b = load(fb);
    const int N = 8192;
    if (a.size() != b.size() || a.size() < sizeof(int) * 2 * N) { printf("output sizes differ\n"); return 1; }
    const int* va = (const int*)a.data(); const int* vb = (const int*)b.data();
    int dv = 0; for (int i = 0; i < 2 * N; ++i) dv += va[i] != vb[i];
    const float* xa = (const float*)a.data() + 2 * N; const float* xb = (const float*)b.data() + 2 * N;
    size_t nf = a.size() / 4 - 2 * N, bad = 0;
    for (size_t i = 0; i < nf; ++i) {
        float x = xa[i], y = xb[i];
        if (x != y && !(std::isnan(x) && std::isnan(y)) && std::fabs(x - y) > 1e-3f * std::fmax(std::fmax(std::fabs(x), std::fabs(y)), 1e-6f)) ++bad;
    }
    printf("childValid differs in %d of %d slots; %zu of %zu output floats differ by more than 1e-3 relative\n", dv, 2 * N, bad, nf);
    return dv || bad ? 2 : 0;
}

int main(int argc, char** argv) {
    if (argc == 4 && !strcmp(argv[1], "--compare")) return compare(argv[2], argv[3]);
    if (argc != 5) { fprintf(stderr, "usage: shade_hits_alone PROGRAM.cl OPTIONS PLATFORM OUT.bin | --compare A B\n"); return 1; }
    std::ifstream in(argv[1]); std::stringstream ss; ss << in.rdbuf(); std::string src = ss.str();
    cl_platform_id ps[8]; cl_uint np; clGetPlatformIDs(8, ps, &np); cl_platform_id pl = 0;
    for (cl_uint i = 0; i < np; ++i) { char name[256]; clGetPlatformInfo(ps[i], CL_PLATFORM_NAME, 256, name, 0); if (strstr(name, argv[3])) pl = ps[i]; }
    if (!pl) { fprintf(stderr, "no OpenCL platform named *%s*\n", argv[3]); return 1; }
    cl_device_id dev; clGetDeviceIDs(pl, CL_DEVICE_TYPE_ALL, 1, &dev, 0);
    cl_int e; cl_context ctx = clCreateContext(0, 1, &dev, 0, 0, &e); cl_command_queue q = clCreateCommandQueue(ctx, dev, 0, &e);
    const char* s = src.c_str();
    cl_program p = clCreateProgramWithSource(ctx, 1, &s, 0, &e);
    e = clBuildProgram(p, 1, &dev, argv[2], 0, 0);
    static char log[1 << 20]; clGetProgramBuildInfo(p, dev, CL_PROGRAM_BUILD_LOG, sizeof log, log, 0);
    if (e) { fprintf(stderr, "build %d\n%s\n", e, log); return 1; }
    cl_kernel k = clCreateKernel(p, "shade_hits", &e); CK(e);
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
    auto ro = [&](size_t bytes, const void* data) { cl_int e2; cl_mem m = clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, (void*)data, &e2); CK(e2); return m; };
    auto rw = [&](size_t bytes) { cl_int e2; cl_mem m = clCreateBuffer(ctx, CL_MEM_READ_WRITE, bytes, 0, &e2); CK(e2);
        std::vector<unsigned char> z(bytes, 0xAB); clEnqueueWriteBuffer(q, m, CL_TRUE, 0, bytes, z.data(), 0, 0, 0); return m; };
    cl_mem bPaths = ro(sizeof(PathState) * N, paths.data()), bRays = ro(sizeof(Ray) * N, rays.data()), bHits = ro(sizeof(Hit) * N, hits.data());
    cl_mem bTris = ro(sizeof(Triangle) * N, tris.data()), bSh = ro(sizeof(TriangleShading) * N, sh.data()), bAttr = ro(sizeof(float) * attr.size(), attr.data()), bSph = ro(sizeof sph, &sph), bPla = ro(sizeof pla, &pla);
    cl_mem bMat = ro(sizeof(Material) * 3, mats.data()), bTs = ro(sizeof ts, &ts), bTm = ro(sizeof tm, &tm), bImg = ro(sizeof img, &img), bTex = ro(sizeof texel, &texel);
    cl_mem bLight = ro(sizeof light, &light), bEnv = ro(sizeof envd, &envd);
    cl_mem bPts = rw(sizeof(ShadingPoint) * N), bRad = rw(sizeof(float4) * N), bNP = rw(sizeof(PathState) * 2 * N), bNR = rw(sizeof(Ray) * 2 * N), bV = rw(sizeof(int) * 2 * N);
    int a = 0; int cnt = N;
    CK(clSetKernelArg(k, a++, sizeof cnt, &cnt)); CK(clSetKernelArg(k, a++, sizeof sc, &sc)); CK(clSetKernelArg(k, a++, sizeof cam, &cam));
    cl_mem bufs[] = {bPaths, bRays, bHits, bTris, bSh, bAttr, bSph, bPla, bMat, bTs, bTm, bImg, bTex, bLight, bPts, bRad, bEnv, bNP, bNR, bV};
    for (cl_mem& m : bufs) CK(clSetKernelArg(k, a++, sizeof(cl_mem), &m));
    size_t g = N, l = 64;
    CK(clEnqueueNDRangeKernel(q, k, 1, 0, &g, &l, 0, 0, 0)); clFinish(q);
    std::vector<int> valid(2 * N); std::vector<PathState> np2(2 * N); std::vector<Ray> nr(2 * N); std::vector<ShadingPoint> pts(N); std::vector<float4> rad(N);
    clEnqueueReadBuffer(q, bV, 1, 0, sizeof(int) * 2 * N, valid.data(), 0, 0, 0);
    clEnqueueReadBuffer(q, bNP, 1, 0, sizeof(PathState) * 2 * N, np2.data(), 0, 0, 0);
    clEnqueueReadBuffer(q, bNR, 1, 0, sizeof(Ray) * 2 * N, nr.data(), 0, 0, 0);
    clEnqueueReadBuffer(q, bPts, 1, 0, sizeof(ShadingPoint) * N, pts.data(), 0, 0, 0);
    clEnqueueReadBuffer(q, bRad, 1, 0, sizeof(float4) * N, rad.data(), 0, 0, 0);
    // only the valid children count
    for (int i = 0; i < 2 * N; ++i) if (!valid[i]) { memset(&np2[i], 0, sizeof(PathState)); memset(&nr[i], 0, sizeof(Ray)); }
    FILE* o = fopen(argv[4], "wb");
    fwrite(valid.data(), sizeof(int), 2 * N, o); fwrite(np2.data(), sizeof(PathState), 2 * N, o); fwrite(nr.data(), sizeof(Ray), 2 * N, o);
    fwrite(rad.data(), sizeof(float4), N, o); fclose(o);
    return 0;
}
