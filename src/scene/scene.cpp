// scene.cpp — small operations on the scene model (scene.h) that are not parsing.
#include "scene/scene.h"

#include "shared/type_tables.h"

namespace clrt {

bool parseEnvSampler(const std::string& name, dev::EnvSamplerKind& out) {
    return lookupType(envSamplers(), name, out);
}

void overrideEnvSampling(Scene& scene, dev::EnvSamplerKind sampler) {
    for (Light& l : scene.lights)
        if (l.type == dev::LIGHT_ENVIRONMENT) l.sampler = sampler;
}

}  // namespace clrt
