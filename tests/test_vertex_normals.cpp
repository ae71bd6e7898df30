// Smooth-shading vertex normals (src/flatten/vertex_normals.h): the object-space rule (area-weighted
// face normals summed per vertex index, given PLY normals as they are) against hand-computed values
// that tell it from the other candidates (unweighted, angle-weighted, shared by position), and the
// flattened world-space normals: the object-space ones by the inverse transpose, for a mesh and an
// instance of it under non-uniform scalings, which for area weighting equals averaging in world space.
#include <catch.hpp>

#include "flatten/device_scene.h"
#include "flatten/flatten.h"
#include "flatten/vertex_normals.h"
#include "scene/scene_loader.h"
#include "scene/transforms.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

bool near(const Vec3& a, const Vec3& b, float tol = 1e-6f) { return length(a - b) <= tol; }

// Two faces meeting at vertex 0 at a right angle: F1 in z = 0 (normal +z, cross product length 1),
// F2 in x = 0 (normal +x, length 4); vertex 4 is vertex 0's position again (a PLY's duplicate) with
// a face of its own in y = 0 (normal −y); vertex 5 is used by no face.
MeshData cornerMesh() {
    MeshData m;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 2, 0), Vec3(0, 0, 0), Vec3(7, 7, 7),
                   Vec3(0, 0, 2), Vec3(1, 0, 0)};
    m.indices = {0, 1, 2,  0, 3, 6,  4, 7, 6};
    return m;
}

}  // namespace

TEST_CASE("object-space vertex normals: area-weighted face normals summed per vertex index", "[flatten][smooth]") {
    const std::vector<Vec3> n = objectVertexNormals(cornerMesh());
    REQUIRE(n.size() == 8);
    // Area-weighted: (0, 0, 1) + (4, 0, 0). Unweighted or angle-weighted (both angles are 90°) would
    // give (1, 0, 1)/√2; sharing by position would add vertex 4's (0, −2, 0) face as well.
    CHECK(near(n[0], normalize(Vec3(4, 0, 1))));
    CHECK(near(n[1], Vec3(0, 0, 1)));
    CHECK(near(n[3], Vec3(1, 0, 0)));
    CHECK(near(n[4], Vec3(0, -1, 0)));  // the duplicate keeps its own face's normal
    CHECK(near(n[6], normalize(Vec3(4, -2, 0))));
    CHECK(n[5] == Vec3(0, 0, 0));  // no face: none (the caller uses the face normal)
    MeshData given = cornerMesh();
    given.normals.assign(8, Vec3(0, 0, 3));
    given.normals[2] = Vec3(0, 0, 0);
    const std::vector<Vec3> g = objectVertexNormals(given);
    CHECK(near(g[0], Vec3(0, 0, 1)));  // given normals win, normalised
    CHECK(g[2] == Vec3(0, 0, 0));      // a zero given normal: none
}

TEST_CASE("flattened smooth normals are the object-space ones by the inverse transpose", "[flatten][smooth]") {
    TempDir dir;
    // The corner mesh under a non-uniform scaling and a rotation, and an instance under another
    // scaling (which mirrors x: its winding is reversed, its normals still point outward).
    const std::string xml = R"(<Scene><BackgroundColor>0 0 0</BackgroundColor>
<Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution>
<ImageName>v.png</ImageName></Camera></Cameras>
<Lights><AmbientLight>1 1 1</AmbientLight></Lights>
<Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
<Transformations><Scaling id="1">4 1 0.5</Scaling><Rotation id="1">30 1 1 0</Rotation><Scaling id="2">-2 3 1</Scaling><Translation id="1">5 0 0</Translation></Transformations>
<VertexData>0 0 0  1 0 0  0 1 0  0 2 0  0 0 2</VertexData>
<Objects><Mesh id="1" shadingMode="smooth"><Material>1</Material><Transformations>s1 r1</Transformations><Faces>1 2 3  1 4 5</Faces></Mesh>
<MeshInstance id="2" baseMeshId="1" resetTransform="true"><Transformations>s2 t1</Transformations></MeshInstance></Objects></Scene>)";
    const std::string path = dir.file("smooth.xml");
    writeFileBytes(path, xml);
    const Scene scene = loadScene(path);
    const DeviceScene ds = flattenScene(scene);
    REQUIRE(ds.params.numTriangles == 4);
    const Vec3 nObj0 = normalize(Vec3(4, 0, 1));  // vertex 1 of the XML: both faces
    int checked = 0;
    for (const Shape& s : scene.shapes) {
        Mat4 inv;
        REQUIRE(s.transform.inverse(inv));
        const Vec3 expectWorld = normalize(inv.transposed().transformVector(nObj0));
        const Vec3 cornerWorld = s.transform.transformPoint(Vec3(0, 0, 0));
        // World-space area weighting gives the same direction: cross(Ma, Mb) = det(M)·M⁻ᵀ·cross(a, b).
        const Vec3 e1 = s.transform.transformVector(Vec3(1, 0, 0)), e2 = s.transform.transformVector(Vec3(0, 1, 0));
        const Vec3 e3 = s.transform.transformVector(Vec3(0, 2, 0)), e4 = s.transform.transformVector(Vec3(0, 0, 2));
        const float det = float(linearDeterminant(s.transform));
        CHECK(near(normalize((cross(e1, e2) + cross(e3, e4)) * det), expectWorld, 1e-5f));
        for (size_t t = 0; t < ds.triangles.size(); ++t) {
            const dev::Triangle& tri = ds.triangles[t];
            const TriangleCorners corners = triangleCorners(ds, t);
            const dev::float4* v[3] = {&tri.v0, &tri.v1, &tri.v2};
            const Vec3* n = corners.normal;
            for (int k = 0; k < 3; ++k) {
                if (!near(Vec3(v[k]->x, v[k]->y, v[k]->z), cornerWorld, 1e-5f)) continue;
                INFO("shape " << s.source << ", triangle " << t);
                CHECK(near(n[k], expectWorld, 1e-5f));
                ++checked;
            }
        }
    }
    CHECK(checked == 4);  // the shared corner of both faces, in the mesh and in the instance
}
