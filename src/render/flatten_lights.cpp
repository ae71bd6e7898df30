// flatten_lights.cpp — scene lights -> dev::Light, one case per light type (environment lights:
// flatten_environment.cpp); see flatten.h.
#include <algorithm>
#include <cmath>

#include "render/flatten.h"

namespace clrt {

void flattenLights(const Scene& scene, DeviceScene& ds, ImageAtlas& atlas) {
    ds.params.envLight = CLRT_INVALID;
    for (const Light& l : scene.lights) {
        dev::Light d{};
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
            Vec3 n = normalize(l.direction);
            Vec3 helper = std::fabs(n.x) > 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
            Vec3 u = normalize(cross(helper, n)), v = cross(n, u);
            d.edgeU = toFloat4(u * l.size);
            d.edgeV = toFloat4(v * l.size);
            d.area = l.size * l.size;
            break;
        }
        case dev::LIGHT_ENVIRONMENT:
            flattenEnvironmentLight(scene, l, int(ds.lights.size()), d, ds, atlas);
            break;
        }
        ds.lights.push_back(d);
    }
    if (ds.lights.empty()) ds.lights.push_back(dev::Light{});  // never an empty buffer; numLights stays 0
    if (ds.envDistribution.empty()) ds.envDistribution.push_back(0.0f);
    ds.params.numLights = int(scene.lights.size());  // every light is flattened
}

}  // namespace clrt
