// Environment maps on the host: the direction <-> (u, v) mappings of SCENE_FORMAT.md (lat-long and
// probe), their Jacobians, the bilinear radiance lookup, and the piecewise-constant 2D importance
// distribution over the map's cells (texel luminance integrated over the bilinear reconstruction,
// times the cell's solid angle), built once and flattened into the float layout that
// cl_kernels/envmap.cl reads. The host sampling/pdf functions here mirror the device ones
// float-for-float; they are the reference the tests compare the kernels with.
#pragma once
#include <cstdint>
#include <vector>

#include "shared/device_types.h"
#include "util/math.h"

namespace clrt {

// A view of one image in the texel atlas (float4 texels, row-major, row 0 at the top).
struct EnvMapView {
    const dev::float4* texels = nullptr;
    int width = 0, height = 0;
    int mapping = dev::ENV_LATLONG;  // EnvMappingKind
};

// Direction (unit, y up) -> (u, v) in [0,1]^2.
void envDirToUv(int mapping, const Vec3& d, float& u, float& v);
// (u, v) -> unit direction; false when (u, v) carries no light (probe: outside the disc).
bool envUvToDir(int mapping, float u, float v, Vec3& d);
// pdf over solid angle = pdf over (u, v) * envUvToSolidAngle(mapping, u, v); 0 where degenerate.
float envUvToSolidAngle(int mapping, float u, float v);
// Bilinear lookup with texel centres at ((i + 0.5)/W, (j + 0.5)/H); lat-long wraps in u; rows (and
// probe columns) clamp.
Vec3 envLookup(const EnvMapView& map, float u, float v);

// Float layout (also the device's; `distribution` in dev::Light is the offset of its first float):
//   [0] W, [1] H, [2] mapping, [3] 0,
//   [4, 4+H]                    marginal CDF over rows (H+1 values, 0 ... 1),
//   then H rows of W+1 values   conditional CDF over the cells of each row (0 ... 1),
//   then W*H values             fraction of each cell inside the map's domain (1 for lat-long),
//   then H+1 values             cos θ at the row boundaries (lat-long: 1 ... -1).
// The probability of a cell is computed from the float CDF differences, so evaluation matches
// sampling exactly; every cell the radiance can be non-zero in has a positive probability. Within a
// cell, lat-long samples are uniform in solid angle (cos θ uniform between the row's bounds: no
// 1/sin θ pole singularity, pdf = P_cell / Ω_cell); probe samples are uniform in (u, v) over the
// part of the cell inside the disc (rejection), pdf = P_cell·W·H/frac · |d(u,v)/dω|.
struct EnvDistribution {
    int width = 0, height = 0, mapping = dev::ENV_LATLONG;
    std::vector<float> data;

    static constexpr int kMaxRejections = 32;  // probe: tries to land inside the disc in a rim cell

    bool probe() const { return mapping == dev::ENV_PROBE; }
    // Importance sample from two uniforms in [0,1); false when no direction was produced.
    bool sample(float u1, float u2, Vec3& dir, float& pdfSolidAngle) const;
    // pdf over solid angle of `dir` (unit).
    float pdf(const Vec3& dir) const;
};

EnvDistribution buildEnvDistribution(const EnvMapView& map);

// The counter hash of cl_kernels/common.cl (Rng_Hash), for the host mirrors of device sampling.
inline uint32_t envHash(uint32_t v) {
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
// The k-th pair of extra uniforms derived from (u1, u2) (rejection retries), as envmap.cl does.
void envRetryUniforms(float u1, float u2, uint32_t k, float& a, float& b);

}  // namespace clrt
