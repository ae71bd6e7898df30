// flatten_materials.cpp — scene materials -> dev::Material (see flatten.h), with the parameters of
// the BRDF each names (Scene::brdfs, from <BRDFs>) copied in.
#include "flatten/flatten.h"

namespace clrt {

// The BRDF a material names (Material BRDF="id"): its kind, exponent and flags, copied into the
// material; CLRT_INVALID keeps the classic Blinn-Phong shading.
static void flattenBrdf(const Scene& scene, const Material& m, dev::Material& d, FeatureSet& features) {
    d.brdf = CLRT_INVALID;
    if (m.brdf < 0) return;
    const Brdf& b = scene.brdfs.at(size_t(m.brdf));
    d.brdf = b.type;
    d.brdfExponent = b.exponent;
    d.brdfFlags = (b.normalized ? CLRT_BRDF_NORMALIZED : 0) | (b.kdFresnel ? CLRT_BRDF_KD_FRESNEL : 0);
    features.add(b.type);
}

// Whether d's non-specular f is direction-free (CLRT_BRDF_LAMBERTIAN): ks = 0, and no BRDF or one of those
// whose value at ks = 0 is kd or kd/π. A new BRDF joins the list only when it is one of them.
static bool materialIsLambertian(const dev::Material& d) {
    const bool knownBrdf = d.brdf == CLRT_INVALID || d.brdf == dev::BRDF_ORIGINAL_PHONG ||
                           d.brdf == dev::BRDF_ORIGINAL_BLINN_PHONG || d.brdf == dev::BRDF_MODIFIED_PHONG ||
                           d.brdf == dev::BRDF_MODIFIED_BLINN_PHONG ||
                           (d.brdf == dev::BRDF_TORRANCE_SPARROW && !(d.brdfFlags & CLRT_BRDF_KD_FRESNEL));
    return d.specular.x == 0.0f && d.specular.y == 0.0f && d.specular.z == 0.0f && knownBrdf;
}

void flattenMaterials(const Scene& scene, DeviceScene& ds) {
    for (const Material& m : scene.materials) {
        dev::Material d{};
        d.ambient = toFloat4(m.ambient);
        d.diffuse = toFloat4(m.diffuse);
        d.specular = toFloat4(m.specular);
        d.mirror = toFloat4(m.mirror);
        d.absorption = toFloat4(m.absorptionCoefficient);
        d.phongExponent = m.phongExponent;
        d.refractionIndex = m.refractionIndex;
        d.absorptionIndex = m.absorptionIndex;
        d.roughness = m.roughness;
        d.kind = m.type;
        flattenBrdf(scene, m, d, ds.features);
        if (materialIsLambertian(d)) d.brdfFlags |= CLRT_BRDF_LAMBERTIAN;
        ds.materials.push_back(d);
        ds.features.add(m.type);
    }
    if (ds.materials.empty()) {
        dev::Material d{};
        d.brdf = CLRT_INVALID;
        ds.materials.push_back(d);
    }
}

}  // namespace clrt
