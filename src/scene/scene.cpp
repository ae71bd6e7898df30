// scene.cpp — small operations on the scene model (scene.h) that are not parsing.
#include "scene/scene.h"

#include "shared/type_tables.h"

namespace clrt {

bool parseEnvStrategy(const std::string& name, dev::EnvStrategy& out) {
    return lookupType(envStrategies(), name, out);
}

void overrideEnvStrategy(Scene& scene, dev::EnvStrategy strategy) {
    for (Light& l : scene.lights)
        if (l.type == dev::LIGHT_ENVIRONMENT) l.envStrategy = strategy;
}

}  // namespace clrt
