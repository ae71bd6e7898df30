// Plain C++ reference intersection routines: the watertight ray/triangle test of Woop, Benthin &
// Wald (JCGT 2013) with a consistent tie-break on shared edges and vertices, the numerically stable
// ray/sphere test of Ray Tracing Gems ch. 7, and a near-first BVH traversal (closest hit and any
// hit). Tests use them as the ground truth the OpenCL kernels are compared against.
#pragma once
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "bvh/bvh.h"
#include "util/math.h"

namespace clrt {

namespace detail {

// Whether the ray's 2D point (the origin of the projected space) counts as inside the half-plane of
// one triangle edge. e: edge function value; (gx, gy): its gradient; positive: whether the
// triangle's interior is where e > 0. A point exactly on the edge (e == 0) belongs to the side
// that a tiny move along (1, +tiny) enters, so of two triangles on opposite sides of a shared edge
// exactly one owns it (the same rule settles vertices shared by a fan).
template <class Real>
inline bool insideEdge(Real e, float gx, float gy, bool positive) {
    if (e != 0) return (e > 0) == positive;
    if (!positive) { gx = -gx; gy = -gy; }
    return gx > 0 || (gx == 0 && gy > 0);
}

// The part of the watertight test after the edge functions; Real is float, or double when a float
// edge function came out as exactly zero (its sign is then recomputed exactly).
template <class Real>
inline bool finishTriangle(Real U, Real V, Real W, const float* Ax, const float* Bx, const float* Cx,
                           float tMax, float& t, float& b1, float& b2) {
    // Ax/Bx/Cx: projected x, y and scaled z of each vertex.
    if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0)) return false;
    Real det = U + V + W;
    if (det == 0) return false;
    bool pos = det > 0;
    if (!insideEdge(U, Cx[1] - Bx[1], Bx[0] - Cx[0], pos)) return false;  // edge B-C
    if (!insideEdge(V, Ax[1] - Cx[1], Cx[0] - Ax[0], pos)) return false;  // edge C-A
    if (!insideEdge(W, Bx[1] - Ax[1], Ax[0] - Bx[0], pos)) return false;  // edge A-B
    Real T = U * Real(Ax[2]) + V * Real(Bx[2]) + W * Real(Cx[2]);
    float tt = float(T / det);
    if (!(tt > 0 && tt < tMax)) return false;
    t = tt;
    b1 = float(V / det);
    b2 = float(W / det);
    return true;
}

}  // namespace detail

// Watertight ray/triangle test (Woop, Benthin & Wald 2013), no backface culling, no epsilon.
// On a hit with 0 < t < tMax returns true with t and the barycentrics of v1 (b1) and v2 (b2):
// p = (1 - b1 - b2) v0 + b1 v1 + b2 v2. dir need not be normalized.
inline bool intersectTriangleWatertight(const Vec3& org, const Vec3& dir, const Vec3& v0,
                                        const Vec3& v1, const Vec3& v2, float tMax, float& t,
                                        float& b1, float& b2) {
    // Permute so that z is the largest direction component, keeping the winding.
    float ax = std::fabs(dir.x), ay = std::fabs(dir.y), az = std::fabs(dir.z);
    int kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (dir[kz] < 0) std::swap(kx, ky);
    if (!(dir[kz] != 0)) return false;  // zero or NaN direction
    // Shear so the ray becomes the +z axis through the origin.
    float Sx = dir[kx] / dir[kz], Sy = dir[ky] / dir[kz], Sz = 1.0f / dir[kz];
    Vec3 A = v0 - org, B = v1 - org, C = v2 - org;
    float Ap[3] = {A[kx] - Sx * A[kz], A[ky] - Sy * A[kz], Sz * A[kz]};
    float Bp[3] = {B[kx] - Sx * B[kz], B[ky] - Sy * B[kz], Sz * B[kz]};
    float Cp[3] = {C[kx] - Sx * C[kz], C[ky] - Sy * C[kz], Sz * C[kz]};
    // Edge functions. A float result is zero or has the exact sign (rounding is monotone), so only
    // zeros need the exact double evaluation (products of floats are exact in double).
    float U = Cp[0] * Bp[1] - Cp[1] * Bp[0];
    float V = Ap[0] * Cp[1] - Ap[1] * Cp[0];
    float W = Bp[0] * Ap[1] - Bp[1] * Ap[0];
    if (U == 0 || V == 0 || W == 0) {
        double Ud = double(Cp[0]) * Bp[1] - double(Cp[1]) * Bp[0];
        double Vd = double(Ap[0]) * Cp[1] - double(Ap[1]) * Cp[0];
        double Wd = double(Bp[0]) * Ap[1] - double(Bp[1]) * Ap[0];
        return detail::finishTriangle<double>(Ud, Vd, Wd, Ap, Bp, Cp, tMax, t, b1, b2);
    }
    return detail::finishTriangle<float>(U, V, W, Ap, Bp, Cp, tMax, t, b1, b2);
}

// Ray/sphere test after Haines et al., "Precision Improvements for Ray/Sphere Intersection" (Ray
// Tracing Gems ch. 7): the discriminant comes from the perpendicular offset |f - (f.d)d| instead
// of b^2 - c, and the roots from the stable form q = b + sign(b) sqrt(disc), x0 = c / q, x1 = q.
// Returns the nearest root with 0 < t < tMax; dir need not be normalized.
inline bool intersectSphere(const Vec3& org, const Vec3& dir, const Vec3& center, float radius,
                            float tMax, float& t) {
    float len = length(dir);
    if (!(len > 0) || !std::isfinite(len)) return false;
    Vec3 d = dir / len;
    Vec3 f = org - center;
    float b = -dot(f, d);             // distance along d to the point closest to the centre
    Vec3 l = f + b * d;               // offset from the centre to that point
    float r2 = radius * radius;
    float disc = r2 - dot(l, l);
    if (!(disc >= 0)) return false;
    float c = dot(f, f) - r2;
    float q = b + std::copysign(std::sqrt(disc), b);
    if (q == 0) return false;         // both roots at the origin
    float x0 = c / q, x1 = q;
    if (x0 > x1) std::swap(x0, x1);
    float x = x0 > 0 ? x0 : x1;
    float tt = x / len;
    if (!(tt > 0 && tt < tMax)) return false;
    t = tt;
    return true;
}

namespace detail {

// Precomputed per-ray data for the slab test.
struct SlabRay {
    Vec3 org, inv;
    bool flat[3];  // direction component is zero (or so small 1/d overflows)
    SlabRay(const Vec3& o, const Vec3& d) : org(o) {
        for (int a = 0; a < 3; ++a) {
            float r = 1.0f / d[a];
            flat[a] = !std::isfinite(r);
            inv[a] = flat[a] ? 0.f : r;
        }
    }
};

// Conservative slab test. The box is padded by a few ulps of its extent around the ray origin, so
// rounding (here and in the watertight triangle test, whose hit may lie a few ulps outside the
// triangle's box) never culls a primitive that the brute-force loop would hit.
inline bool slab(const BvhNode& nd, const SlabRay& r, float tMax, float& tNear) {
    float lo[3] = {nd.boundsMin.x - r.org.x, nd.boundsMin.y - r.org.y, nd.boundsMin.z - r.org.z};
    float hi[3] = {nd.boundsMax.x - r.org.x, nd.boundsMax.y - r.org.y, nd.boundsMax.z - r.org.z};
    float m = 0;
    for (int a = 0; a < 3; ++a) m = std::max(m, std::max(std::fabs(lo[a]), std::fabs(hi[a])));
    float pad = m * 1e-6f + FLT_MIN;
    float t0 = 0, t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        float l = lo[a] - pad, h = hi[a] + pad;
        if (r.flat[a]) {
            if (!(l <= 0 && h >= 0)) return false;
            continue;
        }
        float ta = l * r.inv[a], tb = h * r.inv[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    tNear = t0;
    return t0 <= t1 * (1 + 4 * FLT_EPSILON);
}

// Shared walk: near child first (by the split axis and the direction's sign), far child on a
// stack of CLRT_BVH_STACK_SIZE entries like the device. test(prim, tMax) returns true to stop.
template <class F>
bool walkBvh(const Bvh& bvh, const Vec3& org, const Vec3& dir, float& tMax, F&& test) {
    if (bvh.primRefs.empty() || bvh.nodes.empty()) return false;
    SlabRay ray(org, dir);
    int stack[CLRT_BVH_STACK_SIZE];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const BvhNode& nd = bvh.nodes[size_t(stack[--sp])];
        float tNear;
        if (!slab(nd, ray, tMax, tNear)) continue;
        if (nd.count > 0) {
            for (int i = nd.first; i < nd.first + nd.count; ++i)
                if (test(bvh.primRefs[size_t(i)], tMax)) return true;
            continue;
        }
        if (sp + 2 > CLRT_BVH_STACK_SIZE) throw std::logic_error("BVH traversal stack overflow");
        int left = int(&nd - bvh.nodes.data()) + 1, right = nd.first;
        bool flip = dir[nd.axis] < 0;
        stack[sp++] = flip ? left : right;  // far child
        stack[sp++] = flip ? right : left;  // near child, popped next
    }
    return false;
}

}  // namespace detail

// Closest-hit traversal: calls testPrim(primRef, tMax) for every primitive whose leaf the ray
// reaches before tMax; testPrim shrinks tMax when it finds a closer hit.
template <class F>
void traverseBvh(const Bvh& bvh, const Vec3& org, const Vec3& dir, float& tMax, F&& testPrim) {
    detail::walkBvh(bvh, org, dir, tMax, [&](int prim, float& tm) {
        testPrim(prim, tm);
        return false;
    });
}

// Any-hit traversal (shadow rays): testPrim(primRef, tMax) returns true on a hit in (0, tMax);
// traversal stops at the first one. Returns whether there was a hit.
template <class F>
bool anyHit(const Bvh& bvh, const Vec3& org, const Vec3& dir, float tMax, F&& testPrim) {
    return detail::walkBvh(bvh, org, dir, tMax,
                           [&](int prim, float& tm) { return bool(testPrim(prim, tm)); });
}

}  // namespace clrt
