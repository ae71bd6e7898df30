// Motion blur (<MotionBlur>x y z</MotionBlur> on meshes, mesh instances, triangles and spheres): a
// world-space translation over the shutter interval [0, 1], one uniform time per camera sample that
// its shadow and secondary rays share. Parsing and its errors; the feature flag (scenes without
// motion build kernels without it, and a zero motion renders bit-identically to none); the flattened
// motion and swept boxes; and a render of a sphere moving across a wall lit from the camera, compared
// with a host integration of the same picture against the noise floor of two independent renders;
// a procedural texture moves with its object. (The device-vs-host intersection test of moving primitives is in test_intersect.cpp.)
#include <catch.hpp>

#include <cmath>
#include <cstring>

#include "flatten/device_scene.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// Camera at the origin looking down −z (near plane ±0.5 at distance 1), a point light at the camera,
// a white wall at z = −10 and a sphere of radius 1 at (−1.5, 0, −5) with the given <MotionBlur>
// element ("" for none). Diffuse materials only, no ambient: every value is kd·I·cosθ/d².
std::string movingSphereScene(const std::string& motion, int width = 32, int height = 24) {
    return R"(<Scene><BackgroundColor>0 0 0</BackgroundColor>
<Cameras><Camera id="1"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-0.5 0.5 -0.375 0.375</NearPlane><NearDistance>1</NearDistance>
<ImageResolution>)" + std::to_string(width) + " " + std::to_string(height) + R"(</ImageResolution>
<ImageName>m.exr</ImageName></Camera></Cameras>
<Lights><PointLight id="1"><Position>0 0 0</Position><Intensity>1000 1000 1000</Intensity></PointLight></Lights>
<Materials>
<Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
<Material id="2"><DiffuseReflectance>0.5 0.25 1</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
</Materials>
<VertexData>-100 -100 -10  100 -100 -10  100 100 -10  -100 100 -10  -1.5 0 -5</VertexData>
<Objects>
<Mesh id="1"><Material>1</Material><Faces>1 2 3  1 3 4</Faces></Mesh>
<Sphere id="1"><Material>2</Material><Center>5</Center><Radius>1</Radius>)" + motion + R"(</Sphere>
</Objects></Scene>)";
}

// The picture of movingSphereScene on the host: each pixel the mean over a grid of positions in the
// pixel and of shutter times of what the ray sees (the sphere at its position at that time, else the
// wall), as kd·I·cosθ/d² with the light at the eye (cosθ = the cosine to the ray).
ImageRGB hostMovingSphere(const Vec3& motion, int width, int height) {
    const int grid = 12, times = 48;
    const Vec3 kdSphere(0.5f, 0.25f, 1.0f);
    ImageRGB img;
    img.width = width;
    img.height = height;
    img.pixels.assign(size_t(width) * height * 3, 0.0f);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double sum[3] = {0, 0, 0};
            for (int sy = 0; sy < grid; ++sy)
                for (int sx = 0; sx < grid; ++sx) {
                    const double px = (x + (sx + 0.5) / grid) / width, py = (y + (sy + 0.5) / grid) / height;
                    Vec3 d = normalize(Vec3(float(-0.5 + px), float(0.375 - 0.75 * py), -1.0f));
                    const double wall = 1000.0 * (-d.z) / std::pow(10.0 / -d.z, 2.0);  // cosθ/d², d = 10/cos
                    for (int k = 0; k < times; ++k) {
                        const Vec3 c = Vec3(-1.5f, 0, -5) + motion * float((k + 0.5) / times);
                        const double b = dot(c, d), disc = b * b - (dot(c, c) - 1.0);
                        if (disc < 0 || b - std::sqrt(disc) <= 0) {
                            for (double& s : sum) s += wall;
                            continue;
                        }
                        const double t = b - std::sqrt(disc);
                        const Vec3 n = normalize(d * float(t) - c);
                        const double e = 1000.0 * std::max(0.0, double(dot(n, d * -1.0f))) / (t * t);
                        for (int ch = 0; ch < 3; ++ch) sum[ch] += e * kdSphere[ch];
                    }
                }
            for (int ch = 0; ch < 3; ++ch) img.at(x, y, ch) = float(sum[ch] / (grid * grid * times));
        }
    return img;
}

Scene loadText(TempDir& dir, const std::string& name, const std::string& xml) {
    const std::string path = dir.file(name);
    writeFileBytes(path, xml);
    return loadScene(path);
}

bool hasDefine(const FeatureSet& f, const std::string& d) {
    for (const std::string& s : f.defines())
        if (s.find(d) != std::string::npos) return true;
    return false;
}

}  // namespace

TEST_CASE("MotionBlur is read on meshes, instances, triangles and spheres; errors name the element", "[motion][scene]") {
    TempDir dir;
    const std::string objects = R"(<Scene>
<Cameras><Camera id="1"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up><NearPlane>-1 1 -1 1</NearPlane>
<NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution><ImageName>x.png</ImageName></Camera></Cameras>
<Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
<VertexData>0 0 0  1 0 0  0 1 0</VertexData>
<Objects>
<Mesh id="1"><Material>1</Material><Faces>1 2 3</Faces><MotionBlur>1 2 3</MotionBlur></Mesh>
<MeshInstance id="2" baseMeshId="1"></MeshInstance>
<MeshInstance id="3" baseMeshId="1"><MotionBlur>0 0 -4</MotionBlur></MeshInstance>
<Triangle id="4"><Material>1</Material><Indices>1 2 3</Indices><MotionBlur>0.5 0 0</MotionBlur></Triangle>
<Sphere id="5"><Material>1</Material><Center>1</Center><Radius>1</Radius><MotionBlur>0 1e-3 0</MotionBlur></Sphere>
<Sphere id="6"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere>
BAD</Objects></Scene>)";
    auto with = [&](const std::string& bad) {
        std::string s = objects;
        s.replace(s.find("BAD"), 3, bad);
        return s;
    };
    Scene scene = loadText(dir, "ok.xml", with(""));
    REQUIRE(scene.shapes.size() == 6);
    CHECK(scene.shapes[0].motion == Vec3(1, 2, 3));
    CHECK(scene.shapes[1].motion == Vec3(0, 0, 0));  // an instance moves only by its own MotionBlur
    CHECK(scene.shapes[2].motion == Vec3(0, 0, -4));
    CHECK(scene.shapes[3].motion == Vec3(0.5f, 0, 0));
    CHECK(scene.shapes[4].motion == Vec3(0, 1e-3f, 0));
    CHECK(scene.shapes[5].motion == Vec3(0, 0, 0));

    const std::string sphere = "<Sphere id=\"9\"><Material>1</Material><Center>1</Center><Radius>1</Radius>";
    struct Bad { const char* element; const char* message; };
    for (const Bad& b : {Bad{"<MotionBlur>1 2</MotionBlur>", "has 2 values, expected 3"},
                         Bad{"<MotionBlur>1 2 3 4</MotionBlur>", "has 4 values, expected 3"},
                         Bad{"<MotionBlur>1 x 3</MotionBlur>", "'x'"},
                         Bad{"<MotionBlur>1e39 0 0</MotionBlur>", "1e39"},
                         Bad{"<MotionBlur>nan 0 0</MotionBlur>", "nan"},
                         Bad{"<MotionBlur></MotionBlur>", "has 0 values, expected 3"}}) {
        INFO(b.element);
        const std::string name = "bad.xml";
        try {
            loadText(dir, name, with(sphere + b.element + "</Sphere>"));
            FAIL("no error");
        } catch (const Error& e) {
            const std::string msg = e.what();
            INFO(msg);
            CHECK(msg.find(dir.file(name) + ":13:") == 0);  // file:line:col of the element
            CHECK(msg.find("MotionBlur") != std::string::npos);
            CHECK(msg.find(b.message) != std::string::npos);
            CHECK(msg.find('\n') == std::string::npos);
        }
    }
}

TEST_CASE("motion blur: the feature flag, the flattened motion and the swept BVH boxes", "[motion]") {
    TempDir dir;
    Scene still = loadText(dir, "still.xml", movingSphereScene(""));
    Scene zero = loadText(dir, "zero.xml", movingSphereScene("<MotionBlur>0 0 0</MotionBlur>"));
    Scene moving = loadText(dir, "moving.xml", movingSphereScene("<MotionBlur>3 0.5 0</MotionBlur>"));
    DeviceScene dsStill = flattenScene(still), dsZero = flattenScene(zero), dsMoving = flattenScene(moving);
    CHECK_FALSE(dsStill.features.motionBlur);
    CHECK_FALSE(hasDefine(dsStill.features, "CLRT_HAS_MOTION_BLUR"));
    CHECK_FALSE(dsZero.features.motionBlur);
    CHECK(dsMoving.features.motionBlur);
    CHECK(hasDefine(dsMoving.features, "CLRT_HAS_MOTION_BLUR"));
    CHECK(hasDefine(FeatureSet::all(), "CLRT_HAS_MOTION_BLUR"));
    REQUIRE(dsMoving.spheres.size() == 1);
    CHECK(dsMoving.spheres[0].motion.x == 3.0f);
    CHECK(dsMoving.spheres[0].motion.y == 0.5f);
    CHECK(dsStill.spheres[0].motion.x == 0.0f);
    // The root box holds the sphere at both ends of its motion: x in [-2.5, 2.5], y up to 1.5.
    const Aabb& root = dsMoving.bvh.bounds;
    CHECK(root.min.x <= -2.5f);
    CHECK(root.max.y >= 1.5f - 1e-6f);
    // Triangles carry their motion in the w of their vertices.
    std::string triXml = movingSphereScene("");
    triXml.replace(triXml.find("<Faces>"), 7, "<MotionBlur>1 2 3</MotionBlur><Faces>");
    Scene tri = loadText(dir, "tri.xml", triXml);
    DeviceScene dsTri = flattenScene(tri);
    REQUIRE(dsTri.triangles.size() == 2);
    for (const dev::Triangle& t : dsTri.triangles) CHECK((t.v0.w == 1.0f && t.v1.w == 2.0f && t.v2.w == 3.0f));
    CHECK(dsTri.features.motionBlur);
    for (const dev::Triangle& t : dsStill.triangles) CHECK((t.v0.w == 0.0f && t.v1.w == 0.0f && t.v2.w == 0.0f));
}

TEST_CASE("a zero MotionBlur renders bit-identically to none", "[motion][render]") {
    TempDir dir;
    Scene still = loadText(dir, "still.xml", movingSphereScene("", 16, 12));
    Scene zero = loadText(dir, "zero.xml", movingSphereScene("<MotionBlur>0 0 0</MotionBlur>", 16, 12));
    ImageRGB a = renderCamera(still, still.cameras[0], 4, 3), b = renderCamera(zero, zero.cameras[0], 4, 3);
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
}

// Textures move with their object: a procedural texture is evaluated at the hit point in the rest
// frame. The sphere lies inside one checkerboard cell at rest (cells 10 units wide, faces at
// x = −3, 7, …; y = −3, 7, …; z = −3, −13, …) and moves by −3 in x across the face at x = −3: it must
// come out in one checker colour, exactly as the same sphere without a texture and that colour as its
// diffuse reflectance. (Which of the two colours depends on the checkerboard's parity convention; both
// are accepted.)
TEST_CASE("a moving object's procedural texture moves with it", "[motion][render]") {
    TempDir dir;
    auto scene = [&](const std::string& name, const std::string& sphereKd, bool textured) {
        std::string xml = movingSphereScene("<MotionBlur>-3 0 0</MotionBlur>", 16, 12);
        const std::string kd = "<DiffuseReflectance>0.5 0.25 1</DiffuseReflectance>";
        xml.replace(xml.find(kd), kd.size(), "<DiffuseReflectance>" + sphereKd + "</DiffuseReflectance>");
        if (textured) {
            xml.replace(xml.find("<Objects>"), 9,
                        "<Textures><TextureMap id=\"1\" type=\"checkerboard\"><DecalMode>replace_kd</DecalMode>"
                        "<BlackColor>0.5 0.25 1</BlackColor><WhiteColor>0 1 0</WhiteColor><Scale>0.1</Scale>"
                        "<Offset>3</Offset></TextureMap></Textures><Objects>");
            xml.replace(xml.find("<Center>5</Center>"), 18, "<Textures>1</Textures><Center>5</Center>");
        }
        return loadText(dir, name, xml);
    };
    Scene textured = scene("textured.xml", "0 0 0", true);
    Scene black = scene("black.xml", "0.5 0.25 1", false), white = scene("white.xml", "0 1 0", false);
    ImageRGB a = renderCamera(textured, textured.cameras[0], 16, 5);
    ImageRGB b = renderCamera(black, black.cameras[0], 16, 5), w = renderCamera(white, white.cameras[0], 16, 5);
    const double dBlack = meanSquaredDiff(a, b), dWhite = meanSquaredDiff(a, w), dColours = meanSquaredDiff(b, w);
    INFO("MSE to the black-colour sphere " << dBlack << ", to the white-colour sphere " << dWhite
                                            << ", between the two " << dColours);
    CHECK(dColours > 1.0);
    CHECK(std::min(dBlack, dWhite) < 1e-8 * dColours);
}

// A sphere moving across a wall, the light at the eye: a camera ray that passes the sphere at its
// time t reaches the wall, and the wall's shadow ray runs back along it at the same time t, so the
// sphere never shadows the wall. Shadow rays at another time than their camera ray would darken the
// wall along the sphere's path. 32×24 pixels at 256 spp (about a second on PoCL).
TEST_CASE("a moving sphere renders as the host integration over the shutter, within the noise floor", "[motion][render]") {
    TempDir dir;
    const Vec3 motion(3.0f, 0.5f, 0.0f);
    Scene scene = loadText(dir, "moving.xml", movingSphereScene("<MotionBlur>3 0.5 0</MotionBlur>"));
    const int spp = 256;
    ImageRGB a = renderCamera(scene, scene.cameras[0], spp, 1), b = renderCamera(scene, scene.cameras[0], spp, 2);
    ImageRGB want = hostMovingSphere(motion, 32, 24), still = hostMovingSphere(Vec3(0, 0, 0), 32, 24);
    const double noise = meanSquaredDiff(a, b) / 2;  // the variance of one render
    const double err = meanSquaredDiff(a, want), blur = meanSquaredDiff(still, want);
    double sumA = 0, sumWant = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) { sumA += a.pixels[i]; sumWant += want.pixels[i]; }
    INFO("MSE vs host " << err << ", noise floor " << noise << ", host blurred vs still " << blur
                        << "; mean " << sumA / a.pixels.size() << " vs host " << sumWant / a.pixels.size());
    CHECK(noise > 0);
    CHECK(blur > 100 * noise);          // the motion is far above the noise
    CHECK(err < 1.5 * noise + 1e-4);    // no error beyond the noise (a bias would add to it)
    CHECK(std::fabs(sumA - sumWant) / sumWant < 2e-3);
}
