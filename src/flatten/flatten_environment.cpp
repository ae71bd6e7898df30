// flatten_environment.cpp — environment (SphericalDirectionalLight) lights: the map in the texel
// atlas, mapping and env strategy, the importance distribution (env_distribution.h), and the first
// environment light's fields in SceneParams (rays that miss sum every environment light's map from
// there, shade.cl Shade_Miss); see flatten.h.
#include "flatten/env_distribution.h"
#include "flatten/flatten.h"
#include "util/error.h"

namespace clrt {

bool isEnvironmentTurned(const Light& l) {
    if (l.type != dev::LIGHT_ENVIRONMENT) return false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (l.envToWorld.m[i][j] != (i == j ? 1.0 : 0.0)) return true;
    return false;
}

void flattenEnvironmentLight(const Scene& scene, const Light& l, int lightIndex, dev::Light& d, DeviceScene& ds,
                             ImageAtlas& atlas) {
    d.radiance = {1, 1, 1, 0};
    // The rows of the world -> map rotation (the transpose of envToWorld): lights.cl, EnvLight_ToMap.
    const Mat4& r = l.envToWorld;
    d.direction = {float(r.m[0][0]), float(r.m[1][0]), float(r.m[2][0]), 0};
    d.edgeU = {float(r.m[0][1]), float(r.m[1][1]), float(r.m[2][1]), 0};
    d.edgeV = {float(r.m[0][2]), float(r.m[1][2]), float(r.m[2][2]), 0};
    const int full = atlas.use(l.imageIndex);  // float4: what the distribution is built from
    d.image = atlas.useEnvironment(l.imageIndex);  // what the device reads (half4 where exact)
    d.mapping = l.mapping;
    d.envStrategy = l.envStrategy;
    const dev::ImageInfo& info = ds.images[size_t(full)];
    EnvMapView view{&ds.texels[info.offset], info.width, info.height, d.mapping};
    auto te = std::chrono::steady_clock::now();
    EnvDistribution dist = buildEnvDistribution(view);
    d.distribution = int(ds.envDistribution.size());
    ds.envDistribution.insert(ds.envDistribution.end(), dist.data.begin(), dist.data.end());
    if (d.envStrategy == dev::ENV_STRATEGY_MIS) {  // light samples drawn by the shading normal's bucket
        const EnvCosineTable table(dist);
        d.envCosine = int(ds.envDistribution.size());
        ds.envDistribution.insert(ds.envDistribution.end(), table.data().begin(), table.data().end());
    }
    ds.envDistSeconds += secondsSince(te);
    if (ds.params.envLight == CLRT_INVALID) {
        ds.params.envLight = lightIndex;
        ds.params.envScale = d.radiance;
        ds.params.envImage = d.image;
        ds.params.envMapping = d.mapping;
    }
}

}  // namespace clrt
