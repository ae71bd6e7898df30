// flatten_materials.cpp — scene materials -> dev::Material (see flatten.h).
#include "render/flatten.h"

namespace clrt {

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
        ds.materials.push_back(d);
        ds.features.add(m.type);
    }
    if (ds.materials.empty()) ds.materials.push_back(dev::Material{});
}

}  // namespace clrt
