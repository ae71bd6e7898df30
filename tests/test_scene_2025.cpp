// Tests for what the course's 2025 scenes add to the scene reader (issue 29): <Transformations> inside
// a <Camera> and inside lights (the camera or light moved as an object: positions by the full matrix,
// directions by the linear part, an area light's normal by the inverse transpose and its side by the
// area scale), and a camera's own <MaxRecursionDepth> (which overrides the scene's: checked through
// the binary's images), MinRecursionDepth and SplittingFactor. Each case is checked against the same
// scene written out by hand without the transformation, in XML and in the JSON form.
#include <catch.hpp>

#include <cmath>
#include <string>

#include "image/image.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
using namespace clrt::test;

namespace {

bool near(const Vec3& a, const Vec3& b, float eps = 1e-5f) { return length(a - b) <= eps; }

// s with the first `from` replaced by `to` (which must be there).
std::string sub(std::string s, const std::string& from, const std::string& to) {
    size_t at = s.find(from);
    REQUIRE(at != std::string::npos);
    return s.replace(at, from.size(), to);
}

// A scene whose camera block is `camera` and whose <Lights> hold `lights`; the named transformations
// t1 (translation 1 2 3), r1 (90° about +y), s1 (uniform 2), s2 (1 2 3), m1 (mirror x).
std::string scene2025(const std::string& camera, const std::string& lights = "") {
    return "<Scene>\n<Transformations>\n"
           "  <Translation id=\"1\">1 2 3</Translation><Rotation id=\"1\">90 0 1 0</Rotation>\n"
           "  <Scaling id=\"1\">2 2 2</Scaling><Scaling id=\"2\">1 2 3</Scaling><Scaling id=\"3\">-1 1 1</Scaling>\n"
           "</Transformations>\n<Cameras>\n" + camera + "</Cameras>\n<Lights>" + lights + "</Lights>\n"
           "<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>\n"
           "<VertexData>0 0 0</VertexData><Objects><Sphere id=\"1\"><Material>1</Material><Center>1</Center>"
           "<Radius>1</Radius></Sphere></Objects>\n</Scene>\n";
}

// A simple camera at `pos` looking along `gaze`, with `extra` children.
std::string simpleCamera(const std::string& pos, const std::string& gaze, const std::string& up,
                         const std::string& extra = "") {
    return "<Camera id=\"1\"><Position>" + pos + "</Position><Gaze>" + gaze + "</Gaze><Up>" + up +
           "</Up><NearPlane>-1 1 -0.5 0.5</NearPlane><NearDistance>2</NearDistance>"
           "<ImageResolution>8 4</ImageResolution><ImageName>out.png</ImageName>" + extra + "</Camera>\n";
}

Scene loadText(const TempDir& d, const std::string& name, const std::string& text) {
    writeFileBytes(d.file(name), text);
    return loadScene(d.file(name));
}

void expectSameCamera(const Camera& a, const Camera& b) {
    CHECK(near(a.position, b.position));
    CHECK(near(a.u, b.u));
    CHECK(near(a.v, b.v));
    CHECK(near(a.w, b.w));
    // The image plane's extent over its distance is what fixes the rays.
    CHECK(std::fabs(a.left / a.nearDistance - b.left / b.nearDistance) < 1e-6f);
    CHECK(std::fabs(a.top / a.nearDistance - b.top / b.nearDistance) < 1e-6f);
}

}  // namespace

TEST_CASE("scene 2025: <Transformations> in a <Camera> move it as an object", "[scene][scene2025]") {
    TempDir d;
    SECTION("rotation then translation: position by the full matrix, gaze and up by the linear part") {
        // r1 turns -z into -x and +x into -z; then t1 moves it.
        Scene moved = loadText(d, "m.xml", scene2025(simpleCamera("1 0 0", "0 0 -1", "0 1 0",
                                                                  "<Transformations>r1 t1</Transformations>")));
        Scene byHand = loadText(d, "h.xml", scene2025(simpleCamera("1 2 2", "-1 0 0", "0 1 0")));
        expectSameCamera(moved.cameras.at(0), byHand.cameras.at(0));
        CHECK(near(moved.cameras[0].position, {1, 2, 2}));
    }
    SECTION("a lookAt camera's GazePoint moves with it") {
        const std::string la = "<Camera id=\"1\" type=\"lookAt\"><Position>0 0 0</Position><GazePoint>0 0 -5</GazePoint>"
                               "<Up>0 1 0</Up><FovY>40</FovY><NearDistance>1</NearDistance>"
                               "<ImageResolution>8 4</ImageResolution><ImageName>out.png</ImageName>";
        Scene moved = loadText(d, "la.xml", scene2025(la + "<Transformations>r1 t1</Transformations></Camera>\n"));
        Scene byHand = loadText(d, "lah.xml", scene2025(sub(sub(la, "<Position>0 0 0", "<Position>1 2 3"),
                                                            "<GazePoint>0 0 -5", "<GazePoint>-4 2 3") + "</Camera>\n"));
        expectSameCamera(moved.cameras.at(0), byHand.cameras.at(0));
    }
    SECTION("a uniform scale: same rays, the lens scales with the camera") {
        const std::string lens = "<FocusDistance>5</FocusDistance><ApertureSize>0.5</ApertureSize>";
        Scene moved = loadText(d, "s.xml", scene2025(simpleCamera("1 1 1", "0 0 -1", "0 1 0",
                                                                  lens + "<Transformations>s1</Transformations>")));
        Scene plain = loadText(d, "sp.xml", scene2025(simpleCamera("2 2 2", "0 0 -1", "0 1 0", lens)));
        expectSameCamera(moved.cameras.at(0), plain.cameras.at(0));
        CHECK(moved.cameras[0].focusDistance == 10);
        CHECK(moved.cameras[0].apertureSize == 1);
    }
    SECTION("a mirror flips the image horizontally, as handedness=\"left\" does") {
        Scene mirrored = loadText(d, "mi.xml", scene2025(simpleCamera("1 0 0", "0 0 -1", "0 1 0",
                                                                      "<Transformations>s3</Transformations>")));
        const Camera& c = mirrored.cameras.at(0);
        CHECK(near(c.position, {-1, 0, 0}));
        CHECK(near(c.w, {0, 0, 1}));
        CHECK(near(c.u, {-1, 0, 0}));  // unmirrored: +x
    }
    SECTION("the JSON form reads the same") {
        const std::string json = R"({"Scene": {
  "Transformations": {"Translation": {"_id": "1", "_data": "1 2 3"}, "Rotation": {"_id": "1", "_data": "90 0 1 0"}},
  "Cameras": {"Camera": {"_id": "1", "Position": "1 0 0", "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -0.5 0.5",
     "NearDistance": "2", "ImageResolution": "8 4", "ImageName": "out.png", "Transformations": "r1 t1"}},
  "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}},
  "VertexData": {"_data": "0 0 0"}, "Objects": {"Sphere": {"_id": "1", "Material": "1", "Center": "1", "Radius": "1"}}}})";
        Scene j = loadText(d, "c.json", json);
        Scene byHand = loadText(d, "h.xml", scene2025(simpleCamera("1 2 2", "-1 0 0", "0 1 0")));
        expectSameCamera(j.cameras.at(0), byHand.cameras.at(0));
    }
    SECTION("errors: an undefined reference, a singular matrix") {
        writeFileBytes(d.file("u.xml"), scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0", "<Transformations>t9</Transformations>")));
        CHECK_THROWS_WITH(loadScene(d.file("u.xml")), Catch::Contains("u.xml:") && Catch::Contains("t9"));
        writeFileBytes(d.file("z.xml"), sub(scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0", "<Transformations>s1</Transformations>")),
                                            "<Scaling id=\"1\">2 2 2", "<Scaling id=\"1\">2 0 2"));
        CHECK_THROWS_WITH(loadScene(d.file("z.xml")), Catch::Contains("z.xml:") && Catch::Contains("singular"));
    }
}

TEST_CASE("scene 2025: <Transformations> in lights", "[scene][scene2025]") {
    TempDir d;
    const std::string lights = R"(
  <PointLight id="1"><Position>1 0 0</Position><Intensity>1 1 1</Intensity><Transformations>r1 t1</Transformations></PointLight>
  <SpotLight id="2"><Position>0 0 0</Position><Direction>0 0 -1</Direction><Intensity>1 1 1</Intensity>
    <CoverageAngle>40</CoverageAngle><FalloffAngle>20</FalloffAngle><Transformations>r1 t1</Transformations></SpotLight>
  <DirectionalLight id="3"><Direction>0 0 -1</Direction><Radiance>1 1 1</Radiance><Transformations>r1 t1 s2</Transformations></DirectionalLight>
  <AreaLight id="4"><Position>0 1 0</Position><Normal>1 0 0</Normal><Size>2</Size><Radiance>1 1 1</Radiance><Transformations>s2</Transformations></AreaLight>
  <AreaLight id="5"><Position>0 1 0</Position><Normal>0 0 1</Normal><Size>2</Size><Radiance>1 1 1</Radiance><Transformations>s2 r1</Transformations></AreaLight>
  <AreaLight id="6"><Position>0 1 0</Position><Normal>1 1 0</Normal><Size>2</Size><Radiance>1 1 1</Radiance><Transformations>s2</Transformations></AreaLight>
)";
    Scene s = loadText(d, "l.xml", scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0"), lights));
    REQUIRE(s.lights.size() == 6);
    CHECK(near(s.lights[0].position, {1, 2, 2}));          // (1,0,0) -> r1 (0,0,-1) -> t1
    CHECK(near(s.lights[1].position, {1, 2, 3}));
    CHECK(near(s.lights[1].direction, {-1, 0, 0}));        // -z -> r1 -x
    CHECK(near(s.lights[2].direction, {-1, 0, 0}));        // s2 keeps -x a unit -x
    // A square in the yz plane scaled by 2 in y and 3 in z: area ×6, side ×√6; the normal stays +x.
    CHECK(near(s.lights[3].position, {0, 2, 0}));
    CHECK(near(s.lights[3].direction, {1, 0, 0}));
    CHECK(std::fabs(s.lights[3].size - 2 * std::sqrt(6.0f)) < 1e-5f);
    // In the xy plane: area ×2, then turned to face +x.
    CHECK(near(s.lights[4].direction, {1, 0, 0}));
    CHECK(std::fabs(s.lights[4].size - 2 * std::sqrt(2.0f)) < 1e-5f);
    // A tilted normal: by the inverse transpose, (1, 1/2, 0) normalised; area |det|·|M⁻ᵀn| = 6·|(1, 1/2, 0)|/√2.
    CHECK(near(s.lights[5].direction, Vec3(1, 0.5f, 0) * (1 / std::sqrt(1.25f))));
    CHECK(std::fabs(s.lights[5].size - 2 * std::sqrt(6 * std::sqrt(1.25f) / std::sqrt(2.0f))) < 1e-5f);

    SECTION("an environment light's Transformations turn its map: a rotation, translations and uniform scalings ignored") {
        auto envScene = [&](const std::string& name, const std::string& transforms) {
            const std::string env = "<SphericalDirectionalLight id=\"7\"><ImageId>1</ImageId><Transformations>" + transforms +
                                    "</Transformations></SphericalDirectionalLight>";
            std::string text = sub(scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0"), env), "<Lights>",
                                   "<Textures><Images><Image id=\"1\">env.exr</Image></Images></Textures>\n<Lights>");
            writeFileBytes(d.file(name), text);
            return d.file(name);
        };
        const Mat4 r1 = Mat4::rotation(90, Vec3(0, 1, 0));
        for (const char* t : {"r1", "t1 r1", "s1 r1 t1", "r1 s1 s1"}) {
            INFO(t);
            Scene e = loadScene(envScene("e.xml", t));
            REQUIRE(e.lights.size() == 1);
            CHECK(e.lights[0].type == dev::LIGHT_ENVIRONMENT);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) CHECK(std::fabs(e.lights[0].envToWorld.m[i][j] - r1.m[i][j]) < 1e-12);
        }
        Scene mirrored = loadScene(envScene("m.xml", "s3"));  // a mirror keeps solid angles
        CHECK(mirrored.lights[0].envToWorld.m[0][0] == -1);
        // A non-uniform scaling would distort the map: an error naming the file and the element.
        CHECK_THROWS_WITH(loadScene(envScene("n.xml", "r1 s2")),
                          Catch::Contains("n.xml:") && Catch::Contains("SphericalDirectionalLight") &&
                              Catch::Contains("must be rotations"));
        // The JSON form: the same rotation; the error names the key path.
        const std::string json = R"({"Scene": {
  "Transformations": {"Rotation": {"_id": "1", "_data": "90 0 1 0"}, "Scaling": {"_id": "2", "_data": "1 2 3"}},
  "Cameras": {"Camera": {"_id": "1", "Position": "0 0 0", "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -0.5 0.5",
     "NearDistance": "2", "ImageResolution": "8 4", "ImageName": "out.png"}},
  "Textures": {"Images": {"Image": {"_id": "1", "_data": "env.exr"}}},
  "Lights": {"SphericalDirectionalLight": {"_id": "7", "ImageId": "1", "Transformations": "TRANSFORMS"}},
  "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}},
  "VertexData": {"_data": "0 0 0"}, "Objects": {"Sphere": {"_id": "1", "Material": "1", "Center": "1", "Radius": "1"}}}})";
        Scene j = loadText(d, "e.json", sub(json, "TRANSFORMS", "r1"));
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) CHECK(std::fabs(j.lights.at(0).envToWorld.m[i][k] - r1.m[i][k]) < 1e-12);
        writeFileBytes(d.file("n.json"), sub(json, "TRANSFORMS", "r1 s2"));
        CHECK_THROWS_WITH(loadScene(d.file("n.json")),
                          Catch::Contains("n.json: Scene.Lights.SphericalDirectionalLight.Transformations") &&
                              Catch::Contains("must be rotations"));
    }
}

TEST_CASE("scene 2025: a camera's own path-tracing settings", "[scene][scene2025]") {
    TempDir d;
    Scene s = loadText(d, "p.xml", scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0",
        "<Renderer>PathTracing</Renderer><RendererParams>RussianRoulette</RendererParams>"
        "<MaxRecursionDepth>3</MaxRecursionDepth><MinRecursionDepth>2</MinRecursionDepth><SplittingFactor>4</SplittingFactor>")));
    CHECK(s.cameras.at(0).maxRecursionDepth == 3);
    CHECK(s.cameras.at(0).minRecursionDepth == 2);
    Scene plain = loadText(d, "q.xml", scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0")));
    CHECK(plain.cameras.at(0).maxRecursionDepth == -1);  // the scene's
    writeFileBytes(d.file("n.xml"), scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0", "<MaxRecursionDepth>-1</MaxRecursionDepth>")));
    CHECK_THROWS_WITH(loadScene(d.file("n.xml")), Catch::Contains("n.xml:") && Catch::Contains("must not be negative"));
    writeFileBytes(d.file("f.xml"), scene2025(simpleCamera("0 0 0", "0 0 -1", "0 1 0", "<SplittingFactor>0</SplittingFactor>")));
    CHECK_THROWS_WITH(loadScene(d.file("f.xml")), Catch::Contains("f.xml:") && Catch::Contains("at least 1"));
}

// Two facing mirrors: each bounce adds light, so the depth limit shows in the image. Camera 1 carries
// <MaxRecursionDepth>1</MaxRecursionDepth>, camera 2 none (the scene's 6); camera 1's image must equal
// a render of the scene with MaxRecursionDepth 1 and differ from camera 2's.
TEST_CASE("scene 2025: <MaxRecursionDepth> in a <Camera> overrides the scene's in the render", "[scene2025][cli]") {
    TempDir d;
    auto sceneText = [](const std::string& sceneDepth, const std::string& camExtra) {
        return "<Scene><MaxRecursionDepth>" + sceneDepth + "</MaxRecursionDepth>\n<Cameras>"
               "<Camera id=\"1\"><Position>0 0 0.5</Position><Gaze>0.1 0 -1</Gaze><Up>0 1 0</Up><NearPlane>-0.5 0.5 -0.5 0.5</NearPlane>"
               "<NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution><ImageName>a.exr</ImageName>" + camExtra +
               "</Camera></Cameras>\n<Lights><AmbientLight>1 1 1</AmbientLight>"
               "<PointLight id=\"1\"><Position>0 0.5 0.5</Position><Intensity>2 2 2</Intensity></PointLight></Lights>\n"
               "<Materials><Material id=\"1\" type=\"mirror\"><AmbientReflectance>0.1 0.1 0.1</AmbientReflectance>"
               "<DiffuseReflectance>0.2 0.2 0.2</DiffuseReflectance><MirrorReflectance>0.8 0.8 0.8</MirrorReflectance></Material></Materials>\n"
               "<VertexData>-10 -10 -3  10 -10 -3  10 10 -3  -10 10 -3  -10 -10 3  10 -10 3  10 10 3  -10 10 3</VertexData>\n"
               "<Objects><Mesh id=\"1\"><Material>1</Material><Faces>1 2 3 1 3 4 6 5 8 6 8 7</Faces></Mesh></Objects></Scene>\n";
    };
    auto renderExr = [&](const std::string& name, const std::string& text) {
        writeFileBytes(d.file(name), text);
        return renderedPixels("render " + d.file(name) + " -o " + d.path.string(), d.file("log.txt"), d.file("a.exr"));
    };
    const std::vector<float> own = renderExr("own.xml", sceneText("6", "<MaxRecursionDepth>1</MaxRecursionDepth>"));
    const std::vector<float> scene1 = renderExr("s1.xml", sceneText("1", ""));
    const std::vector<float> scene6 = renderExr("s6.xml", sceneText("6", ""));
    CHECK(own == scene1);
    CHECK(own != scene6);
    const std::vector<float> deeper = renderExr("own6.xml", sceneText("1", "<MaxRecursionDepth>6</MaxRecursionDepth>"));
    CHECK(deeper == scene6);
}
