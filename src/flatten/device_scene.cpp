// The device scene's own functions (see device_scene.h): the feature set's -D flags and the camera
// parameters. The flattening itself is flatten_scene.cpp (the driver) and flatten_*.cpp (its parts).
#include "flatten/device_scene.h"

#include <algorithm>

#include "shared/type_tables.h"

namespace clrt {

bool FeatureSet::bounces() const {
    for (const auto& row : materialTypes())
        if (row.bounces && has(row.kind)) return true;
    return false;
}

std::vector<std::string> FeatureSet::defines() const {
    std::vector<std::string> d;
    auto add = [&](bool on, const char* name) {
        if (on && *name) d.push_back(std::string("-D") + name + "=1");
    };
    for (const auto& row : lightTypes()) add(has(row.kind), row.flag);
    for (const auto& row : materialTypes()) add(has(row.kind), row.flag);
    for (const auto& row : brdfTypes()) add(has(row.kind), row.flag);
    add(brdfKinds != 0, "CLRT_HAS_BRDFS");  // Material_EvalDirect reads the material's BRDF
    add(textures, "CLRT_HAS_TEXTURES");
    add(normalMaps, "CLRT_HAS_NORMAL_MAP");
    add(bumpMaps, "CLRT_HAS_BUMP_MAP");
    add(mipMaps, "CLRT_HAS_MIPMAPS");
    add(spheres, "CLRT_HAS_SPHERES");
    add(motionBlur, "CLRT_HAS_MOTION_BLUR");
    add(instances, "CLRT_HAS_INSTANCES");
    add(pathTracing, "CLRT_HAS_PATH_TRACING");
    add(zsobol, "CLRT_HAS_ZSOBOL");
    add(correlatedSampler, "CLRT_HAS_CORRELATED_SAMPLER");
    add(meshLightsByArea, "CLRT_MESHLIGHT_BY_AREA");
    add(envRotation, "CLRT_HAS_ENV_ROTATION");
    add(backfaceCulling, "CLRT_HAS_BACKFACE_CULLING");
    add(lanes, "CLRT_HAS_LANES");
    // Rounded up to a multiple of 8 so that scenes of similar depth share a cached program.
    if (bvhStack > 0) d.push_back("-DCLRT_BVH8_STACK_SIZE=" + std::to_string((bvhStack + 7) / 8 * 8));
    return d;
}

std::string lanesFamily(const DeviceScene& ds) {
    const FeatureSet& f = ds.features;
    // A classic camera gains from the lanes only through an environment light's multi-sample MIS in steps
    // (Lanes_EnvMisShadows, at the camera rays' hits; their children go as in render_fused: Lanes_Direct).
    if (!f.pathTracing && !f.has(dev::LIGHT_ENVIRONMENT)) return "no path-traced camera, no environment light";
    if (f.mipMaps) return "mip-mapped textures";
    if (f.motionBlur) return "motion blur";
    return "";
}

// Whether some primitive of ds (triangle, sphere, plane, instance; not the arrays' dummy entries) has a
// (material, texture set) for which pred holds.
template <typename Pred>
static bool someSurface(const DeviceScene& ds, Pred pred) {
    for (int i = 0; i < ds.params.numTriangles; ++i)  // not the arrays' dummy entries (flattenGeometry)
        if (pred(ds.triangleShading[size_t(i)].material, ds.triangleShading[size_t(i)].textureSet)) return true;
    for (int i = 0; i < ds.params.numSpheres; ++i)
        if (pred(ds.spheres[size_t(i)].material, ds.spheres[size_t(i)].textureSet)) return true;
    for (const dev::Plane& pl : ds.planes)  // the dummy plane has a zero normal and is never hit
        if ((pl.normal.x != 0.0f || pl.normal.y != 0.0f || pl.normal.z != 0.0f) && pred(pl.material, pl.textureSet))
            return true;
    for (const dev::Instance& in : ds.instances)
        if (pred(in.material, in.textureSet)) return true;
    return false;
}

std::string lanesNoGain(const DeviceScene& ds, bool classic, bool envMis) {
    if (classic) return envMis ? "" : "classic camera without an environment light sampled by MIS (the rest is per lane: no faster than render_fused)";
    if (envMis) return "";  // its MIS pair in steps across the lanes (Lanes_EnvMisShadows)
    // A surface the lanes shade in lanes: untextured, with a diffuse or glossy part (kd or ks > 0; its f
    // direction-free, CLRT_BRDF_LAMBERTIAN, or any BRDF and the classic lobe: cl_kernels/lanes_brdf.cl). A
    // light's black surface and a purely specular one have nothing to shade there.
    auto inLanes = [&](int material, int textureSet) {
        if (textureSet != CLRT_INVALID || material < 0 || size_t(material) >= ds.materials.size()) return false;
        const dev::Material& m = ds.materials[size_t(material)];
        return m.diffuse.x > 0.0f || m.diffuse.y > 0.0f || m.diffuse.z > 0.0f || m.specular.x > 0.0f ||
               m.specular.y > 0.0f || m.specular.z > 0.0f;
    };
    if (someSurface(ds, inLanes)) return "";
    return "no untextured surface with a diffuse or glossy part (the rest is shaded per lane: no faster than render_fused)";
}

float pathAlbedoBound(const dev::Material& m) {
    // The BRDFs whose diffuse term is kd/π: normalized Modified(Blinn)Phong and TorranceSparrow
    // (docs/scene-format.md, conventions); the classic model and the others take kd (f·cosθ = kd·cosθ).
    const bool overPi = ((m.brdf == dev::BRDF_MODIFIED_PHONG || m.brdf == dev::BRDF_MODIFIED_BLINN_PHONG) &&
                         (m.brdfFlags & CLRT_BRDF_NORMALIZED)) ||
                        m.brdf == dev::BRDF_TORRANCE_SPARROW;
    const float kd = std::max(m.diffuse.x, std::max(m.diffuse.y, m.diffuse.z));
    const float mirror = std::max(m.mirror.x, std::max(m.mirror.y, m.mirror.z));
    float specular = 0.0f;  // the specular child's weight (a conductor's Fresnel factor is at most 1)
    if (m.kind == dev::MATERIAL_MIRROR || m.kind == dev::MATERIAL_CONDUCTOR) specular = mirror;
    if (m.kind == dev::MATERIAL_DIELECTRIC) specular = 1.0f;  // reflection or refraction by Fresnel weight
    return (overPi ? kd : kd * 3.14159265f) + specular;
}

int energyGainingMaterial(const DeviceScene& ds) {
    int worst = -1;
    someSurface(ds, [&](int material, int) {
        if (material < 0 || size_t(material) >= ds.materials.size()) return false;
        const float a = pathAlbedoBound(ds.materials[size_t(material)]);
        if (a > 1.0f && (worst < 0 || a > pathAlbedoBound(ds.materials[size_t(worst)]))) worst = material;
        return false;  // visit every surface
    });
    return worst;
}

dev::CameraParams makeCameraParams(const Camera& cam) {
    dev::CameraParams c{};
    c.position = toFloat4(cam.position);
    c.u = toFloat4(cam.u);
    c.v = toFloat4(cam.v);
    c.w = toFloat4(cam.w);
    c.nearPlane = {cam.left, cam.right, cam.bottom, cam.top};
    c.nearDistance = cam.nearDistance;
    c.focusDistance = cam.focusDistance;
    c.apertureSize = cam.apertureSize;
    c.nearMode = cam.nearMode;
    c.width = cam.width;
    c.height = cam.height;
    setSamplesPerPixel(c, cam.numSamples);
    return c;
}

void setSamplesPerPixel(dev::CameraParams& c, int spp) {
    c.spp = std::max(1, spp);
}

}  // namespace clrt
