// Materials and the reflection models they name. Reads:
//   BRDFs (course hw6): one element per BRDF, named by the rows of CLRT_BRDF_TABLE (OriginalPhong
//     OriginalBlinnPhong ModifiedPhong ModifiedBlinnPhong TorranceSparrow), each with an id, <Exponent>
//     and the attributes normalized, kdfresnel.
//   Materials/Material (attributes id, type, degamma, BRDF): AmbientReflectance DiffuseReflectance
//     SpecularReflectance MirrorReflectance PhongExponent RefractionIndex AbsorptionIndex Roughness
//     AbsorptionCoefficient Transparency (the older course format's dielectric: see readTransparency).
// Degamma'd colours are checked to stay finite.
#include <cmath>
#include <limits>

#include "scene/scene_walker.h"
#include "shared/type_tables.h"

namespace clrt::walker {
namespace {

void readBrdf(Walker& w, const SceneNode& n) {
    Brdf b;
    if (!lookupType(brdfTypes(), n.name(), b.type))
        fail(n, "unknown BRDF <" + n.name() + "> in <BRDFs> (expected " + typeNames(brdfTypes()) + ")");
    w.checkChildren(n, {"Exponent"});
    b.id = requiredId(n);
    if (auto c = n.child("Exponent")) {
        b.exponent = number(*c);
        if (!(b.exponent >= 0)) fail(*c, describe(n) + ": <Exponent> must not be negative");
    }
    if (auto a = n.attribute("normalized")) b.normalized = boolean(n, *a, describe(n) + ": normalized");
    if (auto a = n.attribute("kdfresnel")) b.kdFresnel = boolean(n, *a, describe(n) + ": kdfresnel");
    if (!w.brdfIds.emplace(b.id, int(w.scene.brdfs.size())).second)
        fail(n, "duplicate BRDF id " + std::to_string(b.id));
    w.scene.brdfs.push_back(b);
}

// The type attribute: a row of CLRT_MATERIAL_TABLE; none or "phong" is Blinn-Phong.
dev::MaterialKind materialType(const SceneNode& n) {
    dev::MaterialKind kind = dev::MATERIAL_BLINN_PHONG;
    std::string type = lower(trim(n.attribute("type").value_or("")));
    if (type.empty() || type == "phong") type = typeRow(materialTypes(), dev::MATERIAL_BLINN_PHONG).name;
    if (!lookupType(materialTypes(), type, kind))
        fail(n, describe(n) + ": unknown material type '" + *n.attribute("type") + "'");
    return kind;
}

// The four reflectance colours, raised to 2.2 with degamma="true".
void readReflectances(const SceneNode& n, bool degamma, Material& m) {
    auto colour = [&](const char* name, Vec3& out) {
        if (auto c = n.child(name)) {
            out = vec3(*c);
            if (degamma)
                out = Vec3(std::pow(out.x, 2.2f), std::pow(out.y, 2.2f), std::pow(out.z, 2.2f));
            if (!isFinite(out))  // pow of a negative value, or beyond float range
                fail(*c, describe(n) + ": <" + name + "> is not finite after degamma (negative, or overflows a 32-bit float)");
        }
    };
    colour("AmbientReflectance", m.ambient);
    colour("DiffuseReflectance", m.diffuse);
    colour("SpecularReflectance", m.specular);
    colour("MirrorReflectance", m.mirror);
}

void readMaterialScalars(const SceneNode& n, Material& m) {
    if (auto c = n.child("PhongExponent")) m.phongExponent = number(*c);
    if (auto c = n.child("RefractionIndex")) m.refractionIndex = number(*c);
    if (auto c = n.child("AbsorptionIndex")) m.absorptionIndex = number(*c);
    if (auto c = n.child("Roughness")) m.roughness = number(*c);
    if (auto c = n.child("AbsorptionCoefficient")) {
        auto v = numbers(*c);
        if (v.size() == 1) m.absorptionCoefficient = Vec3(float(v[0]));
        else if (v.size() == 3) m.absorptionCoefficient = Vec3(float(v[0]), float(v[1]), float(v[2]));
        else fail(*c, "<AbsorptionCoefficient> has " + std::to_string(v.size()) + " values, expected 1 or 3");
    }
}

// <Transparency>T</Transparency> with <RefractionIndex>: the course's older material format (kept in
// hw6's cornellbox_jaroslav_path_diffuse.xml; the students' parsers of that format make a material
// refractive when T is non-zero, split reflection and refraction by Fresnel, and weight light that
// crossed the inside by T^d, d the distance travelled: T is the fraction kept per unit distance).
// That is this renderer's dielectric with Beer's coefficient -ln T, added to any
// <AbsorptionCoefficient>; a channel with T = 0 keeps nothing. T = 0 0 0 leaves the material opaque.
void readTransparency(const SceneNode& n, const SceneNode& c, Material& m) {
    auto v = numbers(c);
    if (v.size() != 1 && v.size() != 3)
        fail(c, describe(n) + ": <Transparency> has " + std::to_string(v.size()) + " values, expected 1 or 3");
    if (v.size() == 1) v.assign(3, v[0]);
    for (double t : v)
        if (!(t >= 0.0 && t <= 1.0))
            fail(c, describe(n) + ": <Transparency> " + trim(c.text()) +
                        ": each value is the fraction of light kept per unit distance, in [0, 1]");
    if (v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0) return;
    if (auto type = n.attribute("type"); type && m.type != dev::MATERIAL_DIELECTRIC)
        fail(c, describe(n) + ": <Transparency> makes a dielectric, but the material has type=\"" + *type + "\"");
    m.type = dev::MATERIAL_DIELECTRIC;
    float* a[3] = {&m.absorptionCoefficient.x, &m.absorptionCoefficient.y, &m.absorptionCoefficient.z};
    for (int k = 0; k < 3; ++k)
        *a[k] = v[k] > 0.0 ? *a[k] - float(std::log(v[k])) : std::numeric_limits<float>::max();
}

void readMaterial(Walker& w, const SceneNode& n) {
    w.checkChildren(n, {"AmbientReflectance", "DiffuseReflectance", "SpecularReflectance", "MirrorReflectance",
                        "PhongExponent", "RefractionIndex", "AbsorptionCoefficient", "AbsorptionIndex",
                        "Roughness", "Transparency"});
    Material m;
    m.id = requiredId(n);
    m.type = materialType(n);
    bool degamma = false;
    if (auto d = n.attribute("degamma")) degamma = boolean(n, *d, describe(n) + ": degamma");
    readReflectances(n, degamma, m);
    readMaterialScalars(n, m);
    if (auto c = n.child("Transparency")) readTransparency(n, *c, m);
    if (n.attribute("BRDF")) {
        int id = intAttribute(n, "BRDF", 0);
        auto it = w.brdfIds.find(id);
        if (it == w.brdfIds.end()) fail(n, describe(n) + ": BRDF " + std::to_string(id) + " is not defined in <BRDFs>");
        m.brdf = it->second;
    }
    if (!w.materialIds.emplace(m.id, int(w.scene.materials.size())).second)
        fail(n, "duplicate Material id " + std::to_string(m.id));
    w.scene.materials.push_back(m);
}

}  // namespace

void readBrdfs(Walker& w, const SceneNode& n) {
    for (auto& c : n.children()) readBrdf(w, *c);
}

void readMaterials(Walker& w, const SceneNode& n) {
    w.readInTableOrder(n, {{"Material", readMaterial}});
}

}  // namespace clrt::walker
