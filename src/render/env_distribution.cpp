// Environment-map mappings, lookup and the importance distribution (see env_distribution.h). Every
// function that has a device twin in cl_kernels/envmap.cl uses the same float operations in the same
// order, so host and device agree to a few ulps.
#include "render/env_distribution.h"

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
        float theta = kPi * r, st = std::sin(theta);
        d = Vec3(st * x / r, st * y / r, -std::cos(theta));
        return true;
    }
    float phi = kPi * (2.0f * u - 1.0f), theta = kPi * v;
    float st = std::sin(theta);
    d = Vec3(st * std::sin(phi), std::cos(theta), -st * std::cos(phi));
    return true;
}

float envUvToSolidAngle(int mapping, float u, float v) {
    if (mapping == dev::ENV_PROBE) {
        float x = 2.0f * u - 1.0f, y = 1.0f - 2.0f * v;
        float r = std::sqrt(x * x + y * y);
        if (!(r <= 1.0f)) return 0.0f;
        if (r < 1e-6f) return 1.0f / (4.0f * kPi * kPi);
        float s = std::sin(kPi * r);
        return s > 0.0f ? r / (4.0f * kPi * s) : 0.0f;
    }
    float s = std::sin(kPi * v);
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

float EnvDistribution::pdf(const Vec3& dir) const {
    const int W = width, H = height;
    float u, v;
    envDirToUv(mapping, dir, u, v);
    int i = std::clamp(int(u * float(W)), 0, W - 1), j = std::clamp(int(v * float(H)), 0, H - 1);
    const float* marg = &data[4];
    const float* cond = &data[4 + H + 1 + size_t(j) * (W + 1)];
    float p = (marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]);
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
    pdfSolidAngle = 0.0f;
    const float* marg = &data[4];
    int j = findInterval(marg, H, u2);
    float dv = std::min((u2 - marg[j]) / (marg[j + 1] - marg[j]), kOneMinus);
    const float* cond = &data[4 + H + 1 + size_t(j) * (W + 1)];
    int i = findInterval(cond, W, u1);
    float du = std::min((u1 - cond[i]) / (cond[i + 1] - cond[i]), kOneMinus);
    float p = (marg[j + 1] - marg[j]) * (cond[i + 1] - cond[i]);
    if (!probe()) {  // uniform in solid angle within the cell: z = cos θ uniform between the row's bounds
        const float* zr = &data[4 + H + 1 + size_t(H) * (W + 1) + size_t(W) * H];
        float z = zr[j] - dv * (zr[j] - zr[j + 1]);
        float st = std::sqrt(std::max(0.0f, 1.0f - z * z));
        float phi = kPi * (2.0f * ((float(i) + du) / float(W)) - 1.0f);
        dir = Vec3(st * std::sin(phi), z, -st * std::cos(phi));
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
