// Host-side vector and matrix math: Vec3 (double-free, float), Mat4 (row-major affine/projective).
// Used by the scene model, the BVH builder and the flattening step. Device code has its own
// OpenCL built-ins; the two agree because both are plain IEEE float arithmetic.
#pragma once
#include <algorithm>
#include <cmath>

namespace clrt {

struct Vec3 {
    float x = 0, y = 0, z = 0;
    Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    explicit constexpr Vec3(float s) : x(s), y(s), z(s) {}
    float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    Vec3 operator+(const Vec3& b) const { return {x + b.x, y + b.y, z + b.z}; }
    Vec3 operator-(const Vec3& b) const { return {x - b.x, y - b.y, z - b.z}; }
    Vec3 operator*(const Vec3& b) const { return {x * b.x, y * b.y, z * b.z}; }
    Vec3 operator/(const Vec3& b) const { return {x / b.x, y / b.y, z / b.z}; }
    Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3& operator+=(const Vec3& b) { x += b.x; y += b.y; z += b.z; return *this; }
    Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
    bool operator==(const Vec3& b) const { return x == b.x && y == b.y && z == b.z; }
    bool operator!=(const Vec3& b) const { return !(*this == b); }
};
inline Vec3 operator*(float s, const Vec3& v) { return v * s; }
inline float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(const Vec3& a) {
    float l = length(a);
    return l > 0 ? a / l : Vec3(0, 0, 0);
}
// The course's orthonormal basis across unit r (the host twin of cl_kernels/common.cl courseBasis): t = r with
// its smallest-magnitude component set to 1, u = unit(t × r), v = r × u. Not continuous in r: a square spanned
// by (u, v) turns with r, as the course's renderer turns its glossy squares and its AreaLight squares.
inline void courseBasis(const Vec3& r, Vec3& u, Vec3& v) {
    Vec3 t = r;
    const float ax = std::fabs(r.x), ay = std::fabs(r.y), az = std::fabs(r.z);
    if (ax <= ay && ax <= az) t.x = 1.0f;
    else if (ay <= az) t.y = 1.0f;
    else t.z = 1.0f;
    u = normalize(cross(t, r));
    v = cross(r, u);
}
inline Vec3 vmin(const Vec3& a, const Vec3& b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 vmax(const Vec3& a, const Vec3& b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
// (cos 2πt, sin 2πt) for finite t in turns: the host replica of the device's Math_SinCos2Pi (common.cl),
// the same float operations in the same order (the device may fuse a multiply-add: within an ulp of this).
inline void sinCos2Pi(float t, float& cosOut, float& sinOut) {
    const float r0 = t - std::rint(t);
    const float q = std::rint(4.0f * r0);
    const float r = r0 - 0.25f * q, r2 = r * r;
    const float s = r * (6.2831854820e+00f + r2 * (-4.1341659546e+01f + r2 * (8.1592155457e+01f + r2 * -7.5395851135e+01f)));
    const float c = 1.0f + r2 * (-1.9739208221e+01f + r2 * (6.4939331055e+01f + r2 * (-8.5444244385e+01f + r2 * 5.9263893127e+01f)));
    const int k = std::isfinite(q) ? static_cast<int>(q) & 3 : 0;
    const float cq = (k & 1) ? -s : c, sq = (k & 1) ? c : s;
    cosOut = (k & 2) ? -cq : cq;
    sinOut = (k & 2) ? -sq : sq;
}
inline bool isFinite(const Vec3& a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

struct Vec2 {
    float x = 0, y = 0;
};

// Row-major 4x4 matrix; points are column vectors: p' = M * p.
struct Mat4 {
    double m[4][4];
    Mat4() { *this = identity(); }
    static Mat4 identity() {
        Mat4 r(0);
        for (int i = 0; i < 4; ++i) r.m[i][i] = 1;
        return r;
    }
    static Mat4 translation(const Vec3& t) {
        Mat4 r;
        r.m[0][3] = t.x; r.m[1][3] = t.y; r.m[2][3] = t.z;
        return r;
    }
    static Mat4 scaling(const Vec3& s) {
        Mat4 r;
        r.m[0][0] = s.x; r.m[1][1] = s.y; r.m[2][2] = s.z;
        return r;
    }
    // Rotation by angleDeg degrees about axis (Rodrigues); right-handed (counter-clockwise looking
    // down the axis towards the origin).
    static Mat4 rotation(double angleDeg, Vec3 axis) {
        Mat4 r;
        double len = std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y + double(axis.z) * axis.z);
        if (len == 0) return r;
        double x = axis.x / len, y = axis.y / len, z = axis.z / len;
        double a = angleDeg * M_PI / 180.0, c = std::cos(a), s = std::sin(a), t = 1 - c;
        r.m[0][0] = t * x * x + c;     r.m[0][1] = t * x * y - s * z; r.m[0][2] = t * x * z + s * y;
        r.m[1][0] = t * x * y + s * z; r.m[1][1] = t * y * y + c;     r.m[1][2] = t * y * z - s * x;
        r.m[2][0] = t * x * z - s * y; r.m[2][1] = t * y * z + s * x; r.m[2][2] = t * z * z + c;
        return r;
    }
    Mat4 operator*(const Mat4& b) const {
        Mat4 r(0);
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                double s = 0;
                for (int k = 0; k < 4; ++k) s += m[i][k] * b.m[k][j];
                r.m[i][j] = s;
            }
        return r;
    }
    Vec3 transformPoint(const Vec3& p) const {
        double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
        double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
        double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
        double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
        if (w != 1 && w != 0) { x /= w; y /= w; z /= w; }
        return {float(x), float(y), float(z)};
    }
    Vec3 transformVector(const Vec3& v) const {
        return {float(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z),
                float(m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z),
                float(m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z)};
    }
    Mat4 transposed() const {
        Mat4 r(0);
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
        return r;
    }
    // General 4x4 inverse (Gauss-Jordan with partial pivoting, in double). Returns false if singular.
    bool inverse(Mat4& out) const {
        double a[4][8];
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) { a[i][j] = m[i][j]; a[i][j + 4] = (i == j); }
        for (int c = 0; c < 4; ++c) {
            int p = c;
            for (int r = c + 1; r < 4; ++r)
                if (std::fabs(a[r][c]) > std::fabs(a[p][c])) p = r;
            if (std::fabs(a[p][c]) < 1e-300) return false;
            if (p != c) for (int j = 0; j < 8; ++j) std::swap(a[p][j], a[c][j]);
            double inv = 1.0 / a[c][c];
            for (int j = 0; j < 8; ++j) a[c][j] *= inv;
            for (int r = 0; r < 4; ++r)
                if (r != c) {
                    double f = a[r][c];
                    if (f != 0) for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
                }
        }
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) out.m[i][j] = a[i][j + 4];
        return true;
    }
    // Normals transform with the inverse transpose; returns the un-normalized result.
    Vec3 transformNormal(const Vec3& n) const {
        Mat4 inv;
        if (!inverse(inv)) return n;
        return inv.transposed().transformVector(n);
    }

private:
    explicit Mat4(int) { for (auto& row : m) for (double& v : row) v = 0; }
};

}  // namespace clrt
