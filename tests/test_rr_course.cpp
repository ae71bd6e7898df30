// The course's Russian roulette (clrt render --rr-rule course, cl_kernels/path.cl Path_CourseRoulette;
// docs/studies/2026-12-03-russian-roulette-references.md): q = min(1, largest component of T), T the
// product of the BRDF values f along the path (1 for the camera ray), played at every hit after its own
// radiance is gathered; a survivor divides that radiance and the rest of the path by q, a killed path
// keeps it undivided. In a closed diffuse enclosure of albedo a (normalized ModifiedPhong, exponent 1,
// kd = a: f = a/π) under ImportanceSampling every bounce weighs exactly a, so q_i = (a/π)^(i−1) and a
// sample's value depends only on the hit K where the path dies: a discrete set of values with known
// probabilities. The tests render 1 spp and check every pixel against that set (host reference below)
// and the share of the two likeliest values against their probabilities. A dielectric under the rule
// traces both Fresnel children, weights F and 1 − F, each with T times its weight: behind a glass plate at
// normal incidence a lit wall is seen at Le·(1 − F) or Le/(1 − F) (the course's glass box shows Le·kd/(1 − F)
// on its sphere), never at Le as a Fresnel pick would give. Reads scenes it writes itself.
#include <catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "flatten/device_scene.h"
#include "image/image.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

struct Atom {
    double value, probability;  // the sample value of a path that dies at hit K, and P(K)
};

// Host reference: hit i (1-based) gathers radiance L1 (i = 1) or L (i > 1) and reaches it with the
// cosine-sampled weight a^(i−1); S_i = q_1·…·q_i. A path dying at hit K (K ≥ 2, as q_1 = 1) is worth
// Σ_{i<K} a^(i−1)·L_i/S_i + a^(K−1)·L_K/S_(K−1), with probability S_(K−1)·(1 − q_K).
std::vector<Atom> courseAtoms(double a, double L1, double L, int kMax) {
    std::vector<Atom> atoms;
    const double f = a / M_PI;
    double S = 1.0, sum = L1, weight = 1.0, q = 1.0;  // after hit 1: S_1 = 1, sum = L1/S_1
    for (int K = 2; K <= kMax; ++K) {
        q *= f;                                          // q_K = f^(K−1)
        weight *= a;                                     // a^(K−1)
        atoms.push_back({sum + weight * L / S, S * (1.0 - q)});
        S *= q;
        sum += weight * L / S;
    }
    return atoms;
}

std::string write(const TempDir& d, const std::string& name, const std::string& text) {
    std::ofstream(d.file(name), std::ios::binary) << text;
    return d.file(name);
}

std::string camera(const std::string& params, int size) {
    std::ostringstream s;
    s << "<Cameras><Camera id=\"1\" type=\"lookAt\"><Position>0.05 0.02 0.03</Position><GazePoint>0.3 0.2 -1</GazePoint>"
      << "<Up>0 1 0</Up><FovY>90</FovY><NearDistance>0.1</NearDistance><ImageResolution>" << size << " " << size
      << "</ImageResolution><ImageName>out.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>" << params
      << "</RendererParams></Camera></Cameras>";
    return s.str();
}

std::string diffuseMaterial(double a) {
    std::ostringstream s;
    s << "<BRDFs><ModifiedPhong id=\"1\" normalized=\"true\"><Exponent>1</Exponent></ModifiedPhong></BRDFs>"
      << "<Materials><Material id=\"1\" BRDF=\"1\"><DiffuseReflectance>" << a << " " << a << " " << a
      << "</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material></Materials>";
    return s.str();
}

// The camera inside a cube LightMesh (half size 1, faces towards the inside) emitting Le, albedo a.
std::string emittingCube(const std::string& params, double a, double Le, int size) {
    std::ostringstream s;
    s << "<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>3</MaxRecursionDepth>" << camera(params, size)
      << diffuseMaterial(a)
      << "<VertexData>-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1</VertexData>"
      << "<Objects><LightMesh id=\"1\"><Material>1</Material><Radiance>" << Le << " " << Le << " " << Le
      << "</Radiance><Faces>1 2 3  1 3 4  5 8 7  5 7 6  1 5 6  1 6 2  4 3 7  4 7 8  1 4 8  1 8 5  2 6 7  2 7 3"
      << "</Faces></LightMesh></Objects></Scene>";
    return s.str();
}

// The camera inside a diffuse sphere of radius R (albedo a) with a point light of intensity I at its
// centre: next-event estimation gathers exactly f·I/R² = a·I/(π·R²) at every hit (normal incidence).
std::string litSphere(const std::string& params, double a, double I, double R, int size) {
    std::ostringstream s;
    s << "<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>3</MaxRecursionDepth>" << camera(params, size)
      << "<Lights><PointLight id=\"1\"><Position>0 0 0</Position><Intensity>" << I << " " << I << " " << I
      << "</Intensity></PointLight></Lights>" << diffuseMaterial(a)
      << "<VertexData>0 0 0</VertexData><Objects><Sphere id=\"1\"><Material>1</Material><Center>1</Center><Radius>" << R
      << "</Radius></Sphere></Objects></Scene>";
    return s.str();
}

// The camera looking through a glass plate (index 1.5, no absorption; z = -1 and -1.2) at a LightMesh wall
// emitting Le (z = -3), everything at normal incidence (FovY 2°), no NEE.
std::string glassPlate(const std::string& params, double Le, int size) {
    std::ostringstream s;
    s << "<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>3</MaxRecursionDepth>"
      << "<Cameras><Camera id=\"1\" type=\"lookAt\"><Position>0 0 0</Position><GazePoint>0 0 -1</GazePoint>"
      << "<Up>0 1 0</Up><FovY>2</FovY><NearDistance>0.1</NearDistance><ImageResolution>" << size << " " << size
      << "</ImageResolution><ImageName>out.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>" << params
      << "</RendererParams></Camera></Cameras>"
      << "<Materials><Material id=\"1\"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0"
      << "</SpecularReflectance></Material><Material id=\"2\" type=\"dielectric\"><DiffuseReflectance>0 0 0"
      << "</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance><MirrorReflectance>1 1 1</MirrorReflectance>"
      << "<AbsorptionCoefficient>0 0 0</AbsorptionCoefficient><RefractionIndex>1.5</RefractionIndex></Material></Materials>"
      << "<VertexData>-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 -1.2  1 -1 -1.2  1 1 -1.2  -1 1 -1.2"
      << "  -2 -2 -3  2 -2 -3  2 2 -3  -2 2 -3</VertexData>"
      << "<Objects><Mesh id=\"1\"><Material>2</Material><Faces>1 2 3  1 3 4  5 8 7  5 7 6</Faces></Mesh>"
      << "<LightMesh id=\"2\"><Material>1</Material><Radiance>" << Le << " " << Le << " " << Le
      << "</Radiance><Faces>9 10 11  9 11 12</Faces></LightMesh></Objects></Scene>";
    return s.str();
}

ImageRGB renderRule(const Scene& scene, RouletteRule rule, int spp, uint32_t seed) {
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = spp;
    rs.seed = seed;
    rs.rouletteRule = rule;
    RenderCounters c;
    return r.render(scene.cameras.at(0), rs, c);
}

// Every pixel (1 spp) one of the atoms within relTol (relative), but for at most `unmatched` pixels, and
// the shares of the two likeliest atoms within 4 binomial standard deviations of their probabilities.
void checkAtoms(const ImageRGB& img, const std::vector<Atom>& atoms, double relTol = 1e-4, size_t allowed = 0) {
    const size_t n = img.pixels.size() / 3;
    std::vector<size_t> count(atoms.size(), 0);
    size_t unmatched = 0;
    for (size_t p = 0; p < n; ++p) {
        const double v = img.pixels[3 * p];
        size_t best = 0;
        for (size_t k = 1; k < atoms.size(); ++k)
            if (std::fabs(v - atoms[k].value) < std::fabs(v - atoms[best].value)) best = k;
        if (std::fabs(v - atoms[best].value) <= relTol * atoms[best].value) ++count[best];
        else if (++unmatched <= 3) WARN("pixel " << p << " = " << v << ", nearest course value " << atoms[best].value);
    }
    CHECK(unmatched <= allowed);
    for (size_t k = 0; k < 2; ++k) {
        const double expected = atoms[k].probability * double(n);
        const double sd = std::sqrt(double(n) * atoms[k].probability * (1.0 - atoms[k].probability));
        INFO("death at hit " << k + 2 << ": value " << atoms[k].value << ", " << count[k] << " pixels, expected "
                             << expected << " ± " << sd);
        CHECK(std::fabs(double(count[k]) - expected) <= 4.0 * sd);
    }
}

}  // namespace

TEST_CASE("--rr-rule course: a killed path keeps its last hit's emission undivided (emitting enclosure)", "[path][render][rr]") {
    TempDir d;
    const double a = 0.5, Le = 1.0;
    Scene scene = loadScene(write(d, "cube.xml", emittingCube("ImportanceSampling RussianRoulette", a, Le, 64)));
    // Le + a·Le when the path dies at the second hit (probability 1 − a/π), then 1 + π + π/2, …
    const std::vector<Atom> atoms = courseAtoms(a, Le, Le, 12);
    REQUIRE(atoms[0].value == Approx(1.5));
    REQUIRE(atoms[1].value == Approx(1.0 + M_PI + M_PI / 2));
    checkAtoms(renderRule(scene, RouletteRule::Course, 1, 7), atoms);
}

TEST_CASE("--rr-rule course: next-event estimation is inside the roulette too (point light in a sphere)", "[path][render][rr]") {
    TempDir d;
    const double a = 0.6, I = 2.0, R = 1.5, D = a * I / (M_PI * R * R);
    Scene scene =
        loadScene(write(d, "sphere.xml", litSphere("NextEventEstimation ImportanceSampling RussianRoulette", a, I, R, 64)));
    checkAtoms(renderRule(scene, RouletteRule::Course, 1, 3), courseAtoms(a, D, D, 12));
}

TEST_CASE("--rr-rule course: a dielectric traces both Fresnel children, T times their weights (glass plate)", "[path][render][rr]") {
    TempDir d;
    const double Le = 2.0, F = 0.04;  // ((1.5 - 1) / (1.5 + 1))^2 at normal incidence
    Scene scene = loadScene(write(d, "plate.xml", glassPlate("ImportanceSampling RussianRoulette", Le, 64)));
    // Refracted in (weight 1 - F, T = 1 - F), out at the back face after its roulette (q = 1 - F: divided),
    // weight 1 - F, T = (1 - F)^2: the wall's Le·(1 - F)^2 / (1 - F), divided again by q = (1 - F)^2 when the
    // path survives there. Killed at the back face (probability F): 0. The plate's inner reflections reach the
    // wall only after surviving q = (1 - F)·F and (1 - F)·F² (about 6e-5 of the samples): 2 pixels allowed.
    // Within 1e-3: F varies by less than that over the 2° field.
    const std::vector<Atom> atoms = {{Le / (1 - F), (1 - F) * (1 - F) * (1 - F)},
                                     {Le * (1 - F), (1 - F) * (1 - (1 - F) * (1 - F))},
                                     {0.0, F}};
    checkAtoms(renderRule(scene, RouletteRule::Course, 1, 11), atoms, 1e-3, 2);
}

TEST_CASE("--rr-rule: unbiased by default; course only changes RussianRoulette cameras", "[path][render][rr]") {
    TempDir d;
    // Unbiased: the image mean of the emitting enclosure is Le/(1 − a) (the course rule's would be
    // Le·(2/(1 − a) − 1/(1 − a²/π)) = 2.91 for a = 0.5).
    Scene rr = loadScene(write(d, "rr.xml", emittingCube("ImportanceSampling RussianRoulette", 0.5, 1.0, 32)));
    const ImageRGB unbiased = renderRule(rr, RouletteRule::Unbiased, 64, 5);
    double sum = 0;
    for (size_t i = 0; i < unbiased.pixels.size(); i += 3) sum += unbiased.pixels[i];
    CHECK(sum / double(unbiased.pixels.size() / 3) == Approx(2.0).epsilon(0.02));
    // Without RussianRoulette the rule is not used: the same image, bit for bit.
    Scene plain = loadScene(write(d, "plain.xml", emittingCube("ImportanceSampling", 0.5, 1.0, 16)));
    CHECK(renderRule(plain, RouletteRule::Course, 4, 5).pixels == renderRule(plain, RouletteRule::Unbiased, 4, 5).pixels);
    // The command line: --rr-rule course is accepted, anything else is a usage error naming the values.
    const std::string base = "render " + d.file("plain.xml") + " -o " + d.path.string() + " --spp 1" + deviceArg();
    CHECK(runClrt(base + " --rr-rule course", d.file("log")) == 0);
    const int rc = runClrt(base + " --rr-rule fixed", d.file("log"));
    CHECK(cliResult(rc, readFileBytes(d.file("log"))).rc == 1);
    CHECK(readFileBytes(d.file("log")).find("--rr-rule: expected unbiased or course, got 'fixed'") != std::string::npos);
}

TEST_CASE("--rr-rule course: one renderer alternating three-slot and two-slot renders of different sizes", "[path][render][rr]") {
    // The queues grow to the largest request and never shrink: a smaller render with three child slots per
    // path between two larger two-slot ones must leave the second large render equal to the first.
    TempDir d;
    Scene scene = loadScene(write(d, "plate.xml", glassPlate("ImportanceSampling RussianRoulette", 2.0, 64)));
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    Camera big = scene.cameras.at(0), small = big;
    big.width = big.height = 96;
    small.width = small.height = 24;
    auto render = [&](const Camera& cam, RouletteRule rule) {
        RenderSettings rs;
        rs.spp = 2;
        rs.seed = 4;
        rs.rouletteRule = rule;
        rs.pipeline = Pipeline::Wavefront;
        RenderCounters c;
        ImageRGB img = r.render(cam, rs, c);
        CHECK(c.fullQueues == 0);
        return img;
    };
    const ImageRGB first = render(big, RouletteRule::Unbiased);
    const ImageRGB course = render(small, RouletteRule::Course);
    CHECK(course.pixels.size() == size_t(24 * 24 * 3));
    CHECK(render(big, RouletteRule::Unbiased).pixels == first.pixels);
    CHECK(render(big, RouletteRule::Course).pixels.size() == first.pixels.size());
}
