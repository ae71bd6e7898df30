// Enclosed LightMeshes (src/flatten/light_enclosure.cpp, flattened into Light.position by flatten_lights.cpp):
// which light meshes bound a closed convex volume, alone or with the scene geometry that closes their openings,
// and which do not (open, flat, concave; a cover too small, holed, offset, transparent or moving).
#include <catch.hpp>

#include <fstream>
#include <string>

#include "flatten/device_scene.h"
#include "flatten/light_enclosure.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// The hw6 boxes' light: five faces of the box [-0.25, 0.25]² × [1.16, 1.28] (z up), open at z = 1.28; then
// the cover's vertices (13-16: a ceiling square at z = 1.28 by default) and the objects `objects`.
const char* kBox = "-0.25 0.25 1.16  0.25 0.25 1.16  0.25 0.25 1.28  -0.25 0.25 1.28  "
                   "-0.25 -0.25 1.16  0.25 -0.25 1.16  0.25 -0.25 1.28  -0.25 -0.25 1.28  ";
const char* kBoxFaces = "1 2 6  6 5 1  1 4 3  3 2 1  2 3 7  7 6 2  6 7 8  8 5 6  5 8 4  4 1 5";

std::string sceneXml(const std::string& vertices, const std::string& objects) {
    return "<Scene><Cameras><Camera id=\"1\"><Position>0 0 -3</Position><Gaze>0 0 1</Gaze><Up>0 1 0</Up>"
           "<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution>"
           "<ImageName>o.exr</ImageName></Camera></Cameras><Materials><Material id=\"1\"/>"
           "<Material id=\"2\" type=\"dielectric\"><Transparency>1 1 1</Transparency><RefractionIndex>1.5</RefractionIndex></Material></Materials>"
           "<VertexData>" + vertices + "</VertexData><Objects><LightMesh id=\"1\"><Material>1</Material>"
           "<Radiance>5 5 5</Radiance><Faces>" + std::string(kBoxFaces) + "</Faces></LightMesh>" +
           objects + "</Objects></Scene>";
}

std::string ceiling(const char* material = "1", const char* faces = "9 10 11  9 11 12") {
    return std::string("<Mesh id=\"1\"><Material>") + material + "</Material><Faces>" + faces + "</Faces></Mesh>";
}
const char* kCeiling = "-2 -2 1.28  2 -2 1.28  2 2 1.28  -2 2 1.28";

dev::float4 lightPosition(const std::string& xml) {
    TempDir d;
    std::string p = d.file("s.xml");
    std::ofstream(p) << xml;
    const DeviceScene ds = flattenScene(loadScene(p));
    REQUIRE(ds.lights.size() >= 1);
    REQUIRE(ds.lights[0].kind == dev::LIGHT_MESH);
    return ds.lights[0].position;
}

}  // namespace

TEST_CASE("light enclosure: a closed convex LightMesh, or one whose opening opaque geometry covers, is enclosed",
          "[objlight][enclosure]") {
    SECTION("the hw6 light box under a ceiling of two triangles whose diagonal crosses its opening") {
        dev::float4 p = lightPosition(sceneXml(std::string(kBox) + kCeiling, ceiling()));
        CHECK(p.w == 1.0f);
        CHECK(p.x == Approx(0.0f).margin(1e-6));
        CHECK(p.y == Approx(0.0f).margin(1e-6));
        CHECK(p.z == Approx(1.22f));
    }
    SECTION("the light box closed by its own top (12 triangles)") {
        std::string xml = sceneXml(kBox, "");
        xml.replace(xml.find(kBoxFaces), std::string(kBoxFaces).size(), std::string(kBoxFaces) + "  3 4 8  8 7 3");
        CHECK(lightPosition(xml).w == 1.0f);
    }
    SECTION("under a Plane") {
        CHECK(lightPosition(sceneXml(std::string(kBox) + "0 0 1.28", "<Plane id=\"1\"><Material>1</Material><Point>9</Point>"
                                                                     "<Normal>0 0 -1</Normal></Plane>")).w == 1.0f);
    }
    SECTION("under a MeshInstance of a mesh elsewhere, moved up to the ceiling") {
        auto instanceAt = [](const char* z) {  // the base mesh lies at z = 0: only its instance can cover
            std::string xml = sceneXml(std::string(kBox) + "-2 -2 0  2 -2 0  2 2 0  -2 2 0",
                                       ceiling() + "<MeshInstance id=\"2\" baseMeshId=\"1\"><Material>1</Material>"
                                                   "<Transformations>t1</Transformations></MeshInstance>");
            xml.insert(xml.find("<VertexData>"), std::string("<Transformations><Translation id=\"1\">0 0 ") + z +
                                                     "</Translation></Transformations>");
            return lightPosition(xml).w;
        };
        CHECK(instanceAt("1.28") == 1.0f);
        CHECK(instanceAt("1.3") == 0.0f);
    }
    SECTION("under a ceiling of four triangles that meet inside the opening") {
        CHECK(lightPosition(sceneXml(std::string(kBox) + kCeiling + "  0.1 -0.05 1.28",
                                     ceiling("1", "9 10 13  10 11 13  11 12 13  12 9 13"))).w == 1.0f);
    }
}

TEST_CASE("light enclosure: open, flat, concave or uncovered LightMeshes are not enclosed", "[objlight][enclosure]") {
    SECTION("no ceiling") { CHECK(lightPosition(sceneXml(kBox, "")).w == 0.0f); }
    SECTION("a ceiling too small for the opening") {
        CHECK(lightPosition(sceneXml(std::string(kBox) + "-0.2 -2 1.28  2 -2 1.28  2 2 1.28  -0.2 2 1.28", ceiling())).w == 0.0f);
    }
    SECTION("a ceiling with a hole over a corner of the opening (three of four triangles)") {
        CHECK(lightPosition(sceneXml(std::string(kBox) + kCeiling + "  0.1 -0.05 1.28",
                                     ceiling("1", "9 10 13  10 11 13  11 12 13"))).w == 0.0f);
    }
    SECTION("a ceiling 1e-3 above the opening") {
        CHECK(lightPosition(sceneXml(std::string(kBox) + "-2 -2 1.281  2 -2 1.281  2 2 1.281  -2 2 1.281", ceiling())).w == 0.0f);
    }
    SECTION("a glass ceiling") { CHECK(lightPosition(sceneXml(std::string(kBox) + kCeiling, ceiling("2"))).w == 0.0f); }
    SECTION("a moving ceiling") {
        std::string c = ceiling();
        c.insert(c.find("</Mesh>"), "<MotionBlur>0 0 0.5</MotionBlur>");
        CHECK(lightPosition(sceneXml(std::string(kBox) + kCeiling, c)).w == 0.0f);
    }
    SECTION("a flat light (one square)") {
        std::string xml = sceneXml(kBox, "");
        xml.replace(xml.find(kBoxFaces), std::string(kBoxFaces).size(), "1 2 6  6 5 1");
        CHECK(lightPosition(xml).w == 0.0f);
    }
    SECTION("a concave closed light (the box with its bottom pushed in)") {
        std::string xml = sceneXml(std::string(kBox) + "0 0 1.2", "");
        xml.replace(xml.find(kBoxFaces), std::string(kBoxFaces).size(),
                    "1 2 9  2 6 9  6 5 9  5 1 9  2 3 7  7 6 2  6 7 8  8 5 6  5 8 4  4 1 5  1 4 3  3 2 1  3 4 8  8 7 3");
        CHECK(lightPosition(xml).w == 0.0f);
    }
}

TEST_CASE("light enclosure: findMeshLightEnclosure's inside point lies strictly inside", "[objlight][enclosure]") {
    // A tetrahedron: closed and convex, the mean of its vertices inside it.
    Scene s;
    s.materials.emplace_back();
    s.shapes.emplace_back();
    const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
    MeshLightEnclosure e = findMeshLightEnclosure(s, 0, {a, b, c, a, b, d, a, c, d, b, c, d});
    CHECK(e.enclosed);
    CHECK(e.inside.x == Approx(0.25f));
    CHECK(e.inside.z == Approx(0.25f));
    // One triangle short: open, nothing to cover it.
    CHECK_FALSE(findMeshLightEnclosure(s, 0, {a, b, c, a, b, d, a, c, d}).enclosed);
}
