// Light tests: environment maps (mappings and their round trips at poles and seam; the importance
// distribution's pdf integrating to one over the sphere, chi-square of its samples, pdf from
// evaluation = pdf from sampling, on real maps incl. sunset.exr and on 1x1 maps; the device sampling
// and lookup functions against these host references on PoCL; half4 texels: packed only when exact,
// looked up bit for bit as their float4 image), the white furnace per sampler and
// mapping (a kd = 0.5 sphere under radiance 1 shows π/2), spot/directional/area/environment
// Light_Sample kernels against host reference evaluations at random points, the mis env strategy's
// cosine-weighted tables (each bucket's pdf integrating to one, chi-square, cells and buckets covering
// texels and normals, the device's bucket, samples and pdfs against EnvCosineTable), Math_Atan2
// against libm, and (tagged [.slow],
// run by scripts/env_sampling_compare.sh) the relMSE of each env strategy on sunset.exr.
#include <catch.hpp>

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <fstream>
#include <random>
#include <sstream>

#include "cl/check.h"
#include "flatten/device_scene.h"
#include "flatten/env_distribution.h"
#include "image/image_compare.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

constexpr double kPiD = 3.14159265358979323846;

struct HostMap {
    std::vector<dev::float4> texels;
    EnvMapView view;
    EnvDistribution dist;
};

HostMap makeMap(const ImageRGB& img, int mapping) {
    HostMap m;
    m.texels.resize(size_t(img.width) * img.height);
    for (size_t p = 0; p < m.texels.size(); ++p)
        m.texels[p] = {img.pixels[p * 3], img.pixels[p * 3 + 1], img.pixels[p * 3 + 2], 0};
    m.view = EnvMapView{m.texels.data(), img.width, img.height, mapping};
    m.dist = buildEnvDistribution(m.view);
    return m;
}

ImageRGB constantImage(int w, int h, float value) {
    ImageRGB img;
    img.width = w;
    img.height = h;
    img.isHdr = true;
    img.pixels.assign(size_t(w) * h * 3, value);
    return img;
}

// A w×h map of odd sizes with dark texels (every 5th, and all of row 3 and column 4): rows and cells of zero
// probability, and CDF searches over lengths that are not powers of two (the shared maps' are).
ImageRGB patternImage(int w, int h) {
    ImageRGB img = constantImage(w, h, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                const bool dark = (x * 7 + y * 3) % 5 == 0 || y == 3 || x == 4;
                img.pixels[(size_t(y) * w + x) * 3 + c] = dark ? 0.0f : 0.1f + float((x * 13 + y * 29 + c * 5) % 17);
            }
    return img;
}

// ∫ f(ω) dω over the sphere, by the midpoint rule on the six faces of a cube (M×M cells each): a
// parameterisation independent of both env mappings.
template <class F> double integrateSphere(F f, int M) {
    double sum = 0;
    for (int face = 0; face < 6; ++face)
        for (int b = 0; b < M; ++b)
            for (int a = 0; a < M; ++a) {
                double s = 2.0 * (a + 0.5) / M - 1.0, t = 2.0 * (b + 0.5) / M - 1.0;
                double dw = (4.0 / (double(M) * M)) / std::pow(1.0 + s * s + t * t, 1.5);
                Vec3 d;
                int axis = face / 2;
                float sign = (face & 1) ? -1.0f : 1.0f;
                if (axis == 0) d = Vec3(sign, float(s), float(t));
                else if (axis == 1) d = Vec3(float(s), sign, float(t));
                else d = Vec3(float(s), float(t), sign);
                sum += f(normalize(d)) * dw;
            }
    return sum;
}

// Upper critical value of chi-square with k degrees of freedom at z standard deviations (Wilson-Hilferty).
double chi2Critical(int k, double z) {
    double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

struct NamedMap {
    std::string name;
    HostMap map;
};

std::vector<NamedMap> testMaps() {
    std::vector<NamedMap> maps;
    maps.push_back({"1x1 latlong", makeMap(constantImage(1, 1, 2.0f), dev::ENV_LATLONG)});
    maps.push_back({"1x1 probe", makeMap(constantImage(1, 1, 2.0f), dev::ENV_PROBE)});
    maps.push_back({"37x19 latlong pattern", makeMap(patternImage(37, 19), dev::ENV_LATLONG)});
    maps.push_back({"21x21 probe pattern", makeMap(patternImage(21, 21), dev::ENV_PROBE)});
    if (haveShared()) {
        std::string e = sharedDir() + "/envmaps/";
        maps.push_back({"sunset.exr", makeMap(readImage(e + "sunset.exr"), dev::ENV_LATLONG)});
        maps.push_back({"sunset_probe.exr", makeMap(readImage(e + "sunset_probe.exr"), dev::ENV_PROBE)});
        maps.push_back({"interior.exr", makeMap(readImage(e + "interior.exr"), dev::ENV_LATLONG)});
        maps.push_back({"courtyard_probe.exr", makeMap(readImage(e + "courtyard_probe.exr"), dev::ENV_PROBE)});
    } else {
        WARN("../shared is not present: real environment maps skipped");
    }
    return maps;
}

const std::vector<NamedMap>& sharedMaps() {
    static std::vector<NamedMap> maps = testMaps();
    return maps;
}

float angleBetween(const Vec3& a, const Vec3& b) {  // robust for tiny angles (acos of a dot is not)
    return 2.0f * std::asin(std::min(1.0f, 0.5f * length(normalize(a) - normalize(b))));
}

std::string writeFile(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    return path;
}

// A scene: camera at the origin looking down -z, a sphere (radius 2 at z = -5, kd given, no specular)
// under an environment light on `image` (relative to the scene), and optionally more.
std::string envSceneXml(const std::string& image, const std::string& type, const std::string& sampler, int size,
                        int spp, const std::string& kd = "0.5 0.5 0.5", const std::string& extraObjects = "",
                        const std::string& ks = "0 0 0", float fovY = 60, const std::string& camPos = "0 0 0",
                        const std::string& gazePoint = "0 0 -1") {
    std::ostringstream s;
    s << "<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>2</MaxRecursionDepth>"
      << "<Cameras><Camera id=\"1\" type=\"lookAt\"><Position>" << camPos << "</Position><GazePoint>" << gazePoint
      << "</GazePoint>"
      << "<Up>0 1 0</Up><FovY>" << fovY << "</FovY><NearDistance>1</NearDistance><ImageResolution>" << size << " "
      << size << "</ImageResolution><ImageName>out.exr</ImageName><NumSamples>" << spp << "</NumSamples></Camera></Cameras>"
      << "<VertexData>0 0 -5  -30 -2 30  30 -2 30  30 -2 -60  -30 -2 -60</VertexData>"
      << "<Materials><Material id=\"1\"><AmbientReflectance>0 0 0</AmbientReflectance><DiffuseReflectance>" << kd
      << "</DiffuseReflectance><SpecularReflectance>" << ks << "</SpecularReflectance><PhongExponent>20</PhongExponent>"
      << "</Material><Material id=\"2\"><DiffuseReflectance>0.6 0.6 0.6</DiffuseReflectance></Material></Materials>"
      << "<Textures><Images><Image id=\"1\">" << image << "</Image></Images></Textures>"
      << "<Lights><SphericalDirectionalLight id=\"1\" type=\"" << type << "\" sampler=\"" << sampler
      << "\"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>"
      << "<Objects><Sphere id=\"1\"><Center>1</Center><Radius>2</Radius><Material>1</Material></Sphere>" << extraObjects
      << "</Objects></Scene>";
    return s.str();
}

// The light feature flags of the program for the light kinds in `kinds` (bit per dev::LightKind), from
// the light table: the kernels compile the Light_Sample cases of these kinds only.
std::vector<std::string> lightFlags(uint32_t kinds) {
    FeatureSet f;
    f.lightKinds = kinds;
    return f.defines();
}

ImageRGB renderFile(const std::string& path, int spp, dev::EnvStrategy* override = nullptr, uint32_t seed = 1) {
    Scene scene = loadScene(path);
    if (override) overrideEnvStrategy(scene, *override);
    return renderCamera(scene, scene.cameras.at(0), spp, seed);
}

const char* kSamplerNames[] = {"uniform", "cosine", "importance", "mis"};

}  // namespace

TEST_CASE("env mappings round-trip at the poles, the seam and the probe rim", "[lights][env]") {
    for (int mapping : {int(dev::ENV_LATLONG), int(dev::ENV_PROBE)}) {
        INFO("mapping " << mapping);
        std::vector<Vec3> dirs = {{0, 1, 0}, {0, -1, 0}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0},
                                  {0, 0.999999f, 0.0014f}, {0, -0.999999f, -0.0014f},  // next to the poles
                                  {-1e-6f, 0.3f, 0.95f}, {1e-6f, 0.3f, 0.95f},       // either side of the seam
                                  {0.001f, 0.002f, 0.99999f}, {0.3f, -0.2f, 0.93f}};  // near the probe rim
        std::mt19937 rng(5);
        std::normal_distribution<float> g;
        for (int k = 0; k < 2000; ++k) dirs.push_back(Vec3(g(rng), g(rng), g(rng)));
        float worst = 0;
        for (Vec3 d : dirs) {
            d = normalize(d);
            float u, v;
            envDirToUv(mapping, d, u, v);
            REQUIRE(u >= 0.0f);
            REQUIRE(u <= 1.0f);
            REQUIRE(v >= 0.0f);
            REQUIRE(v <= 1.0f);
            Vec3 back;
            REQUIRE(envUvToDir(mapping, u, v, back));
            worst = std::max(worst, angleBetween(d, back));
        }
        CHECK(worst < 1e-5f);  // radians
        // (u,v) -> dir -> (u,v), including u = 0 / 1 (seam) and v = 0 / 1 (poles).
        for (float u : {0.0f, 1e-4f, 0.25f, 0.5f, 0.9999f, 1.0f})
            for (float v : {0.0f, 1e-4f, 0.3f, 0.5f, 0.9999f, 1.0f}) {
                Vec3 d;
                if (!envUvToDir(mapping, u, v, d)) continue;
                float u2, v2;
                envDirToUv(mapping, d, u2, v2);
                Vec3 d2;
                REQUIRE(envUvToDir(mapping, u2, v2, d2));
                CHECK(angleBetween(d, d2) < 1e-5f);
                bool pole = mapping == dev::ENV_LATLONG && (v < 1e-3f || v > 0.999f);
                bool rim = mapping == dev::ENV_PROBE && ((2 * u - 1) * (2 * u - 1) + (1 - 2 * v) * (1 - 2 * v) > 0.999f);
                if (!pole && !rim) {
                    float du = std::fabs(u - u2);
                    if (mapping == dev::ENV_LATLONG) du = std::min(du, 1.0f - du);  // the seam
                    CHECK(du < 1e-3f);
                    CHECK(std::fabs(v - v2) < 1e-3f);
                }
            }
    }
    // The conventions of SCENE_FORMAT.md at a few fixed points.
    float u, v;
    envDirToUv(dev::ENV_LATLONG, Vec3(0, 0, -1), u, v);
    CHECK(u == Approx(0.5f));
    CHECK(v == Approx(0.5f));
    envDirToUv(dev::ENV_LATLONG, Vec3(1, 0, 0), u, v);
    CHECK(u == Approx(0.75f));
    envDirToUv(dev::ENV_PROBE, Vec3(0, 0, -1), u, v);
    CHECK(u == Approx(0.5f));
    CHECK(v == Approx(0.5f));
    envDirToUv(dev::ENV_PROBE, Vec3(0, 1, 0), u, v);  // θ = π/2: R = 1/2 upwards
    CHECK(u == Approx(0.5f));
    CHECK(v == Approx(0.25f));
}

TEST_CASE("env importance pdf integrates to one over the sphere", "[lights][env]") {
    for (const NamedMap& nm : sharedMaps()) {
        INFO(nm.name);
        const EnvDistribution& d = nm.map.dist;
        const int M = nm.name.rfind("1x1", 0) == 0 ? 256 : 2048;  // interior.exr: 0.9908 at 1024, 1.0048 at 2048, 1.0004 at 4096
        double integral = integrateSphere([&](const Vec3& w) { return double(d.pdf(w)); }, M);
        WARN(nm.name << ": ∫pdf dω = " << integral);
        CHECK(integral == Approx(1.0).epsilon(0.01));
        if (nm.name == "1x1 latlong") {  // uniform over the sphere: within a cell, uniform in solid angle
            CHECK(d.pdf(Vec3(0, 1, 0)) == Approx(1.0 / (4 * kPiD)).epsilon(1e-4));
            CHECK(d.pdf(normalize(Vec3(0.3f, 0.4f, -0.5f))) == Approx(1.0 / (4 * kPiD)).epsilon(1e-4));
        }
    }
}

TEST_CASE("env importance samples follow the pdf (chi-square) and report the pdf evaluation gives", "[lights][env]") {
    for (const NamedMap& nm : sharedMaps()) {
        INFO(nm.name);
        const EnvDistribution& d = nm.map.dist;
        const int W = d.width, H = d.height;
        // Bins: blocks of cells; expected probabilities from the distribution's own cell masses.
        const int BU = std::min(W, 32), BV = std::min(H, 16);
        std::vector<double> expected(BU * BV, 0.0), observed(BU * BV, 0.0);
        const float* marg = &d.data[4];
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const float* cond = &d.data[4 + H + 1 + size_t(j) * (W + 1)];
                expected[(j * BV / H) * BU + i * BU / W] += double(marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]);
            }
        const int N = 400000;
        std::mt19937 rng(17);
        std::uniform_real_distribution<float> uni(0.0f, 1.0f);
        int failed = 0, pdfMismatch = 0, invalid = 0;
        for (int n = 0; n < N; ++n) {
            float u1 = std::min(uni(rng), 0.99999994f), u2 = std::min(uni(rng), 0.99999994f);
            Vec3 w;
            float pdf;
            if (!d.sample(u1, u2, w, pdf)) { ++failed; continue; }
            if (!(std::fabs(length(w) - 1.0f) < 1e-4f)) ++invalid;
            float u, v;
            envDirToUv(d.mapping, w, u, v);
            int bi = std::clamp(int(u * W), 0, W - 1) * BU / W, bj = std::clamp(int(v * H), 0, H - 1) * BV / H;
            observed[bj * BU + bi] += 1;
            float pe = d.pdf(w);
            if (!(std::fabs(pe - pdf) <= 1e-3f * pdf)) ++pdfMismatch;
        }
        CHECK(invalid == 0);
        CHECK(failed <= N / 10000);          // probe rim rejections that ran out of tries
        CHECK(pdfMismatch <= N / 1000);      // cell-boundary round-off only
        double chi2 = 0;
        int dof = -1;
        double pool = 0, poolObs = 0;
        for (size_t b = 0; b < expected.size(); ++b) {
            double e = expected[b] * (N - failed);
            if (e < 5) { pool += e; poolObs += observed[b]; continue; }
            chi2 += (observed[b] - e) * (observed[b] - e) / e;
            ++dof;
        }
        if (pool >= 5) { chi2 += (poolObs - pool) * (poolObs - pool) / pool; ++dof; }
        if (dof >= 1) {
            double crit = chi2Critical(dof, 4.0);
            WARN(nm.name << ": chi2 " << chi2 << " with " << dof << " dof (critical " << crit << "), pdf mismatches "
                         << pdfMismatch << ", failed " << failed);
            CHECK(chi2 < crit);
        }
    }
    // The 1×1 maps in direction space: 1×1 lat-long is uniform over the sphere; check the fraction
    // of samples in the upper hemisphere and in a polar cap against the pdf's integral there.
    for (const NamedMap& nm : sharedMaps()) {
        if (nm.name.rfind("1x1", 0) != 0) continue;
        INFO(nm.name);
        const EnvDistribution& d = nm.map.dist;
        auto cap = [&](const Vec3& w) { return w.z < -0.5f ? 1.0 : 0.0; };
        double pCap = integrateSphere([&](const Vec3& w) { return cap(w) * d.pdf(w); }, 256);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
        int N = 200000, in = 0, ok = 0;
        for (int n = 0; n < N; ++n) {
            Vec3 w;
            float pdf;
            if (!d.sample(uni(rng), uni(rng), w, pdf)) continue;
            ++ok;
            in += cap(w) > 0;
        }
        double frac = double(in) / ok, sigma = std::sqrt(pCap * (1 - pCap) / ok);
        CHECK(std::fabs(frac - pCap) < 5 * sigma + 1e-3);
    }
}

TEST_CASE("env sampling and lookup kernels match the host references", "[lights][env][cl]") {
    const char* src = R"CLC(
__kernel void env_test(const __global float* dist, const __global float4* texels, ImageInfo img, int mapping,
                       const __global float4* in, __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    float4 a = in[i];
    float3 d; float pdf;
    int ok = EnvDist_Sample(dist, a.x, a.y, &d, &pdf);
    out[5 * i] = (float4)(d, ok ? pdf : -1.0f);
    float3 q = normalize((float3)(a.z, a.w, a.x - 0.5f));
    out[5 * i + 1] = (float4)(EnvMap_Radiance(texels, img, mapping, (float3)(1.0f), q),
                            EnvDist_PdfUv(dist, EnvMap_DirToUv(mapping, q)));
    float2 uv = EnvMap_DirToUv(mapping, q);
    float3 back;
    int okb = EnvMap_UvToDir(mapping, uv.x, uv.y, &back);
    out[5 * i + 2] = (float4)(uv, okb ? EnvMap_UvToSolidAngle(mapping, uv.x, uv.y) : -1.0f, 0.0f);
    out[5 * i + 3] = (float4)(back, 0.0f);
    /* u outside [0, 1] too (the lookup's general wrap), v in [0, 1) */
    out[5 * i + 4] = (float4)(EnvMap_Lookup(texels, img, mapping, 1.75f * a.z + 0.5f, a.x), 0.0f);
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"envmap.cl"});
    sources.push_back({"env_test.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, {});
    cl::Kernel k = CL_CPP(cl::Kernel(program, "env_test"));
    for (const NamedMap& nm : sharedMaps()) {
        INFO(nm.name);
        const HostMap& m = nm.map;
        const int n = 20000;
        std::mt19937 rng(11);
        std::uniform_real_distribution<float> uni(0.0f, 0.99999994f), sym(-1.0f, 1.0f);
        std::vector<dev::float4> in(n), out(5 * size_t(n));
        for (auto& a : in) a = {uni(rng), uni(rng), sym(rng), sym(rng)};
        cl::Context& ctx = dc.context();
        auto ro = [&](const void* p, size_t bytes) {
            return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(p)));
        };
        cl::Buffer dist = ro(m.dist.data.data(), m.dist.data.size() * sizeof(float));
        cl::Buffer tex = ro(m.texels.data(), m.texels.size() * sizeof(dev::float4));
        cl::Buffer inBuf = ro(in.data(), in.size() * sizeof(dev::float4));
        cl::Buffer outBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
        dev::ImageInfo img{0, m.view.width, m.view.height, 0};
        int mapping = m.view.mapping;
        k.setArg(0, dist); k.setArg(1, tex); k.setArg(2, sizeof(img), &img); k.setArg(3, mapping);
        k.setArg(4, inBuf); k.setArg(5, outBuf); k.setArg(6, n);
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(outBuf, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
        int sampleBad = 0, okMismatch = 0, radBad = 0, pdfBad = 0, uvBad = 0, wrapBad = 0;
        for (int i = 0; i < n; ++i) {
            Vec3 w;
            float pdf;
            bool ok = m.dist.sample(in[i].x, in[i].y, w, pdf);
            const dev::float4& o = out[5 * i];
            if (ok != (o.w >= 0)) { ++okMismatch; continue; }
            if (ok && (angleBetween(w, Vec3(o.x, o.y, o.z)) > 1e-4f || std::fabs(o.w - pdf) > 1e-3f * pdf)) {
                if (++sampleBad <= 3)
                    WARN("sample " << in[i].x << " " << in[i].y << ": host " << w.x << " " << w.y << " " << w.z << " pdf " << pdf
                                   << ", device " << o.x << " " << o.y << " " << o.z << " pdf " << o.w);
            }
            Vec3 q = normalize(Vec3(in[i].z, in[i].w, in[i].x - 0.5f));
            Vec3 L = envLookup(m.view, 0, 0);
            float u, v;
            envDirToUv(mapping, q, u, v);
            L = envLookup(m.view, u, v);
            const dev::float4& r = out[5 * i + 1];
            float scale = std::max(1e-3f, std::max(L.x, std::max(L.y, L.z)));
            if (std::fabs(r.x - L.x) > 1e-3f * scale || std::fabs(r.y - L.y) > 1e-3f * scale ||
                std::fabs(r.z - L.z) > 1e-3f * scale)
                ++radBad;
            float pq = m.dist.pdf(q);
            if (std::fabs(r.w - pq) > 1e-3f * pq + 1e-6f) ++pdfBad;
            const dev::float4& uv = out[5 * i + 2];
            float du = std::fabs(uv.x - u);
            if (mapping == dev::ENV_LATLONG) du = std::min(du, 1.0f - du);
            if (du > 1e-4f || std::fabs(uv.y - v) > 1e-4f) ++uvBad;
            if (std::fabs(uv.z - envUvToSolidAngle(mapping, u, v)) > 1e-3f * envUvToSolidAngle(mapping, u, v)) ++uvBad;
            if (angleBetween(Vec3(out[5 * i + 3].x, out[5 * i + 3].y, out[5 * i + 3].z), q) > 2e-3f) ++uvBad;
            const Vec3 Lw = envLookup(m.view, 1.75f * in[i].z + 0.5f, in[i].x);  // wraps (lat-long) or clamps (probe)
            const dev::float4& lw = out[5 * i + 4];
            float sw = std::max(1e-3f, std::max(Lw.x, std::max(Lw.y, Lw.z)));
            if (std::fabs(lw.x - Lw.x) > 1e-3f * sw || std::fabs(lw.y - Lw.y) > 1e-3f * sw || std::fabs(lw.z - Lw.z) > 1e-3f * sw)
                ++wrapBad;
        }
        // A few may land in the neighbouring texel (ulp differences of acos/atan2 between libm and PoCL).
        CHECK(okMismatch <= n / 2000);
        CHECK(sampleBad <= n / 1000);
        CHECK(radBad <= n / 1000);
        CHECK(pdfBad <= n / 1000);
        CHECK(uvBad <= n / 1000);
        CHECK(wrapBad <= n / 1000);  // the host's % wrap, for any u (a wrong texel would miss on most)
    }
}

TEST_CASE("half4 environment texels: packed only when exact, and the device lookup reads the same values", "[lights][env][cl]") {
    // Host: packHalf4Exact keeps every value (imageTexels unpacks it bit for bit) or refuses.
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> bits(0, 0x7bff);  // finite non-negative halves, subnormals and 0 included
    const int w = 37, h = 19;                            // odd: the last float4 holds one texel
    std::vector<dev::float4> tex(size_t(w) * h);
    auto halfValue = [&]() { half v; v.setBits(uint16_t(bits(rng))); return float(v); };
    for (auto& t : tex) t = {halfValue(), halfValue(), halfValue(), 0.0f};
    tex[3].y = -0.0f;
    tex[4].z = 65504.0f;  // the largest half
    std::vector<dev::float4> packed;
    REQUIRE(packHalf4Exact(tex.data(), tex.size(), packed));
    CHECK(packed.size() == (tex.size() + 1) / 2);
    DeviceScene ds;
    ds.texels.assign(tex.begin(), tex.end());
    ds.texels.insert(ds.texels.end(), packed.begin(), packed.end());
    ds.images = {dev::ImageInfo{0, w, h, dev::TEXELS_FLOAT4}, dev::ImageInfo{int(tex.size()), w, h, dev::TEXELS_HALF4}};
    const std::vector<dev::float4> back = imageTexels(ds, 1);
    REQUIRE(back.size() == tex.size());
    CHECK(std::memcmp(back.data(), tex.data(), tex.size() * sizeof(dev::float4)) == 0);
    for (float bad : {0.1f, 65520.0f, 1e-8f, std::numeric_limits<float>::infinity(), std::nanf("")}) {
        std::vector<dev::float4> one = tex;
        one[7].x = bad;
        std::vector<dev::float4> none;
        CHECK_FALSE(packHalf4Exact(one.data(), one.size(), none));
        CHECK(none.empty());
    }

    // Device: EnvMap_Lookup of the half4 copy equals the float4 image's, bit for bit (both mappings, u
    // and v inside and outside [0, 1]).
    const char* src = R"CLC(
__kernel void half_lookup(const __global float4* texels, ImageInfo a, ImageInfo b, int mapping,
                          const __global float2* uv, __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    out[2 * i] = (float4)(EnvMap_Lookup(texels, a, mapping, uv[i].x, uv[i].y), 0.0f);
    out[2 * i + 1] = (float4)(EnvMap_Lookup(texels, b, mapping, uv[i].x, uv[i].y), 0.0f);
}
/* Env_HalfRgb (the nvptx fallback) against vload_half4: half i in every channel, i < 0x7c00 and its negative */
__kernel void half_decode(__global int* bad) {
    uint i = get_global_id(0);
    if (i >= 0x7c00u) return;
    uint hs[2] = {i, i | 0x8000u};
    for (int k = 0; k < 2; ++k) {
        ushort q[4] = {(ushort)hs[k], (ushort)hs[k], (ushort)hs[k], 0};
        float3 ref = vload_half4(0, (const half*)q).xyz;
        float3 got = Env_HalfRgb((uint2)(hs[k] | (hs[k] << 16), hs[k]));
        if (any(as_uint3(ref) != as_uint3(got))) atomic_inc(bad);
    }
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"envmap.cl"});
    sources.push_back({"half_lookup.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, {});
    cl::Kernel k = CL_CPP(cl::Kernel(program, "half_lookup"));
    const int n = 4096;
    std::uniform_real_distribution<float> uni(-0.25f, 1.25f);
    std::vector<dev::float2> uv(n);
    for (auto& q : uv) q = {uni(rng), uni(rng)};
    cl::Context& ctx = dc.context();
    auto ro = [&](const void* p, size_t bytes) {
        return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(p)));
    };
    cl::Buffer texBuf = ro(ds.texels.data(), ds.texels.size() * sizeof(dev::float4));
    cl::Buffer uvBuf = ro(uv.data(), uv.size() * sizeof(dev::float2));
    cl::Buffer outBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, 2 * size_t(n) * sizeof(dev::float4)));
    for (int mapping : {int(dev::ENV_LATLONG), int(dev::ENV_PROBE)}) {
        INFO("mapping " << mapping);
        std::vector<dev::float4> out(2 * size_t(n));
        k.setArg(0, texBuf); k.setArg(1, sizeof(dev::ImageInfo), &ds.images[0]);
        k.setArg(2, sizeof(dev::ImageInfo), &ds.images[1]); k.setArg(3, mapping);
        k.setArg(4, uvBuf); k.setArg(5, outBuf); k.setArg(6, n);
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(outBuf, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
        int differ = 0, nonzero = 0;
        for (int i = 0; i < n; ++i) {
            differ += std::memcmp(&out[2 * i], &out[2 * i + 1], 3 * sizeof(float)) != 0;
            nonzero += out[2 * i].x != 0.0f;
        }
        CHECK(differ == 0);
        CHECK(nonzero > n / 2);  // the lookups read the map (not all zero)
    }
    cl::Kernel dk = CL_CPP(cl::Kernel(program, "half_decode"));
    int zero = 0, bad = -1;
    cl::Buffer badBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof(int), &zero));
    dk.setArg(0, badBuf);
    CL_CPP(dc.queue().enqueueNDRangeKernel(dk, cl::NullRange, cl::NDRange(0x7c00), cl::NDRange(64)));
    CL_CPP(dc.queue().enqueueReadBuffer(badBuf, CL_TRUE, 0, sizeof(int), &bad));
    CHECK(bad == 0);  // Env_HalfRgb: every finite half, both signs, bit for bit
}

TEST_CASE("spot, directional, area and environment Light_Sample kernels match host references", "[lights][cl]") {
    // Lights come from a scene file, so the loader and flattenScene branches are exercised too.
    TempDir tmp;
    writeExr(tmp.file("env.exr"), constantImage(16, 8, 1.0f));
    {
        ImageRGB grad = constantImage(32, 16, 0.0f);
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 32; ++x) {
                grad.at(x, y, 0) = 0.1f + x;
                grad.at(x, y, 1) = 0.5f + y;
                grad.at(x, y, 2) = (x == 5 && y == 3) ? 500.0f : 1.0f;
            }
        writeExr(tmp.file("grad.exr"), grad);
    }
    std::string xml = envSceneXml("grad.exr", "latlong", "importance", 4, 1, "0.5 0.5 0.5",
                                  "<Triangle id=\"1\"><Indices>2 3 4</Indices><Material>2</Material></Triangle>");
    std::string lights =
        "<Lights><SpotLight id=\"1\"><Position>1 2 3</Position><Direction>0 -1 0.2</Direction><Intensity>100 200 300"
        "</Intensity><CoverageAngle>60</CoverageAngle><FalloffAngle>30</FalloffAngle></SpotLight>"
        "<DirectionalLight id=\"2\"><Direction>0.3 -1 0.1</Direction><Radiance>2 3 4</Radiance></DirectionalLight>"
        "<AreaLight id=\"3\"><Position>0 5 0</Position><Normal>0.2 -1 0.1</Normal><Size>2</Size><Radiance>10 20 30"
        "</Radiance></AreaLight>"
        "<SphericalDirectionalLight id=\"4\" type=\"latlong\" sampler=\"importance\"><ImageId>1</ImageId>"
        "</SphericalDirectionalLight></Lights>";
    xml.replace(xml.find("<Lights>"), xml.find("</Lights>") + 9 - xml.find("<Lights>"), lights);
    Scene scene = loadScene(writeFile(tmp.file("lights.xml"), xml));
    DeviceScene ds = flattenScene(scene);
    REQUIRE(ds.params.numLights == 4);
    REQUIRE(ds.lights.size() == 4);
    REQUIRE(ds.lights[0].kind == dev::LIGHT_SPOT);
    REQUIRE(ds.lights[1].kind == dev::LIGHT_DIRECTIONAL);
    REQUIRE(ds.lights[2].kind == dev::LIGHT_AREA);
    REQUIRE(ds.lights[3].kind == dev::LIGHT_ENVIRONMENT);
    REQUIRE(ds.params.envLight == 3);
    const dev::Light& area = ds.lights[2];
    Vec3 an = normalize(Vec3(0.2f, -1, 0.1f)), eu(area.edgeU.x, area.edgeU.y, area.edgeU.z),
         ev(area.edgeV.x, area.edgeV.y, area.edgeV.z);
    CHECK(length(eu) == Approx(2.0f));
    CHECK(length(ev) == Approx(2.0f));
    CHECK(std::fabs(dot(eu, an)) < 1e-5f);
    CHECK(std::fabs(dot(ev, an)) < 1e-5f);
    CHECK(std::fabs(dot(eu, ev)) < 1e-5f);
    // along the course's basis across the normal (courseBasis: t = n with its smallest-magnitude component set to
    // 1, here z; u = unit(t × n), v = n × u), signs included: --sampler correlated pairs them with the jitter
    const Vec3 t(an.x, an.y, 1.0f), uc = normalize(cross(t, an));
    CHECK(dot(eu, uc) == Approx(2.0f).epsilon(1e-5));
    CHECK(dot(ev, cross(an, uc)) == Approx(2.0f).epsilon(1e-5));
    CHECK(area.area == Approx(4.0f));

    const char* src = R"CLC(
__kernel void light_test(const __global Light* lights, int numLights, const __global float4* pts,
                         const __global float4* nrm, const __global ImageInfo* images, const __global float4* texels,
                         const __global float* envDist, __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    for (int l = 0; l < numLights; ++l) {
        float3 wi; float dist;
        float3 e = Light_Sample(&lights[l], pts[i].xyz, nrm[i].xyz, (float2)(pts[i].w, nrm[i].w), images, texels,
                                envDist, texels /* no object lights */, &wi, &dist);
        out[2 * (i * numLights + l)] = (float4)(e, dist);
        out[2 * (i * numLights + l) + 1] = (float4)(wi, 0.0f);
    }
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"lights.cl"});
    sources.push_back({"light_test.cl", src});
    cl::Program program = buildProgramFromSources(
        dc, sources, lightFlags(~0u));  // every light type
    cl::Kernel k = CL_CPP(cl::Kernel(program, "light_test"));
    const int n = 4096, L = 4;
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> pos(-4, 4), uni(0.0f, 0.99999994f);
    std::normal_distribution<float> g;
    std::vector<dev::float4> pts(n), nrm(n), out(size_t(2) * n * L);
    for (int i = 0; i < n; ++i) {
        pts[i] = {pos(rng), pos(rng), pos(rng), uni(rng)};
        if (i % 4 == 0) pts[i].y = 5.5f + 0.5f * std::fabs(pts[i].y);  // above the area light: its back face
        Vec3 nn = normalize(Vec3(g(rng), g(rng), g(rng)));
        nrm[i] = {nn.x, nn.y, nn.z, uni(rng)};
    }
    cl::Context& ctx = dc.context();
    auto ro = [&](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * v.size(), const_cast<T*>(v.data())));
    };
    cl::Buffer lb = ro(ds.lights), pb = ro(pts), nb = ro(nrm), ib = ro(ds.images), tb = ro(ds.texels), eb = ro(ds.envDistribution);
    cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
    k.setArg(0, lb); k.setArg(1, L); k.setArg(2, pb); k.setArg(3, nb); k.setArg(4, ib); k.setArg(5, tb);
    k.setArg(6, eb); k.setArg(7, ob); k.setArg(8, n);
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
    CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));

    // Host references in double precision, written from SCENE_FORMAT.md (not from the kernels).
    const dev::ImageInfo& envImg = ds.images[ds.lights[3].image];
    HostMap env;
    env.texels = imageTexels(ds, ds.lights[3].image);  // half4 (exact) in the atlas: unpacked
    env.view = EnvMapView{env.texels.data(), envImg.width, envImg.height, dev::ENV_LATLONG};
    env.dist = buildEnvDistribution(env.view);
    int bad[4] = {0, 0, 0, 0}, spotPartial = 0, spotZero = 0, areaLit = 0, areaBack = 0;
    auto close3 = [](const dev::float4& a, double x, double y, double z) {
        double s = std::max({1e-6, std::fabs(x), std::fabs(y), std::fabs(z)});
        return std::fabs(a.x - x) <= 2e-4 * s && std::fabs(a.y - y) <= 2e-4 * s && std::fabs(a.z - z) <= 2e-4 * s;
    };
    for (int i = 0; i < n; ++i) {
        Vec3 p(pts[i].x, pts[i].y, pts[i].z);
        const dev::float4* o = &out[size_t(2) * i * L];
        {  // spot
            Vec3 d = Vec3(1, 2, 3) - p;
            double d2 = dot(d, d), dl = std::sqrt(d2);
            Vec3 wi = d / float(dl), axis = normalize(Vec3(0, -1, 0.2f));
            double cosA = -dot(wi, axis), cc = std::cos(30 * kPiD / 180), cf = std::cos(15 * kPiD / 180);
            double s = cosA >= cf ? 1.0 : cosA <= cc ? 0.0 : std::pow((cosA - cc) / (cf - cc), 4.0);
            spotPartial += s > 0 && s < 1;
            spotZero += s == 0;
            if (!close3(o[0], 100 * s / d2, 200 * s / d2, 300 * s / d2) || std::fabs(o[0].w - dl) > 1e-4 * dl ||
                (s > 0 && angleBetween(Vec3(o[1].x, o[1].y, o[1].z), wi) > 1e-4f)) {
                ++bad[0];
                WARN("spot: s " << s << " cosA " << cosA << " host " << 100 * s / d2 << " device " << o[0].x << " d " << dl
                                << " vs " << o[0].w);
            }
        }
        {  // directional
            Vec3 wi = -normalize(Vec3(0.3f, -1, 0.1f));
            if (!close3(o[2], 2, 3, 4) || !std::isinf(o[2].w) || angleBetween(Vec3(o[3].x, o[3].y, o[3].z), wi) > 1e-5f)
                ++bad[1];
        }
        {  // area: the point (u.x - 1/2, u.y - 1/2) in the light's own edge frame
            double ux = pts[i].w, uy = nrm[i].w;
            Vec3 q = Vec3(0, 5, 0) + eu * float(ux - 0.5) + ev * float(uy - 0.5);
            Vec3 d = q - p;
            double d2 = dot(d, d), dl = std::sqrt(d2);
            Vec3 wi = d / float(dl);
            double cosL = std::fabs(double(dot(an, wi)));  // both faces emit
            double e = cosL > 0 ? 4.0 * cosL / d2 : 0.0;
            areaLit += e > 0;
            areaBack += e > 0 && dot(an, wi) > 0;  // p beyond the light's back face
            if (!close3(o[4], 10 * e, 20 * e, 30 * e) || (e > 0 && std::fabs(o[4].w - dl) > 1e-4 * dl)) ++bad[2];
        }
        {  // environment, importance strategy: L(wi) / pdf(wi)
            Vec3 w;
            float pdf;
            bool ok = env.dist.sample(pts[i].w, nrm[i].w, w, pdf);
            double ex = 0, ey = 0, ez = 0;
            if (ok) {
                float u, v;
                envDirToUv(dev::ENV_LATLONG, w, u, v);
                Vec3 Lr = envLookup(env.view, u, v);
                ex = Lr.x / pdf; ey = Lr.y / pdf; ez = Lr.z / pdf;
            }
            if (!close3(o[6], ex, ey, ez) || !std::isinf(o[6].w) ||
                (ok && angleBetween(Vec3(o[7].x, o[7].y, o[7].z), w) > 1e-4f))
                ++bad[3];
        }
    }
    INFO("spot partially lit " << spotPartial << ", unlit " << spotZero << "; area lit " << areaLit << ", from behind " << areaBack);
    CHECK(spotPartial > 50);
    CHECK(spotZero > 50);
    CHECK(areaLit > 50);
    CHECK(areaBack > 50);  // the back face is exercised: a one-sided light fails bad[2] there
    CHECK(bad[0] == 0);
    CHECK(bad[1] == 0);
    CHECK(bad[2] == 0);
    CHECK(bad[3] <= n / 1000);
}

TEST_CASE("white furnace: a kd=0.5 sphere under radiance 1 shows pi/2 with every sampler and mapping", "[lights][env][render]") {
    TempDir tmp;
    writeExr(tmp.file("latlong.exr"), constantImage(64, 32, 1.0f));
    writeExr(tmp.file("probe.exr"), constantImage(64, 64, 1.0f));
    const int size = 32, spp = 64;
    for (const char* type : {"latlong", "probe"})
        for (int s = 0; s < 4; ++s) {
            INFO(type << " / " << kSamplerNames[s]);
            std::string path = writeFile(tmp.file(std::string("furnace_") + type + ".xml"),
                                         envSceneXml(std::string(type) + ".exr", type, kSamplerNames[s], size, spp));
            ImageRGB img = renderFile(path, spp);
            // Classify pixels by their centre ray's angle to the sphere's centre (half-angle asin(2/5)),
            // leaving out a margin of two pixels around the silhouette.
            const double half = std::asin(2.0 / 5.0), t = std::tan(30 * kPiD / 180), pix = 2 * t / size;
            double sphereSum = 0, bgSum = 0, bgMax = 0;
            int sphereN = 0, bgN = 0;
            for (int y = 0; y < size; ++y)
                for (int x = 0; x < size; ++x) {
                    double sx = (2.0 * (x + 0.5) / size - 1.0) * t, sy = (2.0 * (y + 0.5) / size - 1.0) * t;
                    double ang = std::atan(std::sqrt(sx * sx + sy * sy));
                    double lum = (img.at(x, y, 0) + img.at(x, y, 1) + img.at(x, y, 2)) / 3.0;
                    if (ang < half - 2 * pix) { sphereSum += lum; ++sphereN; }
                    if (ang > half + 2 * pix) { bgSum += lum; ++bgN; bgMax = std::max(bgMax, std::fabs(lum - 1.0)); }
                }
            REQUIRE(sphereN > 100);
            REQUIRE(bgN > 100);
            double sphereMean = sphereSum / sphereN, bgMean = bgSum / bgN;
            WARN(type << " " << kSamplerNames[s] << ": sphere " << sphereMean << " (pi/2 = " << kPiD / 2 << "), background "
                      << bgMean);
            CHECK(sphereMean == Approx(kPiD / 2).epsilon(0.01));
            CHECK(bgMean == Approx(1.0).epsilon(0.01));
            CHECK(bgMax < 0.01);
        }
}

namespace {
// A map of w×h with a smooth, asymmetric base and one bright 3×3 patch at (px, py): importance sampling
// and the cosine tables matter, and any turn of the map shows.
ImageRGB spotImage(int w, int h, int px, int py) {
    ImageRGB img = constantImage(w, h, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                const bool spot = std::abs(x - px) <= 1 && std::abs(y - py) <= 1;
                img.pixels[(size_t(y) * w + x) * 3 + c] = spot ? 40.0f : 0.2f + 0.05f * float((x + 2 * y + 3 * c) % 9);
            }
    return img;
}

// The map that, unturned, shows what `img` turned by rotation `turn` shows (each texel moved as the
// rotation moves its direction, worked out by hand from the mappings of SCENE_FORMAT.md):
//   latlong, 90° about +y: the map's direction at u shows at u − 1/4, so texel (x, y) ← (x + w/4, y);
//   probe, 90° about +z (the view axis; square maps): texel (x, y) ← (w − 1 − y, x).
ImageRGB turnedByHand(const ImageRGB& img, bool probe) {
    ImageRGB out = img;
    const int w = img.width, h = img.height;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int sx = probe ? w - 1 - y : (x + w / 4) % w, sy = probe ? x : y;
            for (int c = 0; c < 3; ++c) out.pixels[(size_t(y) * w + x) * 3 + c] = img.pixels[(size_t(sy) * w + sx) * 3 + c];
        }
    return out;
}
}  // namespace

TEST_CASE("a turned environment map (<Transformations>) renders as the map turned by hand", "[lights][env][render]") {
    // The same scene twice: the map turned by the light's rotation, and unturned the map whose texels
    // were moved by hand. Renders of different seeds then differ by noise alone: their mean squared
    // difference is that of two seeds of the hand-turned scene, within a factor 2 (the noise rule). The
    // unturned map, as a control, must differ far more (the test can fail).
    TempDir tmp;
    const int size = 32, spp = 64;
    struct Case { const char* type; int w, h; const char* rotation; };
    for (const Case& k : {Case{"latlong", 64, 32, "90 0 1 0"}, Case{"probe", 64, 64, "90 0 0 1"}}) {
        const bool probe = std::string(k.type) == "probe";
        const ImageRGB map = spotImage(k.w, k.h, probe ? 36 : 44, probe ? 32 : 10);  // probe: in view, beside the sphere
        writeExr(tmp.file("map.exr"), map);
        writeExr(tmp.file("byhand.exr"), turnedByHand(map, probe));
        for (const char* sampler : {"uniform", "importance", "mis", "path"}) {
            INFO(k.type << " / " << sampler);
            const bool path = std::string(sampler) == "path";
            auto scene = [&](const std::string& image, bool turned) {
                std::string xml = envSceneXml(image, k.type, path ? "importance" : sampler, size, spp, "0.5 0.5 0.5", "",
                                              "0.3 0.3 0.3");
                if (turned) {
                    xml.replace(xml.find("<ImageId>1</ImageId>"), 20, "<ImageId>1</ImageId><Transformations>r1</Transformations>");
                    xml.replace(0, 7, std::string("<Scene><Transformations><Rotation id=\"1\">") + k.rotation +
                                          "</Rotation></Transformations>");
                }
                if (path)
                    xml.replace(xml.find("</Camera>"), 9, "<Renderer>PathTracing</Renderer><RendererParams>"
                                                          "MultipleImportanceSampling</RendererParams></Camera>");
                const std::string name = std::string(turned ? "turned_" : "plain_") + image + ".xml";
                return writeFile(tmp.file(name), xml);
            };
            const ImageRGB turned = renderFile(scene("map.exr", true), spp, nullptr, 1);
            const ImageRGB byHand1 = renderFile(scene("byhand.exr", false), spp, nullptr, 1);
            const ImageRGB byHand2 = renderFile(scene("byhand.exr", false), spp, nullptr, 2);
            const ImageRGB unturned = renderFile(scene("map.exr", false), spp, nullptr, 2);
            const double noise = meanSquaredDiff(byHand1, byHand2), err = meanSquaredDiff(turned, byHand2),
                         control = meanSquaredDiff(unturned, byHand2);
            WARN(k.type << " " << sampler << ": turned vs by hand " << err << ", two seeds " << noise << ", unturned " << control);
            CHECK(noise > 0);
            CHECK(err <= 2 * noise);
            CHECK(control > 10 * noise);
        }
    }
}

// Several environment lights (SphericalDirectionalLights) light the scene and show, where rays miss, as one
// light whose map is their sum: each is sampled on its own, and a ray that misses brings back the sum of
// their maps (in the path tracer each weighted against its own samples). Two lat-long maps with bright
// patches in different places against the one map of their texel sums, every strategy and the path
// tracer's MIS: squared difference within 2x that of two seeds of the one-map scene; the first map alone
// differs far more (where the strategy's noise lets it show: not under uniform sampling).
TEST_CASE("two environment lights render as one whose map is their sum", "[lights][env][render]") {
    TempDir tmp;
    const int size = 32, spp = 64;
    const ImageRGB a = spotImage(64, 32, 44, 10), b = spotImage(64, 32, 20, 14);
    ImageRGB sum = a;
    for (size_t i = 0; i < sum.pixels.size(); ++i) sum.pixels[i] = a.pixels[i] + b.pixels[i];
    writeExr(tmp.file("a.exr"), a);
    writeExr(tmp.file("b.exr"), b);
    writeExr(tmp.file("sum.exr"), sum);
    for (const char* sampler : {"uniform", "importance", "mis", "path"}) {
        INFO(sampler);
        const bool path = std::string(sampler) == "path";
        auto scene = [&](const std::string& name, const std::string& image, bool second) {
            // path: the importance strategy, whose misses the path tracer weighs by MIS (Path_EnvLightPdf)
            std::string xml = envSceneXml(image, "latlong", path ? "importance" : sampler, size, spp, "0.5 0.5 0.5", "", "0.3 0.3 0.3");
            if (second) {
                xml.replace(xml.find("</Image></Images>"), 17, "</Image><Image id=\"2\">b.exr</Image></Images>");
                xml.replace(xml.find("</Lights>"), 9, std::string("<SphericalDirectionalLight id=\"2\" type=\"latlong\" sampler=\"") +
                                                          (path ? "importance" : sampler) + "\"><ImageId>2</ImageId></SphericalDirectionalLight></Lights>");
            }
            if (path)
                xml.replace(xml.find("</Camera>"), 9, "<Renderer>PathTracing</Renderer><RendererParams>"
                                                      "MultipleImportanceSampling</RendererParams></Camera>");
            return writeFile(tmp.file(name), xml);
        };
        const ImageRGB two = renderFile(scene("two.xml", "a.exr", true), spp, nullptr, 1);
        const ImageRGB one1 = renderFile(scene("one.xml", "sum.exr", false), spp, nullptr, 1);
        const ImageRGB one2 = renderFile(scene("one.xml", "sum.exr", false), spp, nullptr, 2);
        const ImageRGB firstOnly = renderFile(scene("a.xml", "a.exr", false), spp, nullptr, 2);
        const double noise = meanSquaredDiff(one1, one2), err = meanSquaredDiff(two, one2), control = meanSquaredDiff(firstOnly, one2);
        WARN(sampler << ": two lights vs their sum " << err << ", two seeds " << noise << ", first light alone " << control);
        CHECK(noise > 0);
        CHECK(err <= 2 * noise);
        if (std::string(sampler) != "uniform") CHECK(control > 10 * noise);  // uniform: 2.2x, its noise is large
    }
}

namespace {
// Side-by-side strip for the docs: x·exposure / (1 + x·exposure), gamma 2.2.
void writeStrip(const std::string& path, const std::vector<const ImageRGB*>& imgs, float exposure) {
    int w = imgs[0]->width, h = imgs[0]->height, gap = 4, W = int(imgs.size()) * (w + gap) - gap;
    std::vector<unsigned char> rgb(size_t(W) * h * 3, 255);
    for (size_t k = 0; k < imgs.size(); ++k)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    double v = std::max(0.0f, imgs[k]->at(x, y, c)) * exposure;
                    v = std::pow(v / (1.0 + v), 1.0 / 2.2);
                    rgb[(size_t(y) * W + k * (w + gap) + x) * 3 + c] = (unsigned char)std::lround(255 * std::min(1.0, v));
                }
    writePng8(path, W, h, rgb);
}
}  // namespace

TEST_CASE("env strategies on sunset.exr: importance and MIS beat uniform >= 10x in relMSE", "[.slow][envcompare]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    TempDir tmp;
    const char* sizeEnv = std::getenv("CLRT_ENV_COMPARE_SIZE");
    const char* sppEnv = std::getenv("CLRT_ENV_COMPARE_SPP");
    const char* refEnv = std::getenv("CLRT_ENV_COMPARE_REF_SPP");
    const char* outEnv = std::getenv("CLRT_ENV_COMPARE_OUT");
    int size = sizeEnv ? std::atoi(sizeEnv) : 128, spp = sppEnv ? std::atoi(sppEnv) : 16;
    int refSpp = refEnv ? std::atoi(refEnv) : 1024;
    std::string image = sharedDir() + "/envmaps/sunset.exr";
    std::string ground = "<Mesh id=\"1\"><Material>2</Material><Faces>2 3 4 2 4 5</Faces></Mesh>";
    // The sun of sunset.exr is low, towards (0.59, 0.06, -0.81): the camera stands on its side of the
    // sphere (at z = -5), so the sunlit half is seen. The sun holds ~2.6% of the map's power but
    // ~10⁴ times the sky's radiance: uniform and cosine sampling find it rarely (fireflies, or
    // missing it), importance and MIS every time.
    std::string path = writeFile(tmp.file("sunset.xml"),
                                 envSceneXml(image, "latlong", "mis", size, spp, "0.5 0.4 0.3", ground, "0.3 0.3 0.3", 60,
                                             "4.4 1.0 -11.0", "0 0 -5"));
    dev::EnvStrategy mis = dev::ENV_STRATEGY_MIS;
    ImageRGB ref = renderFile(path, refSpp, &mis, 12345);
    std::vector<ImageRGB> imgs;
    std::vector<double> err;
    for (int s = 0; s < 4; ++s) {
        dev::EnvStrategy es = dev::EnvStrategy(s);
        imgs.push_back(renderFile(path, spp, &es, 7));
        err.push_back(relativeMse(imgs.back(), ref));
        WARN("sunset.exr, " << size << "x" << size << ", " << spp << " spp, " << kSamplerNames[s] << ": relMSE " << err.back()
                            << " (uniform / this = " << err[0] / err.back() << ")");
    }
    if (outEnv) {
        std::vector<const ImageRGB*> strip = {&imgs[0], &imgs[1], &imgs[2], &imgs[3], &ref};
        writeStrip(std::string(outEnv) + "/env_sampling_sunset.png", strip, 1.0f);
        std::ofstream md(std::string(outEnv) + "/env_sampling_sunset.txt");
        md << "sunset.exr (lat-long), " << size << "x" << size << ", " << spp << " spp per sampler, reference MIS at "
           << refSpp << " spp; relMSE = mean (x - ref)^2 / (ref^2 + 0.01)\n";
        md << "images left to right: uniform, cosine, importance, mis, reference\n";
        for (int s = 0; s < 4; ++s)
            md << kSamplerNames[s] << " relMSE " << err[s] << "  uniform/this " << err[0] / err[s] << "\n";
    }
    CHECK(err[0] / err[2] >= 10.0);
    CHECK(err[0] / err[3] >= 10.0);
}

TEST_CASE("Math_Atan2 (the env mappings' and spheres' atan2) is within 3e-7 rad (an ulp of pi) of atan2", "[lights][env][cl]") {
    const char* src = R"CLC(
__kernel void atan_test(const __global float2* in, __global float* out, int n) {
    int i = get_global_id(0);
    if (i < n) out[i] = Math_Atan2(in[i].x, in[i].y);
}
)CLC";
    std::vector<dev::float2> in;
    std::mt19937 rng(9);
    std::normal_distribution<float> g;
    for (int i = 0; i < 200000; ++i) in.push_back({g(rng), g(rng)});
    for (float a : {0.0f, -0.0f, 1.0f, -1.0f, 1e-30f, -1e-30f, 3e7f, -3e7f})  // axes, diagonals, extremes
        for (float b : {0.0f, 1.0f, -1.0f, 1e-30f, -1e-30f, 3e7f, -3e7f}) in.push_back({a, b});
    const int n = int(in.size());
    const std::vector<float> out = runElementwiseKernel<float>({"common.cl"}, "atan_test", src, in);
    double worst = 0;
    for (int i = 0; i < n; ++i) {
        double e = std::atan2(double(in[i].x), double(in[i].y)), d = std::fabs(out[i] - e);
        d = std::min(d, std::fabs(d - 2 * kPiD));  // atan2(±0, x<0): +π or −π, the same direction
        INFO(in[i].x << ", " << in[i].y << ": " << out[i] << " vs " << e);
        REQUIRE(std::isfinite(out[i]));
        worst = std::max(worst, d);
        if (d > 3e-7) CHECK(d <= 3e-7);
    }
    WARN("Math_Atan2: largest error " << worst << " rad over " << n << " pairs");
}

// Maps for the cosine tables: odd sizes (cells of one texel), a lat-long map larger than the coarse grid
// (cells of 2 x 2 texels, and of 1-2 texels where the sizes do not divide), a probe map, and shared ones.
std::vector<NamedMap> cosineTestMaps() {
    std::vector<NamedMap> maps;
    maps.push_back({"37x19 latlong pattern", makeMap(patternImage(37, 19), dev::ENV_LATLONG)});
    maps.push_back({"256x128 latlong pattern", makeMap(patternImage(256, 128), dev::ENV_LATLONG)});
    maps.push_back({"300x101 latlong pattern", makeMap(patternImage(300, 101), dev::ENV_LATLONG)});
    maps.push_back({"21x21 probe pattern", makeMap(patternImage(21, 21), dev::ENV_PROBE)});
    maps.push_back({"1x1 latlong", makeMap(constantImage(1, 1, 2.0f), dev::ENV_LATLONG)});
    if (haveShared()) {
        std::string e = sharedDir() + "/envmaps/";
        maps.push_back({"sunrise.exr", makeMap(readImage(e + "sunrise.exr"), dev::ENV_LATLONG)});
        maps.push_back({"courtyard_probe.exr", makeMap(readImage(e + "courtyard_probe.exr"), dev::ENV_PROBE)});
    }
    return maps;
}

// Buckets: a downward corner, near the top, a side (and, on the small maps, three more).
const int kCosineTestBuckets[] = {0, 66, 30, 77, 143, 100};

// Host only (tagged [env], not [lights]: the Intel pass of scripts/test_implementations.sh need not repeat it).
TEST_CASE("env cosine tables: each bucket's pdf integrates to one, samples follow it (chi-square), pdfs agree", "[env]") {
    for (const NamedMap& nm : cosineTestMaps()) {
        const HostMap& m = nm.map;
        const EnvCosineTable table(m.dist);
        const int W = m.dist.width, H = m.dist.height;
        const bool big = W > 300;  // the shared maps: 3 buckets, the quadrature fine enough for sunrise's sun
        for (int bi = 0; bi < (big ? 3 : 6); ++bi) {
            const int b = kCosineTestBuckets[bi];
            INFO(nm.name << ", bucket " << b);
            // sunrise.exr: 1.012-1.015 at M = 1024 (its sun); the pattern maps: within 1e-4 at 512
            const int M = W * H == 1 ? 256 : (big ? 2048 : 512);
            if (!big || bi == 1) {
                double integral = integrateSphere([&](const Vec3& w) { return double(table.pdf(b, w)); }, M);
                CHECK(integral == Approx(1.0).epsilon(0.01));
            }
            const int BU = std::min(W, 32), BV = std::min(H, 16);
            std::vector<double> expected(BU * BV, 0.0), observed(BU * BV, 0.0);
            double mass = 0;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const double p = table.texelProbability(b, x, y);
                    expected[(y * BV / H) * BU + x * BU / W] += p;
                    mass += p;
                }
            CHECK(mass == Approx(1.0).epsilon(1e-4));
            const int N = 100000;
            std::mt19937 rng(23 + b);
            std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
            int failed = 0, pdfMismatch = 0;
            for (int n = 0; n < N; ++n) {
                Vec3 w;
                float pdf;
                if (!table.sample(b, uni(rng), uni(rng), w, pdf)) { ++failed; continue; }
                float u, v;
                envDirToUv(m.dist.mapping, w, u, v);
                int bi = std::clamp(int(u * W), 0, W - 1) * BU / W, bj = std::clamp(int(v * H), 0, H - 1) * BV / H;
                observed[bj * BU + bi] += 1;
                if (!(std::fabs(table.pdf(b, w) - pdf) <= 1e-3f * pdf)) ++pdfMismatch;
            }
            CHECK(failed <= N / 10000);
            CHECK(pdfMismatch <= N / 1000);
            double chi2 = 0, pool = 0, poolObs = 0;
            int dof = -1;
            for (size_t k = 0; k < expected.size(); ++k) {
                double e = expected[k] * (N - failed);
                if (e < 5) { pool += e; poolObs += observed[k]; continue; }
                chi2 += (observed[k] - e) * (observed[k] - e) / e;
                ++dof;
            }
            if (pool >= 5) { chi2 += (poolObs - pool) * (poolObs - pool) / pool; ++dof; }
            if (dof >= 1) CHECK(chi2 < chi2Critical(dof, 4.0));
        }
    }
}

TEST_CASE("env cosine tables: cells cover the texels, buckets cover the sphere of normals", "[env]") {
    for (int texels : {1, 19, 37, 64, 101, 300, 1000, 1024})
        for (int cells : {1, 7, 64, 128}) {
            if (cells > texels) continue;
            INFO(texels << " texels, " << cells << " cells");
            int prev = -1;
            for (int t = 0; t < texels; ++t) {  // every texel in one cell, cells in order, none empty
                const int c = envCosineCellOf(t, texels, cells);
                REQUIRE((c == prev || c == prev + 1));
                REQUIRE(int(int64_t(c) * texels / cells) <= t);
                REQUIRE(t < int(int64_t(c + 1) * texels / cells));
                prev = c;
            }
            CHECK(prev == cells - 1);
        }
    const int k = kEnvCosineBuckets;
    for (int b = 0; b < k * k; ++b) {
        INFO("bucket " << b);
        CHECK(envCosineBucket(envCosineBucketNormal(b)) == b);  // each centre lies in its own cell
    }
    // Every normal lies within its bucket's radius of the bucket's centre (the tables' largest cosine).
    std::mt19937 rng(2);
    std::normal_distribution<float> g;
    int outside = 0;
    for (int i = 0; i < 200000; ++i) {
        const Vec3 n = normalize(Vec3(g(rng), g(rng), g(rng)));
        const int b = envCosineBucket(n);
        if (std::acos(std::clamp(double(dot(n, envCosineBucketNormal(b))), -1.0, 1.0)) > envCosineBucketRadius(b)) ++outside;
    }
    CHECK(outside == 0);
}

TEST_CASE("env cosine tables: the device picks the host's bucket and samples and evaluates as the host", "[lights][env][cl]") {
    const char* src = R"CLC(
__kernel void cos_test(const __global float* own, const __global float* tab, const __global float4* in,
                       __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    const float4 a = in[i];
    const float3 nrm = (float3)(a.z, a.w, a.x - 0.5f);
    const int b = EnvCos_Bucket(tab, nrm);
    float3 d = (float3)(0.0f);
    float pdf = -1.0f;
    float2 uv = (float2)(0.0f);
    int ok = b >= 0 && EnvCos_SampleUv(own, tab, b, a.x, a.y, &d, &pdf, &uv);
    out[3 * i] = (float4)(d, ok ? pdf : -1.0f);
    out[3 * i + 1] = (float4)((float)b, b >= 0 ? EnvCos_PdfUv(own, tab, b, EnvMap_DirToUv((int)own[2], normalize(nrm))) : -1.0f,
                              uv);
    out[3 * i + 2] = (float4)(0.0f);
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"envmap.cl"});
    sources.push_back({"cos_test.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, {});
    cl::Kernel kern = CL_CPP(cl::Kernel(program, "cos_test"));
    for (const NamedMap& nm : cosineTestMaps()) {
        INFO(nm.name);
        const HostMap& m = nm.map;
        const EnvCosineTable table(m.dist);
        std::vector<dev::float4> in;
        std::mt19937 rng(31);
        std::uniform_real_distribution<float> uni(0.0f, 0.99999994f), sym(-1.0f, 1.0f);
        for (int i = 0; i < 20000; ++i) in.push_back({uni(rng), uni(rng), sym(rng), sym(rng)});
        const float nan = std::numeric_limits<float>::quiet_NaN();
        for (float a : {0.0f, -0.0f, 0.5f, 1e-30f, nan})  // axes, octant seams, degenerate normals
            for (float b : {0.0f, -0.0f, 1.0f, -1.0f, 0.5f})
                for (float c : {0.5f, 0.0f, 1.0f}) in.push_back({c, 0.25f, a, b});
        const int n = int(in.size());
        std::vector<dev::float4> out(3 * size_t(n));
        cl::Context& ctx = dc.context();
        auto ro = [&](const void* p, size_t bytes) {
            return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(p)));
        };
        cl::Buffer own = ro(m.dist.data.data(), m.dist.data.size() * sizeof(float));
        cl::Buffer tab = ro(table.data().data(), table.data().size() * sizeof(float));
        cl::Buffer inBuf = ro(in.data(), in.size() * sizeof(dev::float4));
        cl::Buffer outBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
        kern.setArg(0, own); kern.setArg(1, tab); kern.setArg(2, inBuf); kern.setArg(3, outBuf); kern.setArg(4, n);
        CL_CPP(dc.queue().enqueueNDRangeKernel(kern, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(outBuf, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
        int bucketBad = 0, okMismatch = 0, sampleBad = 0, pdfBad = 0;
        for (int i = 0; i < n; ++i) {
            const Vec3 nrm(in[i].z, in[i].w, in[i].x - 0.5f);
            const int b = envCosineBucket(nrm);
            if (int(out[3 * i + 1].x) != b) {
                if (bucketBad++ < 3) FAIL_CHECK("normal " << nrm.x << " " << nrm.y << " " << nrm.z << ": device bucket "
                                                         << out[3 * i + 1].x << ", host " << b);
                continue;
            }
            if (b < 0) continue;
            Vec3 w;
            float pdf;
            const bool ok = table.sample(b, in[i].x, in[i].y, w, pdf);
            const dev::float4& o = out[3 * i];
            if (ok != (o.w >= 0)) { ++okMismatch; continue; }
            if (ok && (angleBetween(w, Vec3(o.x, o.y, o.z)) > 1e-4f || std::fabs(o.w - pdf) > 1e-3f * pdf)) ++sampleBad;
            const float pq = table.pdf(b, normalize(nrm));
            if (std::fabs(out[3 * i + 1].y - pq) > 1e-3f * pq + 1e-6f) ++pdfBad;
        }
        CHECK(bucketBad == 0);
        CHECK(okMismatch <= n / 2000);
        CHECK(sampleBad <= n / 1000);  // a few land in the neighbouring texel (ulps of acos between libm and PoCL)
        CHECK(pdfBad <= n / 1000);
    }
}

TEST_CASE("env multi-sample MIS (EnvLight_SampleMis) is unbiased: cos-weighted sum matches quadrature", "[lights][env][cl]") {
    // Two maps of different character: a smooth gradient with one hot texel (importance wins), and a
    // dim map whose one texel holds ~99.9% of the power. For 6 normals, the mean over 40000 sample pairs of
    // cos(wi_0)·e_0 + cos(wi_1)·e_1 must match ∫ L(w)·max(0, n·w) dw (cube quadrature) within 4 standard
    // errors plus 0.5% (the quadrature's own error near the hot texel); the power weights make each
    // sample's share bounded: e_k·p_k <= L.
    TempDir tmp;
    ImageRGB grad = constantImage(32, 16, 0.0f), hot = constantImage(64, 32, 0.01f);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            grad.at(x, y, 0) = 0.1f + x;
            grad.at(x, y, 1) = 0.5f + y;
            grad.at(x, y, 2) = (x == 5 && y == 3) ? 500.0f : 1.0f;
        }
    for (int c = 0; c < 3; ++c) hot.at(20, 10, c) = 3000.0f;
    writeExr(tmp.file("grad.exr"), grad);
    writeExr(tmp.file("hot.exr"), hot);
    const char* src = R"CLC(
__kernel void mis_test(const __global Light* lights, const __global float4* nrm, const __global float4* us,
                       const __global ImageInfo* images, const __global float4* texels, const __global float* envDist,
                       __global float4* out, int n, float cosShare) {
    int i = get_global_id(0);
    if (i >= n) return;
    float3 wiL, eL, wiB, eB;
    float3 nn = nrm[i].xyz;
    int withCos = cosShare >= 1.0f || (i & 1) == 0;  /* share ½: every other point, as sample parity */
    EnvLight_SampleMis(&lights[0], nn, us[i].xy, us[i].zw, cosShare, withCos, images, texels, envDist, &wiL, &eL,
                       &wiB, &eB);
    out[i] = (float4)(fmax(dot(nn, wiL), 0.0f) * eL + fmax(dot(nn, wiB), 0.0f) * eB, 0.0f);
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"lights.cl"});
    sources.push_back({"mis_test.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, lightFlags(~0u));
    cl::Kernel k = CL_CPP(cl::Kernel(program, "mis_test"));
    const Vec3 normals[6] = {Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(1, 0, 0), Vec3(0.3f, 0.5f, -0.8f), Vec3(-0.6f, 0.2f, 0.7f),
                             Vec3(0.1f, -0.4f, 0.9f)};
    const int per = 40000, n = 6 * per;
    for (float cosShare : {1.0f, 0.5f})
    for (const char* name : {"grad.exr", "hot.exr"}) {
        INFO(name << ", cosine share " << cosShare);
        Scene scene = loadScene(writeFile(tmp.file("mis.xml"), envSceneXml(name, "latlong", "mis", 4, 1)));
        DeviceScene ds = flattenScene(scene);
        REQUIRE(ds.lights.size() == 1);
        REQUIRE(ds.lights[0].envStrategy == dev::ENV_STRATEGY_MIS);
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
        std::vector<dev::float4> nrm(n), us(n), out(n);
        for (int i = 0; i < n; ++i) {
            Vec3 nn = normalize(normals[i / per]);
            nrm[i] = {nn.x, nn.y, nn.z, 0};
            us[i] = {uni(rng), uni(rng), uni(rng), uni(rng)};
        }
        cl::Context& ctx = dc.context();
        auto ro = [&](const auto& v) {
            using T = typename std::decay_t<decltype(v)>::value_type;
            return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * v.size(), const_cast<T*>(v.data())));
        };
        cl::Buffer lb = ro(ds.lights), nb = ro(nrm), ub = ro(us), ib = ro(ds.images), tb = ro(ds.texels), eb = ro(ds.envDistribution);
        cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
        k.setArg(0, lb); k.setArg(1, nb); k.setArg(2, ub); k.setArg(3, ib); k.setArg(4, tb); k.setArg(5, eb);
        k.setArg(6, ob); k.setArg(7, n); k.setArg(8, cosShare);
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
        const dev::ImageInfo& img = ds.images[ds.lights[0].image];
        std::vector<dev::float4> tex = imageTexels(ds, ds.lights[0].image);
        EnvMapView view{tex.data(), img.width, img.height, dev::ENV_LATLONG};
        for (int j = 0; j < 6; ++j) {
            Vec3 nn = normalize(normals[j]);
            for (int c = 0; c < 3; ++c) {
                double exact = integrateSphere(
                    [&](const Vec3& w) {
                        float u, v;
                        envDirToUv(dev::ENV_LATLONG, w, u, v);
                        Vec3 L = envLookup(view, u, v);
                        return double(c == 0 ? L.x : c == 1 ? L.y : L.z) * std::max(0.0f, dot(nn, w));
                    },
                    384);
                double sum = 0, sum2 = 0;
                for (int i = j * per; i < (j + 1) * per; ++i) {
                    double x = c == 0 ? out[i].x : c == 1 ? out[i].y : out[i].z;
                    sum += x;
                    sum2 += x * x;
                }
                // (share ½: pairs of neighbours, one with and one without the cosine sample, are the unit)
                double mean = sum / per, se = std::sqrt(std::max(0.0, sum2 / per - mean * mean) / per);
                INFO("normal " << j << " channel " << c << ": MIS mean " << mean << " +- " << se << ", quadrature " << exact);
                CHECK(std::fabs(mean - exact) <= 4 * se + 5e-3 * exact);
            }
        }
    }
}

TEST_CASE("light sampling edge cases: 1xN maps, points on the light, spot angles at their limits", "[lights][robust]") {
    // 1xN and Nx1 maps (one column / one row) with a luminance gradient: pdf still integrates to one
    // and every sample's pdf equals the evaluated pdf.
    for (int mapping : {int(dev::ENV_LATLONG), int(dev::ENV_PROBE)})
        for (auto wh : {std::make_pair(1, 64), std::make_pair(64, 1)}) {
            ImageRGB img = constantImage(wh.first, wh.second, 0.0f);
            for (size_t p = 0; p < img.pixels.size(); ++p) img.pixels[p] = float(1 + (p / 3) % 7);
            HostMap m = makeMap(img, mapping);
            INFO("mapping " << mapping << ", " << wh.first << "x" << wh.second);
            double integral = integrateSphere([&](const Vec3& w) { return double(m.dist.pdf(w)); }, 512);
            CHECK(integral == Approx(1.0).epsilon(0.01));
            std::mt19937 rng(3);
            std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
            int mismatch = 0, samples = 0;
            for (int i = 0; i < 4000; ++i) {
                Vec3 w;
                float pdf;
                if (!m.dist.sample(uni(rng), uni(rng), w, pdf)) continue;
                ++samples;
                CHECK(std::isfinite(pdf));
                float pe = m.dist.pdf(w);
                if (std::fabs(pe - pdf) > 1e-3f * std::max(pe, pdf)) ++mismatch;
            }
            CHECK(samples > 3900);
            CHECK(mismatch <= samples / 500);
        }

    // Device: spot lights with coverage == falloff, falloff 0 and coverage 180; shading points exactly
    // at a point light and on an area light: finite, never NaN, within physical bounds.
    const char* src = R"CLC(
__kernel void edge_test(const __global Light* lights, int numLights, const __global float4* pts,
                        const __global ImageInfo* images, const __global float4* texels, const __global float* envDist,
                        __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    for (int l = 0; l < numLights; ++l) {
        float3 wi; float dist;
        float3 e = Light_Sample(&lights[l], pts[i].xyz, (float3)(0.0f, 1.0f, 0.0f), (float2)(pts[i].w, 0.5f), images,
                                texels, envDist, texels /* no object lights */, &wi, &dist);
        out[i * numLights + l] = (float4)(e, dist);
    }
}
)CLC";
    std::vector<dev::Light> lights;
    auto spot = [&](float coverage, float falloff) {
        dev::Light l{};
        l.kind = dev::LIGHT_SPOT;
        l.position = {0, 2, 0, 0};
        l.direction = {0, -1, 0, 0};
        l.radiance = {100, 100, 100, 0};
        l.cosCoverageHalf = float(std::cos(coverage * 0.5 * kPiD / 180));
        l.cosFalloffHalf = float(std::cos(falloff * 0.5 * kPiD / 180));
        l.image = l.distribution = CLRT_INVALID;
        lights.push_back(l);
    };
    spot(60, 60);    // hard edge: coverage == falloff
    spot(60, 0);     // falloff 0: the quartic ramp over the whole cone
    spot(180, 90);   // a hemisphere
    dev::Light point{};
    point.kind = dev::LIGHT_POINT;
    point.position = {0, 0, 0, 0};
    point.radiance = {10, 10, 10, 0};
    lights.push_back(point);
    dev::Light area{};
    area.kind = dev::LIGHT_AREA;
    area.position = {0, 0, 0, 0};
    area.direction = {0, -1, 0, 0};
    area.edgeU = {1, 0, 0, 0};
    area.edgeV = {0, 0, 1, 0};
    area.area = 1;
    area.radiance = {5, 5, 5, 0};
    lights.push_back(area);
    const int L = int(lights.size());
    std::vector<dev::float4> pts;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> pos(-3, 3), uni(0, 0.99999994f);
    pts.push_back({0, 0, 0, 0.5f});  // exactly at the point light / area light centre
    pts.push_back({0, 2, 0, 0.5f});  // exactly at the spot position
    for (int i = 0; i < 2046; ++i) pts.push_back({pos(rng), i % 3 == 0 ? 0.0f : pos(rng), pos(rng), uni(rng)});
    const int n = int(pts.size());
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"lights.cl"});
    sources.push_back({"edge_test.cl", src});
    cl::Program program = buildProgramFromSources(
        dc, sources, lightFlags((1u << dev::LIGHT_SPOT) | (1u << dev::LIGHT_AREA) | (1u << dev::LIGHT_POINT)));
    cl::Kernel k = CL_CPP(cl::Kernel(program, "edge_test"));
    cl::Context& ctx = dc.context();
    auto ro = [&](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * v.size(), const_cast<T*>(v.data())));
    };
    std::vector<dev::ImageInfo> images(1, dev::ImageInfo{0, 1, 1, 0});
    std::vector<dev::float4> texels(1, dev::float4{0, 0, 0, 0});
    std::vector<float> dist(4, 0.0f);
    std::vector<dev::float4> out(size_t(n) * L);
    cl::Buffer lb = ro(lights), pb = ro(pts), ib = ro(images), tb = ro(texels), db = ro(dist);
    cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
    k.setArg(0, lb); k.setArg(1, L); k.setArg(2, pb); k.setArg(3, ib); k.setArg(4, tb); k.setArg(5, db);
    k.setArg(6, ob); k.setArg(7, n);
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(size_t(n), 64)), cl::NDRange(64)));
    CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
    int nonFinite = 0, outOfBounds = 0, hardEdgeMixed = 0;
    for (int i = 0; i < n; ++i)
        for (int l = 0; l < L; ++l) {
            const dev::float4& o = out[size_t(i) * L + l];
            if (!std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.z) || std::isnan(o.w)) ++nonFinite;
            if (o.x < 0) ++outOfBounds;
            if (l < 3) {  // spot: never above I/d²
                Vec3 d = Vec3(0, 2, 0) - Vec3(pts[i].x, pts[i].y, pts[i].z);
                double d2 = dot(d, d);
                if (d2 > 0 && o.x > 100.0 / d2 * (1 + 1e-5)) ++outOfBounds;
                if (l == 0 && d2 > 0) {  // hard edge: either full or nothing
                    double v = o.x * d2 / 100.0;
                    if (v > 1e-6 && std::fabs(v - 1) > 1e-4) ++hardEdgeMixed;
                }
            }
        }
    CHECK(nonFinite == 0);
    CHECK(outOfBounds == 0);
    CHECK(hardEdgeMixed == 0);
    // At the light's own position the contribution is zero, not Inf.
    CHECK(out[size_t(0) * L + 3].x == 0.0f);  // point light at the shading point
    CHECK(out[size_t(1) * L + 0].x == 0.0f);  // spot light at the shading point
}
