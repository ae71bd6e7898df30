// Lights: <Lights> and its children, in document order. Reads AmbientLight (the scene's ambient
// radiance) and the light types named by the rows of CLRT_LIGHT_TABLE (shared/type_tables.h
// lightTypes()), each with an optional id:
//   PointLight (Position Intensity), AreaLight (Position Normal Size Radiance), DirectionalLight
//   (Direction Radiance), SpotLight (Position Direction Intensity CoverageAngle FalloffAngle),
//   SphericalDirectionalLight (ImageId, type/Type latlong|probe, sampler/Sampler: the env strategy).
// Each may carry <Transformations> (2025 scenes; transformLight).
// LightMesh and LightSphere are shapes as well as lights: read in <Objects> (read_objects.cpp); here
// they are an error.
#include <cmath>
#include <optional>

#include "scene/scene_walker.h"
#include "scene/transforms.h"
#include "shared/type_tables.h"
#include "util/error.h"

namespace clrt::walker {
namespace {

// A direction child (Normal, Direction), normalised; zero is an error.
Vec3 direction(const SceneNode& l, const char* child) {
    auto dn = need(l, child);
    Vec3 d = unit(vec3(*dn));
    if (length(d) == 0) fail(*dn, describe(l) + ": " + child + " is zero");
    return d;
}

void readPointLight(Walker& w, const SceneNode& l, Light& light) {
    w.checkChildren(l, {"Position", "Intensity", "Transformations"});
    light.position = vec3(*need(l, "Position"));
    light.intensity = vec3(*need(l, "Intensity"));
}

void readAreaLight(Walker& w, const SceneNode& l, Light& light) {
    w.checkChildren(l, {"Position", "Normal", "Size", "Radiance", "Transformations"});
    light.position = vec3(*need(l, "Position"));
    light.direction = direction(l, "Normal");
    auto sn = need(l, "Size");
    light.size = number(*sn);
    if (!(light.size > 0)) fail(*sn, describe(l) + ": Size must be positive");
    if (!std::isfinite(light.size * light.size)) fail(*sn, describe(l) + ": Size² overflows a 32-bit float");
    light.intensity = vec3(*need(l, "Radiance"));
}

void readDirectionalLight(Walker& w, const SceneNode& l, Light& light) {
    w.checkChildren(l, {"Direction", "Radiance", "Transformations"});
    light.direction = direction(l, "Direction");
    light.intensity = vec3(*need(l, "Radiance"));
}

void readSpotLight(Walker& w, const SceneNode& l, Light& light) {
    w.checkChildren(l, {"Position", "Direction", "Intensity", "CoverageAngle", "FalloffAngle", "FallOffAngle",
                        "Transformations"});
    light.position = vec3(*need(l, "Position"));
    light.direction = direction(l, "Direction");
    light.intensity = vec3(*need(l, "Intensity"));
    light.coverageAngle = number(*need(l, "CoverageAngle"));
    auto fo = l.child("FalloffAngle");
    if (!fo) fo = l.child("FallOffAngle");
    if (!fo) fail(l, describe(l) + " has no <FalloffAngle>");
    light.falloffAngle = number(*fo);
    if (!(light.coverageAngle > 0) || light.falloffAngle < 0 || light.falloffAngle > light.coverageAngle)
        fail(l, describe(l) + ": need 0 <= FalloffAngle <= CoverageAngle and CoverageAngle > 0");
}

// An attribute, or else the text of a child element (both spellings occur in the course's files).
std::optional<std::string> attributeOrChild(const SceneNode& l, const char* attr, const char* child) {
    std::optional<std::string> v = l.attribute(attr);
    if (!v)
        if (auto c = l.child(child)) v = c->text();
    return v;
}

void readEnvironmentLight(Walker& w, const SceneNode& l, Light& light) {
    w.checkChildren(l, {"ImageId", "Type", "Sampler", "Transformations"});
    light.imageIndex = imageRef(w, l, *need(l, "ImageId"));
    std::optional<std::string> type = attributeOrChild(l, "type", "Type");
    if (type && !lookupType(envMappings(), lower(trim(*type)), light.mapping))
        fail(l, describe(l) + ": unknown type '" + *type + "' (latlong or probe)");
    std::optional<std::string> sampler = attributeOrChild(l, "sampler", "Sampler");
    if (sampler && !lookupType(envStrategies(), lower(trim(*sampler)), light.envStrategy))
        fail(l, describe(l) + ": unknown sampler '" + *sampler + "' (" + typeNames(envStrategies()) + ")");
}

// An environment light's Transformations turn its map: the rotation R (M's linear part over its uniform
// scale; translations and uniform scalings mean nothing at infinity), so that the map's direction d
// shows in world direction R·d. Anything else (a non-uniform scaling, a shear) would distort the map
// and its sampling densities: an error. Mirrors (det < 0) keep solid angles and are allowed.
Mat4 environmentRotation(const SceneNode& t, const SceneNode& l, const Mat4& m, double det) {
    if (!isSimilarity(m, 1e-5 / 3))  // MᵀM/s² within 1e-5 of I (a rotation written to 5-6 digits passes)
        fail(t, describe(l) + ": its Transformations must be rotations (with translations and uniform "
                "scalings, which an environment ignores): a non-uniform scaling or shear would distort its map");
    const double s = std::cbrt(std::fabs(det));
    Mat4 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r.m[i][j] = m.m[i][j] / s;
    return r;
}

// <Transformations> inside a light (2025): the light moved as an object. Positions by the full matrix;
// directions (Directional, Spot) by the linear part; an area light's normal by the inverse transpose
// and its side by the square root of the area scale |det|·|M⁻ᵀn| (the transformed square's area; it
// stays a square in clrt's own orientation about its normal); an environment map turned by the rotation
// (environmentRotation).
void transformLight(const Walker& w, const SceneNode& l, Light& light) {
    auto t = l.child("Transformations");
    if (!t) return;
    Mat4 m = transformOf(w, l);
    double det = linearDeterminant(m);
    if (!(std::fabs(det) > 0) || !std::isfinite(det)) fail(*t, describe(l) + ": its Transformations are singular");
    if (light.type == dev::LIGHT_ENVIRONMENT) {
        light.envToWorld = environmentRotation(*t, l, m, det);
        return;
    }
    light.position = m.transformPoint(light.position);
    if (light.type == dev::LIGHT_AREA) {
        Vec3 n = m.transformNormal(light.direction);  // light.direction is unit
        double areaScale = std::fabs(det) * double(length(n));
        light.size = float(double(light.size) * std::sqrt(areaScale));
        light.direction = unit(n);
    } else if (light.type == dev::LIGHT_DIRECTIONAL || light.type == dev::LIGHT_SPOT) {
        light.direction = unit(m.transformVector(light.direction));
    }
    if (!isFinite(light.position) || !isFinite(light.direction) || !std::isfinite(light.size * light.size) ||
        !(light.size > 0))
        fail(*t, describe(l) + ": the transformed light overflows a 32-bit float");
}

// LightMesh, LightSphere: shapes as well as lights, read by read_objects.cpp.
void refuseObjectLight(Walker&, const SceneNode& l, Light&) {
    fail(l, "<" + l.name() + "> is an object: it belongs in <Objects>, not in <Lights>");
}

// The reader of each light type (a row of CLRT_LIGHT_TABLE, which names its element).
struct LightReader {
    dev::LightKind kind;
    void (*read)(Walker& w, const SceneNode& l, Light& light);
};
const LightReader kLightReaders[] = {
    {dev::LIGHT_POINT, readPointLight},
    {dev::LIGHT_AREA, readAreaLight},
    {dev::LIGHT_DIRECTIONAL, readDirectionalLight},
    {dev::LIGHT_SPOT, readSpotLight},
    {dev::LIGHT_ENVIRONMENT, readEnvironmentLight},
    {dev::LIGHT_MESH, refuseObjectLight},
    {dev::LIGHT_SPHERE, refuseObjectLight},
};

void readLight(Walker& w, const SceneNode& l, Light& light) {
    for (const LightReader& r : kLightReaders)
        if (r.kind == light.type) return r.read(w, l, light);
    throw Error(std::string("internal: no reader for light type ") + typeRow(lightTypes(), light.type).name);
}

}  // namespace

void readLights(Walker& w, const SceneNode& n) {
    std::vector<std::string> known = {"AmbientLight"};
    for (const auto& row : lightTypes()) known.push_back(row.name);
    w.checkChildren(n, known);
    for (auto& c : n.children()) {
        std::string name = c->name();
        const SceneNode& l = *c;
        Light light;
        light.id = intAttribute(l, "id", 0);  // checked on every child, AmbientLight included
        if (name == "AmbientLight") {
            w.scene.ambientLight = vec3(l);
            continue;
        }
        const TypeRow<dev::LightKind>* row = findType(lightTypes(), name);
        if (!row) continue;
        light.type = row->kind;
        readLight(w, l, light);
        transformLight(w, l, light);
        w.scene.lights.push_back(light);
    }
}

}  // namespace clrt::walker
