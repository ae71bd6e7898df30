// Object lights (LightMesh, LightSphere; cl_kernels/object_lights.cl, src/flatten/flatten_lights.cpp):
// parsing and its errors; the device samplers (Light_Sample) against host references written here in
// double precision from the scene model; per light shape, Mitsuba-style checks of the device's samples:
// chi-square of the directions against the host pdf, the pdf integrating to one over the sphere of
// directions, pdf(sample) = pdf(evaluate); furnace checks of the irradiance the device sampler
// estimates (sphere: π·L·sin²θ, parallel square: π·L·form factor) within 1%; renders: camera and mirror
// rays see the Radiance (both faces of a LightMesh), two PoCL devices give the one-device image; and (tagged
// [shared][hw6]) the course's diffuse_area cornell box at reduced spp against its reference.
#include <catch.hpp>

#include <cfloat>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <regex>
#include <sstream>

#include "cl/check.h"
#include "flatten/device_scene.h"
#include "image/image_compare.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;
using namespace clrt::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct D3 {
    double x = 0, y = 0, z = 0;
};
D3 d3(const Vec3& v) { return {v.x, v.y, v.z}; }
D3 d3(const dev::float4& v) { return {v.x, v.y, v.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(double s, D3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double len(D3 a) { return std::sqrt(dot(a, a)); }
D3 unit(D3 a) { return (1.0 / len(a)) * a; }
double angle(D3 a, D3 b) { return 2.0 * std::asin(std::min(1.0, 0.5 * len(unit(a) - unit(b)))); }

// The orthonormal frame the kernels build around unit n (Duff et al. 2017).
void basis(D3 n, D3& t, D3& b) {
    double sign = n.z >= 0 ? 1.0 : -1.0, a = -1.0 / (sign + n.z), c = n.x * n.y * a;
    t = {1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x};
    b = {c, sign + n.y * n.y * a, -n.y};
}

// Test scene: light 0 = a square LightMesh (side 2, at y = 3, facing down), light 1 = a LightMesh of
// three coplanar triangles of areas 0.5, 0.15 and 1.425 (facing −y before a rotation of 30°), light 2 = a LightSphere of radius 0.5 scaled by 2 (radius 1) at
// (0.5, 3, -0.2), light 3 = a LightSphere scaled (1, 3, 1) (an ellipsoid) at (-3, 1, 0), light 4 = a LightMesh of
// 20 triangles (a fan: a regular 20-gon of radius 1 at y = 4, more than CLRT_MESHLIGHT_PICK_MAX: picked by area),
// light 5 = a closed cube of 12 LightMesh triangles ([-1.5, -0.5] × [-0.5, 0.5] × [0.5, 1.5], mixed winding): enclosed
// (src/flatten/light_enclosure.h), so that from outside only its outer sides get samples.
const char* kLightsXml = R"(<Scene>
<Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
<FovY>60</FovY><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution><ImageName>o.exr</ImageName></Camera></Cameras>
<Materials><Material id="1"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material></Materials>
<Transformations><Translation id="1">0 3 0</Translation><Translation id="2">0.5 3 -0.2</Translation>
<Translation id="3">-3 1 0</Translation><Scaling id="1">2 2 2</Scaling><Scaling id="2">1 3 1</Scaling>
<Rotation id="1">30 1 1 0</Rotation><Translation id="4">1.5 4 0.5</Translation></Transformations>
<VertexData>-1 0 -1  1 0 -1  1 0 1  -1 0 1  0 0 0
  0 1 0  1 1 0  1 1 1  0.3 1 1  0 1 1  -2 1 -1  -0.1 1 -1  -0.1 1 0.5
  0 0 0  1.000000 0 0.000000 0.951057 0 0.309017 0.809017 0 0.587785 0.587785 0 0.809017 0.309017 0 0.951057 0.000000 0 1.000000 -0.309017 0 0.951057 -0.587785 0 0.809017 -0.809017 0 0.587785 -0.951057 0 0.309017 -1.000000 0 0.000000 -0.951057 0 -0.309017 -0.809017 0 -0.587785 -0.587785 0 -0.809017 -0.309017 0 -0.951057 -0.000000 0 -1.000000 0.309017 0 -0.951057 0.587785 0 -0.809017 0.809017 0 -0.587785 0.951057 0 -0.309017
  -1.5 -0.5 0.5  -0.5 -0.5 0.5  -0.5 0.5 0.5  -1.5 0.5 0.5  -1.5 -0.5 1.5  -0.5 -0.5 1.5  -0.5 0.5 1.5  -1.5 0.5 1.5</VertexData>
<Objects>
<LightMesh id="1"><Material>1</Material><Radiance>1 2 3</Radiance><Transformations>t1</Transformations>
  <Faces>1 2 3  1 3 4</Faces></LightMesh>
<LightMesh id="2"><Material>1</Material><Radiance>4 5 6</Radiance><Transformations>r1</Transformations>
  <Faces vertexOffset="5">1 2 3  1 4 5  6 7 8</Faces></LightMesh>
<LightSphere id="1"><Material>1</Material><Center>5</Center><Radius>0.5</Radius><Radiance>7 8 9</Radiance>
  <Transformations>s1 t2</Transformations></LightSphere>
<LightSphere id="2"><Material>1</Material><Center>5</Center><Radius>0.5</Radius><Radiance>2 2 2</Radiance>
  <Transformations>s2 t3</Transformations></LightSphere>
<LightMesh id="3"><Material>1</Material><Radiance>3 2 1</Radiance><Transformations>t4</Transformations>
  <Faces vertexOffset="13">1 2 3 1 3 4 1 4 5 1 5 6 1 6 7 1 7 8 1 8 9 1 9 10 1 10 11 1 11 12 1 12 13 1 13 14 1 14 15 1 15 16 1 16 17 1 17 18 1 18 19 1 19 20 1 20 21 1 21 2</Faces></LightMesh>
<LightMesh id="4"><Material>1</Material><Radiance>2 1 3</Radiance>
  <Faces vertexOffset="34">1 2 3  1 3 4  5 7 6  5 8 7  1 2 6  1 6 5  4 7 3  4 8 7  1 4 8  1 8 5  2 3 7  2 7 6</Faces></LightMesh>
</Objects></Scene>)";

std::string writeText(const TempDir& dir, const std::string& name, const std::string& text) {
    std::string p = dir.file(name);
    std::ofstream(p, std::ios::binary) << text;
    return p;
}

// Host reference of one object light, from the scene model (not from ds.lightData).
struct HostLight {
    bool sphere = false;
    D3 radiance;
    std::vector<D3> v;          // mesh: 3 per triangle, world space
    std::vector<double> cdf;    // mesh: running area / total
    double area = 0;
    bool enclosed = false;      // mesh: bounds a closed convex volume (the flattened Light.position.w; enclosedHost)
    D3 inside;                  // mesh, enclosed: a point inside that volume (Light.position.xyz)
    D3 center;                  // sphere: world centre
    double boundR = 0;          // sphere: bounding radius (given by the test, from the transform)
    Mat4 toObject;              // sphere: world -> object
    Mat4 toWorld;               // sphere: object -> world
    bool ellipsoid = false;     // sphere: the transform is no similarity (sampled in object space)
    D3 objCenter;
    double objR = 0;
};

// Rows of m's 3x4 affine part applied to v (w = 1: a point, 0: a direction).
D3 affine(const Mat4& m, D3 v, double w) {
    auto row = [&](int r) { return m.m[r][0] * v.x + m.m[r][1] * v.y + m.m[r][2] * v.z + w * m.m[r][3]; };
    return {row(0), row(1), row(2)};
}

// dω_obj/dω_world along unit world direction w: |det A| / |A·w|³, A the linear part of toObject.
double directionScale(const HostLight& h, D3 w) {
    const auto& a = h.toObject.m;
    double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                 a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    double l = len(affine(h.toObject, w, 0));
    return std::fabs(det) / (l * l * l);
}

HostLight hostLight(const Scene& s, int li, double boundR = 0) {
    const Light& l = s.lights.at(size_t(li));
    const Shape& sh = s.shapes.at(size_t(l.shapeIndex));
    HostLight h;
    h.radiance = d3(l.intensity);
    if (l.type == dev::LIGHT_MESH) {
        const MeshData& m = s.meshes.at(size_t(sh.meshIndex));
        std::vector<double> areas;
        for (size_t t = 0; t < m.indices.size(); t += 3) {
            for (int k = 0; k < 3; ++k) h.v.push_back(d3(sh.transform.transformPoint(m.positions[size_t(m.indices[t + k])])));
            D3* q = &h.v[h.v.size() - 3];
            areas.push_back(0.5 * len(cross(q[1] - q[0], q[2] - q[0])));
            h.area += areas.back();
        }
        double run = 0;
        for (double a : areas) h.cdf.push_back((run += a) / h.area);
    } else {
        h.sphere = true;
        h.center = d3(sh.transform.transformPoint(sh.center));
        h.boundR = boundR;
        REQUIRE(sh.transform.inverse(h.toObject));
        h.toWorld = sh.transform;
        D3 c0 = affine(h.toWorld, {1, 0, 0}, 0), c1 = affine(h.toWorld, {0, 1, 0}, 0), c2 = affine(h.toWorld, {0, 0, 1}, 0);
        double g = dot(c0, c0);  // a similarity maps the unit axes to equal, orthogonal lengths
        h.ellipsoid = std::fabs(dot(c1, c1) - g) > 1e-9 * g || std::fabs(dot(c2, c2) - g) > 1e-9 * g ||
                      std::fabs(dot(c0, c1)) > 1e-9 * g || std::fabs(dot(c0, c2)) > 1e-9 * g || std::fabs(dot(c1, c2)) > 1e-9 * g;
        h.objCenter = d3(sh.center);
        h.objR = sh.radius;
    }
    return h;
}

// Distance along unit w from p to the outside of the sphere light, or -1.
double sphereHit(const HostLight& h, D3 p, D3 w) {
    auto row = [&](int r, D3 v, double wgt) {
        return h.toObject.m[r][0] * v.x + h.toObject.m[r][1] * v.y + h.toObject.m[r][2] * v.z + wgt * h.toObject.m[r][3];
    };
    D3 o{row(0, p, 1), row(1, p, 1), row(2, p, 1)}, d{row(0, w, 0), row(1, w, 0), row(2, w, 0)};
    D3 f = o - h.objCenter;
    double a = dot(d, d), b = dot(f, d), c = dot(f, f) - h.objR * h.objR, disc = b * b - a * c;
    if (c <= 0 || b >= 0 || disc < 0) return -1;
    return (-b - std::sqrt(disc)) / a;
}

struct Sample {
    D3 e, wi;
    double dist = 0;
};

// MeshLight_Weight (object_lights.cl) in double: tan(Ω/2) of triangle (a, b, c)'s solid angle from p, at most
// 8 (CLRT_MESHLIGHT_WEIGHT_CAP), 0 where p lies in its plane. Meshes of at most 16 triangles
// (CLRT_MESHLIGHT_PICK_MAX) pick by it.
constexpr size_t kPickMax = 16;
double hostWeight(D3 a, D3 b, D3 c, D3 p) {
    D3 ra = a - p, rb = b - p, rc = c - p;
    double la = len(ra), lb = len(rb), lc = len(rc);
    double num = std::fabs(dot(ra, cross(b - a, c - a)));  // = ra·(rb×rc), as MeshLight_Subtended
    double den = la * lb * lc + dot(ra, rb) * lc + dot(ra, rc) * lb + dot(rb, rc) * la;
    if (!(num > 0)) return 0;
    return den * 8 > num ? num / den : 8.0;
}

// MeshLight_Facing: 1 where p sees the inner side of triangle (a, b, c) of the volume around `inside`, -1 where
// p lies on its outer side by more than 1e-5 (relative), else 0.
int hostFacing(D3 a, D3 b, D3 c, D3 p, D3 inside) {
    D3 n = cross(b - a, c - a), ra = a - p;
    double s = dot(a - inside, n) > 0 ? dot(ra, n) : -dot(ra, n);
    return s > 0 ? 1 : (s < 0 && s * s > 1e-10 * dot(ra, ra) * dot(n, n) ? -1 : 0);
}

// The weights (hostWeight) of mesh light h's triangles from p (at most 16); where h is enclosed and p outside
// it, 0 for the triangles that show p their inner side (MeshLight_Weights).
std::vector<double> hostWeights(const HostLight& h, D3 p) {
    const size_t n = h.v.size() / 3;
    std::vector<double> w(n);
    std::vector<bool> inner(n, false);
    bool outside = false;
    for (size_t i = 0; i < n; ++i) {
        w[i] = hostWeight(h.v[3 * i], h.v[3 * i + 1], h.v[3 * i + 2], p);
        if (!h.enclosed) continue;
        int f = hostFacing(h.v[3 * i], h.v[3 * i + 1], h.v[3 * i + 2], p, h.inside);
        inner[i] = f > 0;
        outside = outside || f < 0;
    }
    for (size_t i = 0; i < n; ++i)
        if (outside && inner[i]) w[i] = 0;
    return w;
}

// tan(Ω/2) = num / den of the solid angle triangle (a, b, c) subtends at p (MeshLight_Subtended), and Ω.
double hostSolidAngle(D3 a, D3 b, D3 c, D3 p) {
    D3 ra = a - p, rb = b - p, rc = c - p;
    double la = len(ra), lb = len(rb), lc = len(rc);
    double num = std::fabs(dot(ra, cross(b - a, c - a)));  // = ra·(rb×rc), as MeshLight_Subtended
    double den = la * lb * lc + dot(ra, rb) * lc + dot(ra, rc) * lb + dot(rb, rc) * la;
    return 2 * std::atan2(num, den);
}
// Picked triangles of Ω in (3e-4, 6.2) sr are sampled uniformly in Ω (CLRT_MESHLIGHT_SPHERICAL_MIN/MAX).
bool hostBySolidAngle(double omega) { return omega > 3e-4 && omega < 6.2; }

// MeshLight_SphericalDirection in double: uniform in the spherical triangle of unit a, b, c (Arvo 1995).
D3 hostSphericalDirection(D3 a, D3 b, D3 c, double omega, double u1, double u2) {
    D3 nab = unit(cross(a, b)), nac = unit(cross(a, c));
    double cosAlpha = dot(nab, nac), sinAlpha = len(cross(nab, nac));
    double phi = u1 * omega - std::atan2(sinAlpha, cosAlpha);  // the sub-area less α
    double s = std::sin(phi), t = std::cos(phi), u = t - cosAlpha, v = s + sinAlpha * dot(a, b);
    double q = std::clamp(((v * t - u * s) * cosAlpha - v) / ((v * s + u * t) * sinAlpha), -1.0, 1.0);
    D3 cHat = q * a + std::sqrt(std::max(0.0, 1 - q * q)) * unit(c - dot(c, a) * a);
    double z = 1 - u2 * (1 - dot(cHat, b));
    return unit(z * b + std::sqrt(std::max(0.0, 1 - z * z)) * unit(cHat - dot(cHat, b) * b));
}

// 1 / the density over the area with which mesh light h, sampled from p, draws point q of its triangle k:
// 1/P(k) (by weight Σw / w_k; by area, larger meshes, A / A_k), then Ω_k·d²/cosθ_L (uniform in the triangle's
// solid angle) or A_k.
double hostInvAreaPdf(const HostLight& h, D3 p, size_t k, D3 q) {
    const size_t n = h.v.size() / 3;
    const D3* v = &h.v[3 * k];
    const double areaK = 0.5 * len(cross(v[1] - v[0], v[2] - v[0]));
    double invPick = h.area / areaK;
    if (n <= kPickMax) {
        const std::vector<double> weights = hostWeights(h, p);
        double total = 0;
        for (double x : weights) total += x;
        double w = weights[k];  // 0 where hidden: never sampled
        if (!(w > 0)) return 0.0;
        invPick = total / w;
    }
    double omega = hostSolidAngle(v[0], v[1], v[2], p);
    if (hostBySolidAngle(omega)) {
        D3 d = q - p;
        double cosL = std::fabs(dot(unit(cross(v[1] - v[0], v[2] - v[0])), unit(d)));
        return cosL > 0 ? omega * invPick * dot(d, d) / cosL : 0.0;
    }
    return areaK * invPick;
}

// The sampler, in double: what Light_Sample should return for point p and uniforms (u1, u2).
Sample hostSample(const HostLight& h, D3 p, double u1, double u2) {
    Sample s;
    if (!h.sphere) {
        size_t k = 0;
        double ux = 0;
        const size_t n = h.v.size() / 3;
        if (n <= kPickMax) {  // by weight: the first k whose share holds u1·Σw
            const std::vector<double> w = hostWeights(h, p);
            double total = 0, below = 0;
            for (double x : w) total += x;
            if (!(total > 0)) return s;
            double x = u1 * total;
            while (k + 1 < n && !(x < below + w[k])) below += w[k++];
            if (!(w[k] > 0)) return s;
            ux = (x - below) / w[k];
        } else {
            while (k + 1 < h.cdf.size() && !(h.cdf[k] > u1)) ++k;
            double c0 = k ? h.cdf[k - 1] : 0.0;
            ux = (u1 - c0) / (h.cdf[k] - c0);
        }
        const D3* v = &h.v[3 * k];
        D3 q;
        double omega = hostSolidAngle(v[0], v[1], v[2], p);
        if (hostBySolidAngle(omega)) {  // the direction, then its point on the triangle's plane
            D3 w = hostSphericalDirection(unit(v[0] - p), unit(v[1] - p), unit(v[2] - p), omega, ux, u2);
            D3 nL = unit(cross(v[1] - v[0], v[2] - v[0]));
            q = p + (dot(nL, v[0] - p) / dot(nL, w)) * w;
        } else {
            double su = std::sqrt(ux);
            double b0 = 1 - su, b1 = u2 * su;
            q = b0 * v[0] + b1 * v[1] + (1 - b0 - b1) * v[2];
        }
        D3 d = q - p;
        s.dist = len(d);
        s.wi = (1.0 / s.dist) * d;
        double cosL = std::fabs(dot(unit(cross(v[1] - v[0], v[2] - v[0])), s.wi));  // both faces emit
        if (cosL > 0) s.e = (hostInvAreaPdf(h, p, k, q) * cosL / (s.dist * s.dist)) * h.radiance;
        if (cosL > 0) {  // the shadow ray's length (MeshLight_ShadowLength): short of q by offset / cosθ_L
            double m = std::max({std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
            double offset = std::max(16.0 * FLT_EPSILON * m, 1.0 / 65536.0);
            s.dist = std::max(s.dist - offset / cosL, 0.5 * s.dist);
        }
        return s;
    }
    if (h.ellipsoid) {  // the object-space sphere's cone from the object-space point; value L·Ω_obj
        D3 po = affine(h.toObject, p, 1), f = po - h.objCenter;
        double d2 = dot(f, f), R = h.objR;
        if (!(d2 > R * R)) return s;
        double oneMinusCosMax = 1 - std::sqrt(1 - R * R / d2), omc = u1 * oneMinusCosMax;
        double cosT = 1 - omc, sinT = std::sqrt(omc * (2 - omc)), phi = 2 * kPi * u2;
        D3 n = unit(-1.0 * f), t, b;
        basis(n, t, b);
        D3 wo = unit(sinT * std::cos(phi) * t + sinT * std::sin(phi) * b + cosT * n);
        double bb = dot(f, wo), disc = std::max(0.0, bb * bb - (d2 - R * R));
        D3 q = affine(h.toWorld, po + (-bb - std::sqrt(disc)) * wo, 1), d = q - p;
        s.dist = len(d);
        s.wi = (1.0 / s.dist) * d;
        s.e = (2 * kPi * oneMinusCosMax) * h.radiance;
        D3 no = po + (-bb - std::sqrt(disc)) * wo - h.objCenter;  // world normal: toObjectᵀ·n_obj
        D3 nw{h.toObject.m[0][0] * no.x + h.toObject.m[1][0] * no.y + h.toObject.m[2][0] * no.z,
              h.toObject.m[0][1] * no.x + h.toObject.m[1][1] * no.y + h.toObject.m[2][1] * no.z,
              h.toObject.m[0][2] * no.x + h.toObject.m[1][2] * no.y + h.toObject.m[2][2] * no.z};
        double cosL = std::max(-dot(unit(nw), s.wi), 1e-4);  // short of q by the offset / cosθ_L, as a mesh
        double m = std::max({std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
        s.dist = std::max(s.dist - std::max(16.0 * FLT_EPSILON * m, 1.0 / 65536.0) / cosL, 0.5 * s.dist);
        return s;
    }
    D3 axis = h.center - p;
    double d2 = dot(axis, axis), invPdf;
    D3 w;
    if (d2 > h.boundR * h.boundR) {
        double oneMinusCosMax = 1 - std::sqrt(1 - h.boundR * h.boundR / d2), omc = u1 * oneMinusCosMax;
        double cosT = 1 - omc, sinT = std::sqrt(omc * (2 - omc)), phi = 2 * kPi * u2;
        D3 n = unit(axis), t, b;
        basis(n, t, b);
        w = unit(sinT * std::cos(phi) * t + sinT * std::sin(phi) * b + cosT * n);
        invPdf = 2 * kPi * oneMinusCosMax;
    } else {
        double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u2;
        w = {r * std::cos(phi), r * std::sin(phi), z};
        invPdf = 4 * kPi;
    }
    double t = sphereHit(h, p, w);
    if (t > 0) {
        s.wi = w;
        s.dist = t;
        s.e = invPdf * h.radiance;
    }
    return s;
}

// The sampler's pdf (solid angle) of direction w from p: mesh by its pick's density over the area (every
// triangle the ray crosses, either side), sphere uniform in its cone; an ellipsoid uniform in its object-space cone.
double hostPdf(const HostLight& h, D3 p, D3 w) {
    if (h.ellipsoid) {  // the object-space cone's pdf times dω_obj/dω_world
        D3 f = h.objCenter - affine(h.toObject, p, 1), wo = unit(affine(h.toObject, w, 0));
        double d2 = dot(f, f), cosMax = std::sqrt(1 - h.objR * h.objR / d2);
        return dot(wo, unit(f)) >= cosMax ? directionScale(h, w) / (2 * kPi * (1 - cosMax)) : 0.0;
    }
    if (h.sphere) {
        D3 axis = h.center - p;
        double d2 = dot(axis, axis), cosMax = std::sqrt(1 - h.boundR * h.boundR / d2);
        return dot(w, unit(axis)) >= cosMax ? 1.0 / (2 * kPi * (1 - cosMax)) : 0.0;
    }
    double pdf = 0;
    for (size_t k = 0; k < h.v.size(); k += 3) {  // Möller–Trumbore
        D3 e1 = h.v[k + 1] - h.v[k], e2 = h.v[k + 2] - h.v[k], pv = cross(w, e2);
        double det = dot(e1, pv);
        if (std::fabs(det) < 1e-300) continue;
        D3 tv = p - h.v[k];
        double u = dot(tv, pv) / det;
        D3 qv = cross(tv, e1);
        double v = dot(w, qv) / det, t = dot(e2, qv) / det;
        if (u < 0 || v < 0 || u + v > 1 || t <= 0) continue;
        double cosL = std::fabs(dot(unit(cross(e1, e2)), w)), inv = hostInvAreaPdf(h, p, k / 3, p + t * w);
        if (inv > 0) pdf += t * t / (inv * cosL);
    }
    return pdf;
}

// ∫ f(ω) dω over the sphere by the midpoint rule on the six faces of a cube (M×M cells each).
template <class F> double integrateSphere(F f, int M) {
    double sum = 0;
    for (int face = 0; face < 6; ++face)
        for (int b = 0; b < M; ++b)
            for (int a = 0; a < M; ++a) {
                double s = 2.0 * (a + 0.5) / M - 1.0, t = 2.0 * (b + 0.5) / M - 1.0, sign = (face & 1) ? -1.0 : 1.0;
                double dw = (4.0 / (double(M) * M)) / std::pow(1.0 + s * s + t * t, 1.5);
                D3 d = face / 2 == 0 ? D3{sign, s, t} : face / 2 == 1 ? D3{s, sign, t} : D3{s, t, sign};
                sum += f(unit(d)) * dw;
            }
    return sum;
}

double chi2Critical(int k, double z) {  // Wilson–Hilferty
    double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

// Runs Light_Sample on the test device for light `light` at points/uniforms `in` (xyz = p, w unused;
// uniforms in `u`): per input (e, dist) and (wi, 0).
std::vector<dev::float4> deviceSamples(const DeviceScene& ds, int light, const std::vector<dev::float4>& pts,
                                       const std::vector<dev::float2>& u) {
    const char* src = R"CLC(
__kernel void objlight_test(const __global Light* lights, int light, const __global float4* pts,
                            const __global float2* u, const __global float4* lightData, __global float4* out, int n) {
    int i = get_global_id(0);
    if (i >= n) return;
    float3 wi; float dist;
    float3 e = Light_Sample(&lights[light], pts[i].xyz, (float3)(0.0f, 1.0f, 0.0f), u[i], 0, 0, 0, lightData, &wi, &dist);
    out[2 * i] = (float4)(e, dist);
    out[2 * i + 1] = (float4)(wi, 0.0f);
}
)CLC";
    DeviceContext& dc = testContext();
    static cl::Program program;  // built once (the flags are those of the object lights)
    if (!program()) {
        auto sources = loadKernelSources({"lights.cl"});
        sources.push_back({"objlight_test.cl", src});
        FeatureSet f;
        f.add(dev::LIGHT_MESH);
        f.add(dev::LIGHT_SPHERE);
        program = buildProgramFromSources(dc, sources, f.defines());
    }
    cl::Kernel k = CL_CPP(cl::Kernel(program, "objlight_test"));
    cl::Context& ctx = dc.context();
    auto ro = [&](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        return CL_CPP(cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(T) * v.size(), const_cast<T*>(v.data())));
    };
    const int n = int(pts.size());
    std::vector<dev::float4> out(2 * pts.size());
    cl::Buffer lb = ro(ds.lights), pb = ro(pts), ub = ro(u), db = ro(ds.lightData);
    cl::Buffer ob = CL_CPP(cl::Buffer(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(dev::float4)));
    k.setArg(0, lb); k.setArg(1, light); k.setArg(2, pb); k.setArg(3, ub); k.setArg(4, db); k.setArg(5, ob); k.setArg(6, n);
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(size_t(n), 64)), cl::NDRange(64)));
    CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, out.size() * sizeof(dev::float4), out.data()));
    return out;
}

// u on a jittered n×n grid (stratified; deterministic).
std::vector<dev::float2> stratified(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    std::vector<dev::float2> u;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            u.push_back({std::min((i + uni(rng)) / n, 0.99999994f), std::min((j + uni(rng)) / n, 0.99999994f)});
    return u;
}

struct LightsFixture {
    TempDir dir;
    Scene scene;
    DeviceScene ds;
    LightsFixture() {
        scene = loadScene(writeText(dir, "lights.xml", kLightsXml));
        ds = flattenScene(scene);
    }
};

// hostLight of light li with its enclosure as flattened (Light.position: the kernels' input).
HostLight enclosedHost(const LightsFixture& f, int li) {
    HostLight h = hostLight(f.scene, li);
    const dev::float4& p = f.ds.lights.at(size_t(li)).position;
    h.enclosed = p.w > 0;
    h.inside = {p.x, p.y, p.z};
    return h;
}

}  // namespace

TEST_CASE("object lights: LightMesh and LightSphere parse into a shape and a light each", "[objlight][scene]") {
    LightsFixture f;
    const Scene& s = f.scene;
    REQUIRE(s.lights.size() == 6);
    REQUIRE(s.shapes.size() == 6);
    for (int i = 0; i < 6; ++i) {
        CHECK(s.lights[size_t(i)].shapeIndex == i);
        CHECK(s.shapes[size_t(i)].lightIndex == i);
    }
    CHECK(s.lights[0].type == dev::LIGHT_MESH);
    CHECK(s.lights[2].type == dev::LIGHT_SPHERE);
    CHECK(s.shapes[0].type == ShapeType::Mesh);
    CHECK(s.shapes[2].type == ShapeType::Sphere);
    CHECK(s.lights[2].intensity.y == 8.0f);
    CHECK(s.meshes[size_t(s.shapes[1].meshIndex)].indices.size() == 9);  // vertexOffset applied
    // Flattened: triangles and spheres point at their lights; feature flags of both kinds.
    const DeviceScene& ds = f.ds;
    CHECK(ds.features.has(dev::LIGHT_MESH));
    CHECK(ds.features.has(dev::LIGHT_SPHERE));
    int meshTris = 0;
    for (const dev::TriangleShading& t : ds.triangleShading) meshTris += t.light == 0 || t.light == 1;
    CHECK(meshTris == 5);
    CHECK(ds.spheres.at(0).light == 2);
    CHECK(ds.spheres.at(1).light == 3);
    CHECK(ds.lights[0].objCount == 2);
    CHECK(ds.lights[0].area == Approx(4.0f));
    CHECK(ds.lights[2].objRadius == Approx(1.0f).epsilon(1e-5));
    CHECK(ds.lights[3].objRadius == Approx(1.5f).epsilon(1e-5));
    // Only the cube is enclosed, around the mean of its vertices (flat meshes: position.w 0).
    for (int l : {0, 1, 4}) CHECK(ds.lights[size_t(l)].position.w == 0.0f);
    CHECK(ds.lights[5].objCount == 12);
    CHECK(ds.lights[5].position.w == 1.0f);
    CHECK(ds.lights[5].position.x == Approx(-1.0f));
    CHECK(ds.lights[5].position.z == Approx(1.0f));
    // A mirrored LightMesh (Scaling -1 1 1) keeps emitting downwards: its sampling triangles take the
    // winding flattenGeometry gives its geometry (reversed under a mirror).
    {
        TempDir dm;
        std::string xml = std::regex_replace(std::string(kLightsXml), std::regex("<Transformations>t1</Transformations>"),
                                             "<Transformations>s3 t1</Transformations>");
        xml = std::regex_replace(xml, std::regex("<Rotation id=\"1\">"), "<Scaling id=\"3\">-1 1 1</Scaling><Rotation id=\"1\">");
        DeviceScene dsm = flattenScene(loadScene(writeText(dm, "mirror.xml", xml)));
        REQUIRE(dsm.lights[0].objCount == 2);
        for (int k = 0; k < 2; ++k) {
            D3 a = d3(dsm.lightData[size_t(dsm.lights[0].objFirst + 3 * k)]), b = d3(dsm.lightData[size_t(dsm.lights[0].objFirst + 3 * k + 1)]),
               c = d3(dsm.lightData[size_t(dsm.lights[0].objFirst + 3 * k + 2)]);
            CHECK(unit(cross(b - a, c - a)).y == Approx(-1.0));
        }
        int geomDown = 0;
        for (size_t t = 0; t < dsm.triangles.size(); ++t)
            if (dsm.triangleShading[t].light == 0) {
                const dev::Triangle& tr = dsm.triangles[t];
                geomDown += unit(cross(d3(tr.v1) - d3(tr.v0), d3(tr.v2) - d3(tr.v0))).y < -0.999;
            }
        CHECK(geomDown == 2);
    }
    // A scene without object lights gets neither flag.
    TempDir d;
    FeatureSet none = flattenScene(loadScene(writeText(d, "plain.xml",
        "<Scene><Materials><Material id=\"1\"/></Materials><VertexData>0 0 0 1 0 0 0 1 0</VertexData><Objects>"
        "<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces></Mesh><Sphere id=\"1\"><Material>1</Material>"
        "<Center>1</Center><Radius>1</Radius></Sphere></Objects></Scene>"))).features;
    CHECK_FALSE(none.has(dev::LIGHT_MESH));
    CHECK_FALSE(none.has(dev::LIGHT_SPHERE));
    for (const std::string& def : none.defines()) CHECK(def.find("LIGHT_") == std::string::npos);
}

TEST_CASE("object lights: parse errors name the element and its line", "[objlight][scene]") {
    TempDir d;
    auto expectError = [&](const std::string& name, const std::string& xml, const std::string& needle) {
        std::string path = writeText(d, name, xml);
        try {
            loadScene(path);
            FAIL("no error for " << name);
        } catch (const Error& e) {
            std::string msg = e.what();
            INFO(msg);
            CHECK(msg.find(path + ":") == 0);
            CHECK(msg.find('\n') == std::string::npos);
            CHECK(msg.find(needle) != std::string::npos);
        }
    };
    const std::string head = "<Scene><Materials><Material id=\"1\"/></Materials><VertexData>0 0 0 1 0 0 0 1 0</VertexData>";
    expectError("noradiance.xml", head + "<Objects><LightMesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces>"
                                         "</LightMesh></Objects></Scene>", "Radiance");
    expectError("negative.xml", head + "<Objects><LightSphere id=\"1\"><Material>1</Material><Center>1</Center>"
                                       "<Radius>1</Radius><Radiance>1 -1 1</Radiance></LightSphere></Objects></Scene>",
                "non-negative");
    expectError("short.xml", head + "<Objects><LightSphere id=\"1\"><Material>1</Material><Center>1</Center>"
                                    "<Radius>1</Radius><Radiance>1 1</Radiance></LightSphere></Objects></Scene>", "Radiance");
    expectError("noradius.xml", head + "<Objects><LightSphere id=\"1\"><Material>1</Material><Center>1</Center>"
                                       "<Radiance>1 1 1</Radiance></LightSphere></Objects></Scene>", "Radius");
    expectError("badface.xml", head + "<Objects><LightMesh id=\"1\"><Material>1</Material><Radiance>1 1 1</Radiance>"
                                      "<Faces>1 2 9</Faces></LightMesh></Objects></Scene>", "LightMesh");
    {  // other lights are not objects: a PointLight inside <Objects> is an unknown element (warned, skipped)
        Scene sc = loadScene(writeText(d, "pointobj.xml", head + "<Objects><PointLight id=\"1\"><Position>0 0 0</Position>"
                                                               "<Intensity>1 1 1</Intensity></PointLight></Objects></Scene>"));
        CHECK(sc.lights.empty());
        CHECK(sc.shapes.empty());
    }
    expectError("inlights.xml", head + "<Lights><LightSphere id=\"1\"><Radiance>1 1 1</Radiance></LightSphere></Lights>"
                                       "</Scene>", "belongs in <Objects>");
}

TEST_CASE("object lights: the device samplers equal the host references", "[objlight][lights][cl]") {
    LightsFixture f;
    std::vector<HostLight> hosts = {hostLight(f.scene, 0), hostLight(f.scene, 1), hostLight(f.scene, 2, 1.0),
                                    hostLight(f.scene, 3, 1.5), hostLight(f.scene, 4), enclosedHost(f, 5)};
    REQUIRE(hosts[5].enclosed);
    const int n = 4096;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> px(-3.5f, 2.5f), py(-2.0f, 2.0f), pz(-2.0f, 2.0f), uni(0.0f, 0.99999994f);
    std::vector<dev::float4> pts(n);
    std::vector<dev::float2> u(n);
    for (int i = 0; i < n; ++i) {
        pts[size_t(i)] = {px(rng), py(rng), pz(rng), 0};
        u[size_t(i)] = {uni(rng), uni(rng)};
    }
    for (int l = 0; l < 6; ++l) {
        INFO("light " << l);
        std::vector<dev::float4> out = deviceSamples(f.ds, l, pts, u);
        int bad = 0, lit = 0, unlit = 0, inside = 0;
        if (l == 5)  // points inside the cube: every side gets samples
            for (const dev::float4& q : pts) inside += q.x > -1.5f && q.x < -0.5f && std::fabs(q.y) < 0.5f && q.z > 0.5f && q.z < 1.5f;
        for (int i = 0; i < n; ++i) {
            D3 p = d3(pts[size_t(i)]);
            Sample h = hostSample(hosts[size_t(l)], p, u[size_t(i)].x, u[size_t(i)].y);
            const dev::float4 &e = out[2 * size_t(i)], &w = out[2 * size_t(i) + 1];
            double hm = std::max({h.e.x, h.e.y, h.e.z}), tol = 1e-3 * std::max(hm, 1e-6);
            bool zero = hm == 0;
            (zero ? unlit : lit)++;
            if (hosts[size_t(l)].sphere && dot(hosts[size_t(l)].center - p, hosts[size_t(l)].center - p) <= 2.25) ++inside;
            bool ok = std::fabs(e.x - h.e.x) <= tol && std::fabs(e.y - h.e.y) <= tol && std::fabs(e.z - h.e.z) <= tol;
            if (ok && !zero) ok = angle(d3(w), h.wi) < 2e-4 && std::fabs(e.w - h.dist) <= 1e-4 * h.dist;
            if (!ok && ++bad <= 3)
                WARN("point " << p.x << " " << p.y << " " << p.z << " u " << u[size_t(i)].x << " " << u[size_t(i)].y << ": host "
                              << h.e.x << " dist " << h.dist << ", device " << e.x << " dist " << e.w);
        }
        INFO("lit " << lit << ", unlit " << unlit << ", inside bounding sphere " << inside);
        CHECK(lit > n / 10);
        CHECK(bad <= n / 2000);  // CDF and cone-edge round-off only
        if (l == 3 || l == 5) CHECK(inside > 5);
        if (l == 3) CHECK(unlit > 20);  // points inside the ellipsoid (its object-space cone never misses)
    }
}

TEST_CASE("object lights: directions uniform in a small triangle's solid angle stay in it (float accuracy)",
          "[objlight][lights][cl]") {
    // The square LightMesh (light 0: two triangles of area 2) from points 12–45 units away, where each triangle
    // subtends 1e-3–1.5e-2 sr: every device direction must agree with the host's (Arvo's formula in double) to
    // 1e-3 of the triangle's angular size √Ω and hit the square. In float, Arvo's own formula strayed by up to
    // 1.5e-2 rad for 0.1% of such samples (object_lights.cl MeshLight_SphericalDirection).
    LightsFixture f;
    HostLight h = hostLight(f.scene, 0);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> dist(12.0, 45.0), dir(-1.0, 1.0);
    std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
    const int points = 64, per = 256, n = points * per;
    std::vector<dev::float4> pts(static_cast<size_t>(n));
    std::vector<dev::float2> u(static_cast<size_t>(n));
    for (int i = 0; i < points; ++i) {
        D3 d;
        do d = {dir(rng), dir(rng), dir(rng)};
        while (len(d) > 1 || std::fabs(unit(d).y) < 0.3);  // not grazing the square's plane
        D3 p = D3{0, 3, 0} + dist(rng) * unit(d);
        for (int j = 0; j < per; ++j) {
            pts[size_t(i * per + j)] = {float(p.x), float(p.y), float(p.z), 0};
            u[size_t(i * per + j)] = {uni(rng), uni(rng)};
        }
    }
    std::vector<dev::float4> out = deviceSamples(f.ds, 0, pts, u);
    int spherical = 0, off = 0, miss = 0;
    double worst = 0;
    for (int i = 0; i < n; ++i) {
        D3 p = d3(pts[size_t(i)]);
        Sample hs = hostSample(h, p, u[size_t(i)].x, u[size_t(i)].y);
        double omegaMax = std::max(hostSolidAngle(h.v[0], h.v[1], h.v[2], p), hostSolidAngle(h.v[3], h.v[4], h.v[5], p));
        if (hostBySolidAngle(omegaMax)) ++spherical;
        D3 w = d3(out[2 * size_t(i) + 1]);
        double rel = angle(w, hs.wi) / std::sqrt(omegaMax);
        worst = std::max(worst, rel);
        if (rel > 1e-3) ++off;
        if (!(hostPdf(h, p, unit(w)) > 0)) ++miss;
    }
    WARN(spherical << " samples: worst angle to the host's / sqrt(omega) " << worst << ", beyond 1e-3: " << off
                   << ", missing the square: " << miss);
    CHECK(spherical == n);
    CHECK(off <= n / 1000);
    CHECK(miss <= n / 1000);  // directions within rounding of the square's edges
}

TEST_CASE("object lights: samples follow the pdf (chi-square), pdf integrates to one, pdf(sample) = pdf(eval)",
          "[objlight][lights][cl]") {
    LightsFixture f;
    struct Case {
        const char* name;
        int light;
        HostLight h;
        D3 p;
    };
    std::vector<Case> cases = {{"square LightMesh", 0, hostLight(f.scene, 0), {0.3, 0.0, 0.2}},
                               {"three-triangle LightMesh", 1, hostLight(f.scene, 1), {}},
                               {"LightSphere", 2, hostLight(f.scene, 2, 1.0), {0.1, 0.4, 0.3}},
                               {"ellipsoidal LightSphere", 3, hostLight(f.scene, 3, 1.5), {-1.2, 1.9, 0.4}},
                               {"20-triangle LightMesh (by area)", 4, hostLight(f.scene, 4), {1.2, 2.2, 0.9}},
                               {"enclosed cube LightMesh (three faces seen)", 5, enclosedHost(f, 5), {0.4, 1.3, 2.6}}};
    REQUIRE(cases[3].h.ellipsoid);
    REQUIRE_FALSE(cases[2].h.ellipsoid);
    {  // the three triangles seen from their front: 2 units from their centroid along their normal
        const std::vector<D3>& v = cases[1].h.v;
        D3 centroid;
        for (const D3& q : v) centroid = centroid + (1.0 / v.size()) * q;
        cases[1].p = centroid + 2.0 * unit(cross(v[1] - v[0], v[2] - v[0]));
    }
    for (Case& c : cases) {
        INFO(c.name);
        // ∫ pdf dω over the sphere of directions = 1 (independent of the sampler's parameterisation).
        double integral = integrateSphere([&](D3 w) { return hostPdf(c.h, c.p, w); }, c.h.sphere ? 1024 : 400);
        CHECK(integral == Approx(1.0).epsilon(5e-3));
        // Device samples from the point.
        const int side = 512, N = side * side;
        std::vector<dev::float4> pts(size_t(N), dev::float4{float(c.p.x), float(c.p.y), float(c.p.z), 0});
        std::mt19937 rng(9);
        std::uniform_real_distribution<float> uni(0.0f, 0.99999994f);
        std::vector<dev::float2> u(static_cast<size_t>(N));
        for (auto& x : u) x = {uni(rng), uni(rng)};
        std::vector<dev::float4> out = deviceSamples(f.ds, c.light, pts, u);
        // Bins around the axis to the light's centre: (1 − cosθ) / (1 − cosBound) × φ.
        D3 centre = c.h.center;
        if (!c.h.sphere) {
            centre = {};
            for (const D3& v : c.h.v) centre = centre + (1.0 / c.h.v.size()) * v;
        }
        D3 axis = unit(centre - c.p), t, b;
        basis(axis, t, b);
        double cosBound = 1;
        if (c.h.sphere) cosBound = std::sqrt(1 - c.h.boundR * c.h.boundR / dot(c.h.center - c.p, c.h.center - c.p)) - 1e-6;
        else
            for (const D3& v : c.h.v) cosBound = std::min(cosBound, dot(unit(v - c.p), axis) - 1e-6);
        const int NU = 12, NV = 16, SUB = c.h.sphere ? 12 : 48;
        std::vector<double> expected(NU * NV, 0.0), observed(NU * NV, 0.0);
        double span = 1 - cosBound, binSum = 0;
        for (int i = 0; i < NU; ++i)
            for (int j = 0; j < NV; ++j)
                for (int a = 0; a < SUB; ++a)
                    for (int bb = 0; bb < SUB; ++bb) {
                        double omc = span * (i + (a + 0.5) / SUB) / NU, phi = 2 * kPi * (j + (bb + 0.5) / SUB) / NV;
                        double ct = 1 - omc, st = std::sqrt(std::max(0.0, omc * (2 - omc)));
                        D3 w = st * std::cos(phi) * t + st * std::sin(phi) * b + ct * axis;
                        double p = hostPdf(c.h, c.p, w) * (span / (NU * SUB)) * (2 * kPi / (NV * SUB));
                        expected[size_t(i * NV + j)] += p;
                        binSum += p;
                    }
        CHECK(binSum == Approx(1.0).epsilon(5e-3));  // the same integral over the bins' cone
        int pdfBad = 0, outside = 0, zero = 0;
        for (int s = 0; s < N; ++s) {
            const dev::float4 &e = out[2 * size_t(s)], &wv = out[2 * size_t(s) + 1];
            if (!(e.x > 0)) { ++zero; continue; }
            D3 w = unit(d3(wv));
            double ct = dot(w, axis), omc = 1 - ct;
            double phi = std::atan2(dot(w, b), dot(w, t));
            if (phi < 0) phi += 2 * kPi;
            int i = int(omc / span * NU), j = std::min(NV - 1, int(phi / (2 * kPi) * NV));
            if (i < 0 || i >= NU) { ++outside; continue; }
            observed[size_t(i * NV + j)] += 1;
            // an ellipsoid returns L·dω_obj/dω_world / pdf (object_lights.cl)
            double pdfDevice = c.h.radiance.x * (c.h.ellipsoid ? directionScale(c.h, w) : 1.0) / e.x;
            double pdfEval = hostPdf(c.h, c.p, w);
            if (!(std::fabs(pdfDevice - pdfEval) <= 1e-3 * pdfEval)) ++pdfBad;
        }
        // The point sees the whole light from its front; a sphere's cone-edge directions may graze it
        // and miss in float (a few in 10^5).
        CHECK(zero <= (c.h.sphere ? N / 20000 : 0));
        CHECK(outside == 0);
        CHECK(pdfBad <= N / 2000);  // edge round-off only
        double chi2 = 0, pool = 0, poolObs = 0;
        int dof = -1;
        for (size_t k = 0; k < expected.size(); ++k) {
            double e = expected[k] / binSum * N;
            if (e < 5) { pool += e; poolObs += observed[k]; continue; }
            chi2 += (observed[k] - e) * (observed[k] - e) / e;
            ++dof;
        }
        if (pool >= 5) { chi2 += (poolObs - pool) * (poolObs - pool) / pool; ++dof; }
        REQUIRE(dof > 20);
        double crit = chi2Critical(dof, 4.0);
        WARN(c.name << ": chi2 " << chi2 << " with " << dof << " dof (critical " << crit << "), integral " << integral
                    << ", over the bins " << binSum << ", pdf mismatches " << pdfBad);
        CHECK(chi2 < crit);
    }
}

TEST_CASE("object lights furnace: irradiance from a LightSphere is pi L sin^2(theta), from a square its form factor",
          "[objlight][lights][cl]") {
    LightsFixture f;
    const int side = 1024;
    std::vector<dev::float2> u = stratified(side, 3);
    // Irradiance at p with normal n from the device sampler: mean of e·max(0, n·wi) (red channel).
    auto irradiance = [&](int light, D3 p, D3 n) {
        std::vector<dev::float4> pts(u.size(), dev::float4{float(p.x), float(p.y), float(p.z), 0});
        std::vector<dev::float4> out = deviceSamples(f.ds, light, pts, u);
        double sum = 0;
        for (size_t s = 0; s < u.size(); ++s) sum += out[2 * s].x * std::max(0.0, dot(n, d3(out[2 * s + 1])));
        return sum / double(u.size());
    };
    // LightSphere (radius 1 after its transform, centre (0.5, 3, -0.2), L = 7) seen from 2.5 below its
    // centre: sinθ = 0.4. Facing it, and tilted by 30° (the cap stays above the horizon: E · cos 30°).
    D3 c{0.5, 3, -0.2}, p = c - D3{0, 2.5, 0};
    double exact = kPi * 7 * 0.16;
    double e0 = irradiance(2, p, {0, 1, 0});
    D3 tilted{std::sin(kPi / 6), std::cos(kPi / 6), 0};
    double e1 = irradiance(2, p, tilted);
    WARN("sphere: " << e0 << " vs " << exact << ", tilted " << e1 << " vs " << exact * std::cos(kPi / 6));
    CHECK(std::fabs(e0 / exact - 1) < 0.01);
    CHECK(std::fabs(e1 / (exact * std::cos(kPi / 6)) - 1) < 0.01);
    // Square LightMesh (side 2 at y = 3, facing down, L = 1) above the origin, parallel: four corner
    // rectangles 1 × 1 at distance 3; F = (1/2π)[X/√(1+X²)·atan(Y/√(1+X²)) + Y/√(1+Y²)·atan(X/√(1+Y²))].
    auto rect = [](double X, double Y) {
        double a = std::sqrt(1 + X * X), b = std::sqrt(1 + Y * Y);
        return (X / a * std::atan(Y / a) + Y / b * std::atan(X / b)) / (2 * kPi);
    };
    double F = 4 * rect(1.0 / 3, 1.0 / 3), eq = irradiance(0, {0, 0, 0}, {0, 1, 0});
    WARN("square: " << eq << " vs pi F = " << kPi * F);
    CHECK(std::fabs(eq / (kPi * F) - 1) < 0.01);
    // From above (its back face), 3 units away: the same (both faces emit).
    double back = irradiance(0, {0, 6, 0}, {0, -1, 0});
    CHECK(std::fabs(back / (kPi * F) - 1) < 0.01);
}

namespace {
// A small box: floor (kd 0.5), a mirror square at the back, a LightMesh ceiling square facing down, a
// LightSphere; camera in front. `extra`: more objects.
std::string renderSceneXml(int size, int spp, const std::string& image) {
    std::ostringstream s;
    s << "<Scene><BackgroundColor>0 0 0</BackgroundColor><MaxRecursionDepth>3</MaxRecursionDepth>"
      << "<Cameras><Camera id=\"1\" type=\"lookAt\"><Position>0 1 4</Position><GazePoint>0 1 0</GazePoint><Up>0 1 0</Up>"
      << "<FovY>70</FovY><NearDistance>1</NearDistance><ImageResolution>" << size << " " << size
      << "</ImageResolution><NumSamples>" << spp << "</NumSamples><ImageName>" << image << "</ImageName></Camera></Cameras>"
      << "<Materials><Material id=\"1\"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>"
      << "<Material id=\"2\"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance><SpecularReflectance>0.2 0.2 0.2"
      << "</SpecularReflectance><PhongExponent>10</PhongExponent></Material>"
      << "<Material id=\"3\" type=\"mirror\"><DiffuseReflectance>0 0 0</DiffuseReflectance><MirrorReflectance>0.5 0.5 0.5"
      << "</MirrorReflectance></Material></Materials>"
      << "<VertexData>-2 0 -2  2 0 -2  2 0 2  -2 0 2  -2 2 -2  2 2 -2  2 2 2  -2 2 2  -0.5 1.99 -0.5  0.5 1.99 -0.5"
      << "  0.5 1.99 0.5  -0.5 1.99 0.5  0.8 0.4 0.5</VertexData>"
      << "<Objects><Mesh id=\"1\"><Material>2</Material><Faces>1 3 2  1 4 3</Faces></Mesh>"
      << "<Mesh id=\"2\"><Material>3</Material><Faces>1 2 6  1 6 5</Faces></Mesh>"
      << "<LightMesh id=\"3\"><Material>1</Material><Radiance>3 3 3</Radiance><Faces>9 10 11  9 11 12</Faces></LightMesh>"
      << "<LightSphere id=\"4\"><Material>1</Material><Center>13</Center><Radius>0.3</Radius><Radiance>2 4 6</Radiance>"
      << "</LightSphere></Objects></Scene>";
    return s.str();
}
}  // namespace

TEST_CASE("object lights in renders: camera and mirror rays see the Radiance, on both faces of a LightMesh",
          "[objlight][render]") {
    TempDir d;
    const int W = 128;
    Scene scene = loadScene(writeText(d, "box.xml", renderSceneXml(W, 1, "box.exr")));
    ImageRGB img = renderCamera(scene, scene.cameras.at(0), 1, 1);
    Camera cam = scene.cameras.at(0);
    auto pixelOf = [&](D3 q) {  // pinhole projection onto the W×W image
        D3 rel = q - d3(cam.position);
        double x = dot(rel, d3(cam.u)), y = dot(rel, d3(cam.v)), z = -dot(rel, d3(cam.w));
        double sx = x / z * cam.nearDistance, sy = y / z * cam.nearDistance;
        int px = int((sx - cam.left) / (cam.right - cam.left) * W), py = int((cam.top - sy) / (cam.top - cam.bottom) * W);
        return std::make_pair(px, py);
    };
    // The pixel through the LightSphere's centre (0.8, 0.4, 0.5): exactly its Radiance (its material is black).
    auto [sx, sy] = pixelOf({0.8, 0.4, 0.5});
    CHECK(img.at(sx, sy, 0) == Approx(2.0f));
    CHECK(img.at(sx, sy, 1) == Approx(4.0f));
    CHECK(img.at(sx, sy, 2) == Approx(6.0f));
    // The ceiling light is seen from below (its front): 3.
    auto [cx, cy] = pixelOf({0.0, 1.99, 0.0});
    CHECK(img.at(cx, cy, 0) == Approx(3.0f));
    // The sphere's reflection in the mirror (back wall z = -2, reflectance 0.5): its mirror image at
    // (0.8, 0.4, -4.5) shows 0.5 · (2, 4, 6) where the camera ray towards it crosses the wall.
    double f = 6.0 / 8.5;
    auto [mx, my] = pixelOf({0.8 * f, 1.0 - 0.6 * f, -2.0});
    CHECK(img.at(mx, my, 0) == Approx(1.0f));
    CHECK(img.at(mx, my, 1) == Approx(2.0f));
    CHECK(img.at(mx, my, 2) == Approx(3.0f));
    // Seen from above (its back face), the ceiling light shows its Radiance too: camera moved over it.
    std::string xml = renderSceneXml(16, 1, "top.exr");
    xml = std::regex_replace(xml, std::regex("<Position>0 1 4</Position><GazePoint>0 1 0</GazePoint><Up>0 1 0</Up>"),
                             "<Position>0 3.5 0</Position><GazePoint>0 0 0</GazePoint><Up>0 0 -1</Up>");
    xml = std::regex_replace(xml, std::regex("<FovY>70</FovY>"), "<FovY>10</FovY>");
    Scene top = loadScene(writeText(d, "top.xml", xml));
    ImageRGB t = renderCamera(top, top.cameras.at(0), 1, 1);
    CHECK(t.at(8, 8, 0) == Approx(3.0f));
}

TEST_CASE("object lights: two PoCL devices render the one-device image", "[objlight][multidevice]") {
    TempDir d;
    std::string scene = writeText(d, "box.xml", renderSceneXml(96, 4, "box.exr"));
    const std::string env = "POCL_DEVICES='pthread pthread' CLRT_CACHE_DIR=" + d.file("cache") + " ";
    std::string log = d.file("devices.txt");
    std::system((env + CLRT_BINARY + " devices >" + log + " 2>&1").c_str());
    std::vector<std::string> pocl;
    std::istringstream in(readFileBytes(log));
    std::smatch m;
    for (std::string line; std::getline(in, line);)
        if (std::regex_search(line, m, std::regex("^\\[(\\d+)\\].*\\(platform: Portable Computing Language\\)")))
            pocl.push_back(m[1]);
    REQUIRE(pocl.size() == 2);
    std::filesystem::create_directories(d.file("one"));
    std::filesystem::create_directories(d.file("two"));
    auto run = [&](const std::string& args) {
        int rc = std::system((env + CLRT_BINARY + " render " + scene + " " + args + " >" + log + " 2>&1").c_str());
        INFO(readFileBytes(log));
        REQUIRE(WIFEXITED(rc));
        REQUIRE(WEXITSTATUS(rc) == 0);
    };
    run("-o " + d.file("one") + " --device " + pocl[0]);
    run("-o " + d.file("two") + " --device " + pocl[0] + "," + pocl[1]);
    ImageRGB a = readImage(d.file("one/box.exr")), b = readImage(d.file("two/box.exr"));
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(a.pixels == b.pixels);
    // Both lights reached the devices: the floor (lit by both) is lit in every quarter of the image's
    // lower half, which the tiles of both devices cover.
    double lower = 0;
    for (int y = 72; y < 96; ++y)
        for (int x = 0; x < 96; ++x) lower += a.at(x, y, 0);
    CHECK(lower > 0.05 * 24 * 96);
}

TEST_CASE("a LightSphere lights diffuse walls as a point light of intensity L pi R^2 at its centre",
          "[objlight][render]") {
    // Exact for every point that sees the whole sphere (irradiance π·L·sin²θ·cos = L·πR²·cos/d²): a box
    // of diffuse walls, a LightSphere (L = 10, R = 0.15) in the middle, then the same box with the
    // point light; the sphere's shadow rays must not hit the sphere itself (they did at grazing angles).
    auto box = [](const std::string& light, const std::string& image) {
        return "<Scene><BackgroundColor>0 0 0</BackgroundColor><Cameras><Camera id=\"1\" type=\"lookAt\">"
               "<Position>0 1 3.9</Position><GazePoint>0 1 0</GazePoint><Up>0 1 0</Up><FovY>60</FovY>"
               "<NearDistance>1</NearDistance><ImageResolution>64 64</ImageResolution><ImageName>" + image +
               "</ImageName></Camera></Cameras>" + (light[1] == 'L' && light[6] == 's' ? light : "") +
               "<Materials><Material id=\"1\"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>"
               "<Material id=\"2\"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance></Material></Materials>"
               "<VertexData>-2 0 -2  2 0 -2  2 0 4  -2 0 4  -2 2 -2  2 2 -2  2 2 4  -2 2 4  0 1 0</VertexData>"
               "<Objects><Mesh id=\"1\"><Material>2</Material><Faces>1 3 2  1 4 3  5 6 7  5 7 8  1 2 6  1 6 5"
               "  1 5 8  1 8 4  2 3 7  2 7 6</Faces></Mesh>" + (light[1] == 'L' && light[6] == 's' ? "" : light) +
               "</Objects></Scene>";
    };
    TempDir d;
    Scene sph = loadScene(writeText(d, "sphere.xml", box("<LightSphere id=\"1\"><Material>1</Material><Center>9</Center>"
                                                         "<Radius>0.15</Radius><Radiance>10 10 10</Radiance></LightSphere>",
                                                         "s.exr")));
    Scene pt = loadScene(writeText(d, "point.xml", box("<Lights><PointLight id=\"1\"><Position>0 1 0</Position>"
                                                       "<Intensity>0.70685835 0.70685835 0.70685835</Intensity>"
                                                       "</PointLight></Lights>", "p.exr")));
    REQUIRE(sph.lights.at(0).type == dev::LIGHT_SPHERE);
    REQUIRE(pt.lights.at(0).type == dev::LIGHT_POINT);
    ImageRGB a = renderCamera(sph, sph.cameras.at(0), 64, 1), b = renderCamera(pt, pt.cameras.at(0), 1, 1);
    // Blocks of 16×16 pixels away from the sphere's own image (the centre 2×2 blocks).
    ImageRGB ba = boxDownsample(a, 16), bb = boxDownsample(b, 16);
    int checked = 0;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            if ((x == 1 || x == 2) && (y == 1 || y == 2)) continue;
            INFO("block " << x << "," << y);
            CHECK(ba.at(x, y, 0) == Approx(bb.at(x, y, 0)).epsilon(0.01));
            ++checked;
        }
    CHECK(checked == 12);
}

namespace {
// The course's hw6 cornell box `name` (optionally rewritten by `edit`) rendered at `spp` with seeds 1
// and 2 against its reference EXR, all box-downsampled 8×8: relMSE(clrt, reference) ≤ 2 × relMSE(seed 1,
// seed 2), and every channel's mean within 1% of the reference's. Sampled independently, as the
// reference was, so that the two noise floors compare (the stratified sampler's is lower).
void checkHw6(const std::string& name, int spp, std::string (*edit)(const std::string&) = nullptr) {
    const std::string hw6 = sharedDir() + "/scenes/hw6/";
    std::string xml = readFileBytes(hw6 + name + ".xml");
    if (edit) xml = edit(xml);
    TempDir d;
    Scene scene = loadScene(writeText(d, "hw6.xml", xml));
    ImageRGB a = boxDownsample(renderCamera(scene, scene.cameras.at(0), spp, 1, PixelSampler::Independent), 8);
    ImageRGB b = boxDownsample(renderCamera(scene, scene.cameras.at(0), spp, 2, PixelSampler::Independent), 8);
    ImageRGB ref = boxDownsample(readImage(hw6 + "_reference_outputs/" + name + ".exr"), 8);
    REQUIRE(a.width == ref.width);
    double toRef = relativeMse(a, ref), floor = relativeMse(a, b);
    std::array<double, 3> ratio = meanRatio(a, ref);
    WARN(name << (edit ? " (edited)" : "") << " at " << spp << " spp: relMSE to reference " << toRef
              << ", between seeds " << floor << "; mean ratio " << ratio[0] << " " << ratio[1] << " " << ratio[2]);
    CHECK(toRef <= 2 * floor);
    for (double r : ratio) CHECK(std::fabs(r - 1) < 0.01);  // no bias beyond 1% in any channel's mean
}

// The copy scripts/compare_hw6_area.sh makes: no BRDF="…", DiffuseReflectance / π (ks = 0 in this
// scene, so this is exactly the normalized ModifiedPhong the reference was rendered with).
std::string kdOverPi(const std::string& xml) {
    std::string t = std::regex_replace(xml, std::regex(" BRDF=\"[^\"]*\""), ""), out;
    std::smatch m;
    std::regex kd("<DiffuseReflectance>([^<]*)</DiffuseReflectance>");
    while (std::regex_search(t, m, kd)) {
        std::istringstream v(m[1].str());
        std::ostringstream o;
        o.precision(9);
        for (double x; v >> x;) o << x / kPi << " ";
        out += m.prefix().str() + "<DiffuseReflectance>" + o.str() + "</DiffuseReflectance>";
        t = m.suffix().str();
    }
    return out + t;
}
}  // namespace

// Reduced from the references' 100 spp to 16 (full 512², so the 8×8 blocks are the script's); the
// full-size check is scripts/compare_hw6_area.sh. The diffuse box's light is its ceiling (a LightMesh of two
// triangles), which clrt samples uniformly in solid angle (object_lights.cl): its noise at 16 spp (floor/2
// 0.00016) is a quarter of the course reference's own at 100 spp (about 0.0006, by the area sampler's noise
// scaled to 100 spp), which relMSE to the reference adds; at 4 spp clrt's noise is again the larger, as the
// check assumes.
TEST_CASE("hw6 cornellbox_jaroslav_diffuse_area (kd/pi copy, no BRDFs) matches its reference at 4 spp",
          "[objlight][shared][hw6]") {
    if (!haveShared()) {
        WARN("../shared is not present: skipped");
        return;
    }
    checkHw6("cornellbox_jaroslav_diffuse_area", 4, kdOverPi);
}

TEST_CASE("hw6 cornellbox_jaroslav_diffuse_area and glossy_area_sphere (BRDF materials) match at 4 and 16 spp",
          "[objlight][shared][hw6]") {
#ifndef CLRT_BRDF_TABLE
    WARN("this build has no BRDFs (CLRT_BRDF_TABLE): the BRDF-material scenes are checked once they land");
#else
    if (!haveShared()) {
        WARN("../shared is not present: skipped");
        return;
    }
    checkHw6("cornellbox_jaroslav_diffuse_area", 4);  // 4 spp: see the comment above the test before
    checkHw6("cornellbox_jaroslav_glossy_area_sphere", 16);
#endif
}

namespace {
// A depth-1 path-traced scene with RendererParams `params`: a diffuse floor (kd 0.3) in a box of black walls
// (y 0..2), a 32² camera at (0, 1, 3.9) looking at (0, gazeY, 0), and `light` (an object light) with its
// `transforms` and the vertices it adds after the box's eight (`extraVertices`: its indices start at 9).
std::string darkBoxScene(const std::string& params, const std::string& gazeY, const std::string& transforms,
                         const std::string& extraVertices, const std::string& light) {
    return "<Scene><MaxRecursionDepth>1</MaxRecursionDepth><BackgroundColor>0 0 0</BackgroundColor><Cameras>"
           "<Camera id=\"1\" type=\"lookAt\"><Position>0 1 3.9</Position><GazePoint>0 " + gazeY + " 0</GazePoint>"
           "<Up>0 1 0</Up><FovY>60</FovY><NearDistance>1</NearDistance><ImageResolution>32 32</ImageResolution>"
           "<ImageName>e.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>" + params +
           "</RendererParams></Camera></Cameras>"
           "<Materials><Material id=\"1\"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>"
           "<Material id=\"2\"><DiffuseReflectance>0.3 0.3 0.3</DiffuseReflectance></Material></Materials>" + transforms +
           "<VertexData>-2 0 -2  2 0 -2  2 0 4  -2 0 4  -2 2 -2  2 2 -2  2 2 4  -2 2 4  " + extraVertices + "</VertexData>"
           "<Objects><Mesh id=\"1\"><Material>2</Material><Faces>1 3 2  1 4 3</Faces></Mesh>"
           "<Mesh id=\"2\"><Material>1</Material><Faces>5 6 7  5 7 8  1 2 6  1 6 5  1 5 8  1 8 4  2 3 7  2 7 6</Faces></Mesh>" +
           light + "</Objects></Scene>";
}

// The same light three ways, `scene(RendererParams)` (a darkBoxScene) at `spp`: NEE (with importance
// sampling), MIS through each of `misPipelines`, and BSDF rays alone (four seeds: the noisiest, so they give
// each block's spread). In 8×8 blocks, every block the BSDF renders light (their mean m, its sigma) holds the
// NEE render's value a and each MIS render's b within 4 sigmas (at most one block off), and b within
// `misTol` of a (both low-noise).
void checkSameLight(const std::function<std::string(const std::string&)>& scene, int spp,
                    std::initializer_list<Pipeline> misPipelines, double misTol) {
    TempDir d;
    Scene nee = loadScene(writeText(d, "nee.xml", scene("NextEventEstimation ImportanceSampling")));
    Scene mis = loadScene(writeText(d, "mis.xml", scene("MultipleImportanceSampling")));
    Scene bsdf = loadScene(writeText(d, "bsdf.xml", scene("ImportanceSampling")));
    const ImageRGB a = boxDownsample(renderCamera(nee, nee.cameras.at(0), spp, 1), 8);
    const DeviceScene misDs = flattenScene(mis);
    std::vector<ImageRGB> bs, c;
    for (Pipeline p : misPipelines) bs.push_back(boxDownsample(renderPipeline(misDs, mis.cameras.at(0), p, spp), 8));
    for (uint32_t seed = 3; seed < 7; ++seed) c.push_back(boxDownsample(renderCamera(bsdf, bsdf.cameras.at(0), spp, seed), 8));
    int checked = 0, far = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            double m = 0, v = 0;
            for (const ImageRGB& img : c) m += img.at(x, y, 0) / c.size();
            for (const ImageRGB& img : c) v += (img.at(x, y, 0) - m) * (img.at(x, y, 0) - m) / (c.size() - 1);
            double sigma = std::sqrt(v / c.size()) + 1e-3 * m;  // of the mean of the four
            if (!(m > 1e-3)) continue;
            ++checked;
            bool off = std::fabs(a.at(x, y, 0) - m) > 4 * sigma;
            for (const ImageRGB& b : bs) {
                INFO("block " << x << "," << y << ": nee " << a.at(x, y, 0) << ", mis " << b.at(x, y, 0) << ", bsdf " << m
                              << " ± " << sigma);
                off = off || std::fabs(b.at(x, y, 0) - m) > 4 * sigma;
                CHECK(b.at(x, y, 0) == Approx(a.at(x, y, 0)).epsilon(misTol));
            }
            if (off && far < 4) WARN("block " << x << "," << y << ": nee " << a.at(x, y, 0) << ", bsdf " << m << " ± " << sigma);
            far += off;
        }
    CHECK(checked >= 8);  // the floor's blocks (the walls are black)
    CHECK(far <= 1);
}

// A darkBoxScene lit by a LightSphere scaled (4, 1, 1) above the floor (sampled in object space: object_lights.cl).
std::string ellipsoidLightScene(const std::string& params) {
    return darkBoxScene(params, "1",
                        "<Transformations><Scaling id=\"1\">4 1 1</Scaling><Translation id=\"1\">0 1.6 0</Translation>"
                        "</Transformations>",
                        "0 0 0",
                        "<LightSphere id=\"1\"><Material>1</Material><Center>9</Center><Radius>0.2</Radius>"
                        "<Radiance>10 10 10</Radiance><Transformations>s1 t1</Transformations></LightSphere>");
}

// A darkBoxScene lit by a box of ten LightMesh triangles, as the hw6 boxes' light (five faces, open at the top,
// closed off by the ceiling), here large and close to the floor.
std::string lightMeshBoxScene(const std::string& params) {
    return darkBoxScene(params, "0.6", "",
                        "-0.8 1.2 -0.8  0.8 1.2 -0.8  0.8 1.2 0.8  -0.8 1.2 0.8  -0.8 2 -0.8  0.8 2 -0.8  0.8 2 0.8  -0.8 2 0.8",
                        "<LightMesh id=\"1\"><Material>1</Material><Radiance>10 10 10</Radiance><Faces>"
                        "9 10 11  9 11 12  9 13 14  9 14 10  10 14 15  10 15 11  11 15 16  11 16 12  12 16 13  12 13 9"
                        "</Faces></LightMesh>");
}

// The same light box with each face cut into four triangles around its centre: 20 triangles, more than
// CLRT_MESHLIGHT_PICK_MAX, so picked by area (then a direction in the triangle's solid angle).
std::string lightMeshBox20Scene(const std::string& params) {
    return darkBoxScene(params, "0.6", "",
                        "-0.8 1.2 -0.8  0.8 1.2 -0.8  0.8 1.2 0.8  -0.8 1.2 0.8  -0.8 2 -0.8  0.8 2 -0.8  0.8 2 0.8  -0.8 2 0.8"
                        "  0 1.2 0  0 1.6 -0.8  0.8 1.6 0  0 1.6 0.8  -0.8 1.6 0",
                        "<LightMesh id=\"1\"><Material>1</Material><Radiance>10 10 10</Radiance><Faces>"
                        "9 10 17  10 11 17  11 12 17  12 9 17  9 13 18  13 14 18  14 10 18  10 9 18  "
                        "10 14 19  14 15 19  15 11 19  11 10 19  11 15 20  15 16 20  16 12 20  12 11 20  "
                        "12 16 21  16 13 21  13 9 21  9 12 21</Faces></LightMesh>");
}
}  // namespace

TEST_CASE("an ellipsoidal LightSphere gives the same light by NEE, by MIS and by BSDF rays alone", "[objlight][path][render]") {
    // A box with a diffuse floor and black walls lit by a LightSphere scaled (4, 1, 1) (object_lights.cl:
    // sampled in object space; what it gives the scene is Radiance·dω_obj/dω_world, and BSDF rays that
    // hit it after a diffuse bounce see that too). Path traced to depth 1 three ways: NEE, NEE with MIS,
    // and BSDF sampling alone; with black walls (NEE at the bounce's vertex adds nothing) all three
    // estimate the floor's direct light: 8×8 blocks within 4 sigmas of the BSDF renders' mean.
    checkSameLight(ellipsoidLightScene, 256, {Pipeline::Auto}, 0.03);
}

TEST_CASE("a LightMesh box gives the same light by NEE, by MIS and by BSDF rays alone", "[objlight][path][render]") {
    // A box of LightMesh triangles as the hw6 boxes' light (five faces, open at the top, closed off by the
    // ceiling), here large and close to the floor so that light and BSDF densities are alike, which picks its
    // triangles by their weight from the shading point (object_lights.cl, MeshLight_PickByWeight); a BSDF ray
    // that hits it gets the same density for MIS (path.cl Path_ObjectLightPdf, MeshLight_InvAreaPdf). Depth 1, black walls: the three estimate the floor's
    // direct light; MIS weights that do not sum to one (a hit density that is not the sampler's) show as a
    // difference between MIS and NEE. 8×8 blocks within 4 sigmas of the BSDF renders' mean, MIS within 1% of NEE.
    // MIS through each pipeline: the lanes (Lanes_MeshLightInvAreaPdf), render_fused and the wavefront
    // (Path_ObjectLightPdf) compute the hit's density each.
    checkSameLight(lightMeshBoxScene, 1024, {Pipeline::Lanes, Pipeline::Fused, Pipeline::Wavefront}, 0.01);
}

TEST_CASE("a LightMesh box of 20 triangles (picked by area) gives the same light by NEE, by MIS and by BSDF rays alone",
          "[objlight][path][render]") {
    // As the test before, with the box's faces cut into four triangles each: picked by area, then a direction
    // uniform in the triangle's solid angle; a BSDF ray that hits it gets that density for MIS
    // (MeshLight_InvAreaPdf's by-area branch).
    checkSameLight(lightMeshBox20Scene, 1024, {Pipeline::Lanes, Pipeline::Fused, Pipeline::Wavefront}, 0.01);
}

TEST_CASE("object lights: emission-only segments are tested against the lights alone first, the image unchanged",
          "[objlight][path][render]") {
    // Under MIS the last vertex's BSDF sample goes out as an emission-only segment (path.cl): it brings back only
    // the emission of an object light it hits first. Where the lights a ray can hit are at most
    // CLRT_EMITTER_TEST_MAX primitives and no environment light shines (SceneParams.emitterTest, set by
    // flatten_lights.cpp), such a ray is first tested against those alone (Path_BoundEmissionOnly): not traced
    // when it meets none, traced up to just past the nearest when it does. The image must be the one of tracing
    // every such ray (the flag cleared), bit for bit, in the lanes, render_fused and the wavefront; the segments carry light
    // in these scenes (depth 0: the floor's MIS-weighted BSDF samples of the light; with the box moved off the lights
    // the image darkens, 0.9% with the large light box, 0.006% with the small sphere);
    // the box holds every light's primitives.
    auto depth0 = [](std::string xml) {
        const std::string from = "<MaxRecursionDepth>1</MaxRecursionDepth>";
        REQUIRE(xml.find(from) != std::string::npos);
        return xml.replace(xml.find(from), from.size(), "<MaxRecursionDepth>0</MaxRecursionDepth>");
    };
    const std::string mis = "MultipleImportanceSampling";
    struct Case { const char* name; std::string xml; int emitterTest; };
    const Case cases[] = {{"LightMesh box of 10 triangles", depth0(lightMeshBoxScene(mis)), 1},
                          {"ellipsoidal LightSphere", depth0(ellipsoidLightScene(mis)), 1},
                          {"LightMesh box of 20 triangles", depth0(lightMeshBox20Scene(mis)), 0}};
    TempDir d;
    int compared = 0;
    for (const Case& c : cases) {
        INFO(c.name);
        const Scene scene = loadScene(writeText(d, "s.xml", c.xml));
        const DeviceScene ds = flattenScene(scene);
        CHECK(ds.params.emitterTest == c.emitterTest);
        const dev::float4 lo = ds.params.emitterLo, hi = ds.params.emitterHi;
        auto inBox = [&](float x, float y, float z, float r) {
            return x - r >= lo.x && y - r >= lo.y && z - r >= lo.z && x + r <= hi.x && y + r <= hi.y && z + r <= hi.z;
        };
        for (const dev::Light& l : ds.lights) {
            if (!ds.params.emitterTest) break;
            for (int i = 0; l.kind == dev::LIGHT_MESH && i < 3 * l.objCount; ++i) {
                const dev::float4& v = ds.lightData[size_t(l.objFirst + i)];
                CHECK(inBox(v.x, v.y, v.z, 0.0f));
            }
            if (l.kind == dev::LIGHT_SPHERE) CHECK(inBox(l.position.x, l.position.y, l.position.z, l.objRadius));
        }
        if (!c.emitterTest) continue;
        DeviceScene traced = ds, empty = ds;
        traced.params.emitterTest = 0;
        empty.params.emitterLo = empty.params.emitterHi = {1e6f, 1e6f, 1e6f, 0}; /* a box away from the lights */
        for (Pipeline p : {Pipeline::Lanes, Pipeline::Fused, Pipeline::Wavefront}) {
            const ImageRGB a = renderPipeline(ds, scene.cameras.at(0), p, 16, 1);
            CHECK(differingFloats(a, renderPipeline(traced, scene.cameras.at(0), p, 16, 1)) == 0);
            const ImageRGB e = renderPipeline(empty, scene.cameras.at(0), p, 16, 1);
            auto sum = [](const ImageRGB& img) { double t = 0; for (float v : img.pixels) t += v; return t; };
            CHECK(differingFloats(a, e) > 0);
            CHECK(sum(e) < sum(a));
            ++compared;
        }
    }
    CHECK(compared == 6);
    if (haveShared()) {  // a point light beside the LightMesh: no ray hits it, the test stays on
        const DeviceScene box = flattenScene(loadScene(sharedDir() + "/scenes/hw6/cornellbox_jaroslav_path_diffuse.xml"));
        CHECK(box.params.numLights == 2);
        CHECK(box.params.emitterTest == 1);
    }
}

TEST_CASE("clrt render --mesh-light-sampling: solid-angle by default, area on request, anything else a usage error",
          "[objlight][cli]") {
    TempDir d;
    std::string xml = lightMeshBoxScene("NextEventEstimation ImportanceSampling");
    xml = std::regex_replace(xml, std::regex("<ImageResolution>32 32</ImageResolution>"), "<ImageResolution>8 8</ImageResolution>");
    writeText(d, "box.xml", xml);
    const std::string base = "render " + d.file("box.xml") + " -o " + d.path.string() + " --spp 4 --seed 2" + deviceArg();
    auto render = [&](const std::string& extra) { return renderedPixels(base + extra, d.file("log"), d.file("e.exr")); };
    const std::vector<float> def = render(""), solid = render(" --mesh-light-sampling solid-angle"),
                             area = render(" --mesh-light-sampling area");
    CHECK(def == solid);
    CHECK(def != area);
    const int rc = runClrt(base + " --mesh-light-sampling cosine", d.file("log"));
    const CliResult r = cliResult(rc, readFileBytes(d.file("log")));
    CHECK(r.rc == 1);
    CHECK(r.errorLines == 1);
    CHECK(readFileBytes(d.file("log")).find("--mesh-light-sampling") != std::string::npos);
}

TEST_CASE("--mesh-light-sampling area: the LightMesh box's light is the same, with more noise", "[objlight][path][render]") {
    // NEE at depth 1 (the floor's direct light) with directions uniform in the picked triangle's solid angle
    // (the default) and by area (FeatureSet::meshLightsByArea, CLRT_MESHLIGHT_BY_AREA: the course's renderer),
    // two seeds each, in 8×8 blocks: the two samplers' means differ by what their noise allows (the blocks'
    // mean squared relative difference at most 3× its expectation (n_sa + n_area) / 4, n the blocks' mean
    // squared relative difference between seeds), and the area sampler is the noisier.
    TempDir d;
    Scene nee = loadScene(writeText(d, "nee.xml", lightMeshBoxScene("NextEventEstimation ImportanceSampling")));
    const DeviceScene dsSolid = flattenScene(nee);
    DeviceScene dsArea = flattenScene(nee);
    dsArea.features.meshLightsByArea = true;
    std::vector<ImageRGB> sa, ar;
    for (uint32_t seed = 1; seed <= 2; ++seed) {
        sa.push_back(boxDownsample(renderPipeline(dsSolid, nee.cameras.at(0), Pipeline::Auto, 64, seed), 8));
        ar.push_back(boxDownsample(renderPipeline(dsArea, nee.cameras.at(0), Pipeline::Auto, 64, seed), 8));
    }
    double nSolid = 0, nArea = 0, diff = 0;
    int blocks = 0;
    for (int y = 0; y < sa[0].height; ++y)
        for (int x = 0; x < sa[0].width; ++x) {
            const double a1 = sa[0].at(x, y, 0), a2 = sa[1].at(x, y, 0), b1 = ar[0].at(x, y, 0), b2 = ar[1].at(x, y, 0);
            const double m = 0.25 * (a1 + a2 + b1 + b2);
            if (!(m > 1e-3)) continue;  // the black walls
            ++blocks;
            nSolid += (a1 - a2) * (a1 - a2) / (m * m);
            nArea += (b1 - b2) * (b1 - b2) / (m * m);
            diff += (0.5 * (a1 + a2) - 0.5 * (b1 + b2)) * (0.5 * (a1 + a2) - 0.5 * (b1 + b2)) / (m * m);
        }
    REQUIRE(blocks >= 8);
    nSolid /= blocks;
    nArea /= blocks;
    diff /= blocks;
    WARN("blocks " << blocks << ": noise between seeds, solid angle " << nSolid << ", area " << nArea
                   << "; squared difference of the means " << diff << " (expected " << 0.25 * (nSolid + nArea) << ")");
    CHECK(diff <= 3 * 0.25 * (nSolid + nArea));
    CHECK(nArea > 2 * nSolid);
}
