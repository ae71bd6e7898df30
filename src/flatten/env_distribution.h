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
    // Within cell (i, j), drawn with probability p: the direction from uniforms du, dv (probe retries
    // derive new ones from the sample's u1, u2), and its pdf; the pdf at (u, v) in cell (i, j).
    bool cellSample(int i, int j, float du, float dv, float p, float u1, float u2, Vec3& dir, float& pdfSolidAngle) const;
    float cellPdf(int i, int j, float p, float u, float v) const;
};

EnvDistribution buildEnvDistribution(const EnvMapView& map);

// Cosine-weighted light sampling, for the mis env strategy (EnvLight_SampleMis, and its one-sample form). The
// map's own distribution ignores the shading normal: on courtyard.exr a third of the luminance lies below
// the horizon, which the light samples of an upward surface waste. Here the light sample at a point with
// normal n comes from the table of n's bucket (a kEnvCosineBuckets² octahedral grid over the sphere of
// normals, y up), in two steps: a cell of a coarse grid (at most kEnvCosineCellsU × kEnvCosineCellsV cells
// of whole texels), with weight = the map distribution's mass in the cell × (the largest cosine between
// the cell's centre and any normal of the bucket + kEnvCosineFloor); then a texel of the cell by its share
// of that mass (one table for all buckets), and the point within the texel as the map's distribution
// places it (EnvDistribution::cellSample). So a small bright source keeps its texel-sharp density, and no
// normal of a bucket finds a light above its horizon weighted by less than its own cosine. A model of the
// 1+1 MIS estimate (experiments/env_cosine_sim.py: 16 normals on each of the 8 maps of ../shared/envmaps) put
// its variance 1.4–3.2× lower than with the map's distribution for the worst normal of each map, 2.3–7.2×
// for the median one; the centre's cosine instead of the largest lost up to 2.9× for some normals (night,
// studio), and coarse cells without the texel step up to 7.7× (6 of the 8 maps). Every texel with solid
// angle keeps a positive probability, so the estimate is unbiased whichever bucket a normal picks; the
// sample's pdf and both MIS weights use the same bucket. Size for a 1024 × 512 map: 144 × 33 KB + 2 MB.
// Table layout (floats, at dev::Light::envCosine): [0] kEnvCosineBuckets, [1] Wc, [2] Hc, [3] S = one
// bucket's size, [4] F = offset of the texel shares, [5..7] 0; bucket b at 8 + b·S: the cells' marginal
// CDF over rows (Hc + 1 values) and conditional CDFs (Hc rows of Wc + 1); at F, W·H floats: the cells in
// row-major order, cell (I, J) at y0·W + x0·(y1 − y0) holding the exclusive cumulative shares of its
// texels in row-major order (x0 = I·W/Wc, y0 = J·H/Hc, floor-divided).
constexpr int kEnvCosineBuckets = 12;
constexpr int kEnvCosineCellsU = 128, kEnvCosineCellsV = 64;
constexpr double kEnvCosineFloor = 0.01;
Vec3 envCosineBucketNormal(int bucket);  // the centre of octahedral cell `bucket`
int envCosineBucket(const Vec3& n);       // the bucket of normal n (mirror of EnvCos_Bucket), -1 for 0/NaN/inf
double envCosineBucketRadius(int bucket); // the largest angle between the bucket's centre and its normals
int envCosineCellOf(int texel, int texels, int cells);  // the cell that holds a texel (mirror of EnvCos_CellOf)

class EnvCosineTable {
  public:
    static constexpr int kHeader = 8;
    explicit EnvCosineTable(const EnvDistribution& own);  // `own`: the map's, outlives this; its masses
    const std::vector<float>& data() const { return data_; }
    // Sample / pdf over solid angle for bucket b (b < 0: the map's own distribution), as the device does.
    bool sample(int b, float u1, float u2, Vec3& dir, float& pdfSolidAngle) const;
    float pdf(int b, const Vec3& dir) const;
    float cellProbability(int b, int I, int J) const;
    float texelProbability(int b, int x, int y) const;  // of texel (x, y) under bucket b (b >= 0)
    int cellsU() const { return Wc_; }
    int cellsV() const { return Hc_; }

  private:
    const EnvDistribution* own_;
    int Wc_ = 0, Hc_ = 0, stride_ = 0, fine_ = 0;
    std::vector<float> data_;
};

// The counter hash of cl_kernels/common.cl (Rng_Hash), for the host mirrors of device sampling.
inline uint32_t envHash(uint32_t v) {
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
// The k-th pair of extra uniforms derived from (u1, u2) (rejection retries), as envmap.cl does.
void envRetryUniforms(float u1, float u2, uint32_t k, float& a, float& b);

}  // namespace clrt
