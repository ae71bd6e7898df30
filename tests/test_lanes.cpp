// The lanes kernel (cl_kernels/lanes.cl, render_lanes; Pipeline::Lanes): four paths per work-item in
// vector lanes. With the same random streams it computes what render_fused computes, up to rounding:
// every camera of the course's hw6 path box (NEE, importance sampling, roulette; LightMesh and
// point light), each also under MIS with the power and the balance heuristic, against render_fused's
// image: the difference under 1e-5 of the noise between two seeds (PoCL: ~1e-13 of it), the same ray
// counts; specular children (a mirror beside a diffuse part, glass; the classic Cornell box with a point
// light only); classic cameras with an environment light (its MIS in steps across the lanes), and their children
// (mirror, glass). Also: which scenes and cameras it takes (lanesFamily, lanesUnsupported, auto), determinism,
// sample counts that are no multiple of four, launches of several passes, the fallback to render_fused.
#include <catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>

#include "flatten/device_scene.h"
#include "render/fused_renderer.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// bench.py's relMSE: mean over pixels and channels of (a − b)² / (b² + 0.01).
double relMse(const ImageRGB& a, const ImageRGB& b) {
    double s = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const double d = double(a.pixels[i]) - double(b.pixels[i]);
        s += d * d / (double(b.pixels[i]) * double(b.pixels[i]) + 0.01);
    }
    return s / double(a.pixels.size());
}

// relMse over the pixels (all three channels) where a and b differ by at most 1e-3 relative, and how many do
// not (*branched): pixels whose paths took another branch somewhere (a roulette decision or a shadow ray's
// hit flipped by another rounding: Intel's runtime contracts the two kernels' arithmetic differently, and a
// roulette path without a depth cap meets ~10 such decisions).
double relMseUnbranched(const ImageRGB& a, const ImageRGB& b, int* branched) {
    double s = 0;
    size_t n = 0;
    *branched = 0;
    for (size_t i = 0; i + 2 < a.pixels.size(); i += 3) {
        bool far = false;
        for (size_t c = i; c < i + 3; ++c)
            far = far || std::fabs(double(a.pixels[c]) - double(b.pixels[c])) > 1e-3 * (std::fabs(double(b.pixels[c])) + 0.1);
        if (far) { ++*branched; continue; }
        for (size_t c = i; c < i + 3; ++c) {
            const double d = double(a.pixels[c]) - double(b.pixels[c]);
            s += d * d / (double(b.pixels[c]) * double(b.pixels[c]) + 0.01);
        }
        n += 3;
    }
    return n ? s / double(n) : 0.0;
}

const char* kPathBox = "hw6/cornellbox_jaroslav_path_diffuse.xml";

// The scene's first sphere made a mirror of reflectance r that keeps its material's diffuse part (a new
// material: the others using the old one keep it).
void mirrorFirstSphere(Scene& scene, float r) {
    for (Shape& sh : scene.shapes) {
        if (sh.type != ShapeType::Sphere) continue;
        Material m = scene.materials.at(size_t(sh.materialIndex));
        m.type = dev::MATERIAL_MIRROR;
        m.mirror = {r, r, r};
        scene.materials.push_back(m);
        sh.materialIndex = int(scene.materials.size()) - 1;
        return;
    }
}

// Renders cam (size × size, 8 spp, the sampler given) with the lanes and with render_fused at seed 3, and render_fused at
// seed 4 for the noise between seeds; checks that the lanes computed render_fused's image up to rounding
// (relMSE under 1e-5 of that noise, which must exceed minNoise, and under maxDiff) with the same rays. Where
// a path took another branch (relMseUnbranched: at most 1 pixel in 2000, or 2; PoCL 1 of 1600 on the glossy
// area-sphere box) the rest holds the rounding bound.
void checkLanesAsFused(Renderer& r, const Camera& cam, int size, double minNoise, double maxDiff = 1e30,
                       PixelSampler sampler = PixelSampler::Stratified) {
    Rendered l = renderWith(r, cam, size, size, 8, 3, Pipeline::Lanes, 0, sampler);
    Rendered f = renderWith(r, cam, size, size, 8, 3, Pipeline::Fused, 0, sampler);
    Rendered f2 = renderWith(r, cam, size, size, 8, 4, Pipeline::Fused, 0, sampler);
    CHECK(l.counters.lanes);
    CHECK_FALSE(f.counters.lanes);
    int branched = 0;
    const double noise = relMse(f2.image, f.image), diff = relMseUnbranched(l.image, f.image, &branched);
    INFO("relMSE lanes/fused " << diff << " (" << branched << " pixels branched), between seeds " << noise);
    CHECK(noise > minNoise);
    CHECK(diff < 1e-5 * noise);  // PoCL ~1e-13 of it, Intel ~1e-7 (other contractions)
    CHECK(branched <= std::max(2, int(l.image.pixels.size() / 3 / 2000)));
    CHECK(diff < maxDiff);
    CHECK(l.counters.cameraRays == f.counters.cameraRays);
    CHECK(l.counters.secondaryRays == f.counters.secondaryRays);
    CHECK(l.counters.shadowRays == f.counters.shadowRays);
    CHECK(l.counters.pathSegments == f.counters.pathSegments);
}

}  // namespace

TEST_CASE("lanes: render_fused's image up to rounding on every path camera of the hw6 box", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
    DeviceScene ds = flattenScene(scene);
    REQUIRE(lanesFamily(ds).empty());
    REQUIRE(ds.features.lanes);
    Renderer r(testContext(), ds);
    int compared = 0;
    for (size_t c = 0; c < scene.cameras.size(); ++c) {
        Camera cam = scene.cameras[c];
        // Roulette (no depth cap, four samples per group at 40²): more depths than render_fused's per-depth
        // sums, so "fused" renders on the wavefront (the same image) and the lanes sum the deepest together.
        for (int mode : {cam.pathMode, CLRT_PATH_ON | CLRT_PATH_MIS, CLRT_PATH_ON | CLRT_PATH_MIS | CLRT_PATH_MIS_BALANCE}) {
            cam.pathMode = mode;
            INFO("camera " << cam.id << ", path mode " << mode);
            checkLanesAsFused(r, cam, 40, 1e-3);
            ++compared;
        }
    }
    CHECK(compared == 24);
}

TEST_CASE("lanes: specular children (mirror beside a diffuse part, glass) as render_fused draws them", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // The hw6 path box with its spheres turned into a mirror with a diffuse part (pSpecular ½) and a
    // rough-free glass (pSpecular 1, Beer's law inside): the specular picks, Path_SpecularBounce per lane.
    Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
    int turned = 0;
    for (Shape& sh : scene.shapes) {
        if (sh.type != ShapeType::Sphere) continue;
        Material m = scene.materials.at(size_t(sh.materialIndex));
        if (turned == 0) { m.type = dev::MATERIAL_MIRROR; m.mirror = {0.7f, 0.7f, 0.7f}; m.diffuse = {0.2f, 0.3f, 0.2f}; }
        else { m.type = dev::MATERIAL_DIELECTRIC; m.diffuse = {0, 0, 0}; m.refractionIndex = 1.5f; m.absorptionCoefficient = {0.2f, 0.1f, 0.0f}; }
        scene.materials.push_back(m);
        sh.materialIndex = int(scene.materials.size()) - 1;
        ++turned;
    }
    REQUIRE(turned == 2);
    // And the classic Cornell box with a mirror and a glass sphere, path traced: point light only.
    Scene recursive = loadScene(sharedDir() + "/scenes/classic/cornellbox_recursive.xml");
    for (Camera& c : recursive.cameras) c.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
    for (Scene* sc : {&scene, &recursive})
    for (int mode : {CLRT_PATH_ON | CLRT_PATH_MIS, CLRT_PATH_ON | CLRT_PATH_NEE}) {
        DeviceScene ds = flattenScene(*sc);
        REQUIRE(lanesFamily(ds).empty());
        Renderer r(testContext(), ds);
        Camera cam = sc->cameras.at(0);
        cam.pathMode = mode;
        INFO(sc->path << ", path mode " << mode);
        checkLanesAsFused(r, cam, 48, 0.0);
    }
}

TEST_CASE("lanes: a LightMesh of more than 16 triangles (picked by area) as render_fused", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // The hw6 box's light has 10 triangles, which both pick by weight (Lanes_PickByWeight, MeshLight_PickByWeight);
    // each cut in four it has 40, more than CLRT_MESHLIGHT_PICK_MAX: the area pick (Lanes_PickTriangle).
    Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
    int cut = 0;
    for (Shape& sh : scene.shapes) {
        if (sh.lightIndex < 0 || sh.type != ShapeType::Mesh) continue;
        MeshData& m = scene.meshes.at(size_t(sh.meshIndex));
        std::vector<int> idx;
        for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
            const int a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
            auto mid = [&m](int i, int j) {
                m.positions.push_back(0.5f * (m.positions[size_t(i)] + m.positions[size_t(j)]));
                return int(m.positions.size()) - 1;
            };
            const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
            idx.insert(idx.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
        }
        m.indices = idx;
        ++cut;
    }
    REQUIRE(cut == 1);
    DeviceScene ds = flattenScene(scene);
    bool large = false;
    for (const dev::Light& l : ds.lights) large = large || (l.kind == dev::LIGHT_MESH && l.objCount > 16);
    REQUIRE(large);
    Renderer r(testContext(), ds);
    for (int c : {0, 2}) {  // NEE, NEE with importance sampling (no roulette: docs/architecture.md); then MIS
        Camera cam = scene.cameras.at(size_t(c));
        INFO("camera " << c);
        checkLanesAsFused(r, cam, 40, 1e-3);
    }
    Camera mis = scene.cameras.at(0);
    mis.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
    checkLanesAsFused(r, mis, 40, 1e-3);
}

TEST_CASE("lanes: glossy lobes (classic Phong and every BRDF kind) as render_fused evaluates and samples them", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // The hw6 path box with every material given a specular lobe: classic Blinn-Phong (no BRDF), then
    // each BRDF kind (the modified ones normalized and not, Torrance-Sparrow with kd·(1 − F) and without),
    // so that f depends on wo and wi: the glossy lanes evaluate Material_EvalDirect, Path_BouncePdf and
    // Path_SampleBounce in lanes (lanes_brdf.cl). A mirror sphere keeps its diffuse part beside the lobe.
    struct Kind { int brdf; bool normalized, kdFresnel; };
    const Kind kinds[] = {{-1, false, false}, {dev::BRDF_ORIGINAL_PHONG, false, false},
                          {dev::BRDF_ORIGINAL_BLINN_PHONG, false, false}, {dev::BRDF_MODIFIED_PHONG, true, false},
                          {dev::BRDF_MODIFIED_PHONG, false, false}, {dev::BRDF_MODIFIED_BLINN_PHONG, true, false},
                          {dev::BRDF_MODIFIED_BLINN_PHONG, false, false}, {dev::BRDF_TORRANCE_SPARROW, false, true},
                          {dev::BRDF_TORRANCE_SPARROW, false, false}};
    int compared = 0;
    for (const Kind& k : kinds) {
        Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
        if (k.brdf >= 0) {
            Brdf b;
            b.id = 99;
            b.type = dev::BrdfKind(k.brdf);
            b.exponent = 30;
            b.normalized = k.normalized;
            b.kdFresnel = k.kdFresnel;
            scene.brdfs.push_back(b);
        }
        for (Material& m : scene.materials) {
            m.specular = {0.3f, 0.25f, 0.2f};
            m.phongExponent = 30;
            m.refractionIndex = 1.6f;
            m.brdf = k.brdf >= 0 ? int(scene.brdfs.size()) - 1 : -1;
        }
        mirrorFirstSphere(scene, 0.5f);
        DeviceScene ds = flattenScene(scene);
        REQUIRE(lanesFamily(ds).empty());
        for (const dev::Material& m : ds.materials) CHECK_FALSE(m.brdfFlags & CLRT_BRDF_LAMBERTIAN);
        Renderer r(testContext(), ds);
        // Every surface glossy and shaded in lanes: auto takes the lanes.
        CHECK(lanesNoGain(ds).empty());
        Camera autoCam = scene.cameras.at(0);
        autoCam.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
        CHECK(renderWith(r, autoCam, 40, 40, 4, 1, Pipeline::Auto).counters.lanes);
        for (int mode : {CLRT_PATH_ON | CLRT_PATH_MIS, CLRT_PATH_ON | CLRT_PATH_NEE | CLRT_PATH_IMPORTANCE,
                         CLRT_PATH_ON | CLRT_PATH_NEE}) {
            Camera cam = scene.cameras.at(0);
            cam.pathMode = mode;
            INFO("brdf " << k.brdf << ", path mode " << mode);
            checkLanesAsFused(r, cam, 40, 1e-3);
            ++compared;
        }
    }
    CHECK(compared == 27);
    // The flag itself: set where f is direction-free (here: ks = 0, no BRDF or a listed one), not elsewhere.
    Scene plain = loadScene(sharedDir() + "/scenes/" + kPathBox);
    const DeviceScene dp = flattenScene(plain);
    int lambertian = 0;
    for (const dev::Material& m : dp.materials) {
        const bool ks0 = m.specular.x == 0.0f && m.specular.y == 0.0f && m.specular.z == 0.0f;
        CHECK(((m.brdfFlags & CLRT_BRDF_LAMBERTIAN) != 0) == ks0);
        lambertian += ks0;
    }
    CHECK(lambertian >= 3);
}

TEST_CASE("lanes: LightSpheres (an ellipsoid too), area and directional lights in lanes, an environment light per lane as render_fused", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // A LightSphere's samples in lanes (Lanes_SphereLightSample), an ellipsoidal one's too (the hw6 sphere
    // box's light scaled by 1.4 in y about its centre: Lanes_EllipsoidLightSample, its MIS density through
    // Lanes_SphereLightDirectionScale); an area and a directional light's (Lanes_LightDirection); an environment
    // light's through the scalar Light_ShadowRays per lane; a LightSphere's emission where a ray hits it through Path_HitEmission per lane; an
    // environment map's through Shade_Miss. The environment light with one light slot (importance
    // sampling) and with two (its default MIS between the light's and the cosine's samples).
    int compared = 0;
    for (const char* f : {"hw6/cornellbox_jaroslav_glossy_area_sphere.xml", "ellipsoid", "hw3/cornellbox_area.xml",
                          "hw5/cube_directional.xml", "hw5/sphere_env_light_courtyard.xml", "env-mis"}) {
        const bool envMis = std::string(f) == "env-mis", ellipsoid = std::string(f) == "ellipsoid";
        if (envMis) f = "hw5/sphere_env_light_courtyard.xml";
        if (ellipsoid) f = "hw6/cornellbox_jaroslav_glossy_area_sphere.xml";
        Scene scene = loadScene(sharedDir() + "/scenes/" + f);
        if (ellipsoid)
            for (Shape& sh : scene.shapes)
                if (sh.type == ShapeType::Sphere && sh.lightIndex >= 0)
                    sh.transform = sh.transform * Mat4::translation(sh.center) * Mat4::scaling(Vec3(1, 1.4f, 1)) *
                                   Mat4::translation(sh.center * -1.0f);
        for (Light& l : scene.lights) l.envStrategy = envMis ? dev::ENV_STRATEGY_MIS : dev::ENV_STRATEGY_IMPORTANCE;
        for (Camera& c : scene.cameras) c.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
        DeviceScene ds = flattenScene(scene);
        for (const dev::Light& l : ds.lights)  // objCount 1: the ellipsoid's object-space sample
            if (l.kind == dev::LIGHT_SPHERE) CHECK((l.objCount != 0) == ellipsoid);
        INFO(f << ": " << lanesFamily(ds));
        REQUIRE(lanesFamily(ds).empty());
        Renderer r(testContext(), ds);
        for (int mode : {CLRT_PATH_ON | CLRT_PATH_MIS, CLRT_PATH_ON | CLRT_PATH_NEE | CLRT_PATH_IMPORTANCE}) {
            Camera cam = scene.cameras.at(0);
            cam.pathMode = mode;
            cam.maxRecursionDepth = 3;
            INFO(f << ", path mode " << mode);
            checkLanesAsFused(r, cam, 40, 1e-4, 1e-5);
            ++compared;
        }
    }
    CHECK(compared == 12);
}

TEST_CASE("lanes: classic cameras with an environment light as render_fused (its MIS in steps across the lanes)", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // Shade_Hit, the shadow rays and every other light per lane; an environment light's multi-sample MIS
    // (two slots) in steps across the lanes (Lanes_EnvMisShadows), with one slot (importance) per lane.
    // A sphere under a lat-long map, a smooth-shaded mesh under a light probe, and scenes/env_turned.xml (a
    // map turned by its light's <Transformations>; its mirror made plain: a classic camera's lanes take no
    // children); on the sphere every sampler (the correlated one draws a classic camera's light samples from
    // its camera sample: Lanes_Light2D).
    int compared = 0;
    for (const std::string& f : {sharedDir() + "/scenes/hw5/sphere_env_light_courtyard.xml",
                                sharedDir() + "/scenes/hw5/head_env_light_courtyard_probe.xml",
                                std::string(CLRT_SOURCE_DIR) + "/scenes/env_turned.xml"}) {
        for (dev::EnvStrategy strategy : {dev::ENV_STRATEGY_MIS, dev::ENV_STRATEGY_IMPORTANCE}) {
            Scene scene = loadScene(f);
            for (Material& m : scene.materials) m.type = dev::MATERIAL_BLINN_PHONG;
            for (Light& l : scene.lights) l.envStrategy = strategy;
            for (PixelSampler sampler : {PixelSampler::Stratified, PixelSampler::ZSobol, PixelSampler::Independent,
                                         PixelSampler::Correlated}) {
                const bool first = f.find("sphere_env_light_courtyard") != std::string::npos;  // every sampler there
                if (sampler != PixelSampler::Stratified && !(strategy == dev::ENV_STRATEGY_MIS && first)) continue;
                DeviceScene ds = flattenScene(scene);
                ds.features.zsobol = sampler == PixelSampler::ZSobol;  // as clrt render --sampler builds it
                ds.features.correlatedSampler = sampler == PixelSampler::Correlated;
                INFO(f << ", strategy " << strategy << ", sampler " << int(sampler) << ": " << lanesFamily(ds));
                REQUIRE(lanesFamily(ds).empty());
                Renderer r(testContext(), ds);
                Camera cam = scene.cameras.at(0);
                REQUIRE(cam.pathMode == 0);
                checkLanesAsFused(r, cam, 40, 1e-5, 1e-6, sampler);
                ++compared;
            }
        }
    }
    CHECK(compared == 9);
}

TEST_CASE("lanes: classic cameras' children (mirror, glass) under an environment light as render_fused", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // The camera rays' hits in the lanes (their MIS pair in steps), their children as render_fused follows them
    // (Lanes_DirectChildren): the sphere under a lat-long map made a mirror with a diffuse part, and the sphere made
    // glass (8 spp: no split, one child by Fresnel weight); scenes/env_turned.xml as it is (its mirror); the
    // course's mirror sphere inside a light probe and glass sphere inside a lat-long map. The children's depths'
    // sums and the ray counts (checkLanesAsFused).
    int compared = 0;
    for (const std::string& f : {sharedDir() + "/scenes/hw5/sphere_env_light_courtyard.xml",
                                std::string(CLRT_SOURCE_DIR) + "/scenes/env_turned.xml",
                                sharedDir() + "/scenes/hw5/mirror_sphere_env_interior_probe.xml",
                                sharedDir() + "/scenes/hw5/glass_sphere_env_interior.xml"}) {
        for (int variant = 0; variant < (f.find("sphere_env_light_courtyard") != std::string::npos ? 2 : 1); ++variant) {
            Scene scene = loadScene(f);
            if (f.find("sphere_env_light_courtyard") != std::string::npos) {
                mirrorFirstSphere(scene, 0.6f);
                if (variant == 1) {
                    Material& m = scene.materials.back();
                    m.type = dev::MATERIAL_DIELECTRIC;
                    m.refractionIndex = 1.5f;
                    m.absorptionCoefficient = {0.1f, 0.2f, 0.3f};
                }
            }
            DeviceScene ds = flattenScene(scene);
            INFO(f << " variant " << variant << ": " << lanesFamily(ds));
            REQUIRE(lanesFamily(ds).empty());
            REQUIRE(ds.features.bounces());
            Renderer r(testContext(), ds);
            Camera cam = scene.cameras.at(0);
            REQUIRE(cam.pathMode == 0);
            checkLanesAsFused(r, cam, 40, 1e-5, 1e-6);
            ++compared;
        }
    }
    CHECK(compared == 5);
}

TEST_CASE("lanes: textures, bump and normal maps, device instances per lane as render_fused", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // A textured, bump-mapped, normal-mapped or instanced hit gets Shade_Hit's surface per lane
    // (Lanes_ScalarSurface: HitTriangle_Load with the instance, Shade_Textures), its f, pdf and bounce per
    // lane from the textured kd and ks.
    // ks = 0: a Lambertian material whose kd comes from a texture (f per hit, not per material).
    struct Case { const char* file; Instancing instancing; bool ks0; };
    const Case cases[] = {{"hw4/cube_wall.xml", Instancing::Auto, false}, {"hw4/wood_box.xml", Instancing::Auto, true},
                          {"hw4/brickwall_with_normalmap.xml", Instancing::Auto, false},
                          {"hw4/sphere_perlin_bump.xml", Instancing::Auto, false},
                          {"hw2/metal_glass_plates.xml", Instancing::TwoLevel, false}};
    int compared = 0;
    for (const Case& c : cases) {
        Scene scene = loadScene(sharedDir() + "/scenes/" + c.file);
        if (c.ks0)
            for (Material& m : scene.materials) m.specular = {0, 0, 0};
        for (Camera& cam : scene.cameras) cam.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
        FlattenOptions opts;
        opts.instancing = c.instancing;
        DeviceScene ds = flattenScene(scene, opts);
        INFO(c.file << ": " << lanesFamily(ds));
        REQUIRE(lanesFamily(ds).empty());
        if (c.instancing == Instancing::TwoLevel) CHECK(ds.features.instances);
        else CHECK(ds.features.textures);
        Renderer r(testContext(), ds);
        Camera cam = scene.cameras.at(0);
        cam.maxRecursionDepth = 3;
        checkLanesAsFused(r, cam, 40, 1e-4, 1e-5);
        ++compared;
    }
    CHECK(compared == 5);
}

TEST_CASE("lanes: scenes/lanes_mix.xml (every per-lane branch at once) as render_fused", "[lanes]") {
    // A plain floor, a Perlin-textured Lambertian block, a glossy and a mirror sphere, sphere, area, point,
    // spot and directional lights, an open front: lanes whose hits take different branches side by side.
    Scene scene = loadScene(std::string(CLRT_SOURCE_DIR) + "/scenes/lanes_mix.xml");
    DeviceScene ds = flattenScene(scene);
    REQUIRE(lanesFamily(ds).empty());
    CHECK(ds.features.textures);
    std::set<int> kinds;
    for (const dev::Light& l : ds.lights) kinds.insert(l.kind);
    CHECK(kinds == std::set<int>{dev::LIGHT_POINT, dev::LIGHT_AREA, dev::LIGHT_SPOT, dev::LIGHT_DIRECTIONAL, dev::LIGHT_SPHERE});
    Renderer r(testContext(), ds);
    for (int mode : {CLRT_PATH_ON | CLRT_PATH_MIS, CLRT_PATH_ON | CLRT_PATH_NEE | CLRT_PATH_IMPORTANCE,
                     CLRT_PATH_ON | CLRT_PATH_IMPORTANCE}) {
        Camera cam = scene.cameras.at(0);
        cam.pathMode = mode;
        INFO("path mode " << mode);
        checkLanesAsFused(r, cam, 48, 1e-3, 1e-5);
    }
}

TEST_CASE("lanes: the zsobol, independent and correlated samplers draw what render_fused draws", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // Sampler_2D per lane (zsobol, independent) or the lanes' stratified form (correlated: path tracing's
    // dimensions are the stratified ones); Sampler_Other1D/2D for the specular pick and the glossy and
    // Fresnel draws. The hw6 box with a mirror beside a diffuse part. (Roulette: the first test case.)
    Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
    mirrorFirstSphere(scene, 0.6f);
    for (PixelSampler sampler : {PixelSampler::ZSobol, PixelSampler::Independent, PixelSampler::Correlated}) {
        DeviceScene ds = flattenScene(scene);
        ds.features.zsobol = sampler == PixelSampler::ZSobol;  // as clrt render --sampler builds it
        ds.features.correlatedSampler = sampler == PixelSampler::Correlated;
        Renderer r(testContext(), ds);
        for (int mode : {CLRT_PATH_ON | CLRT_PATH_MIS, CLRT_PATH_ON | CLRT_PATH_NEE | CLRT_PATH_IMPORTANCE}) {
            Camera cam = scene.cameras.at(0);
            cam.pathMode = mode;
            cam.width = cam.height = 40;
            INFO("sampler " << int(sampler) << ", path mode " << mode);
            RenderSettings rs;
            rs.spp = 8;
            rs.seed = 3;
            rs.pixelSampler = sampler;
            RenderCounters cl, cf, cf2;
            rs.pipeline = Pipeline::Lanes;
            const ImageRGB l = r.render(cam, rs, cl);
            rs.pipeline = Pipeline::Fused;
            const ImageRGB f = r.render(cam, rs, cf);
            rs.seed = 4;
            const ImageRGB f2 = r.render(cam, rs, cf2);
            CHECK(cl.lanes);
            const double noise = relMse(f2, f), diff = relMse(l, f);
            INFO("relMSE lanes/fused " << diff << ", between seeds " << noise);
            CHECK(noise > 1e-3);
            CHECK(diff < 1e-5 * noise);
            CHECK(diff < 1e-5);
            CHECK(cl.secondaryRays == cf.secondaryRays);
            CHECK(cl.shadowRays == cf.shadowRays);
        }
    }
}

TEST_CASE("lanes: deterministic, several launches and sample counts that are no multiple of four", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    Camera cam = scene.cameras.at(0);
    cam.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
    for (int spp : {1, 3, 6}) {
        INFO(spp << " spp");
        Rendered a = renderWith(r, cam, 48, 40, spp, 9, Pipeline::Lanes);
        Rendered b = renderWith(r, cam, 48, 40, spp, 9, Pipeline::Lanes);
        Rendered other = renderWith(r, cam, 48, 40, spp, 10, Pipeline::Lanes);
        Rendered f = renderWith(r, cam, 48, 40, spp, 9, Pipeline::Fused);
        CHECK(a.counters.lanes);
        CHECK(differingFloats(a.image, b.image) == 0);
        CHECK(differingFloats(a.image, other.image) > 0);
        CHECK(relMse(a.image, f.image) < 1e-5 * relMse(other.image, f.image));
    }
    // A large image: one sample per group, four passes in each launch of the lanes kernel.
    Rendered big = renderWith(r, cam, 300, 256, 8, 9, Pipeline::Lanes);
    Rendered bigF = renderWith(r, cam, 300, 256, 8, 9, Pipeline::Fused);
    Rendered bigOther = renderWith(r, cam, 300, 256, 8, 10, Pipeline::Fused);
    CHECK(big.counters.lanes);
    INFO("relMSE lanes/fused " << relMse(big.image, bigF.image) << ", between seeds " << relMse(bigOther.image, bigF.image));
    CHECK(relMse(big.image, bigF.image) < 1e-5 * relMse(bigOther.image, bigF.image));
    CHECK(big.counters.secondaryRays == bigF.counters.secondaryRays);
    // Small pixel batches: the same floats (a pixel's sums do not depend on how the image is cut).
    Rendered batched = renderWith(r, cam, 300, 256, 8, 9, Pipeline::Lanes, 1000 + 17);
    CHECK(differingFloats(batched.image, big.image) == 0);
    CHECK(batched.counters.lanes);
}

TEST_CASE("lanes: which scenes and cameras it takes; auto takes it on CPU devices", "[lanes][shared]") {
    if (!haveShared()) { WARN("../shared is not present: skipped"); return; }
    // Out of its family: motion blur; classic cameras alone without an environment light (with one, a scene
    // whose materials make children is in: a mirror).
    for (const char* f : {kPathBox, "hw5/cube_point.xml"}) {
        INFO(f);
        Scene scene = loadScene(sharedDir() + "/scenes/" + f);
        if (std::string(f) == kPathBox) scene.shapes.at(0).motion = {0.1f, 0.0f, 0.0f};
        else for (Camera& c : scene.cameras) c.pathMode = 0;
        mirrorFirstSphere(scene, 0.6f);
        DeviceScene ds = flattenScene(scene);
        INFO(lanesFamily(ds));
        CHECK_FALSE(lanesFamily(ds).empty());
        CHECK_FALSE(ds.features.lanes);
    }
    // A classic camera with an environment light: auto takes the lanes under its MIS (two slots), not under
    // importance sampling (one slot: nothing in lanes).
    for (dev::EnvStrategy strategy : {dev::ENV_STRATEGY_MIS, dev::ENV_STRATEGY_IMPORTANCE}) {
        Scene env = loadScene(sharedDir() + "/scenes/hw5/sphere_env_light_courtyard.xml");
        for (Light& l : env.lights) l.envStrategy = strategy;
        DeviceScene ds = flattenScene(env);
        REQUIRE(lanesFamily(ds).empty());
        CHECK(lanesNoGain(ds, true, true).empty());
        CHECK_FALSE(lanesNoGain(ds, true, false).empty());
        Renderer r(testContext(), ds);
        Rendered a = renderWith(r, env.cameras.at(0), 40, 40, 4, 1, Pipeline::Auto);
        CHECK(a.counters.lanes == (strategy == dev::ENV_STRATEGY_MIS && (testDevice().type & CL_DEVICE_TYPE_CPU) != 0));
    }
    // A path-traced scene with nothing shaded in lanes (every surface a pure mirror, kd = ks = 0): auto
    // leaves it to render_fused.
    {
        Scene mirrors = loadScene(sharedDir() + "/scenes/" + kPathBox);
        for (Material& m : mirrors.materials) {
            m.type = dev::MATERIAL_MIRROR;
            m.mirror = {0.8f, 0.8f, 0.8f};
            m.diffuse = m.specular = {0.0f, 0.0f, 0.0f};
        }
        DeviceScene dm = flattenScene(mirrors);
        REQUIRE(lanesFamily(dm).empty());
        CHECK_FALSE(lanesNoGain(dm).empty());
        Renderer rm(testContext(), dm);
        Camera mc = mirrors.cameras.at(0);
        mc.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
        CHECK_FALSE(renderWith(rm, mc, 40, 40, 4, 1, Pipeline::Auto).counters.lanes);
    }
    Scene scene = loadScene(sharedDir() + "/scenes/" + kPathBox);
    DeviceScene ds = flattenScene(scene);
    CHECK(lanesNoGain(ds).empty());
    Renderer r(testContext(), ds);
    Camera cam = scene.cameras.at(0);
    cam.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
    Rendered a = renderWith(r, cam, 40, 40, 4, 1, Pipeline::Auto);
    CHECK(a.counters.lanes == ((testDevice().type & CL_DEVICE_TYPE_CPU) != 0));
    // Camera and settings it does not take: the fused kernel renders instead.
    dev::SceneParams sp{};
    sp.pathMode = CLRT_PATH_ON | CLRT_PATH_MIS;
    sp.pixelSampler = CLRT_PIXEL_SAMPLER_STRATIFIED;
    FusedPlan plan;
    CHECK(lanesUnsupported(sp, plan, "", true).empty());
    CHECK_FALSE(lanesUnsupported(sp, plan, "", false).empty());        // not a CPU
    CHECK_FALSE(lanesUnsupported(sp, plan, "planes", true).empty());  // the scene's reason
    dev::SceneParams course = sp;
    course.pathMode |= CLRT_PATH_RR | CLRT_PATH_RR_COURSE;
    CHECK(lanesUnsupported(course, plan, "", true).find("course") != std::string::npos);
    dev::SceneParams indep = sp;  // test "lanes: the zsobol, independent and correlated samplers"
    indep.pixelSampler = CLRT_PIXEL_SAMPLER_INDEPENDENT;
    CHECK(lanesUnsupported(indep, plan, "", true).empty());
    dev::SceneParams classic = sp;  // a classic camera: its children too, but not a split (tree of paths)
    classic.pathMode = 0;
    CHECK(lanesUnsupported(classic, plan, "", true).empty());
    FusedPlan bounces = plan;
    bounces.bounces = true;
    CHECK(lanesUnsupported(classic, bounces, "", true).empty());
    CHECK(lanesUnsupported(sp, bounces, "", true).empty());
    dev::SceneParams split = classic;
    split.splitDepth = 2;
    CHECK_FALSE(lanesUnsupported(split, bounces, "", true).empty());
    FusedPlan tree = plan;
    tree.tree = true;
    CHECK_FALSE(lanesUnsupported(sp, tree, "", true).empty());
    FusedPlan twoSlots = plan;  // an environment light's MIS pair: the lanes take it
    twoSlots.lightSlots = 2;
    CHECK(lanesUnsupported(sp, twoSlots, "", true).empty());
    // Asked for where it cannot run (the course's roulette): the fused kernel, the same image as asking for it.
    RenderSettings rs;
    rs.spp = 2;
    rs.seed = 5;
    rs.rouletteRule = RouletteRule::Course;
    rs.pipeline = Pipeline::Lanes;
    Camera small = cam;
    small.pathMode = CLRT_PATH_ON | CLRT_PATH_NEE | CLRT_PATH_RR;
    small.width = small.height = 40;
    RenderCounters cl, cf;
    const ImageRGB l = r.render(small, rs, cl);
    rs.pipeline = Pipeline::Fused;
    const ImageRGB f = r.render(small, rs, cf);
    CHECK_FALSE(cl.lanes);
    CHECK(differingFloats(l, f) == 0);
    // --all-features programs are built without it.
    Pipeline p = Pipeline::Auto;
    CHECK(parsePipeline("lanes", p));
    CHECK(p == Pipeline::Lanes);
    CHECK(std::string(pipelineName(Pipeline::Lanes)) == "lanes");
    CHECK_FALSE(FeatureSet::all().lanes);
}
