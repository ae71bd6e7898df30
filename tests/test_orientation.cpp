// Triangle orientation conventions: a mesh (or triangle, or mesh instance) whose transformation
// mirrors (det < 0) keeps the orientation of its object space, as in the course: its winding is
// reversed when flattened, so the world-space geometric normal is the object-space one carried by the
// inverse transpose (flatten level); and a triangle seen from behind is shaded at the right point
// (the device's barycentrics of a back-facing hit) with its stored normal, not one turned toward the
// viewer: an opaque surface is lit on its stored side, from whichever side it is seen (shade.cl).
#include <catch.hpp>

#include <cmath>
#include <cstring>

#include "flatten/device_scene.h"
#include "flatten/flatten.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// A camera at the origin looking down −z, a point light at (0 0 lightZ) (default: at the camera), one
// material, and `objects`.
std::string orientationScene(const std::string& transforms, const std::string& objects,
                             const std::string& lightZ = "0") {
    return R"(<Scene><BackgroundColor>0 0 0</BackgroundColor>
<Cameras><Camera id="1"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>
<ImageName>o.exr</ImageName></Camera></Cameras>
<Lights><AmbientLight>5 5 5</AmbientLight><PointLight id="1"><Position>0 0 )" + lightZ + R"(</Position><Intensity>1000 1000 1000</Intensity></PointLight></Lights>
<Materials><Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
<SpecularReflectance>0 0 0</SpecularReflectance><PhongExponent>1</PhongExponent></Material></Materials>
<Transformations>)" + transforms + R"(</Transformations>
<VertexData>-10 -10 -5  10 -10 -5  0 10 -5  0 0 1</VertexData>
<Objects>)" + objects + "</Objects></Scene>";
}

Vec3 xyz(const dev::float4& v) { return Vec3(v.x, v.y, v.z); }
Vec3 faceNormal(const dev::Triangle& t) { return normalize(cross(xyz(t.v1) - xyz(t.v0), xyz(t.v2) - xyz(t.v0))); }

}  // namespace

TEST_CASE("a mirroring transformation (det < 0) keeps the object-space orientation of triangles", "[orientation]") {
    TempDir dir;
    // Faces 1 2 3 face +z in object space; Scaling -1 1 1 mirrors x, which leaves +z as it is (the
    // inverse transpose of diag(-1, 1, 1) maps +z to +z), while the world-space cross product of the
    // mirrored edges would point to −z.
    const std::string transforms = R"(<Scaling id="1">-1 1 1</Scaling><Scaling id="2">1 1 1</Scaling><Rotation id="1">90 0 1 0</Rotation>)";
    const std::string objects = R"(
<Mesh id="1"><Material>1</Material><Transformations>s1</Transformations><Faces>1 2 3</Faces></Mesh>
<Triangle id="2"><Material>1</Material><Transformations>s1</Transformations><Indices>1 2 3</Indices></Triangle>
<MeshInstance id="3" baseMeshId="4"><Transformations>s1</Transformations></MeshInstance>
<Mesh id="4"><Material>1</Material><Transformations>s2</Transformations><Faces>1 2 3</Faces></Mesh>
<Mesh id="5" shadingMode="smooth"><Material>1</Material><Transformations>s1 r1</Transformations><Faces>1 2 3</Faces></Mesh>)";
    const std::string path = dir.file("mirror.xml");
    writeFileBytes(path, orientationScene(transforms, objects));
    Scene scene = loadScene(path);
    DeviceScene ds = flattenScene(scene);
    REQUIRE(ds.params.numTriangles == 5);
    int plusZ = 0, plusX = 0;
    for (int i = 0; i < 5; ++i) {
        const Vec3 n = faceNormal(ds.triangles[size_t(i)]);
        const Vec3 shading = normalize(triangleCorners(ds, size_t(i)).normal[0]);
        INFO("triangle " << i << ": geometric normal " << n.x << " " << n.y << " " << n.z);
        plusZ += length(n - Vec3(0, 0, 1)) < 1e-5f;
        // Mesh 5: mirrored, then turned 90° about y: +z goes to +x. Its smooth (area-weighted)
        // vertex normals agree with the geometric normal.
        plusX += length(n - Vec3(1, 0, 0)) < 1e-5f;
        CHECK(dot(shading, n) > 0.999f);
    }
    CHECK(plusZ == 4);  // the mirrored mesh, triangle and instance, and the unmirrored base mesh
    CHECK(plusX == 1);
}

TEST_CASE("a triangle seen from behind is shaded where it was hit, with its stored normal", "[orientation][render]") {
    // The course's convention (hw2 grass_desert: 29.97 -> 50.80 dB): an opaque surface is lit on its
    // stored side from whichever side it is seen. A triangle at z = -5 facing the camera with the light
    // at the camera, and the same triangle wound the other way (facing away, toward -z) with the light
    // behind it at z = -10, see the same light at the same distance and angle: the two images agree
    // pixel for pixel (which also checks that a back-facing hit is shaded where it was hit). With the
    // light at the camera, the triangle facing away is not lit: ambient only. The old two-sided rule
    // (normal turned toward the viewer) fails both: it lights the third image, darkens the second.
    TempDir dir;
    struct Setup { const char* faces; const char* lightZ; };
    const Setup setups[3] = {{"1 2 3", "0"}, {"1 3 2", "-10"}, {"1 3 2", "0"}};
    ImageRGB img[3];
    for (int k = 0; k < 3; ++k) {
        const std::string path = dir.file("wind" + std::to_string(k) + ".xml");
        writeFileBytes(path, orientationScene("", std::string("<Mesh id=\"1\"><Material>1</Material><Faces>") +
                                                      setups[k].faces + "</Faces></Mesh>", setups[k].lightZ));
        Scene scene = loadScene(path);
        img[k] = renderCamera(scene, scene.cameras.at(0));
    }
    REQUIRE(img[0].pixels.size() == img[1].pixels.size());
    REQUIRE(img[0].pixels.size() == img[2].pixels.size());
    float worst = 0, brightest = 0, unlitWorst = 0;
    int covered = 0;
    for (size_t i = 0; i < img[0].pixels.size(); ++i) {
        worst = std::max(worst, std::fabs(img[0].pixels[i] - img[1].pixels[i]));
        brightest = std::max(brightest, img[0].pixels[i]);
        // Where the triangle is (lit in image 0), image 2 holds the ambient term alone (5); elsewhere 0.
        const float expectUnlit = img[0].pixels[i] > 0.0f ? 5.0f : 0.0f;
        covered += img[0].pixels[i] > 0.0f;
        unlitWorst = std::max(unlitWorst, std::fabs(img[2].pixels[i] - expectUnlit));
    }
    INFO("max |front lit from front - back lit from behind| = " << worst << ", brightest pixel " << brightest
         << ", max |back lit from front - ambient| = " << unlitWorst << " over " << covered << " channel values");
    CHECK(brightest > 30.0f);  // lit: 1000 / 25 + 5 at the centre
    CHECK(covered > 0);
    CHECK(worst <= 1e-4f * brightest);
    CHECK(unlitWorst <= 1e-4f * 5.0f);
}

// Back-face culling (Scene::backfaceCulling, intersect.cl cullBefore): the course's 2025 renderer
// does not see triangles from behind along its camera and reflection rays, and its references show it
// (2025 hw2 grass_desert: 30.4 -> 51.4 dB; hw3 cornellbox_boxes_dynamic, whose camera looks through the back
// of the box's front wall); its 2022 XML references do not cull (hw2 grass_desert 51.0 dB, 30.4 culled). So
// scenes in the JSON form cull, XML scenes do not, and --backface-culling on/off overrides it. Here, seen
// from z = 5: a red quad at z = 2 facing away (−z; mirrored by Scaling −1 1 1, which
// keeps the object-space orientation: flattened with its winding reversed, and as a two-level instance, tested
// in object space) and
// a green one at z = 0 facing the camera; then the
// same behind a closed glass box (z from 3 to 4, index 1, absorption 1 per unit): a ray inside the glass
// must still meet the box's far face from behind to leave it (Beer's law there: e^-length), and the ray that
// leaves is in air again and culls.
TEST_CASE("scenes in the 2025 JSON form cull back faces along camera and reflection rays; XML scenes do not",
          "[orientation][render]") {
    TempDir dir;
    const std::string json = R"({"Scene": {"BackgroundColor": "0 0 0",
 "Cameras": {"Camera": {"_id": "1", "Position": "0 0 5", "Gaze": "0 0 -1", "Up": "0 1 0",
   "NearPlane": "-0.5 0.5 -0.5 0.5", "NearDistance": "1", "ImageResolution": "8 8", "ImageName": "o.png"}},
 "Lights": {"AmbientLight": "1 1 1"},
 "Materials": {"Material": [{"_id": "1", "AmbientReflectance": "1 0 0"}, {"_id": "2", "AmbientReflectance": "0 1 0"},
   {"_id": "3", "_type": "dielectric", "AmbientReflectance": "0 0 0", "DiffuseReflectance": "0 0 0",
    "SpecularReflectance": "0 0 0", "AbsorptionCoefficient": "1 1 1", "RefractionIndex": "1"}]},
 "VertexData": {"_data": "-9 -9 2  9 -9 2  9 9 2  -9 9 2  -9 -9 0  9 -9 0  9 9 0  -9 9 0 -3 -3 3  3 -3 3  3 3 3  -3 3 3  -3 -3 4  3 -3 4  3 3 4  -3 3 4",
   "_type": "xyz"},
 "Transformations": {"Scaling": {"_id": "1", "_data": "-1 1 1"}},
 "Objects": {"Mesh": [{"_id": "1", "Material": "1", "Transformations": "s1", "Faces": {"_data": "1 3 2  1 4 3", "_type": "triangle"}},
                      {"_id": "2", "Material": "2", "Faces": {"_data": "5 6 7  5 7 8", "_type": "triangle"}}GLASS]}}})";
    const std::string glassBox = R"(, {"_id": "3", "Material": "3", "Faces": {"_data": "13 14 15  13 15 16  9 11 10  9 12 11  10 11 15  10 15 14  9 13 16  9 16 12  12 16 15  12 15 11  9 10 14  9 14 13",
      "_type": "triangle"}})";
    for (const bool withGlass : {false, true}) {
        std::string text = json;
        text.replace(text.find("GLASS"), 5, withGlass ? glassBox : "");
        writeFileBytes(dir.file("cull.json"), text);
        Scene scene = loadScene(dir.file("cull.json"));
        CHECK(scene.backfaceCulling);  // the JSON form
        // the camera sees everything before its image plane (z = 4), so that culling alone compiles the test in
        scene.cameras.at(0).nearMode = CLRT_NEAR_ALL;
        // Through the glass: e^-L, L = (1 − ε)·|d| for the pixel's direction d = (u, v, −1) (the refracted ray
        // starts ShadowRayEpsilon ε inside).
        auto seen = [&](size_t pixel) {
            if (!withGlass) return 1.0;
            const double u = -0.5 + (double(pixel % 8) + 0.5) / 8, v = 0.5 - (double(pixel / 8) + 0.5) / 8;
            return std::exp(-(1.0 - scene.shadowRayEpsilon) * std::sqrt(u * u + v * v + 1));
        };
        for (const bool cull : {true, false}) {
          for (Instancing instancing : {Instancing::Flatten, Instancing::TwoLevel}) {
            scene.backfaceCulling = cull;
            FlattenOptions opts;
            opts.instancing = instancing;
            DeviceScene ds = flattenScene(scene, opts);
            CHECK(ds.features.backfaceCulling == cull);
            CHECK(ds.params.numInstances == (instancing == Instancing::TwoLevel ? (withGlass ? 3 : 2) : 0));
            Renderer r(testContext(), ds);
            for (Pipeline pipeline : {Pipeline::Wavefront, Pipeline::Fused}) {
                RenderSettings rs;
                rs.spp = 1;
                rs.pipeline = pipeline;
                RenderCounters counters;
                ImageRGB img = r.render(scene.cameras.at(0), rs, counters);
                INFO((cull ? "culling" : "not culling") << (withGlass ? ", behind glass" : "")
                     << (pipeline == Pipeline::Fused ? ", fused" : ", wavefront")
                     << (instancing == Instancing::TwoLevel ? ", two-level" : ", flattened"));
                for (size_t i = 0; i < img.pixels.size(); i += 3) {  // culled: green through the red quad's back
                    CHECK(img.pixels[i] == Approx(cull ? 0.0 : seen(i / 3)).margin(1e-5));
                    CHECK(img.pixels[i + 1] == Approx(cull ? seen(i / 3) : 0.0).margin(1e-5));
                }
            }
          }
        }
    }
    // The XML form does not cull.
    const std::string xml = R"(<Scene><Cameras><Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
<ImageName>o.png</ImageName></Camera></Cameras><Lights><AmbientLight>1 1 1</AmbientLight></Lights>
<Materials><Material id="1"><AmbientReflectance>1 0 0</AmbientReflectance></Material></Materials>
<VertexData>-9 -9 2  9 -9 2  9 9 2  -9 9 2</VertexData><Objects><Mesh id="1"><Material>1</Material><Faces>1 3 2  1 4 3</Faces></Mesh></Objects></Scene>)";
    writeFileBytes(dir.file("cull.xml"), xml);
    CHECK_FALSE(loadScene(dir.file("cull.xml")).backfaceCulling);
}

// The near segment's culling is compiled in (CLRT_HAS_BACKFACE_CULLING) only where a camera's eye-to-image-plane
// box meets the BVH (nearSegmentMeetsGeometry, flatten_scene.cpp), flattened or as two-level instances; the
// program is otherwise the same as before the rule, so scenes without such geometry render as fast.
TEST_CASE("the near segment's culling is compiled only where geometry lies before an image plane", "[orientation]") {
    TempDir dir;
    writeFileBytes(dir.file("near.xml"), R"(<Scene><Cameras><Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze>
<Up>0 1 0</Up><NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution>
<ImageName>o.png</ImageName></Camera></Cameras><Lights><AmbientLight>1 1 1</AmbientLight></Lights>
<Materials><Material id="1"><AmbientReflectance>1 0 0</AmbientReflectance></Material></Materials>
<VertexData>-1 -1 2  1 -1 2  1 1 2  -1 1 2</VertexData><Objects><Mesh id="1"><Material>1</Material>
<Faces>1 2 3  1 3 4</Faces></Mesh></Objects></Scene>)");
    Scene scene = loadScene(dir.file("near.xml"));
    for (Instancing instancing : {Instancing::Flatten, Instancing::TwoLevel}) {
        FlattenOptions opts;
        opts.instancing = instancing;
        INFO((instancing == Instancing::TwoLevel ? "two-level" : "flattened"));
        scene.cameras.at(0).position = Vec3(0, 0, 5);  // the image plane at z = 4, the quad at z = 2
        CHECK_FALSE(flattenScene(scene, opts).features.backfaceCulling);
        scene.cameras.at(0).position = Vec3(0, 0, 2.5f);  // the image plane at z = 1.5: the quad before it
        CHECK(flattenScene(scene, opts).features.backfaceCulling);
        scene.cameras.at(0).position = Vec3(3, 0, 2.5f);  // beside the quad: the box misses it
        CHECK_FALSE(flattenScene(scene, opts).features.backfaceCulling);
        scene.cameras.at(0).apertureSize = 4.0f;  // a lens as wide as the gap: its rays may meet it
        scene.cameras.at(0).focusDistance = 1.0f;
        CHECK(flattenScene(scene, opts).features.backfaceCulling);
        scene.cameras.at(0).apertureSize = 0.0f;
    }
}

// Smooth shading: an opaque surface of the classic renderer keeps its interpolated vertex normal as it is,
// even where it faces away from the geometric normal (the course's 2025 hw1 smooth references:
// windmill_smooth 39.93 -> 41.42 dB, tower, low_poly, berserker +0.9 to +1.2 dB); dielectrics and the path
// tracer turn it to the geometric normal's side. A triangle facing the camera (and the light beside it)
// whose PLY gives every vertex the normal (0, 0, -1): lit by the ambient light alone.
TEST_CASE("smooth shading keeps a vertex normal that faces away from the geometric normal (classic, opaque)",
          "[orientation][render]") {
    TempDir dir;
    writeFileBytes(dir.file("tri.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                         "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                         "-10 -10 -5 0 0 -1\n10 -10 -5 0 0 -1\n0 10 -5 0 0 -1\n3 0 1 2\n");
    const std::string path = dir.file("smooth.xml");
    writeFileBytes(path, orientationScene("", R"(<Mesh id="1" shadingMode="smooth"><Material>1</Material><Faces plyFile="tri.ply"/></Mesh>)"));
    Scene scene = loadScene(path);
    DeviceScene ds = flattenScene(scene);
    for (Pipeline pipeline : {Pipeline::Wavefront, Pipeline::Fused}) {
        ImageRGB img = renderPipeline(ds, scene.cameras.at(0), pipeline);
        // the centre pixel sees the triangle: ambient (5) only, not 1000/25 + 5
        const size_t centre = (size_t(img.height / 2) * size_t(img.width) + size_t(img.width / 2)) * 3;
        INFO((pipeline == Pipeline::Fused ? "fused" : "wavefront") << ": centre " << img.pixels[centre]);
        CHECK(img.pixels[centre] == Approx(5.0f).epsilon(1e-5));
    }
}

// What camera rays see between the eye and the image plane (Camera::nearMode, camera.cl; clrt render
// --ray-origin): by default only triangles' front faces, as the course's references show (hw3
// cornellbox_boxes_dynamic: its camera is 10 behind the box's front wall, seen from behind, and the image plane
// 0.01 inside it: no wall; the 2020 hw1 spheres: the floor the camera looks down on before the plane is seen);
// --ray-origin eye sees everything, plane nothing. Here a red quad between the eye (z = 5) and the image plane
// (z = 4), facing the camera or away from it, and a green one at z = 0 facing the camera, in either form: the
// JSON form's classic renderer culls back faces everywhere (the test above), so the red quad from behind is
// seen only from an XML scene's eye.
TEST_CASE("camera rays see only front faces before the image plane; --ray-origin eye all, plane none", "[orientation][render]") {
    TempDir dir;
    const std::string xml = R"(<Scene><BackgroundColor>0 0 0</BackgroundColor>
<Cameras><Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution>
<ImageName>o.png</ImageName></Camera></Cameras><Lights><AmbientLight>1 1 1</AmbientLight></Lights>
<Materials><Material id="1"><AmbientReflectance>1 0 0</AmbientReflectance></Material>
<Material id="2"><AmbientReflectance>0 1 0</AmbientReflectance></Material></Materials>
<VertexData>-9 -9 4.5  9 -9 4.5  9 9 4.5  -9 9 4.5  -9 -9 0  9 -9 0  9 9 0  -9 9 0</VertexData>
<Objects><Mesh id="1"><Material>1</Material><Faces>RED</Faces></Mesh>
<Mesh id="2"><Material>2</Material><Faces>5 6 7  5 7 8</Faces></Mesh></Objects></Scene>)";
    const std::string json = R"({"Scene": {"BackgroundColor": "0 0 0",
 "Cameras": {"Camera": {"_id": "1", "Position": "0 0 5", "Gaze": "0 0 -1", "Up": "0 1 0",
   "NearPlane": "-0.5 0.5 -0.5 0.5", "NearDistance": "1", "ImageResolution": "4 4", "ImageName": "o.png"}},
 "Lights": {"AmbientLight": "1 1 1"},
 "Materials": {"Material": [{"_id": "1", "AmbientReflectance": "1 0 0"}, {"_id": "2", "AmbientReflectance": "0 1 0"}]},
 "VertexData": {"_data": "-9 -9 4.5  9 -9 4.5  9 9 4.5  -9 9 4.5  -9 -9 0  9 -9 0  9 9 0  -9 9 0", "_type": "xyz"},
 "Objects": {"Mesh": [{"_id": "1", "Material": "1", "Faces": {"_data": "RED", "_type": "triangle"}},
                      {"_id": "2", "Material": "2", "Faces": {"_data": "5 6 7  5 7 8", "_type": "triangle"}}]}}})";
    // Every pixel red (1) or green (0): the colour of the whole image, or -1 for a mix.
    auto colour = [](const Scene& scene) {
        DeviceScene ds = flattenScene(scene);
        Renderer r(testContext(), ds);
        RenderSettings rs;
        rs.spp = 1;
        RenderCounters counters;
        const ImageRGB img = r.render(scene.cameras.at(0), rs, counters);
        int red = 0, green = 0;
        for (size_t i = 0; i < img.pixels.size(); i += 3) {
            red += img.pixels[i] == 1.0f && img.pixels[i + 1] == 0.0f;
            green += img.pixels[i] == 0.0f && img.pixels[i + 1] == 1.0f;
        }
        return red == 16 ? 1 : green == 16 ? 0 : -1;
    };
    for (const bool facing : {true, false}) {
        for (const bool isJson : {false, true}) {
            std::string text = isJson ? json : xml;
            text.replace(text.find("RED"), 3, facing ? "1 2 3  1 3 4" : "1 3 2  1 4 3");
            const std::string path = dir.file(isJson ? "o.json" : "o.xml");
            writeFileBytes(path, text);
            Scene scene = loadScene(path);
            INFO((isJson ? "JSON" : "XML") << ", the red quad " << (facing ? "facing the camera" : "facing away"));
            CHECK(scene.cameras.at(0).nearMode == CLRT_NEAR_FRONT);
            CHECK(colour(scene) == (facing ? 1 : 0));
            scene.cameras.at(0).nearMode = CLRT_NEAR_ALL;
            CHECK(colour(scene) == (facing || !isJson ? 1 : 0));
            scene.cameras.at(0).nearMode = CLRT_NEAR_NONE;
            CHECK(colour(scene) == 0);
        }
    }
    // The command line: --ray-origin eye|plane|auto, anything else a usage error naming the flag.
    const std::string base = "render " + dir.file("o.xml") + " -o " + dir.path.string() + deviceArg();
    CHECK(runClrt(base + " --ray-origin eye", dir.file("log")) == 0);
    CHECK(runClrt(base + " --ray-origin plane", dir.file("log")) == 0);
    CHECK(runClrt(base + " --ray-origin sideways", dir.file("log")) == 1);
    CHECK(readFileBytes(dir.file("log")).find("--ray-origin") != std::string::npos);
}
