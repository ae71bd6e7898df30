// flatten_lights.cpp — scene lights -> dev::Light, one case per light type (environment lights:
// flatten_environment.cpp); see flatten.h. Object lights (LightMesh, LightSphere) also write their
// sampling data to ds.lightData (layout: device_types.h, after struct Light): the mesh's world-space
// triangles with an area CDF, the sphere's object-space centre/radius, worldToObject and objectToWorld rows.
#include <algorithm>
#include <cmath>

#include "flatten/flatten.h"
#include "flatten/light_enclosure.h"
#include "scene/transforms.h"
#include "util/error.h"

namespace clrt {
namespace {

// LightMesh: its triangles in world space (as flattenGeometry places them, mirrored meshes with their
// winding reversed; degenerate and non-finite ones left out) with the area CDF in v0.w and the area in v1.w; total area in d.area.
// d.position: a point inside the closed convex volume the triangles bound, w = 1, where they do (light_enclosure.h).
void flattenMeshLight(const Scene& scene, int shapeIndex, dev::Light& d, DeviceScene& ds, MeshLightEnclosures& enclosures) {
    const Shape& s = scene.shapes.at(size_t(shapeIndex));
    const MeshData& mesh = scene.meshes.at(size_t(s.meshIndex));
    d.objFirst = int(ds.lightData.size());
    std::vector<double> areas;
    std::vector<Vec3> kept;  // the triangles written, for findMeshLightEnclosure
    const bool mirrored = mirrorsOrientation(s.transform);  // winding as flattenGeometry's (both faces emit)
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        Vec3 p[3];
        for (int k = 0; k < 3; ++k) p[k] = s.transform.transformPoint(mesh.positions.at(size_t(mesh.indices[t + k])));
        if (mirrored) std::swap(p[1], p[2]);
        if (!isFinite(p[0]) || !isFinite(p[1]) || !isFinite(p[2])) continue;
        Vec3 c = cross(p[1] - p[0], p[2] - p[0]);
        double area = 0.5 * std::sqrt(double(c.x) * c.x + double(c.y) * c.y + double(c.z) * c.z);
        if (!(area > 0) || !std::isfinite(area) || p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) continue;
        for (int k = 0; k < 3; ++k) ds.lightData.push_back(toFloat4(p[k]));
        kept.insert(kept.end(), p, p + 3);
        areas.push_back(area);
    }
    const MeshLightEnclosure enclosure = enclosures.find(shapeIndex, kept);
    d.position = enclosure.enclosed ? toFloat4(enclosure.inside, 1.0f) : dev::float4{0, 0, 0, 0};
    double total = 0;
    for (double a : areas) total += a;
    double run = 0;
    for (size_t k = 0; k < areas.size(); ++k) {
        run += areas[k];
        ds.lightData[size_t(d.objFirst) + 3 * k].w = k + 1 == areas.size() ? 1.0f : float(run / total);
        ds.lightData[size_t(d.objFirst) + 3 * k + 1].w = float(areas[k]);
    }
    d.objCount = int(areas.size());
    d.area = float(total);
    if (areas.empty()) warn(s.source + ": LightMesh has no non-degenerate triangle; it emits nothing");
}

// Largest singular value of the linear part of m (power iteration on MᵀM, double).
double maxStretch(const Mat4& m) {
    double v[3] = {1, 0.7548776662, 0.5698402910}, norm = 0;
    for (int it = 0; it < 200; ++it) {
        double w[3], x[3];
        for (int r = 0; r < 3; ++r) w[r] = m.m[r][0] * v[0] + m.m[r][1] * v[1] + m.m[r][2] * v[2];
        for (int c = 0; c < 3; ++c) x[c] = m.m[0][c] * w[0] + m.m[1][c] * w[1] + m.m[2][c] * w[2];
        norm = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (!(norm > 0)) return 0;
        for (int c = 0; c < 3; ++c) v[c] = x[c] / norm;
    }
    return std::sqrt(norm);
}

// LightSphere: world-space centre and bounding radius in d, |det M| in d.edgeU.x; d.objCount 1 when M is
// no similarity (sampled in object space: object_lights.cl), else 0. lightData: the object-space sphere,
// worldToObject rows, objectToWorld rows (the layout of dev::Sphere's first 7 float4s).
void flattenSphereLight(const Shape& s, dev::Light& d, DeviceScene& ds) {
    Mat4 inv;
    bool ok = s.transform.inverse(inv);
    const Mat4& m = s.transform;
    d.objFirst = int(ds.lightData.size());
    d.position = toFloat4(s.transform.transformPoint(s.center));
    d.objRadius = ok ? float(s.radius * maxStretch(s.transform) * (1 + 1e-6)) : 0.0f;  // never inside the true sphere
    const double det = std::fabs(linearDeterminant(m));
    d.objCount = isSimilarity(m) ? 0 : 1;
    d.edgeU = {float(det), 0, 0, 0};
    ds.lightData.push_back(toFloat4(s.center, s.radius));
    for (int r = 0; r < 3; ++r)
        ds.lightData.push_back({float(inv.m[r][0]), float(inv.m[r][1]), float(inv.m[r][2]), float(inv.m[r][3])});
    for (int r = 0; r < 3; ++r)
        ds.lightData.push_back({float(m.m[r][0]), float(m.m[r][1]), float(m.m[r][2]), float(m.m[r][3])});
    if (!ok || !(d.objRadius > 0) || !(det > 0) || !std::isfinite(det)) {
        d.radiance = {0, 0, 0, 0};  // the sphere itself is skipped by flattenGeometry (warned there)
        d.objRadius = 0;
    }
}

// SceneParams.emitterTest and the box around the object lights' primitives (their lightData: a LightMesh's
// triangles, a LightSphere's world-space bounding sphere), for a path's emission-only segment
// (cl_kernels/path.cl, Path_BoundEmissionOnly): only where every light is a kind listed below (no environment light:
// a miss would bring its light) and with at most CLRT_EMITTER_TEST_MAX primitives.
void setEmitterTest(DeviceScene& ds) {
    int prims = 0;
    dev::float4 lo{INFINITY, INFINITY, INFINITY, 0}, hi{-INFINITY, -INFINITY, -INFINITY, 0};
    auto grow = [&](float x, float y, float z, float r) {
        lo = {std::min(lo.x, x - r), std::min(lo.y, y - r), std::min(lo.z, z - r), 0};
        hi = {std::max(hi.x, x + r), std::max(hi.y, y + r), std::max(hi.z, z + r), 0};
    };
    for (const dev::Light& l : ds.lights) {
        switch (l.kind) {
        case dev::LIGHT_POINT:
        case dev::LIGHT_SPOT:
        case dev::LIGHT_DIRECTIONAL:
        case dev::LIGHT_AREA: break;  // no ray hits them
        case dev::LIGHT_MESH:
            prims += l.objCount;
            for (int i = 0; i < 3 * l.objCount; ++i) {
                const dev::float4& v = ds.lightData[size_t(l.objFirst + i)];
                grow(v.x, v.y, v.z, 0.0f);
            }
            break;
        case dev::LIGHT_SPHERE:
            ++prims;
            grow(l.position.x, l.position.y, l.position.z, l.objRadius);
            break;
        default: return;  // an environment light (a miss brings its light), or a kind Path_EmitterDistance does not test
        }
    }
    if (prims > CLRT_EMITTER_TEST_MAX) return;
    ds.params.emitterTest = 1;
    ds.params.emitterLo = lo;  // inverted (lo > hi) without object lights: the slab test passes, no primitive is hit
    ds.params.emitterHi = hi;
}

}  // namespace

void flattenLights(const Scene& scene, DeviceScene& ds, ImageAtlas& atlas) {
    ds.params.envLight = CLRT_INVALID;
    MeshLightEnclosures enclosures(scene);
    for (const Light& l : scene.lights) {
        dev::Light d{};
        d.envCosine = CLRT_INVALID;
        d.position = toFloat4(l.position);
        d.radiance = toFloat4(l.intensity);
        d.direction = toFloat4(normalize(l.direction));
        d.image = CLRT_INVALID;
        d.distribution = CLRT_INVALID;
        d.kind = l.type;
        ds.features.add(l.type);
        switch (l.type) {
        case dev::LIGHT_POINT:
        case dev::LIGHT_DIRECTIONAL: break;
        case dev::LIGHT_SPOT: {
            float cov = std::clamp(l.coverageAngle, 0.0f, 360.0f), fall = std::clamp(l.falloffAngle, 0.0f, cov);
            d.cosCoverageHalf = std::cos(double(cov) * 0.5 * M_PI / 180.0);
            d.cosFalloffHalf = std::cos(double(fall) * 0.5 * M_PI / 180.0);
            break;
        }
        case dev::LIGHT_AREA: {
            // The square's edges: the course's basis across its normal (courseBasis; docs/scene-format.md), which
            // --sampler correlated pairs with the pixel jitter's (x, y).
            Vec3 n = normalize(l.direction), u, v;
            courseBasis(n, u, v);
            d.edgeU = toFloat4(u * l.size);
            d.edgeV = toFloat4(v * l.size);
            d.area = l.size * l.size;
            break;
        }
        case dev::LIGHT_ENVIRONMENT:
            flattenEnvironmentLight(scene, l, int(ds.lights.size()), d, ds, atlas);
            break;
        case dev::LIGHT_MESH: flattenMeshLight(scene, l.shapeIndex, d, ds, enclosures); break;
        case dev::LIGHT_SPHERE: flattenSphereLight(scene.shapes.at(size_t(l.shapeIndex)), d, ds); break;
        }
        ds.lights.push_back(d);
    }
    if (ds.lights.empty()) ds.lights.push_back(dev::Light{});  // never an empty buffer; numLights stays 0
    if (ds.envDistribution.empty()) ds.envDistribution.push_back(0.0f);
    if (ds.lightData.empty()) ds.lightData.push_back(dev::float4{});
    ds.params.numLights = int(scene.lights.size());  // every light is flattened
    setEmitterTest(ds);
}

}  // namespace clrt
