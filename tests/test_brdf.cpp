// BRDF tests (course hw6, cl_kernels/brdf.cl; host reference tests/brdf_reference.h):
//   parsing of <BRDFs> and Material BRDF="id" (and its errors), the -D flags of a scene's BRDFs;
//   per BRDF (every row of CLRT_BRDF_TABLE, normalized or not, kdfresnel or not, several wo), Mitsuba
//   style: ∫pdf dω = 1 over the sphere, a chi-square test of sampled directions against the pdf,
//   pdf(sample) = pdf(evaluate), albedo ≤ 1 for the normalized BRDFs (numerical integration), and the
//   device's Brdf_Eval/Brdf_Sample/Brdf_Pdf equal the host reference for the same random numbers;
//   the five brdf_* course scenes (800², 1 spp, deterministic) ≥ 40 dB against their PNGs; the
//   cornellbox_jaroslav_diffuse/glossy EXRs against the noise floor (reduced spp here: see below).
#include <catch.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "brdf_reference.h"
#include "cl/check.h"
#include "cl/program.h"
#include "image/image.h"
#include "flatten/device_scene.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "shared/type_tables.h"
#include "image/image_compare.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string writeText(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

std::string brdfScene(const std::string& brdfs, const std::string& materialAttr) {
    return "<Scene><Cameras><Camera id=\"1\"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>"
           "<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>"
           "<ImageName>o.png</ImageName></Camera></Cameras>"
           "<Lights><PointLight id=\"1\"><Position>0 0 5</Position><Intensity>10 10 10</Intensity></PointLight></Lights>" +
           brdfs + "<Materials><Material id=\"1\"" + materialAttr +
           "><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance></Material></Materials>"
           "<VertexData>0 0 0</VertexData><Objects><Sphere id=\"1\"><Material>1</Material><Center>1</Center>"
           "<Radius>1</Radius></Sphere></Objects></Scene>";
}

struct Case {
    const char* name;
    HostBrdf b;
};

// Every BRDF of the table, normalized and not, Torrance-Sparrow with and without kdfresnel.
std::vector<Case> cases() {
    auto make = [](int kind, float p, int flags, Vec3 kd, Vec3 ks) {
        HostBrdf b;
        b.kind = kind;
        b.exponent = p;
        b.flags = flags;
        b.kd = kd;
        b.ks = ks;
        b.eta = 0.37f;
        b.k = 2.82f;
        return b;
    };
    const Vec3 kd(0.3f, 0.2f, 0.1f), ks(0.6f, 0.7f, 0.8f);
    return {
        {"OriginalPhong p=50", make(dev::BRDF_ORIGINAL_PHONG, 50, 0, kd, ks)},
        {"OriginalBlinnPhong p=20", make(dev::BRDF_ORIGINAL_BLINN_PHONG, 20, 0, kd, ks)},
        {"ModifiedPhong p=10", make(dev::BRDF_MODIFIED_PHONG, 10, 0, kd, ks)},
        {"ModifiedPhong normalized p=90", make(dev::BRDF_MODIFIED_PHONG, 90, CLRT_BRDF_NORMALIZED, kd, ks)},
        {"ModifiedBlinnPhong p=5", make(dev::BRDF_MODIFIED_BLINN_PHONG, 5, 0, kd, ks)},
        {"ModifiedBlinnPhong normalized p=50", make(dev::BRDF_MODIFIED_BLINN_PHONG, 50, CLRT_BRDF_NORMALIZED, kd, ks)},
        {"TorranceSparrow p=50", make(dev::BRDF_TORRANCE_SPARROW, 50, 0, kd, ks)},
        {"TorranceSparrow kdfresnel p=8", make(dev::BRDF_TORRANCE_SPARROW, 8, CLRT_BRDF_KD_FRESNEL, kd, ks)},
        {"ModifiedPhong normalized p=200, kd=0", make(dev::BRDF_MODIFIED_PHONG, 200, CLRT_BRDF_NORMALIZED, Vec3(0), ks)},
        {"ModifiedBlinnPhong p=1, ks=0", make(dev::BRDF_MODIFIED_BLINN_PHONG, 1, 0, kd, Vec3(0))},
    };
}

// An arbitrary (not axis-aligned) frame: the normal, and wo at polar angle `theta` to it.
Vec3 testNormal() { return normalize(Vec3(0.3f, 0.8f, -0.5f)); }
Vec3 woAt(float thetaDeg) {
    Vec3 n = testNormal(), t, b;
    brdfBasis(n, t, b);
    float th = thetaDeg * float(kPi) / 180;
    return normalize(n * std::cos(th) + normalize(t + b * 0.4f) * std::sin(th));
}

// A direction of the (θ, φ) grid about n (θ from n).
Vec3 dirAt(const Vec3& n, double theta, double phi) {
    Vec3 t, b;
    brdfBasis(n, t, b);
    return normalize(n * float(std::cos(theta)) + t * float(std::sin(theta) * std::cos(phi)) +
                     b * float(std::sin(theta) * std::sin(phi)));
}

// ∫ g(ω) dω over θ ∈ [th0, th1] (about n) and all φ, midpoint rule, T × P cells.
template <class G> double integrate(const Vec3& n, G g, double th0, double th1, int T, int P) {
    double sum = 0, dth = (th1 - th0) / T, dph = 2 * kPi / P;
    for (int i = 0; i < T; ++i) {
        double th = th0 + (i + 0.5) * dth, w = std::sin(th) * dth * dph;
        for (int j = 0; j < P; ++j) sum += g(dirAt(n, th, (j + 0.5) * dph)) * w;
    }
    return sum;
}

double chi2Critical(int k, double z) {  // Wilson–Hilferty: the chi-square quantile at z standard deviations
    double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

float angleBetween(const Vec3& a, const Vec3& b) {
    return 2.0f * std::asin(std::min(1.0f, 0.5f * length(normalize(a) - normalize(b))));
}

}  // namespace

TEST_CASE("BRDFs: <BRDFs> and Material BRDF are parsed through the BRDF table", "[brdf][scene]") {
    TempDir tmp;
    std::string brdfs =
        "<BRDFs><OriginalPhong id=\"1\"><Exponent>50</Exponent></OriginalPhong>"
        "<ModifiedBlinnPhong id=\"7\" normalized=\"true\"><Exponent>30</Exponent></ModifiedBlinnPhong>"
        "<TorranceSparrow id=\"3\" kdfresnel=\"true\"><Exponent>12</Exponent></TorranceSparrow></BRDFs>";
    Scene s = loadScene(writeText(tmp.file("a.xml"), brdfScene(brdfs, " BRDF=\"7\"")));
    REQUIRE(s.brdfs.size() == 3);
    CHECK(s.brdfs[0].type == dev::BRDF_ORIGINAL_PHONG);
    CHECK(s.brdfs[1].type == dev::BRDF_MODIFIED_BLINN_PHONG);
    CHECK(s.brdfs[1].normalized);
    CHECK(s.brdfs[1].exponent == 30);
    CHECK(s.brdfs[2].kdFresnel);
    CHECK(s.materials.at(0).brdf == 1);
    DeviceScene ds = flattenScene(s);
    CHECK(ds.materials.at(0).brdf == dev::BRDF_MODIFIED_BLINN_PHONG);
    CHECK(ds.materials.at(0).brdfExponent == 30);
    CHECK((ds.materials.at(0).brdfFlags & ~CLRT_BRDF_LAMBERTIAN) == CLRT_BRDF_NORMALIZED);  // LAMBERTIAN: ks (test_lanes.cpp)
    std::vector<std::string> d = ds.features.defines();
    auto has = [&](const std::string& f) { return std::find(d.begin(), d.end(), "-D" + f + "=1") != d.end(); };
    CHECK(has("CLRT_HAS_BRDF_MODIFIED_BLINN_PHONG"));
    CHECK(has("CLRT_HAS_BRDFS"));
    CHECK_FALSE(has("CLRT_HAS_BRDF_ORIGINAL_PHONG"));  // defined but used by no material
    CHECK_FALSE(has("CLRT_HAS_BRDF_TORRANCE_SPARROW"));

    // Without BRDF=: the classic shading, no BRDF code in the kernels.
    Scene c = loadScene(writeText(tmp.file("b.xml"), brdfScene(brdfs, "")));
    DeviceScene dc = flattenScene(c);
    CHECK(dc.materials.at(0).brdf == CLRT_INVALID);
    for (const std::string& f : dc.features.defines()) CHECK(f.find("BRDF") == std::string::npos);
    // Every BRDF flag is one FeatureSet::all() sets.
    std::vector<std::string> all = FeatureSet::all().defines();
    for (const auto& row : brdfTypes())
        CHECK(std::find(all.begin(), all.end(), std::string("-D") + row.flag + "=1") != all.end());
}

TEST_CASE("BRDFs: bad input is one clear error naming the file and line", "[brdf][scene]") {
    TempDir tmp;
    auto err = [&](const std::string& name, const std::string& brdfs, const std::string& attr) {
        std::string path = writeText(tmp.file(name), brdfScene(brdfs, attr));
        try {
            loadScene(path);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    std::string ok = "<BRDFs><ModifiedPhong id=\"1\"><Exponent>5</Exponent></ModifiedPhong></BRDFs>";
    std::string e = err("undef.xml", ok, " BRDF=\"2\"");
    CHECK(e.find("undef.xml:1:") != std::string::npos);
    CHECK(e.find("BRDF 2 is not defined") != std::string::npos);
    e = err("unknown.xml", "<BRDFs><Lambert id=\"1\"/></BRDFs>", "");
    CHECK(e.find("unknown BRDF <Lambert>") != std::string::npos);
    CHECK(e.find("TorranceSparrow") != std::string::npos);
    e = err("dup.xml", "<BRDFs><ModifiedPhong id=\"1\"/><OriginalPhong id=\"1\"/></BRDFs>", "");
    CHECK(e.find("duplicate BRDF id 1") != std::string::npos);
    e = err("neg.xml", "<BRDFs><ModifiedPhong id=\"1\"><Exponent>-3</Exponent></ModifiedPhong></BRDFs>", "");
    CHECK(e.find("must not be negative") != std::string::npos);
    e = err("bool.xml", "<BRDFs><ModifiedPhong id=\"1\" normalized=\"maybe\"/></BRDFs>", "");
    CHECK(e.find("normalized: 'maybe' is not true or false") != std::string::npos);
    e = err("noid.xml", "<BRDFs><ModifiedPhong/></BRDFs>", "");
    CHECK(e.find("has no id") != std::string::npos);
    e = err("badattr.xml", ok, " BRDF=\"x\"");
    CHECK(e.find("BRDF='x' is not an integer") != std::string::npos);
}

TEST_CASE("BRDF samplers: pdf integrates to one, samples follow it (chi-square), pdf(sample) = pdf(eval)", "[brdf]") {
    const Vec3 n = testNormal();
    for (const Case& c : cases()) {
        for (float thetaO : {0.0f, 30.0f, 70.0f}) {
            INFO(c.name << ", wo at " << thetaO << " deg");
            const Vec3 wo = woAt(thetaO);
            // ∫pdf over the hemisphere + the mass of rejected glossy samples (integrated in the lobe's
            // own domain, the hemisphere about its axis) = 1. Midpoint rule.
            double integral = integrate(n, [&](const Vec3& w) { return double(hostBrdfPdf(c.b, n, wo, w)); }, 0, kPi / 2, 1024, 512);
            double rejected = hostRejectedMass(c.b, n, wo, [&](const Vec3& axis, auto g) {
                return integrate(axis, g, 0, kPi / 2, 1024, 512);
            });
            INFO("integral " << integral << " + rejected " << rejected);
            CHECK(integral + rejected == Approx(1.0).epsilon(0.002));

            // Chi-square: bins of θ (about n) × φ over the sphere, expected mass per bin by integration.
            const int TB = 16, PB = 24, N = 200000;
            std::vector<double> expected(TB * PB), observed(TB * PB, 0.0);
            for (int i = 0; i < TB; ++i)
                for (int j = 0; j < PB; ++j) {
                    double th0 = kPi / 2 * i / TB, th1 = kPi / 2 * (i + 1) / TB, sum = 0;
                    const int S = 24;
                    double dth = (th1 - th0) / S, dph = 2 * kPi / PB / S;
                    for (int a = 0; a < S; ++a)
                        for (int b2 = 0; b2 < S; ++b2) {
                            double th = th0 + (a + 0.5) * dth, ph = 2 * kPi * j / PB + (b2 + 0.5) * dph;
                            sum += hostBrdfPdf(c.b, n, wo, dirAt(n, th, ph)) * std::sin(th) * dth * dph;
                        }
                    expected[i * PB + j] = sum;
                }
            std::mt19937 rng(5);
            std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
            int failed = 0, pdfMismatch = 0;
            Vec3 t, b;
            brdfBasis(n, t, b);
            for (int s = 0; s < N; ++s) {
                Vec3 wi;
                float pdf;
                float u1 = uni(rng), u2 = uni(rng);
                if (!hostBrdfSample(c.b, n, wo, u1, u2, wi, pdf)) { ++failed; continue; }
                float pe = hostBrdfPdf(c.b, n, wo, wi);
                if (!(std::fabs(pe - pdf) <= 2e-3f * pdf)) ++pdfMismatch;
                double th = std::acos(std::clamp(double(dot(wi, n)), -1.0, 1.0));
                double ph = std::atan2(double(dot(wi, b)), double(dot(wi, t)));
                if (ph < 0) ph += 2 * kPi;
                int bi = std::min(TB - 1, int(th / (kPi / 2) * TB)), bj = std::min(PB - 1, int(ph / (2 * kPi) * PB));
                observed[bi * PB + bj] += 1;
            }
            CHECK(pdfMismatch <= N / 1000);
            // The rejected samples are one more bin, expected N · (rejected mass).
            double chi2 = 0, pool = 0, poolObs = 0;
            int dof = -1;
            expected.push_back(rejected);
            observed.push_back(failed);
            for (size_t k = 0; k < expected.size(); ++k) {
                double e = expected[k] * N;
                if (e < 5) { pool += e; poolObs += observed[k]; continue; }
                chi2 += (observed[k] - e) * (observed[k] - e) / e;
                ++dof;
            }
            if (pool >= 5) { chi2 += (poolObs - pool) * (poolObs - pool) / pool; ++dof; }
            REQUIRE(dof >= 3);
            double crit = chi2Critical(dof, 4.0);
            INFO("chi2 " << chi2 << " with " << dof << " dof (critical " << crit << "), pdf mismatches " << pdfMismatch);
            CHECK(chi2 < crit);
        }
    }
}

TEST_CASE("BRDFs: the normalized ones (and Torrance-Sparrow) reflect at most what arrives (albedo <= 1)", "[brdf]") {
    const Vec3 n = testNormal();
    struct Norm { int kind; int flags; };
    for (Norm nb : {Norm{dev::BRDF_MODIFIED_PHONG, CLRT_BRDF_NORMALIZED}, Norm{dev::BRDF_MODIFIED_BLINN_PHONG, CLRT_BRDF_NORMALIZED},
                    Norm{dev::BRDF_TORRANCE_SPARROW, 0}, Norm{dev::BRDF_TORRANCE_SPARROW, CLRT_BRDF_KD_FRESNEL}}) {
        for (float p : {1.0f, 4.0f, 10.0f, 50.0f, 200.0f}) {
            for (Vec3 kdks : {Vec3(0, 1, 0), Vec3(0.5f, 0.5f, 0), Vec3(1, 0, 0)}) {  // (kd, ks), kd + ks = 1
                HostBrdf b;
                b.kind = nb.kind;
                b.flags = nb.flags;
                b.exponent = p;
                b.kd = Vec3(kdks.x);
                b.ks = Vec3(kdks.y);
                b.eta = 0.37f;
                b.k = 2.82f;
                double worst = 0;
                for (float thetaO : {0.0f, 20.0f, 45.0f, 70.0f, 85.0f}) {
                    Vec3 wo = woAt(thetaO);
                    double a = integrate(n, [&](const Vec3& wi) { return double(hostBrdfEval(b, n, wo, wi).x) * std::max(0.0f, dot(n, wi)); },
                                         0, kPi / 2, 1024, 256);
                    worst = std::max(worst, a);
                }
                INFO("kind " << nb.kind << " flags " << nb.flags << " p " << p << " kd " << kdks.x << " ks " << kdks.y
                             << ": largest albedo " << worst);
                // The course's (p+8)/(8π) of ModifiedBlinnPhong is an approximate normalization: it reflects
                // more than arrives (measured: up to 1.075, at p = 10 and wo at 85°; 1.024 at p = 1 and normal
                // incidence). Kept as the course has it (its reference matches at 98 dB); bounded here.
                bool approxNorm = nb.kind == dev::BRDF_MODIFIED_BLINN_PHONG;
                if (approxNorm && kdks.y == 1) WARN("ModifiedBlinnPhong normalized p=" << p << ": largest albedo " << worst);
                CHECK(worst <= (approxNorm ? 1.08 : 1.0 + 2e-3));  // 2e-3: the midpoint rule's error
                if (kdks.x == 1 && !(nb.flags & CLRT_BRDF_KD_FRESNEL))
                    CHECK(worst == Approx(1.0).epsilon(2e-3));  // kd/π alone: exactly 1
            }
        }
    }
}

// Math_PowNonNegative (common.cl), the Phong lobes' x^e: pow's values at x = 0 (it no longer calls pow
// there), and within 1e-5 of pow for x > 0 wherever the result is not negligible.
TEST_CASE("BRDF kernels: Math_PowNonNegative is pow at x = 0 and within 1e-5 of it elsewhere", "[brdf][cl]") {
    const char* src = R"CLC(
__kernel void pow_test(const __global float2* in, __global float* out, int n) {
    int i = get_global_id(0);
    if (i < n) out[i] = Math_PowNonNegative(in[i].x, in[i].y);
}
)CLC";
    const float xs[] = {0.0f, -0.0f, 1e-30f, 1e-6f, 0.25f, 0.5f, 0.9f, 0.999f, 1.0f};
    const float es[] = {0.0f, 1.0f, 2.5f, 10.0f, 100.0f, 1000.0f, -1.0f, NAN};
    std::vector<dev::float2> in;
    for (float x : xs)
        for (float e : es) in.push_back({x, e});
    const int n = int(in.size());
    const std::vector<float> out = runElementwiseKernel<float>({"common.cl"}, "pow_test", src, in);
    for (int i = 0; i < n; ++i) {
        const float x = in[size_t(i)].x, e = in[size_t(i)].y, got = out[size_t(i)];
        const float want = std::pow(x, e);
        INFO("x " << x << " e " << e << ": device " << got << ", pow " << want);
        if (std::signbit(x) && e < 0.0f) continue;  // -0 to a negative power: outside its domain (pow: ±inf)
        if (std::isnan(e)) {
            CHECK((std::isnan(got) || got == want));  // NaN, or pow's 1 at x = 1
        } else if (x == 0.0f) {
            CHECK(got == want);  // 1, 0 or +inf, as pow
        } else if (want > 1e-30f) {
            CHECK(std::fabs(got - want) <= 1e-5f * want);
        } else {
            CHECK(got <= 1e-30f);
        }
    }
}

TEST_CASE("BRDF kernels: Brdf_Eval, Brdf_Sample and Brdf_Pdf equal the host reference", "[brdf][cl]") {
    const char* src = R"CLC(
__kernel void brdf_test(const __global float4* params, const __global float4* in, __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    BrdfParams b;
    b.kind = (int)params[0].x; b.exponent = params[0].y; b.flags = (int)params[0].z;
    b.eta = params[0].w; b.k = params[1].w; b.kd = params[1].xyz; b.ks = params[2].xyz;
    float3 nrm = in[3 * i].xyz, wo = in[3 * i + 1].xyz, wiIn = in[3 * i + 2].xyz;
    float2 u = (float2)(in[3 * i].w, in[3 * i + 1].w);
    float3 wi; float pdf;
    int ok = Brdf_Sample(&b, nrm, wo, u, &wi, &pdf);
    out[3 * i] = (float4)(wi, ok ? pdf : -1.0f);
    out[3 * i + 1] = (float4)(Brdf_Eval(&b, nrm, wo, wiIn), Brdf_Pdf(&b, nrm, wo, wiIn));
    out[3 * i + 2] = (float4)(Brdf_Eval(&b, nrm, wo, wi), 0.0f);
}
)CLC";
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources({"brdf.cl"});
    sources.push_back({"brdf_test.cl", src});
    FeatureSet all;
    all.brdfKinds = ~0u;
    cl::Program program = buildProgramFromSources(dc, sources, all.defines());
    cl::Kernel k = CL_CPP(cl::Kernel(program, "brdf_test"));
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
    std::normal_distribution<float> g;
    for (const Case& c : cases()) {
        INFO(c.name);
        const int n = 8192;
        std::vector<dev::float4> in(3 * size_t(n)), out(3 * size_t(n));
        for (int i = 0; i < n; ++i) {
            Vec3 nn = normalize(Vec3(g(rng), g(rng), g(rng)));
            Vec3 wo = normalize(Vec3(g(rng), g(rng), g(rng)));
            if (dot(wo, nn) < 0) wo = -wo;
            Vec3 wi = normalize(Vec3(g(rng), g(rng), g(rng)));
            if (i % 2 == 0 && dot(wi, nn) < 0) wi = -wi;
            in[3 * i] = {nn.x, nn.y, nn.z, uni(rng)};
            in[3 * i + 1] = {wo.x, wo.y, wo.z, uni(rng)};
            in[3 * i + 2] = {wi.x, wi.y, wi.z, 0};
        }
        dev::float4 params[3] = {{float(c.b.kind), c.b.exponent, float(c.b.flags), c.b.eta},
                                 {c.b.kd.x, c.b.kd.y, c.b.kd.z, c.b.k},
                                 {c.b.ks.x, c.b.ks.y, c.b.ks.z, 0}};
        cl::Context& ctx = dc.context();
        auto ro = [&](const void* p, size_t bytes) {
            return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(p)));
        };
        cl::Buffer pBuf = ro(params, sizeof(params)), inBuf = ro(in.data(), in.size() * sizeof(dev::float4));
        cl::Buffer outBuf = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
        k.setArg(0, pBuf); k.setArg(1, inBuf); k.setArg(2, outBuf); k.setArg(3, n);
        CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(n, 64)), cl::NDRange(64)));
        CL_CPP(dc.queue().enqueueReadBuffer(outBuf, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
        int okMismatch = 0, sampleBad = 0, evalBad = 0, pdfBad = 0, compared = 0;
        auto close = [](float a, float b) { return std::fabs(a - b) <= 1e-3f * std::max(std::fabs(a), std::fabs(b)) + 1e-6f; };
        for (int i = 0; i < n; ++i) {
            Vec3 nn(in[3 * i].x, in[3 * i].y, in[3 * i].z), wo(in[3 * i + 1].x, in[3 * i + 1].y, in[3 * i + 1].z),
                wiIn(in[3 * i + 2].x, in[3 * i + 2].y, in[3 * i + 2].z);
            Vec3 wi;
            float pdf;
            bool ok = hostBrdfSample(c.b, nn, wo, in[3 * i].w, in[3 * i + 1].w, wi, pdf);
            const dev::float4& o = out[3 * i];
            if (ok != (o.w >= 0)) { ++okMismatch; continue; }
            if (ok) {
                ++compared;
                if (angleBetween(wi, Vec3(o.x, o.y, o.z)) > 1e-4f || !close(o.w, pdf)) ++sampleBad;
                Vec3 f = hostBrdfEval(c.b, nn, wo, wi);
                const dev::float4& e = out[3 * i + 2];
                if (!close(e.x, f.x) || !close(e.y, f.y) || !close(e.z, f.z)) ++evalBad;
            }
            Vec3 f = hostBrdfEval(c.b, nn, wo, wiIn);
            const dev::float4& e = out[3 * i + 1];
            if (!close(e.x, f.x) || !close(e.y, f.y) || !close(e.z, f.z)) ++evalBad;
            if (!close(e.w, hostBrdfPdf(c.b, nn, wo, wiIn))) ++pdfBad;
        }
        INFO("sampled " << compared << ", ok mismatches " << okMismatch << ", samples off " << sampleBad << ", eval off "
                        << evalBad << ", pdf off " << pdfBad);
        CHECK(compared >= n / 2);  // the rest: glossy directions below the surface, rejected on both sides alike
        CHECK(okMismatch <= n / 2000);
        CHECK(sampleBad <= n / 1000);  // ulp differences of pow/cos between libm and the device, near a lobe's peak
        CHECK(evalBad <= n / 1000);
        CHECK(pdfBad <= n / 1000);
    }
}

namespace {

ImageRGB renderHw6(const std::string& name, int spp, uint32_t seed, PixelSampler pixelSampler = PixelSampler::Stratified) {
    Scene scene = loadScene(sharedDir() + "/scenes/hw6/" + name + ".xml");
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = spp;
    rs.seed = seed;
    rs.pixelSampler = pixelSampler;
    RenderCounters c;
    return r.render(scene.cameras.at(0), rs, c);
}

}  // namespace

// [course]: scripts/check_course checks the same cameras by the same rule (see tests/test_hw4.cpp).
TEST_CASE("hw6 brdf scenes match the course's PNGs at >= 40 dB (800x800, 1 spp, deterministic)", "[brdf][render][shared][hw6][course]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    for (const char* name : {"brdf_phong_original", "brdf_phong_modified", "brdf_blinnphong_original",
                             "brdf_blinnphong_modified_normalized", "brdf_torrancesparrow"}) {
        ImageRGB img = renderHw6(name, 1, 1);
        ImageRGB ref = readImage(sharedDir() + "/scenes/hw6/_reference_outputs/" + name + ".png");
        REQUIRE(img.width == ref.width);
        REQUIRE(img.height == ref.height);
        double p = psnr8(quantize(img, true), ref);  // --ldr-quantize floor, the course's convention
        WARN(name << ": PSNR " << p << " dB");
        CHECK(p >= 40.0);
    }
}

// The point-lit cornell boxes against the course's 100-spp EXRs, both box-downsampled 8×8. With N spp
// (independent renders a, b; reference at R = 100), relMSE(a, ref) ≈ v_N + v_R + bias² and relMSE(a, b)
// ≈ 2 v_N, v_R = v_N·N/R: the rule is relMSE(a, ref) ≤ relMSE(a, b)·(1 + N/R), which at N = R is the
// issue's "≤ 2× the relMSE of two independent renders at the reference's spp" (bias² ≤ 2 v_R). The
// references jitter each sample independently over the pixel; clrt stratifies (10×10 at 100 spp), which
// has about 5× less variance at the edges, so a and b are rendered unstratified (RenderSettings::pixelSampler)
// to have the reference's noise; the stratified render's numbers are printed too. The suite runs N = 8
// (CLRT_HW6_SPP overrides; scripts/hw6_direct_compare.sh runs N = 100); the means of each channel must
// also agree within 1% (a π or other global factor fails here).
TEST_CASE("hw6 cornellbox_jaroslav diffuse/glossy match the course's EXRs within the noise floor", "[brdf][render][shared][hw6]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    int spp = 8;
    if (const char* e = std::getenv("CLRT_HW6_SPP")) spp = std::max(1, std::atoi(e));
    const double R = 100;
    for (const char* name : {"cornellbox_jaroslav_diffuse", "cornellbox_jaroslav_glossy"}) {
        ImageRGB ref = readImage(sharedDir() + "/scenes/hw6/_reference_outputs/" + name + ".exr");
        ImageRGB a = renderHw6(name, spp, 1, PixelSampler::Independent), b = renderHw6(name, spp, 2, PixelSampler::Independent), st = renderHw6(name, spp, 3);
        REQUIRE(a.width == ref.width);
        REQUIRE(a.height == ref.height);
        ImageRGB ad = boxDownsample(a, 8), bd = boxDownsample(b, 8), rd = boxDownsample(ref, 8), sd = boxDownsample(st, 8);
        double toRef = relativeMse(ad, rd), floorAB = relativeMse(ad, bd), limit = floorAB * (1 + spp / R);
        double mean[2][3] = {};
        for (size_t i = 0; i < a.pixels.size(); ++i) {
            mean[0][i % 3] += a.pixels[i];
            mean[1][i % 3] += ref.pixels[i];
        }
        WARN(name << " at " << spp << " spp, independent jitter: relMSE to reference " << toRef
                  << ", between two renders " << floorAB << " (limit " << limit << "); mean ratio clrt/reference r "
                  << mean[0][0] / mean[1][0] << " g " << mean[0][1] / mean[1][1] << " b " << mean[0][2] / mean[1][2]
                  << "; stratified render: relMSE to reference " << relativeMse(sd, rd) << ", to the first render "
                  << relativeMse(sd, ad));
        CHECK(toRef <= limit);
        for (int c = 0; c < 3; ++c) CHECK(mean[0][c] / mean[1][c] == Approx(1.0).epsilon(0.01));
    }
}
