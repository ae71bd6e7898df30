// The correlated sampler (clrt render --sampler correlated; CLRT_PIXEL_SAMPLER_CORRELATED, Sampler_Camera2D and
// Sampler_Light2D in cl_kernels/common.cl): a camera sample's one stratified 2D point is its pixel jitter, its
// lens point and the classic renderer's light samples at the camera ray's hit, as the course's renderer drew them
// until 2022 (the hits of reflected and refracted rays draw their own).
// Renders of one-pixel scenes against closed forms and host integrals: the lens and the light take the jitter's
// point (and the stratified sampler, on the same scenes, the independent points' values); every other
// dimension is the stratified sampler's, bit for bit; the CLI builds its code only where it runs.
#include <catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "cl/check.h"
#include "flatten/device_scene.h"
#include "image/image.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// A 1x1 camera at the origin looking down -z through a near plane of half-size 0.1 (s = 0.2 at distance 1),
// thin lens: aperture 4, focus 5. A wall at z = -10 (D) emits 1 (ambient) for x > 0.5 and nothing left of it.
// A ray from lens point a = (ja - 1/2)·4 through pixel point (jx - 1/2)·0.2 meets the wall at
// x = a (1 - D/F) + uc D = -4 (ja - 1/2) + 2 (jx - 1/2). With ja = jx (correlated): x = -2 (jx - 1/2) > 0.5 for
// jx < 1/4: the pixel is 0.25. Independent ja, jx: x is the sum of U(-2, 2) and U(-1, 1), above 0.5 with
// probability 1/8 + 1/4 = 0.375.
std::string lensScene() {
    return R"(<Scene>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1">
    <Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-0.1 0.1 -0.1 0.1</NearPlane><NearDistance>1</NearDistance>
    <FocusDistance>5</FocusDistance><ApertureSize>4</ApertureSize>
    <ImageResolution>1 1</ImageResolution><NumSamples>1024</NumSamples><ImageName>lens.exr</ImageName>
  </Camera></Cameras>
  <Lights><AmbientLight>1 1 1</AmbientLight></Lights>
  <Materials><Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>0 0 0</DiffuseReflectance>
    <SpecularReflectance>0 0 0</SpecularReflectance></Material></Materials>
  <VertexData>0.5 -100 -10  100 -100 -10  100 100 -10  0.5 100 -10</VertexData>
  <Objects><Mesh id="1"><Material>1</Material><Faces>1 2 3 1 3 4</Faces></Mesh></Objects>
</Scene>)";
}

// A 1x1 camera 2 above a diffuse floor (kd 1), looking down with up = -z: the pixel point (jx, jy) hits the floor
// at p = (2 (jx - 1/2), 0, 2 (jy - 1/2)). A square AreaLight of side 2 and radiance 1 at height h = 0.5 faces
// down; light sample u lands at q = c + (u.x - 1/2) edgeU + (u.y - 1/2) edgeV. The pixel is the mean of
// kd · A · cos θ_light · cos θ_p / d² = A h² / d⁴, over u = (jx, jy) when correlated, over independent u and
// (jx, jy) otherwise: 28% apart.
std::string lightScene() {
    return R"(<Scene>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1">
    <Position>0 2 0</Position><Gaze>0 -1 0</Gaze><Up>0 0 -1</Up>
    <NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1</NearDistance>
    <ImageResolution>1 1</ImageResolution><NumSamples>4096</NumSamples><ImageName>light.exr</ImageName>
  </Camera></Cameras>
  <Lights><AreaLight id="1"><Position>0 0.5 0</Position><Normal>0 -1 0</Normal><Size>2</Size><Radiance>1 1 1</Radiance></AreaLight></Lights>
  <Materials><Material id="1"><AmbientReflectance>0 0 0</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
    <SpecularReflectance>0 0 0</SpecularReflectance></Material></Materials>
  <VertexData>-10 0 -10  -10 0 10  10 0 10  10 0 -10</VertexData>
  <Objects><Mesh id="1"><Material>1</Material><Faces>1 2 3 1 3 4</Faces></Mesh></Objects>
</Scene>)";
}

Scene sceneFrom(TempDir& d, const std::string& name, const std::string& xml) {
    std::ofstream(d.file(name)) << xml;
    return loadScene(d.file(name));
}

// The light scene's pixel value at floor point (px, pz) for the sample at light point q of light l.
double lightTerm(const dev::Light& l, double px, double pz, const dev::float4& q) {
    const double dx = q.x - px, dy = q.y, dz = q.z - pz;
    const double d2 = dx * dx + dy * dy + dz * dz;
    return l.area * dy * dy / (d2 * d2);
}

dev::float4 lightPoint(const dev::Light& l, double ux, double uy) {
    return {float(l.position.x + (ux - 0.5) * l.edgeU.x + (uy - 0.5) * l.edgeV.x),
            float(l.position.y + (ux - 0.5) * l.edgeU.y + (uy - 0.5) * l.edgeV.y),
            float(l.position.z + (ux - 0.5) * l.edgeU.z + (uy - 0.5) * l.edgeV.z), 0.0f};
}

}  // namespace

TEST_CASE("correlated sampler: the lens point is the pixel jitter's point (closed form)", "[sampler][render]") {
    TempDir d;
    const Scene scene = sceneFrom(d, "lens.xml", lensScene());
    const float correlated = renderCamera(scene, scene.cameras.at(0), 1024, 1, PixelSampler::Correlated).at(0, 0, 0);
    const float stratified = renderCamera(scene, scene.cameras.at(0), 1024, 1, PixelSampler::Stratified).at(0, 0, 0);
    INFO("correlated " << correlated << " (closed form 0.25), stratified " << stratified << " (0.375)");
    CHECK(std::fabs(correlated - 0.25f) < 0.005f);
    CHECK(std::fabs(stratified - 0.375f) < 0.005f);
}

TEST_CASE("correlated sampler: the classic renderer's light samples take the pixel jitter's point (host integral)", "[sampler][render]") {
    TempDir d;
    const Scene scene = sceneFrom(d, "light.xml", lightScene());
    const DeviceScene ds = flattenScene(scene);
    REQUIRE(ds.lights.size() == 1);
    const dev::Light& l = ds.lights[0];  // the square's edges as clrt builds them from its Normal
    // Host: midpoint sums over the pixel jitter (and, independent, the light sample) on n x n grids.
    const int n = 64;
    double hostCorrelated = 0, hostIndependent = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double jx = (i + 0.5) / n, jy = (j + 0.5) / n;
            const double px = 2 * (jx - 0.5), pz = 2 * (jy - 0.5);
            hostCorrelated += lightTerm(l, px, pz, lightPoint(l, jx, jy)) / (n * n);
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b)
                    hostIndependent += lightTerm(l, px, pz, lightPoint(l, (a + 0.5) / n, (b + 0.5) / n)) / (double(n) * n * n * n);
        }
    const float correlated = renderCamera(scene, scene.cameras.at(0), 4096, 1, PixelSampler::Correlated).at(0, 0, 0);
    const float stratified = renderCamera(scene, scene.cameras.at(0), 4096, 1, PixelSampler::Stratified).at(0, 0, 0);
    INFO("correlated " << correlated << " (host " << hostCorrelated << "), stratified " << stratified << " (host "
                       << hostIndependent << ")");
    REQUIRE(std::fabs(hostCorrelated / hostIndependent - 1.0) > 0.2);  // the scene tells the two apart
    CHECK(correlated == Approx(hostCorrelated).epsilon(0.005));  // a 2D integral: the (0,2)-net's error is far below
    CHECK(stratified == Approx(hostIndependent).epsilon(0.02));  // 4D: each pair stratified, not their pairing (0.5% noise)
}

// Glossy perturbations, Fresnel picks and motion-blur times are the stratified sampler's, and so is everything
// in a scene without a lens or light samples: there the two samplers give the same image bit for bit.
TEST_CASE("correlated sampler: without a lens or an area light, the stratified sampler's image bit for bit", "[sampler][render]") {
    TempDir d;
    const Scene scene = sceneFrom(d, "plain.xml", R"(<Scene>
  <BackgroundColor>0.2 0.3 0.4</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 3</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>
    <NumSamples>16</NumSamples><ImageName>p.exr</ImageName></Camera></Cameras>
  <Lights><AmbientLight>0.1 0.1 0.1</AmbientLight><PointLight id="1"><Position>2 3 4</Position><Intensity>30 30 30</Intensity></PointLight></Lights>
  <Materials><Material id="1" type="conductor"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>0.3 0.2 0.1</DiffuseReflectance>
    <SpecularReflectance>0.5 0.5 0.5</SpecularReflectance><PhongExponent>20</PhongExponent><MirrorReflectance>0.8 0.8 0.8</MirrorReflectance>
    <RefractionIndex>0.37</RefractionIndex><AbsorptionIndex>2.8</AbsorptionIndex><Roughness>0.2</Roughness></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>0.8</Radius></Sphere></Objects>
</Scene>)");
    const ImageRGB c = renderCamera(scene, scene.cameras.at(0), 16, 3, PixelSampler::Correlated);
    const ImageRGB s = renderCamera(scene, scene.cameras.at(0), 16, 3, PixelSampler::Stratified);
    CHECK(c.pixels == s.pixels);
}

// Only the camera ray's hit takes the jitter's point for its light samples: the hits of reflected rays draw their
// own, as the course's references show (hw3 cornellbox_area: the ceiling's glow seen in the mirror sphere, block
// err/limit against the 2022 and 2020 references 1.39 and 0.97 with every depth correlated, 0.68 and 0.68 with
// the camera ray's hit alone; docs/scene-format.md). Here the camera sees only a mirror, which shows a diffuse
// wall lit by an area light: the correlated sampler's image is the stratified one's, bit for bit.
TEST_CASE("correlated sampler: light samples of reflected rays' hits are the stratified sampler's", "[sampler][render]") {
    TempDir d;
    const Scene scene = sceneFrom(d, "mirror.xml", R"(<Scene>
  <Cameras><Camera id="1"><Position>0 0 3</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
    <NumSamples>16</NumSamples><ImageName>m.exr</ImageName></Camera></Cameras>
  <Lights><AreaLight id="1"><Position>0 0 4</Position><Normal>0 0 1</Normal><Size>1</Size><Radiance>20 20 20</Radiance></AreaLight></Lights>
  <Materials><Material id="1" type="mirror"><AmbientReflectance>0 0 0</AmbientReflectance><DiffuseReflectance>0 0 0</DiffuseReflectance>
    <SpecularReflectance>0 0 0</SpecularReflectance><MirrorReflectance>1 1 1</MirrorReflectance></Material>
    <Material id="2"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance></Material></Materials>
  <VertexData>-9 -9 0  9 -9 0  9 9 0  -9 9 0  -9 -9 5  9 -9 5  9 9 5  -9 9 5</VertexData>
  <Objects><Mesh id="1"><Material>1</Material><Faces>1 2 3  1 3 4</Faces></Mesh>
    <Mesh id="2"><Material>2</Material><Faces>5 7 6  5 8 7</Faces></Mesh></Objects>
</Scene>)");
    const ImageRGB c = renderCamera(scene, scene.cameras.at(0), 16, 3, PixelSampler::Correlated);
    const ImageRGB s = renderCamera(scene, scene.cameras.at(0), 16, 3, PixelSampler::Stratified);
    float brightest = 0;
    for (float v : s.pixels) brightest = std::max(brightest, v);
    CHECK(brightest > 0.1f);  // the wall is lit, seen in the mirror
    CHECK(c.pixels == s.pixels);
}

TEST_CASE("clrt render --sampler correlated builds its code only where it runs; without it the renderer refuses", "[sampler][cli]") {
    TempDir d;
    std::ofstream(d.file("l.xml")) << lightScene();
    const std::string base = "render " + d.file("l.xml") + " -o " + d.path.string() + " --spp 4 -v" + deviceArg();
    for (const std::string sampler : {"stratified", "correlated"}) {
        const int rc = runClrt(base + " --sampler " + sampler, d.file("log"));
        const std::string log = readFileBytes(d.file("log"));
        INFO(sampler << ": " << log);
        REQUIRE(rc == 0);
        REQUIRE(log.find("-DCLRT_HAS_") != std::string::npos);
        CHECK((log.find("-DCLRT_HAS_CORRELATED_SAMPLER=1") != std::string::npos) == (sampler == "correlated"));
    }
    const Scene scene = loadScene(d.file("l.xml"));
    REQUIRE_FALSE(flattenScene(scene).features.correlatedSampler);  // not a scene's feature
    CHECK(samplerRefusal(scene, PixelSampler::Correlated).find("CLRT_HAS_CORRELATED_SAMPLER") != std::string::npos);
}
