/* object_lights.cl — sampling the object lights (LightMesh, LightSphere: shapes in <Objects> that are
 * lights too) and the emission a ray sees when it hits one. Their data (world-space triangles with an
 * area CDF; a sphere's object-space centre, radius and worldToObject rows) is in the lightData buffer,
 * laid out as device_types.h describes next to struct Light (written by src/flatten/flatten_lights.cpp).
 * Both return, like every Light_Sample case, L(wi) / pdf(wi) for the sampled direction wi (solid angle).
 *   LightMesh:   a triangle, then a direction in it; both faces emit (the AreaLight rule, SCENE_FORMAT.md
 *                conventions). A mesh of at most CLRT_MESHLIGHT_PICK_MAX triangles picks triangle k by its
 *                weight seen from the shading point p (MeshLight_Weight: about half its solid angle Ω_k, 0
 *                where p lies in its plane), so that the triangles that fill p's view of the light get the
 *                samples: P(k) = w_k / Σw; a larger mesh picks by area (binary search of the CDF): P(k) =
 *                A_k / A. Then a direction uniform in Ω_k (MeshLight_SphericalDirection): pdf P(k) / Ω_k;
 *                where Ω_k is too small or too large for that in float, a uniform point on the triangle:
 *                pdf over the area P(k) / A_k, in solid angle that times d²/|cosθ_L|. A BSDF ray that hits
 *                the mesh gets the same density (MeshLight_InvAreaPdf, from its origin: path.cl
 *                Path_ObjectLightPdf). clrt render --mesh-light-sampling area (CLRT_MESHLIGHT_BY_AREA):
 *                every mesh by area, a uniform point, as the course's renderer.
 *   LightSphere: under a similarity, a direction uniform in the cone the sphere subtends: pdf
 *                1/(2π(1 − cosθmax)) (from inside: all directions, 1/4π; the inside emits nothing); under
 *                any other transform (an ellipsoid) the same in object space, from the object-space
 *                shading point, the value divided by that object-space pdf: the light gives the scene
 *                Radiance·dω_obj/dω_world along each world direction (SphereLight_DirectionScale: the
 *                course's ellipsoid reference); a ray that sees it directly (camera, mirror) sees Radiance. */
#ifndef CLRT_OBJECT_LIGHTS_CL
#define CLRT_OBJECT_LIGHTS_CL

#include "../src/shared/device_types.h"
#include "common.cl"

#if defined(CLRT_HAS_LIGHT_MESH) || defined(CLRT_HAS_LIGHT_SPHERE)
#define CLRT_HAS_OBJECT_LIGHTS 1
#endif

/* The triangle of a LightMesh whose CDF interval holds u (first k with cdf[k] > u); *uRest: u
 * rescaled to [0, 1) inside that interval. */
inline int MeshLight_PickTriangle(const __global float4* tri, int n, float u, float* uRest) {
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (tri[3 * mid].w > u) hi = mid;
        else lo = mid + 1;
    }
    float c0 = lo > 0 ? tri[3 * (lo - 1)].w : 0.0f, c1 = tri[3 * lo].w;
    *uRest = c1 > c0 ? clamp((u - c0) / (c1 - c0), 0.0f, 0.99999994f) : 0.5f;
    return lo;
}

/* A LightMesh of at most this many triangles picks them by MeshLight_Weight from the shading point (their
 * weights are computed for every light sample: the cost grows with the count); larger ones by area. With
 * CLRT_MESHLIGHT_BY_AREA (clrt render --mesh-light-sampling area: the course renderer's noise) every mesh
 * picks by area. */
#ifdef CLRT_MESHLIGHT_BY_AREA
#define CLRT_MESHLIGHT_PICK_MAX 0
#else
#define CLRT_MESHLIGHT_PICK_MAX 16
#endif
/* MeshLight_Weight's largest value: tan(Ω/2) at Ω ≈ 0.92π (p close to a large triangle). */
#define CLRT_MESHLIGHT_WEIGHT_CAP 8.0f

/* tan(Ω/2) = *num / *den of the solid angle Ω that light triangle (a, b, c) subtends at p (Van Oosterom and
 * Strackee's formula; *den < 0 where Ω > π). The triple product ra·(rb×rc) as ra·((b − a)×(c − a)) (equal):
 * the cross product of the short edges keeps its digits where p is far or near the triangle's plane (the
 * long vectors' lost up to all of them: Ω then the sampler's pdf). */
inline void MeshLight_Subtended(float3 a, float3 b, float3 c, float3 p, float* num, float* den) {
    const float3 ra = a - p, rb = b - p, rc = c - p;
    const float la = sqrt(dot(ra, ra)), lb = sqrt(dot(rb, rb)), lc = sqrt(dot(rc, rc)); /* as the lanes' */
    *num = fabs(dot(ra, cross(b - a, c - a)));
    *den = la * lb * lc + dot(ra, rb) * lc + dot(ra, rc) * lb + dot(rb, rc) * la;
}

/* The weight of light triangle (a, b, c) seen from p: tan(Ω/2) of its solid angle Ω (MeshLight_Subtended),
 * at most CLRT_MESHLIGHT_WEIGHT_CAP; 0 where p lies in the triangle's plane, which then shows p nothing
 * (cosθ_L = 0 everywhere on it). For small Ω about Ω/2: a triangle gets samples in proportion to how much
 * of p's view it fills. Any positive weight keeps the estimate unbiased; the host reference is
 * tests/test_object_lights.cpp hostWeight. MeshLight_WeightOf: the same from MeshLight_Subtended's num, den. */
inline float MeshLight_WeightOf(float num, float den) {
    if (!(num > 0.0f)) return 0.0f;
    return den * CLRT_MESHLIGHT_WEIGHT_CAP > num ? num / den : CLRT_MESHLIGHT_WEIGHT_CAP;
}
inline float MeshLight_Weight(float3 a, float3 b, float3 c, float3 p) {
    float num, den;
    MeshLight_Subtended(a, b, c, p, &num, &den);
    return MeshLight_WeightOf(num, den);
}

/* An enclosed LightMesh (Light.position.w > 0) bounds a closed convex volume around the point
 * Light.position.xyz (src/flatten/light_enclosure.h: its openings, if any, under opaque scene geometry). A
 * point p outside it sees only the triangles' outer sides: a triangle that shows p its inner side (p on the
 * same side of its plane as the inside point) lies behind the others, no shadow ray reaches it, and it gets
 * weight 0 (MeshLight_Weights). From inside, every triangle keeps its weight. MeshLight_Facing of triangle
 * (a, b, c): 1 where p sees its inner side, -1 where p lies on its outer side by more than rounding (so p is
 * outside the volume), else 0. The host reference is tests/test_object_lights.cpp hostFacing. */
inline int MeshLight_Facing(float3 a, float3 b, float3 c, float3 p, float3 inside) {
    const float3 n = cross(b - a, c - a), ra = a - p;
    const float s = dot(a - inside, n) > 0.0f ? dot(ra, n) : -dot(ra, n);
    return s > 0.0f ? 1 : (s < 0.0f && s * s > 1e-10f * dot(ra, ra) * dot(n, n) ? -1 : 0);
}

/* The weights w[i] (MeshLight_Weight from p) of the light's n <= CLRT_MESHLIGHT_PICK_MAX triangles tri, an
 * enclosed light's hidden ones 0 (MeshLight_Facing); returns their sum, *outside whether p lies outside an
 * enclosed light. */
inline float MeshLight_Weights(const __global Light* light, const __global float4* tri, int n, float3 p, float* w,
                               int* outside) {
    int inner = 0;
    *outside = 0;
    for (int i = 0; i < n && light->position.w > 0.0f; ++i) { /* enclosed: which sides p sees */
        const int f = MeshLight_Facing(tri[3 * i].xyz, tri[3 * i + 1].xyz, tri[3 * i + 2].xyz, p, light->position.xyz);
        inner |= (f > 0) << i;
        *outside |= f < 0;
    }
    float total = 0.0f;
    for (int i = 0; i < n; ++i) {
        w[i] = *outside && ((inner >> i) & 1) ? 0.0f : MeshLight_Weight(tri[3 * i].xyz, tri[3 * i + 1].xyz, tri[3 * i + 2].xyz, p);
        total += w[i];
    }
    return total;
}

/* A picked triangle whose solid angle Ω lies in this range is sampled uniformly in Ω (a spherical
 * triangle: MeshLight_SphericalDirection), any other uniformly by area. Below the minimum the triangle is
 * far or seen edge-on: its area density is then nearly uniform in Ω, and float loses the spherical
 * triangle's angles; above the maximum (p almost on the triangle) its sides are nearly great circles. */
#define CLRT_MESHLIGHT_SPHERICAL_MIN 3e-4f
#ifdef CLRT_MESHLIGHT_BY_AREA
#define CLRT_MESHLIGHT_SPHERICAL_MAX 0.0f /* never: a uniform point, as the course's renderer */
#else
#define CLRT_MESHLIGHT_SPHERICAL_MAX 6.2f
#endif

/* Ω of a triangle from MeshLight_Subtended's num and den, and whether it is sampled in Ω. */
inline float MeshLight_SolidAngle(float num, float den) { return 2.0f * atan2(num, den); }
inline int MeshLight_BySolidAngle(float omega) {
    return omega > CLRT_MESHLIGHT_SPHERICAL_MIN && omega < CLRT_MESHLIGHT_SPHERICAL_MAX;
}

/* A direction drawn uniformly in the spherical triangle of unit vectors a, b, c (halfOmega: half its area,
 * atan2 of MeshLight_Subtended's num and den): u1 picks the sub-triangle a, b, ĉ of area u1·Ω, whose vertex
 * ĉ = cosθ·a + sinθ·c⊥ lies on the arc from a to c, then u2 a point on the arc from b to ĉ, uniform in the
 * sub-triangle's area as in Arvo's method (1995: "Stratified sampling of spherical triangles"). θ comes
 * from Van Oosterom and Strackee's tan(Ω'/2) of the sub-triangle, which is linear in tan(θ/2) = n/d:
 * tan(Ω'/2)·(g + m·tan(θ/2)) = k·tan(θ/2) with g = 1 + a·b, m = b·c⊥, k = |a·(b×c⊥)|. Arvo's own formula
 * for cosθ cancels digits: in float it strayed up to 0.2 rad from the double result on small triangles
 * (this form: 2e-5 rad at most, 2e-6 for 99.9%). The host reference is tests/test_object_lights.cpp
 * hostSphericalDirection (Arvo's formula, in double). */
inline float3 MeshLight_SphericalDirection(float3 a, float3 b, float3 c, float halfOmega, float u1, float u2) {
    /* v·rsqrt(v·v) rather than normalize(): the operations of Lanes_SphericalDirection, which must draw
     * the same directions up to rounding; differences of the unit vectors first, which are accurate */
    const float3 ca = c - a, ba = b - a;
    const float3 cpRaw = ca - a * dot(ca, a);
    const float3 cPerp = cpRaw * rsqrt(dot(cpRaw, cpRaw));
    const float g = 1.0f + dot(a, b), m = dot(ba, cPerp), k = fabs(dot(ba, cross(cPerp, a)));
    const float2 cs = Math_SinCos2Pi(u1 * halfOmega * (0.5f * CLRT_INV_PI)); /* of half the sub-area */
    const float n = cs.y * g, d = fmax(k * cs.x - cs.y * m, 0.0f), r = n * n + d * d;
    if (!(r > 0.0f)) return a;
    const float3 cHat = a * ((d * d - n * n) / r) + cPerp * (2.0f * n * d / r);
    const float3 bc = cHat - b;
    const float oneMinusZ = u2 * 0.5f * dot(bc, bc); /* 1 − cos of the arc from b to the direction */
    const float sinZ = sqrt(fmax(0.0f, oneMinusZ * (2.0f - oneMinusZ)));
    const float3 bpRaw = bc - b * dot(bc, b);
    const float lbp = dot(bpRaw, bpRaw);
    const float3 w = b * (1.0f - oneMinusZ) + (lbp > 0.0f ? bpRaw * (sinZ * rsqrt(lbp)) : (float3)(0.0f));
    return w * rsqrt(dot(w, w));
}

/* The area of light triangle (a, b, c). */
inline float MeshLight_TriangleArea(float3 a, float3 b, float3 c) {
    const float3 n = cross(b - a, c - a);
    return 0.5f * sqrt(dot(n, n));
}

/* The triangle of a LightMesh of n <= CLRT_MESHLIGHT_PICK_MAX triangles picked by u with probability
 * w_k / Σw (MeshLight_Weight from p), *uRest: u rescaled to [0, 1) inside its share; *invPick: the
 * reciprocal of that probability, Σw / w_k (0: nothing to pick, p sees no triangle). */
inline int MeshLight_PickByWeight(const __global Light* light, const __global float4* tri, int n, float3 p, float u,
                                  float* uRest, float* invPick) {
    float w[CLRT_MESHLIGHT_PICK_MAX > 0 ? CLRT_MESHLIGHT_PICK_MAX : 1]; /* 0 under CLRT_MESHLIGHT_BY_AREA */
    int outside;
    const float total = MeshLight_Weights(light, tri, n, p, w, &outside);
    *invPick = 0.0f;
    *uRest = 0.5f;
    if (!(total > 0.0f) || !isfinite(total)) return 0;
    const float x = u * total;
    float below = 0.0f; /* the weights before k */
    int k = 0;
    while (k < n - 1 && !(x < below + w[k])) below += w[k++];
    if (!(w[k] > 0.0f)) return k; /* x at the very end, on a triangle of weight 0: no sample */
    *uRest = clamp((x - below) / w[k], 0.0f, 0.99999994f);
    *invPick = total / w[k];
    return k;
}

/* 1 / (the density over the area) with which MeshLight_Sample, from shading point p, draws point q of the
 * light's triangle (v0, v1, v2), dist away from p and seen there at cosLight: 1/P(pick) (by weight Σw / w_k,
 * by area A / A_k), then uniform in the triangle's solid angle Ω (Ω·dist²/cosLight) or its area A_k. The
 * density a BSDF ray that hits the light there needs for MIS (with p its origin). */
inline float MeshLight_InvAreaPdf(const __global Light* light, const __global float4* data, float3 v0, float3 v1, float3 v2,
                                  float3 p, float dist, float cosLight) {
    float num, den;
    MeshLight_Subtended(v0, v1, v2, p, &num, &den);
    const float omega = MeshLight_SolidAngle(num, den);
    const int bySolidAngle = MeshLight_BySolidAngle(omega);
    float invPick;
    if (light->objCount > CLRT_MESHLIGHT_PICK_MAX) { /* by area */
        if (!bySolidAngle) return light->area;
        invPick = light->area / MeshLight_TriangleArea(v0, v1, v2);
    } else {
        float weights[CLRT_MESHLIGHT_PICK_MAX > 0 ? CLRT_MESHLIGHT_PICK_MAX : 1];
        int outside;
        const float total = MeshLight_Weights(light, data + light->objFirst, light->objCount, p, weights, &outside);
        const float w = MeshLight_WeightOf(num, den);
        if (!(w > 0.0f) || !isfinite(total)) return 0.0f;
        if (outside && MeshLight_Facing(v0, v1, v2, p, light->position.xyz) > 0) return 0.0f; /* hidden: never sampled */
        invPick = total / w;
    }
    if (bySolidAngle) return cosLight > 0.0f ? omega * invPick * (dist * dist / cosLight) : 0.0f;
    return MeshLight_TriangleArea(v0, v1, v2) * invPick;
}

/* How far the shadow ray towards q (on a light triangle, reached at cosθ_L over distance d) may go:
 * short of q by Ray_OffsetOrigin's offset off the surface, measured along the ray (offset / cosθ_L).
 * A ray that meets the light's triangle at a grazing angle lies within rounding distance of its plane
 * over a length that grows as 1/cosθ_L, so a fixed fraction of d (AimShadow's 1e-5) lets the triangle
 * occlude its own sample: inside a closed LightMesh 0.04% of the light samples (the points on the
 * neighbouring triangles, nearly in the shading point's tangent plane) were lost that way (README,
 * "Path tracing"). At most half of d is cut. */
inline float MeshLight_ShadowLength(float d, float3 q, float cosLight) {
    float m = fmax(fmax(fabs(q.x), fabs(q.y)), fabs(q.z));
    float offset = fmax(CLRT_OFFSET_ULPS * FLT_EPSILON * m, 1.0f / 65536.0f);
    return fmax(d - offset / cosLight, 0.5f * d);
}

/* MeshLight_Sample's direction uniform in the solid angle omega of triangle (v0, v1, v2; unit normal nL) seen
 * from p: *wi, *dist to the triangle's plane (MeshLight_ShadowLength's); 0 where the sample fails, else 1. */
inline int MeshLight_SampleDirection(float3 v0, float3 v1, float3 v2, float3 nL, float3 p, float omega, float2 u,
                                     float3* wi, float* dist) {
    const float3 ra = v0 - p, rb = v1 - p, rc = v2 - p;
    *wi = MeshLight_SphericalDirection(ra * rsqrt(dot(ra, ra)), rb * rsqrt(dot(rb, rb)), rc * rsqrt(dot(rc, rc)),
                                       0.5f * omega, u.x, u.y);
    const float cosLight = fabs(dot(nL, *wi)), t = fabs(dot(nL, ra)) / cosLight; /* to the plane */
    if (!(cosLight > 0.0f) || !(t > 0.0f) || !isfinite(t)) return 0;
    *dist = MeshLight_ShadowLength(t, p + t * *wi, cosLight);
    return 1;
}

/* MeshLight_Sample's uniform point on triangle (v0, v1, v2; unit normal nL) seen from p: *wi, *dist
 * (MeshLight_ShadowLength's); returns invAreaPdf·cosθ_L/d² (0 where the sample fails). */
inline float MeshLight_SamplePoint(float3 v0, float3 v1, float3 v2, float3 nL, float3 p, float2 u, float invAreaPdf,
                                   float3* wi, float* dist) {
    float su = sqrt(u.x); /* uniform on the triangle: b0 = 1 − √u1, b1 = u2·√u1 */
    float b0 = 1.0f - su, b1 = u.y * su;
    float3 q = b0 * v0 + b1 * v1 + (1.0f - b0 - b1) * v2;
    float3 d = q - p;
    float d2 = dot(d, d);
    if (!(d2 > 0.0f)) return 0.0f;
    *dist = sqrt(d2);
    *wi = d / *dist;
    float cosLight = fabs(dot(nL, *wi)); /* both faces emit, as an AreaLight's */
    if (!(cosLight > 0.0f)) return 0.0f;
    *dist = MeshLight_ShadowLength(*dist, q, cosLight);
    return invAreaPdf * cosLight / d2;
}

/* A direction towards LightMesh `light` from p (object_lights.cl's header): *wi, *dist (MeshLight_ShadowLength's),
 * L / pdf(wi). */
inline float3 MeshLight_Sample(const __global Light* light, const __global float4* data, float3 p, float2 u,
                               float3* wi, float* dist) {
    if (light->objCount <= 0 || !(light->area > 0.0f)) return (float3)(0.0f);
    const __global float4* tris = data + light->objFirst;
    float ux, invPick = 0.0f, invArea;
    int k;
    if (light->objCount <= CLRT_MESHLIGHT_PICK_MAX) {
        k = MeshLight_PickByWeight(light, tris, light->objCount, p, u.x, &ux, &invPick);
        if (!(invPick > 0.0f)) return (float3)(0.0f);
        invArea = MeshLight_TriangleArea(tris[3 * k].xyz, tris[3 * k + 1].xyz, tris[3 * k + 2].xyz) * invPick;
    } else {
        k = MeshLight_PickTriangle(tris, light->objCount, u.x, &ux);
        invPick = light->area / tris[3 * k + 1].w; /* A / A_k */
        invArea = light->area;
    }
    const float3 v0 = tris[3 * k].xyz, v1 = tris[3 * k + 1].xyz, v2 = tris[3 * k + 2].xyz;
    const float3 nL = normalize(cross(v1 - v0, v2 - v0));
    float num, den;
    MeshLight_Subtended(v0, v1, v2, p, &num, &den);
    const float omega = MeshLight_SolidAngle(num, den);
    if (MeshLight_BySolidAngle(omega)) /* L·Ω / P(k) */
        return MeshLight_SampleDirection(v0, v1, v2, nL, p, omega, (float2)(ux, u.y), wi, dist) ? light->radiance.xyz * (omega * invPick)
                                                                                                : (float3)(0.0f);
    return light->radiance.xyz * MeshLight_SamplePoint(v0, v1, v2, nL, p, (float2)(ux, u.y), invArea, wi, dist);
}

/* Distance along unit wi from p to the front (outside) surface of the light sphere, or −1 when the
 * ray misses it or starts inside it. s: object-space centre/radius, then the 3 worldToObject rows. */
inline float SphereLight_Hit(const __global float4* s, float3 p, float3 wi) {
    float3 o = (float3)(dot(s[1].xyz, p) + s[1].w, dot(s[2].xyz, p) + s[2].w, dot(s[3].xyz, p) + s[3].w);
    float3 d = (float3)(dot(s[1].xyz, wi), dot(s[2].xyz, wi), dot(s[3].xyz, wi));
    float r = s[0].w;
    float3 f = o - s[0].xyz;
    float cc = dot(f, f) - r * r;
    if (!(cc > 0.0f)) return -1.0f; /* inside: the inner side does not emit */
    float a = dot(d, d), b = dot(f, d);
    if (!(b < 0.0f) || !(a > 0.0f)) return -1.0f; /* pointing away */
    float3 l = f - (b / a) * d;
    float disc = a * (r * r - dot(l, l));
    if (!(disc >= 0.0f)) return -1.0f;
    float q = -(b - sqrt(disc)); /* b < 0: q > 0, the near root is cc / q */
    return cc / q;
}

/* The world normal (unnormalized: M⁻ᵀ·nObj) at the point of object-space unit normal nObj. */
inline float3 SphereLight_NormalWorld(const __global float4* s, float3 nObj) {
    return nObj.x * s[1].xyz + nObj.y * s[2].xyz + nObj.z * s[3].xyz;
}

/* dω_obj/dω_world for world direction dirWorld (unit) under the sphere's worldToObject map A:
 * |det A|/|A·dir|³, 1 under a similarity. A LightSphere lights the scene as its object-space sphere does
 * seen from the object-space shading point (the course's ellipsoid reference: SCENE_FORMAT.md
 * conventions), which is the world shape sending Radiance·dω_obj/dω_world along dirWorld. */
inline float SphereLight_DirectionScale(const __global Light* light, const __global float4* s, float3 dirWorld) {
    if (light->objCount == 0) return 1.0f;
    float3 a = (float3)(dot(s[1].xyz, dirWorld), dot(s[2].xyz, dirWorld), dot(s[3].xyz, dirWorld));
    float l = length(a);
    float j = 1.0f / (light->edgeU.x * l * l * l);
    return l > 0.0f && isfinite(j) ? j : 0.0f;
}

/* 2π(1 − cosθmax) of a sphere of radius R whose centre is d2 (squared) away, and a direction in its cone
 * drawn uniformly from u around unit axis n. */
inline float3 SphereLight_ConeDirection(float3 n, float R, float d2, float2 u, float* solidAngle) {
    float sin2Max = R * R / d2, cosMax = sqrt(fmax(0.0f, 1.0f - sin2Max));
    float oneMinusCosMax = sin2Max / (1.0f + cosMax); /* 1 − cosθmax without cancellation */
    float oneMinusCos = u.x * oneMinusCosMax;
    float cosT = 1.0f - oneMinusCos, sinT = sqrt(fmax(0.0f, oneMinusCos * (2.0f - oneMinusCos)));
    float2 cs = Math_SinCos2Pi(u.y);
    float3 t, b;
    makeBasis(n, &t, &b);
    *solidAngle = 2.0f * CLRT_PI * oneMinusCosMax;
    return normalize(sinT * cs.x * t + sinT * cs.y * b + cosT * n);
}

/* A light sphere under a transformation that is no similarity (an ellipsoid): the shading point is taken
 * to object space, a direction drawn uniformly in the cone the object-space sphere subtends there (pdf
 * 1/Ω_obj), its near hit carried back to world space. Value: Radiance·Ω_obj (= Radiance·dω_obj/dω_world
 * over the world pdf). From inside: nothing. */
inline float3 SphereLight_SampleObjectCone(const __global Light* light, const __global float4* s, float3 p, float2 u,
                                           float3* wi, float* dist) {
    float3 pObj = (float3)(dot(s[1].xyz, p) + s[1].w, dot(s[2].xyz, p) + s[2].w, dot(s[3].xyz, p) + s[3].w);
    float3 f = pObj - s[0].xyz;
    float R = s[0].w, d2 = dot(f, f);
    if (!(d2 > R * R)) return (float3)(0.0f);
    float solidAngle;
    float3 wObj = SphereLight_ConeDirection(-f / sqrt(d2), R, d2, u, &solidAngle);
    float b = dot(f, wObj), cc = d2 - R * R;
    float disc = fmax(b * b - cc, 0.0f); /* ≥ 0 inside the cone but for rounding */
    float tObj = -b + sqrt(disc) > 0.0f ? cc / (-b + sqrt(disc)) : 0.0f; /* the near root */
    float3 qObj = pObj + tObj * wObj;
    float3 q = (float3)(dot(s[4].xyz, qObj) + s[4].w, dot(s[5].xyz, qObj) + s[5].w, dot(s[6].xyz, qObj) + s[6].w);
    float3 d = q - p;
    float dl = length(d);
    if (!(dl > 0.0f) || !isfinite(dl)) return (float3)(0.0f);
    *wi = d / dl;
    float3 m = (qObj.x - s[0].x) * s[1].xyz + (qObj.y - s[0].y) * s[2].xyz + (qObj.z - s[0].z) * s[3].xyz;
    float ml = length(m);
    float cosLight = ml > 0.0f ? fmax(-dot(m, *wi) / ml, 1e-4f) : 1.0f; /* world normal M⁻ᵀ·n_obj */
    *dist = MeshLight_ShadowLength(dl, q, cosLight);
    return finiteOrZero(light->radiance.xyz * solidAngle);
}

inline float3 SphereLight_Sample(const __global Light* light, const __global float4* data, float3 p, float2 u,
                                 float3* wi, float* dist) {
    if (light->objCount != 0) return SphereLight_SampleObjectCone(light, data + light->objFirst, p, u, wi, dist);
    float3 axis = light->position.xyz - p;
    float R = light->objRadius, d2 = dot(axis, axis);
    float3 w;
    float invPdf;
    if (d2 > R * R) {
        w = SphereLight_ConeDirection(axis / sqrt(d2), R, d2, u, &invPdf);
    } else { /* inside the sphere: all directions (the inside emits nothing: SphereLight_Hit) */
        float z = 1.0f - 2.0f * u.x, r = sqrt(fmax(0.0f, 1.0f - z * z));
        float2 cs = Math_SinCos2Pi(u.y);
        w = (float3)(r * cs.x, r * cs.y, z);
        invPdf = 4.0f * CLRT_PI;
    }
    float t = SphereLight_Hit(data + light->objFirst, p, w);
    if (!(t > 0.0f)) return (float3)(0.0f);
    *wi = w;
    *dist = t;
    return light->radiance.xyz * invPdf;
}

#ifdef CLRT_HAS_OBJECT_LIGHTS
inline int ObjectLight_IsShape(const __global Light* light) {
    return light->kind == LIGHT_MESH || light->kind == LIGHT_SPHERE;
}

/* Re-aims the shadow ray *sr (from its offset origin) at the sampled point q on an object light. The
 * light is geometry too, so the ray must end just before its surface: it is aimed at q itself rather
 * than sent along the sampled direction from the shading point, whose parallel offset by the origin
 * shift moves the light's hit by shift/cos at grazing incidence (on the hw6 sphere box 9% of such rays
 * hit the light itself short of tMax). Rays of zero contribution (not traced) are left alone. */
inline void ObjectLight_AimShadow(ShadowRay* sr, float3 q) {
    if (!(maxComponent(sr->contribution.xyz) > 0.0f)) return;
    float3 d = q - sr->origin.xyz;
    float len = length(d);
    if (!(len > 0.0f) || !isfinite(len)) {
        sr->contribution = (float4)(0.0f);
        return;
    }
    sr->origin.w = len * (1.0f - 1e-5f);
    sr->direction.xyz = d / len;
}

/* The radiance a ray sees where it hits primitive `prim` (frontFacing: it hit the side the geometric
 * normal points to): the Radiance of its object light from an emitting side (LightMesh: either face;
 * LightSphere: outside), else 0. */
inline float3 ObjectLight_Emission(int prim, int frontFacing, int numTriangles, int numSpheres,
                                   const __global TriangleShading* shading, const __global Sphere* spheres,
                                   const __global Light* lights) {
    int light = CLRT_INVALID;
    if (prim < numTriangles) light = shading[prim].light;
    else if (prim < numTriangles + numSpheres) light = spheres[prim - numTriangles].light;
    if (light == CLRT_INVALID || (!frontFacing && prim >= numTriangles)) return (float3)(0.0f);
    return lights[light].radiance.xyz;
}
#endif

#endif /* CLRT_OBJECT_LIGHTS_CL */
