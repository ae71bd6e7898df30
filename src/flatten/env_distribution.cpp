// Environment-map mappings, lookup and the importance distribution (see env_distribution.h). Every
// function that has a device twin in cl_kernels/envmap.cl uses the same float operations in the same
// order, so host and device agree to a few ulps.
#include "flatten/env_distribution.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace clrt {
namespace {

constexpr float kPi = 3.14159265358979323846f;

float lumOf(const dev::float4& t) {
    float l = 0.2126f * t.x + 0.7152f * t.y + 0.0722f * t.z;
    return std::isfinite(l) && l > 0 ? l : 0.0f;
}

uint32_t floatBits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return b;
}

// Largest k in [0, n-1] with cdf[k] <= x, for cdf[0] = 0 <= x < cdf[n] = 1.
int findInterval(const float* cdf, int n, float x) {
    int lo = 0, hi = n;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (cdf[mid] <= x) lo = mid;
        else hi = mid;
    }
    return lo;
}

constexpr float kOneMinus = 0.99999994f;  // largest float below 1

}  // namespace

void envRetryUniforms(float u1, float u2, uint32_t k, float& a, float& b) {
    uint32_t h1 = envHash(floatBits(u1) ^ envHash(floatBits(u2) + 0x632be5abu * (k + 1u)));
    uint32_t h2 = envHash(h1 ^ 0x9e3779b9u);
    a = float(h1 >> 8) * (1.0f / 16777216.0f);
    b = float(h2 >> 8) * (1.0f / 16777216.0f);
}

void envDirToUv(int mapping, const Vec3& d, float& u, float& v) {
    if (mapping == dev::ENV_PROBE) {
        // θ = acos(-dz), by atan2: accurate near the centre and the rim, where acos is not.
        float s = std::sqrt(d.x * d.x + d.y * d.y);
        float r = std::atan2(s, -d.z) / kPi;
        float x = s > 0.0f ? r * d.x / s : r, y = s > 0.0f ? r * d.y / s : 0.0f;
        u = 0.5f * (x + 1.0f);
        v = 0.5f * (1.0f - y);
    } else {
        u = 0.5f * (1.0f + std::atan2(d.x, -d.z) / kPi);
        v = std::atan2(std::sqrt(d.x * d.x + d.z * d.z), d.y) / kPi;  // acos(dy), accurate at the poles
    }
}

bool envUvToDir(int mapping, float u, float v, Vec3& d) {
    if (mapping == dev::ENV_PROBE) {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        float r = std::sqrt(x * x + y * y);
        if (!(r <= 1.0f)) return false;
        if (r <= 0.0f) {
            d = Vec3(0, 0, -1);
            return true;
        }
        float ct, st;
        sinCos2Pi(0.5f * r, ct, st);  // θ = π·r, as the device
        d = Vec3(st * x / r, st * y / r, -ct);
        return true;
    }
    float cp, sp, ct, st;  // φ = π(2u − 1) = 2πu − π, θ = π·v, as the device
    sinCos2Pi(u, cp, sp);
    sinCos2Pi(0.5f * v, ct, st);
    d = Vec3(-st * sp, ct, st * cp);
    return true;
}

float envUvToSolidAngle(int mapping, float u, float v) {
    if (mapping == dev::ENV_PROBE) {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        float r = std::sqrt(x * x + y * y);
        if (!(r <= 1.0f)) return 0.0f;
        if (r < 1e-6f) return 1.0f / (4.0f * kPi * kPi);
        float c, s;
        sinCos2Pi(0.5f * r, c, s);
        return s > 0.0f ? r / (4.0f * kPi * s) : 0.0f;
    }
    float c, s;
    sinCos2Pi(0.5f * v, c, s);
    return s > 0.0f ? 1.0f / (2.0f * kPi * kPi * s) : 0.0f;
}

Vec3 envLookup(const EnvMapView& map, float u, float v) {
    const int w = map.width, h = map.height;
    float px = u * float(w) - 0.5f, py = v * float(h) - 0.5f;
    float fx = std::floor(px), fy = std::floor(py);
    float dx = px - fx, dy = py - fy;
    int x0 = int(fx), y0 = int(fy), x1 = x0 + 1, y1 = y0 + 1;
    auto fixX = [&](int x) {
        if (map.mapping == dev::ENV_LATLONG) {
            x %= w;
            return x < 0 ? x + w : x;
        }
        return std::clamp(x, 0, w - 1);
    };
    x0 = fixX(x0); x1 = fixX(x1);
    y0 = std::clamp(y0, 0, h - 1); y1 = std::clamp(y1, 0, h - 1);
    auto t = [&](int x, int y) {
        const dev::float4& c = map.texels[size_t(y) * w + x];
        return Vec3(c.x, c.y, c.z);
    };
    return t(x0, y0) * ((1.0f - dx) * (1.0f - dy)) + t(x1, y0) * (dx * (1.0f - dy)) +
           t(x0, y1) * ((1.0f - dx) * dy) + t(x1, y1) * (dx * dy);
}

// Probe mapping: the solid angle of cell (i, j) of a W x H map (the part inside the disc) and that
// part's share of the cell's area, by n x n sub-samples (more for cells the rim cuts).
static void probeCell(int i, int j, int W, int H, double& omega, double& frac) {
    double x0 = 2.0 * i / W - 1.0, x1 = 2.0 * (i + 1) / W - 1.0;
    double y0 = 1.0 - 2.0 * (j + 1) / H, y1 = 1.0 - 2.0 * j / H;
    double nx = std::clamp(0.0, x0, x1), ny = std::clamp(0.0, y0, y1);
    double nearR = std::sqrt(nx * nx + ny * ny);
    double fx = std::max(std::fabs(x0), std::fabs(x1)), fy = std::max(std::fabs(y0), std::fabs(y1));
    double farR = std::sqrt(fx * fx + fy * fy);
    if (nearR >= 1.0) {
        omega = frac = 0.0;
        return;
    }
    const int n = farR <= 1.0 ? 4 : (W * H <= 16 ? 512 : 32);
    double sum = 0;
    int inside = 0;
    for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
            double x = x0 + (x1 - x0) * (a + 0.5) / n, y = y0 + (y1 - y0) * (b + 0.5) / n;
            double r = std::sqrt(x * x + y * y);
            if (r > 1.0) continue;
            ++inside;
            sum += r < 1e-9 ? 4.0 * M_PI * M_PI : 4.0 * M_PI * std::sin(M_PI * r) / r;
        }
    double cellArea = 1.0 / (double(W) * H);
    if (inside == 0) {  // a sliver the sub-samples missed: small but positive
        frac = 0.5 / (double(n) * n);
        omega = 4.0 * M_PI * std::sin(M_PI * nearR) / std::max(nearR, 1e-9) * frac * cellArea;
    } else {
        frac = double(inside) / (double(n) * n);
        omega = sum / (double(n) * n) * cellArea;
    }
}

// The sampling tables (layout: env_distribution.h) from the cell weights, their row sums and total.
static void writeTables(EnvDistribution& d, int W, int H, int mapping, const std::vector<double>& weight,
                        const std::vector<double>& rowSum, double total, const std::vector<double>& frac) {
    const size_t margOff = 4, condOff = margOff + H + 1, fracOff = condOff + size_t(H) * (W + 1);
    const size_t zOff = fracOff + size_t(W) * H;
    d.data.assign(zOff + H + 1, 0.0f);
    for (int j = 0; j <= H; ++j) d.data[zOff + j] = float(std::cos(M_PI * j / H));
    d.data[zOff] = 1.0f;
    d.data[zOff + H] = -1.0f;
    d.data[0] = float(W);
    d.data[1] = float(H);
    d.data[2] = float(mapping);
    double cum = 0;
    for (int j = 0; j < H; ++j) {
        d.data[margOff + j] = float(cum / total);
        cum += rowSum[j];
        float* cond = &d.data[condOff + size_t(j) * (W + 1)];
        double rc = 0;
        for (int i = 0; i < W; ++i) {
            cond[i] = rowSum[j] > 0 ? float(rc / rowSum[j]) : float(i) / float(W);
            rc += weight[size_t(j) * W + i];
        }
        cond[W] = 1.0f;
    }
    d.data[margOff + H] = 1.0f;
    for (size_t c = 0; c < size_t(W) * H; ++c) d.data[fracOff + c] = float(frac[c]);
}

EnvDistribution buildEnvDistribution(const EnvMapView& map) {
    EnvDistribution d;
    const int W = std::max(1, map.width), H = std::max(1, map.height);
    d.width = W;
    d.height = H;
    d.mapping = map.mapping;
    const bool probe = map.mapping == dev::ENV_PROBE;
    auto lum = [&](int x, int y) {
        if (probe) x = std::clamp(x, 0, W - 1);
        else { x %= W; if (x < 0) x += W; }
        y = std::clamp(y, 0, H - 1);
        return map.texels ? lumOf(map.texels[size_t(y) * W + x]) : 1.0f;
    };
    // Integral of the bilinear reconstruction's luminance over cell (i, j), per unit (u, v) area.
    const float k3[3] = {0.125f, 0.75f, 0.125f};
    std::vector<double> cellLum(size_t(W) * H), omega(size_t(W) * H), frac(size_t(W) * H);
    double lumSum = 0;
    size_t lumCount = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double s = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) s += double(k3[dx + 1]) * k3[dy + 1] * lum(i + dx, j + dy);
            size_t c = size_t(j) * W + i;
            cellLum[c] = s;
            // Solid angle of the cell (the part inside the domain) and that part's share of its area.
            if (!probe) {
                omega[c] = 2.0 * M_PI / W * (std::cos(M_PI * j / H) - std::cos(M_PI * (j + 1) / H));
                frac[c] = 1.0;
            } else {
                probeCell(i, j, W, H, omega[c], frac[c]);
            }
            if (omega[c] > 0) { lumSum += s; ++lumCount; }
        }
    // A floor keeps every cell with solid angle sampled (bilinear footprints, MIS-free strategies).
    double mean = lumCount ? lumSum / double(lumCount) : 0.0;
    double floorLum = mean > 0 ? 1e-3 * mean : 1.0;
    std::vector<double> weight(size_t(W) * H), rowSum(H, 0.0);
    double total = 0;
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t c = size_t(j) * W + i;
            weight[c] = omega[c] > 0 ? (cellLum[c] + floorLum) * omega[c] : 0.0;
            rowSum[j] += weight[c];
        }
        total += rowSum[j];
    }
    writeTables(d, W, H, map.mapping, weight, rowSum, total, frac);
    return d;
}

// The unit direction at point (a, b) of the octahedral square [-1, 1]^2 (y up; |a| + |b| > 1: y < 0).
static Vec3 octahedralDir(float a, float b) {
    float y = 1.0f - std::fabs(a) - std::fabs(b), x = a, z = b;
    if (y < 0.0f) {  // the lower hemisphere, folded out to the square's corners
        x = (1.0f - std::fabs(b)) * (a < 0.0f ? -1.0f : 1.0f);
        z = (1.0f - std::fabs(a)) * (b < 0.0f ? -1.0f : 1.0f);
    }
    return normalize(Vec3(x, y, z));
}

// The first texel of cell I of `cells` over `texels` texels (cells of floor-divided, near-equal widths).
static int cellStart(int I, int texels, int cells) { return int(int64_t(I) * texels / cells); }

Vec3 envCosineBucketNormal(int bucket) {
    const int k = kEnvCosineBuckets;
    return octahedralDir((float(bucket % k) + 0.5f) / float(k) * 2.0f - 1.0f, (float(bucket / k) + 0.5f) / float(k) * 2.0f - 1.0f);
}

int envCosineBucket(const Vec3& n) {
    const int k = kEnvCosineBuckets;
    const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) return -1;
    float a = n.x / l1, b = n.z / l1;
    if (n.y < 0.0f) {
        const float a2 = (1.0f - std::fabs(b)) * (a < 0.0f ? -1.0f : 1.0f);
        b = (1.0f - std::fabs(a)) * (b < 0.0f ? -1.0f : 1.0f);
        a = a2;
    }
    const int i = std::clamp(int((a + 1.0f) * 0.5f * float(k)), 0, k - 1);
    const int j = std::clamp(int((b + 1.0f) * 0.5f * float(k)), 0, k - 1);
    return j * k + i;
}

double envCosineBucketRadius(int bucket) {
    const int k = kEnvCosineBuckets, bi = bucket % k, bj = bucket / k;
    const Vec3 c = envCosineBucketNormal(bucket);
    double r = 0;
    for (int t = 0; t <= 32; ++t)  // the cell's farthest point lies on its border (octahedral cells are convex there)
        for (int s = 0; s <= 32; s += (t == 0 || t == 32) ? 1 : 32) {
            const Vec3 d = octahedralDir((bi + s / 32.0f) / float(k) * 2.0f - 1.0f, (bj + t / 32.0f) / float(k) * 2.0f - 1.0f);
            r = std::max(r, std::acos(std::clamp(double(dot(c, d)), -1.0, 1.0)));
        }
    return r + 1e-3;  // and a margin for the sampled border's gaps
}

int envCosineCellOf(int texel, int texels, int cells) { return int((int64_t(texel + 1) * cells - 1) / texels); }

EnvCosineTable::EnvCosineTable(const EnvDistribution& own) : own_(&own) {
    const int W = own.width, H = own.height;
    Wc_ = std::min(W, kEnvCosineCellsU);
    Hc_ = std::min(H, kEnvCosineCellsV);
    const int buckets = kEnvCosineBuckets * kEnvCosineBuckets;
    stride_ = (Hc_ + 1) + Hc_ * (Wc_ + 1);
    fine_ = kHeader + buckets * stride_;
    data_.assign(size_t(fine_) + size_t(W) * H, 0.0f);
    data_[0] = float(kEnvCosineBuckets);
    data_[1] = float(Wc_);
    data_[2] = float(Hc_);
    data_[3] = float(stride_);
    data_[4] = float(fine_);
    // Each texel's probability under the map's own distribution (its weight: luminance + floor, times
    // solid angle); each cell's sum, and the texels' exclusive cumulative shares within it.
    const float* marg = &own.data[4];
    auto texelMass = [&](int x, int y) {
        const float* cond = &own.data[4 + H + 1 + size_t(y) * (W + 1)];
        return double(marg[y + 1] - marg[y]) * double(cond[x + 1] - cond[x]);
    };
    std::vector<double> cellSum(size_t(Wc_) * Hc_, 0.0);
    std::vector<Vec3> centre(size_t(Wc_) * Hc_);
    for (int J = 0; J < Hc_; ++J)
        for (int I = 0; I < Wc_; ++I) {
            const int x0 = cellStart(I, W, Wc_), x1 = cellStart(I + 1, W, Wc_);
            const int y0 = cellStart(J, H, Hc_), y1 = cellStart(J + 1, H, Hc_), w = x1 - x0;
            float* fine = &data_[size_t(fine_) + size_t(y0) * W + size_t(x0) * (y1 - y0)];
            double sum = 0;
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) sum += texelMass(x, y);
            double cum = 0;  // texels in row-major order within the cell
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    fine[(y - y0) * w + (x - x0)] = sum > 0 ? float(cum / sum) : float((y - y0) * w + (x - x0)) / float(w * (y1 - y0));
                    cum += texelMass(x, y);
                }
            cellSum[size_t(J) * Wc_ + I] = sum;
            Vec3 d(0, 0, -1);  // the direction at the cell's centre (probe: outside the disc -> -z, weight 0 anyway)
            envUvToDir(own.mapping, 0.5f * float(x0 + x1) / float(W), 0.5f * float(y0 + y1) / float(H), d);
            centre[size_t(J) * Wc_ + I] = normalize(d);
        }
    // Per bucket: the cells' weights, their sums times the largest cosine any normal of the bucket sees.
    for (int b = 0; b < buckets; ++b) {
        const Vec3 n = envCosineBucketNormal(b);
        const double radius = envCosineBucketRadius(b);
        std::vector<double> weight(cellSum.size()), rowSum(Hc_, 0.0);
        double total = 0;
        for (int J = 0; J < Hc_; ++J) {
            for (int I = 0; I < Wc_; ++I) {
                const size_t k = size_t(J) * Wc_ + I;
                const double theta = std::acos(std::clamp(double(dot(centre[k], n)), -1.0, 1.0));
                const double cosMax = theta - radius < M_PI / 2 ? std::cos(std::max(0.0, theta - radius)) : 0.0;
                weight[k] = cellSum[k] * (cosMax + kEnvCosineFloor);
                rowSum[J] += weight[k];
            }
            total += rowSum[J];
        }
        float* marg = &data_[size_t(kHeader) + size_t(b) * stride_];
        float* cond = marg + Hc_ + 1;
        double cum = 0;
        for (int J = 0; J < Hc_; ++J) {
            marg[J] = float(cum / total);
            cum += rowSum[J];
            double rc = 0;
            for (int I = 0; I < Wc_; ++I) {
                cond[size_t(J) * (Wc_ + 1) + I] = rowSum[J] > 0 ? float(rc / rowSum[J]) : float(I) / float(Wc_);
                rc += weight[size_t(J) * Wc_ + I];
            }
            cond[size_t(J) * (Wc_ + 1) + Wc_] = 1.0f;
        }
        marg[Hc_] = 1.0f;
    }
}

// Cell (I, J) of bucket b: its probability; and the texel range it covers.
float EnvCosineTable::cellProbability(int b, int I, int J) const {
    const float* marg = &data_[size_t(kHeader) + size_t(b) * stride_];
    const float* cond = marg + Hc_ + 1 + size_t(J) * (Wc_ + 1);
    return (marg[J + 1] - marg[J]) * (cond[I + 1] - cond[I]);
}

bool EnvCosineTable::sample(int b, float u1, float u2, Vec3& dir, float& pdfSolidAngle) const {
    if (b < 0) return own_->sample(u1, u2, dir, pdfSolidAngle);
    const int W = own_->width, H = own_->height;
    const float* marg = &data_[size_t(kHeader) + size_t(b) * stride_];
    const int J = findInterval(marg, Hc_, u2);
    const float dv = std::min((u2 - marg[J]) / (marg[J + 1] - marg[J]), kOneMinus);
    const float* cond = marg + Hc_ + 1 + size_t(J) * (Wc_ + 1);
    const int I = findInterval(cond, Wc_, u1);
    const float du = std::min((u1 - cond[I]) / (cond[I + 1] - cond[I]), kOneMinus);
    const float pCell = (marg[J + 1] - marg[J]) * (cond[I + 1] - cond[I]);
    const int x0 = cellStart(I, W, Wc_), y0 = cellStart(J, H, Hc_), y1 = cellStart(J + 1, H, Hc_);
    const int w = cellStart(I + 1, W, Wc_) - x0, n = w * (y1 - y0);
    const float* fine = &data_[size_t(fine_) + size_t(y0) * W + size_t(x0) * (y1 - y0)];
    const int k = findInterval(fine, n, du);
    const float share = (k + 1 < n ? fine[k + 1] : 1.0f) - fine[k];
    const float dt = std::min((du - fine[k]) / share, kOneMinus);
    return own_->cellSample(x0 + k % w, y0 + k / w, dt, dv, pCell * share, u1, u2, dir, pdfSolidAngle);
}

float EnvCosineTable::pdf(int b, const Vec3& dir) const {
    if (b < 0) return own_->pdf(dir);
    const int W = own_->width, H = own_->height;
    float u, v;
    envDirToUv(own_->mapping, dir, u, v);
    const int x = std::clamp(int(u * float(W)), 0, W - 1), y = std::clamp(int(v * float(H)), 0, H - 1);
    return own_->cellPdf(x, y, texelProbability(b, x, y), u, v);
}

float EnvCosineTable::texelProbability(int b, int x, int y) const {
    const int W = own_->width, H = own_->height;
    const int I = envCosineCellOf(x, W, Wc_), J = envCosineCellOf(y, H, Hc_);
    const int x0 = cellStart(I, W, Wc_), y0 = cellStart(J, H, Hc_), y1 = cellStart(J + 1, H, Hc_);
    const int w = cellStart(I + 1, W, Wc_) - x0, n = w * (y1 - y0), k = (y - y0) * w + (x - x0);
    const float* fine = &data_[size_t(fine_) + size_t(y0) * W + size_t(x0) * (y1 - y0)];
    const float share = (k + 1 < n ? fine[k + 1] : 1.0f) - fine[k];
    return cellProbability(b, I, J) * share;
}

float EnvDistribution::pdf(const Vec3& dir) const {
    const int W = width, H = height;
    float u, v;
    envDirToUv(mapping, dir, u, v);
    int i = std::clamp(int(u * float(W)), 0, W - 1), j = std::clamp(int(v * float(H)), 0, H - 1);
    const float* marg = &data[4];
    const float* cond = &data[4 + H + 1 + size_t(j) * (W + 1)];
    return cellPdf(i, j, (marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]), u, v);
}

float EnvDistribution::cellPdf(int i, int j, float p, float u, float v) const {
    const int W = width, H = height;
    if (!probe()) {  // uniform in solid angle within the cell
        const float* z = &data[4 + H + 1 + size_t(H) * (W + 1) + size_t(W) * H];
        float omega = 2.0f * kPi / float(W) * (z[j] - z[j + 1]);
        return omega > 0.0f ? p / omega : 0.0f;
    }
    float f = data[4 + H + 1 + size_t(H) * (W + 1) + size_t(j) * W + i];
    return f > 0.0f ? p * float(W) * float(H) / f * envUvToSolidAngle(mapping, u, v) : 0.0f;
}

bool EnvDistribution::sample(float u1, float u2, Vec3& dir, float& pdfSolidAngle) const {
    const int W = width, H = height;
    const float* marg = &data[4];
    int j = findInterval(marg, H, u2);
    float dv = std::min((u2 - marg[j]) / (marg[j + 1] - marg[j]), kOneMinus);
    const float* cond = &data[4 + H + 1 + size_t(j) * (W + 1)];
    int i = findInterval(cond, W, u1);
    float du = std::min((u1 - cond[i]) / (cond[i + 1] - cond[i]), kOneMinus);
    float p = (marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]);
    return cellSample(i, j, du, dv, p, u1, u2, dir, pdfSolidAngle);
}

bool EnvDistribution::cellSample(int i, int j, float du, float dv, float p, float u1, float u2, Vec3& dir,
                                 float& pdfSolidAngle) const {
    const int W = width, H = height;
    pdfSolidAngle = 0.0f;
    if (!probe()) {  // uniform in solid angle within the cell: z = cos θ uniform between the row's bounds
        const float* zr = &data[4 + H + 1 + size_t(H) * (W + 1) + size_t(W) * H];
        float z = zr[j] - dv * (zr[j] - zr[j + 1]);
        float st = std::sqrt(std::max(0.0f, 1.0f - z * z));
        float cp, sp;  // φ = 2πu − π, as the device
        sinCos2Pi((float(i) + du) / float(W), cp, sp);
        dir = Vec3(-st * sp, z, st * cp);
        float omega = 2.0f * kPi / float(W) * (zr[j] - zr[j + 1]);
        pdfSolidAngle = omega > 0.0f ? p / omega : 0.0f;
        return pdfSolidAngle > 0.0f && std::isfinite(pdfSolidAngle);
    }
    float u = (float(i) + du) / float(W), v = (float(j) + dv) / float(H);
    {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        bool inside = x * x + y * y <= 1.0f;
        for (int k = 0; !inside && k < kMaxRejections; ++k) {
            envRetryUniforms(u1, u2, uint32_t(k), du, dv);
            u = (float(i) + du) / float(W);
            v = (float(j) + dv) / float(H);
            x = 2.0f * u - 1.0f;
            y = 1.0f - 2.0f * v;
            inside = x * x + y * y <= 1.0f;
        }
        if (!inside) return false;
    }
    if (!envUvToDir(mapping, u, v, dir)) return false;
    float f = data[4 + H + 1 + size_t(H) * (W + 1) + size_t(j) * W + i];
    float pUv = f > 0.0f ? p * float(W) * float(H) / f : 0.0f;
    pdfSolidAngle = pUv * envUvToSolidAngle(mapping, u, v);
    return pdfSolidAngle > 0.0f && std::isfinite(pdfSolidAngle);
}

}  // namespace clrt
