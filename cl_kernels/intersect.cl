/* intersect.cl — ray/primitive tests and BVH traversal: watertight triangles (Woop, Benthin & Wald
 * 2013), spheres under an affine transform with the stable quadratic of Ray Tracing Gems ch. 7, a
 * near-first stack traversal, and the two wavefront kernels: closest hit and any hit (shadow rays). */
#ifndef CLRT_INTERSECT_CL
#define CLRT_INTERSECT_CL

#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"
#include "common.cl"

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define CLRT_HAVE_FP64 1
#endif

/* FP_CONTRACT OFF from here to the end of this file:
 * no contraction of a*b - c*d into fma() here: the watertight test relies on a shared edge's function
 * coming out as the exact negation in both triangles (and, when non-zero, with the exact sign), which
 * fma breaks; with it, rays aimed at shared edges slipped through closed meshes. */
#pragma OPENCL FP_CONTRACT OFF

/* Per-ray constants of the watertight test: permuted axes and shear. */
typedef struct {
    int kx, ky, kz;
    float sx, sy, sz;
    int swap;   /* kx, ky are the cyclic successors of kz, exchanged (for a negative dir[kz]) */
} RayShear;

inline float comp(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

inline RayShear RayShear_Make(float3 dir) {
    RayShear s;
    float3 a = fabs(dir);
    s.kz = (a.x > a.y) ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    s.kx = s.kz + 1 == 3 ? 0 : s.kz + 1;
    s.ky = s.kx + 1 == 3 ? 0 : s.kx + 1;
    s.swap = comp(dir, s.kz) < 0.0f;
    if (s.swap) { int t = s.kx; s.kx = s.ky; s.ky = t; }
    float dz = comp(dir, s.kz);
    s.sx = comp(dir, s.kx) / dz;
    s.sy = comp(dir, s.ky) / dz;
    s.sz = 1.0f / dz;
    return s;
}

/* (v[kx], v[ky], v[kz], 0) by swizzles: kz picks the cyclic rotation, swap exchanges x and y. */
inline float4 RayShear_Permute(RayShear s, float3 v3) {
    const float4 v = (float4)(v3, 0.0f);
    const float4 r = s.kz == 0 ? v.yzxw : (s.kz == 1 ? v.zxyw : v);
    return s.swap ? r.yxzw : r;
}

/* What a traversal looks for (the flags argument of the functions below): */
#define CLRT_RAY_ANY_HIT 1   /* any hit before tMax, t >= 0 (shadow rays), else the closest with t > 0 */

/* The course's shadow test counts a triangle that passes exactly through the shadow ray's origin (t = 0,
 * T == 0 in the watertight test) as blocking; every other ray needs t > 0. It decides the points on the
 * edge where two walls meet at a concave corner: their shadow ray starts ShadowRayEpsilon off one wall,
 * in the other wall's plane, and the course's references show them in shadow (hw1 cornellbox and
 * cornellbox_recursive: 39.20 -> 41.09 and 39.10 -> 40.94 dB; docs/scene-format.md, conventions).
 * flags & CLRT_RAY_ANY_HIT: a shadow ray. */
#define TRIANGLE_T_TOO_SMALL(T, flags) (((flags) & CLRT_RAY_ANY_HIT) ? ((T) < 0.0f) : ((T) <= 0.0f))

/* Returns 1 and sets *t, *b1, *b2 (weights of v1, v2) for a hit with 0 < t < tMax (0 <= t for CLRT_RAY_ANY_HIT;
 * none from behind with t < cullBefore under CLRT_HAS_BACKFACE_CULLING: 0 culls nothing, INFINITY every back face). */
__attribute__((always_inline)) inline int Triangle_Intersect(float3 org, RayShear s, float3 v0, float3 v1, float3 v2, float tMax, int flags,
                              float cullBefore, float* tOut, float* b1Out, float* b2Out) {
    /* The vertices relative to the origin, their components permuted to (kx, ky, kz) by whole-vector
     * swizzles and selects (the same values comp() would pick one by one). */
    const float4 A4 = RayShear_Permute(s, v0 - org);
    const float4 B4 = RayShear_Permute(s, v1 - org);
    const float4 C4 = RayShear_Permute(s, v2 - org);
    float Az = A4.z, Bz = B4.z, Cz = C4.z;
    float Ax = A4.x - s.sx * Az, Ay = A4.y - s.sy * Az;
    float Bx = B4.x - s.sx * Bz, By = B4.y - s.sy * Bz;
    float Cx = C4.x - s.sx * Cz, Cy = C4.y - s.sy * Cz;
    float U = Cx * By - Cy * Bx;
    float V = Ax * Cy - Ay * Cx;
    float W = Bx * Ay - By * Ax;
#ifdef CLRT_HAVE_FP64
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        /* Edge case: redo the edge functions in double so a ray through an edge or vertex is
         * classified consistently for both triangles that share it. */
        U = (float)((double)Cx * (double)By - (double)Cy * (double)Bx);
        V = (float)((double)Ax * (double)Cy - (double)Ay * (double)Cx);
        W = (float)((double)Bx * (double)Ay - (double)By * (double)Ax);
    }
#endif
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return 0;
    float det = U + V + W;
    if (det == 0.0f) return 0;
    Az *= s.sz; Bz *= s.sz; Cz *= s.sz;
    float T = U * Az + V * Bz + W * Cz;
    /* A back-facing hit (det < 0): all of U, V, W, T share det's sign, so the weights V/det, W/det
     * need V and W negated along with T and det. */
#ifdef CLRT_HAS_BACKFACE_CULLING
    if (det < 0.0f && T > cullBefore * det) return 0; /* t = T/det < cullBefore, det < 0 */
#endif
    if (det < 0.0f) { T = -T; det = -det; V = -V; W = -W; }
    if (TRIANGLE_T_TOO_SMALL(T, flags) || T >= tMax * det) return 0;
    float inv = 1.0f / det;
    *tOut = T * inv;
    *b1Out = V * inv;
    *b2Out = W * inv;
    return 1;
}

inline float3 affinePoint(const __global float4* rows, float3 p) {
    return (float3)(dot(rows[0].xyz, p) + rows[0].w, dot(rows[1].xyz, p) + rows[1].w, dot(rows[2].xyz, p) + rows[2].w);
}
inline float3 affineVector(const __global float4* rows, float3 v) {
    return (float3)(dot(rows[0].xyz, v), dot(rows[1].xyz, v), dot(rows[2].xyz, v));
}

/* Sphere in object space; the ray is mapped by worldToObject (direction not renormalised, so t is
 * the same parameter in both spaces). Stable roots: q = -(b + sign(b)·√Δ), t0 = c/q, t1 = q/a, with
 * Δ computed from the perpendicular distance (no b² − ac cancellation). */
inline int Sphere_Intersect(const __global Sphere* sp, float3 orgW, float3 dirW, float tMax, float* tOut) {
    float3 o = affinePoint(sp->worldToObject, orgW);
    float3 d = affineVector(sp->worldToObject, dirW);
    float3 c = sp->centerRadius.xyz;
    float r = sp->centerRadius.w;
    float3 f = o - c;
    float a = dot(d, d);
    float b = dot(f, d);
    float3 l = f - (b / a) * d;
    float disc = a * (r * r - dot(l, l));
    if (!(disc >= 0.0f)) return 0;
    float cc = dot(f, f) - r * r;
    float q = -(b + copysign(sqrt(disc), b));
    float t0 = q != 0.0f ? cc / q : 0.0f;
    float t1 = q / a;
    float tn = fmin(t0, t1), tf = fmax(t0, t1);
    if (tn > 0.0f && tn < tMax) { *tOut = tn; return 1; }
    if (tf > 0.0f && tf < tMax) { *tOut = tf; return 1; }
    return 0;
}

/* ---- Motion blur (CLRT_HAS_MOTION_BLUR) ---------------------------------------------------------
 * A moving primitive is stored at its time-0 position with its translation over the shutter
 * (Triangle: v0.w, v1.w, v2.w; Sphere: motion); a ray of time t meets it where the ray moved by
 * −t·motion meets the primitive at rest. The BVH boxes are swept over [0, 1] on the host. */
inline float3 Triangle_Motion(const __global Triangle* tri) { return (float3)(tri->v0.w, tri->v1.w, tri->v2.w); }

/* The unit face normal of a flat triangle, cross(v1 - v0, v2 - v0) / its length: the same float
 * operations in the same order as the flattener's faceNormal (src/flatten/flatten_geometry.cpp; this
 * file's FP_CONTRACT OFF), so shading gets, bit for bit, the normal flattening once stored (the course
 * scenes' images unchanged). The flattener drops triangles whose length is not > 0. */
inline float3 Triangle_FaceNormal(float3 v0, float3 v1, float3 v2) {
    const float3 a = v1 - v0, b = v2 - v0;
    const float3 c = (float3)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    const float len = sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    return c / len;
}

/* The ray origin in the rest frame of a primitive moving by `motion`, at shutter time `time`. */
inline float3 MotionBlur_RestOrigin(float3 org, float time, float3 motion) {
#ifdef CLRT_HAS_MOTION_BLUR
    return org - time * motion;
#else
    return org;
#endif
}

/* A box's exit distance, and the ray's tMax when a box is held against it, widened by 1 + 2γ3 (pbrt): a hit the
 * watertight triangle test accepts exactly on an edge may lie a few ULPs outside the triangle's tight box, and
 * one it accepts within rounding of tMax (T < tMax·det) may lie in a box whose rounded entry is just past tMax
 * (a shadow ray ends just short of its light point: its blocker there was missed, session 33). */
#define CLRT_SLAB_WIDEN 1.0000004f

/* Slab test; returns the entry distance or INFINITY when the box is missed within [0, tMax). */
inline float Aabb_Intersect(float4 bmin, float4 bmax, float3 org, float3 invDir, float tMax) {
    float3 t0 = (bmin.xyz - org) * invDir;
    float3 t1 = (bmax.xyz - org) * invDir;
    /* A zero direction component with the origin exactly on that face gives 0·inf = NaN: the ray
     * lies in the face's plane, so the slab is unbounded (-inf, +inf), whatever the zero's sign.
     * (fmin/fmax would otherwise pick the other, infinite bound and cull the box: rays in the
     * plane of a box face, e.g. aimed exactly at a vertex, escaped closed meshes.) */
    t0 = select(t0, -invDir, isnan(t0));
    t1 = select(t1, invDir, isnan(t1));
    float3 tn = fmin(t0, t1), tf = fmax(t0, t1);
    float tEnter = fmax(fmax(tn.x, tn.y), fmax(tn.z, 0.0f));
    float tExit = fmin(fmin(tf.x, tf.y), tf.z) * CLRT_SLAB_WIDEN;
    tExit = fmin(tExit, tMax * CLRT_SLAB_WIDEN);
    return tEnter <= tExit ? tEnter : INFINITY;
}

inline float3 safeInverse(float3 d) {
    /* 1/±0 = ±inf is fine for the slab test; fmin/fmax drop the NaN of 0·inf. */
    return (float3)(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
}

/* ---- Leaves: four triangles at a time -----------------------------------------------------------
 * A leaf block (LeafBlock) holds its triangles' vertices as struct of arrays: the watertight test of
 * Triangle_Intersect runs on all four lanes at once, each lane computing exactly what the scalar test
 * computes for that triangle (the same operations in the same order, FP_CONTRACT OFF, the double-
 * precision edge fallback per lane). Only the last comparison, T < tMax·det, depends on the hits found
 * before it in the leaf: the lanes are tested against the tMax of the leaf's start, and each surviving
 * lane again, in leaf order, against the tMax left by the lanes before it, so a leaf reports the same
 * hit, bit for bit, as testing its primitives one by one. */

/* The four lanes' edge functions, T and det (det > 0 after the back-face flip; V, W, T flipped with
 * it), for the ray origin orgK in the shear's axis order (RayShear_Permute). Returns the lanes that
 * pass every test of Triangle_Intersect with tMax (and are triangles: isTri). */
__attribute__((always_inline)) inline int4 Triangle4_Intersect(const __global float4* vertex, float4 orgK, RayShear s, int4 isTri, float tMax, int flags,
                                float cullBefore, float4* Vout, float4* Wout, float4* Tout, float4* detOut) {
    float4 Az = vertex[s.kz] - orgK.z, Bz = vertex[3 + s.kz] - orgK.z, Cz = vertex[6 + s.kz] - orgK.z;
    const float4 Ax = (vertex[s.kx] - orgK.x) - s.sx * Az, Ay = (vertex[s.ky] - orgK.y) - s.sy * Az;
    const float4 Bx = (vertex[3 + s.kx] - orgK.x) - s.sx * Bz, By = (vertex[3 + s.ky] - orgK.y) - s.sy * Bz;
    const float4 Cx = (vertex[6 + s.kx] - orgK.x) - s.sx * Cz, Cy = (vertex[6 + s.ky] - orgK.y) - s.sy * Cz;
    float4 U = Cx * By - Cy * Bx;
    float4 V = Ax * Cy - Ay * Cx;
    float4 W = Bx * Ay - By * Ax;
#ifdef CLRT_HAVE_FP64
    const int4 onEdge = isTri & ((U == 0.0f) | (V == 0.0f) | (W == 0.0f));
    if (any(onEdge)) {
        const double4 ax = convert_double4(Ax), ay = convert_double4(Ay), bx = convert_double4(Bx),
                      by = convert_double4(By), cx = convert_double4(Cx), cy = convert_double4(Cy);
        U = select(U, convert_float4(cx * by - cy * bx), onEdge);
        V = select(V, convert_float4(ax * cy - ay * cx), onEdge);
        W = select(W, convert_float4(bx * ay - by * ax), onEdge);
    }
#endif
    const int4 mixed = ((U < 0.0f) | (V < 0.0f) | (W < 0.0f)) & ((U > 0.0f) | (V > 0.0f) | (W > 0.0f));
    float4 det = U + V + W;
    Az *= s.sz; Bz *= s.sz; Cz *= s.sz;
    float4 T = U * Az + V * Bz + W * Cz;
    const int4 back = det < 0.0f;
    T = select(T, -T, back); det = select(det, -det, back);
    *Vout = select(V, -V, back); *Wout = select(W, -W, back);
    *Tout = T; *detOut = det;
    int4 hit = isTri & ~mixed & (det != 0.0f) & ~(TRIANGLE_T_TOO_SMALL(T, flags) | (T >= tMax * det));
#ifdef CLRT_HAS_BACKFACE_CULLING
    hit &= ~(back & (T < cullBefore * det)); /* T, det here with det > 0 */
#endif
    return hit;
}

/* One leaf block in leaf order: its triangle lanes that passed Triangle4_Intersect (candidates) and its
 * sphere lanes, each against the tMax the lanes before it left. Returns 1 if some lane hit. */
inline int Leaf_Block(const __global LeafBlock* block, int4 prim, int4 candidates, float4 V4, float4 W4, float4 T4,
                      float4 det4, const __global Sphere* spheres, int numTriangles, float3 org, float3 dir,
                      float time, int flags, float* tMax, Hit* hit) {
    int cand[4], ref[4];
    float V[4], W[4], T[4], det[4];
    vstore4(candidates, 0, cand); vstore4(prim, 0, ref);
    vstore4(V4, 0, V); vstore4(W4, 0, W); vstore4(T4, 0, T); vstore4(det4, 0, det);
    int found = 0;
    for (int i = 0; i < 4; ++i) {
        float t, b1 = 0.0f, b2 = 0.0f;
        if (ref[i] < numTriangles) {
            if (!cand[i] || T[i] >= *tMax * det[i]) continue; /* empty lanes (ref -1) are never candidates */
            const float inv = 1.0f / det[i];
            t = T[i] * inv; b1 = V[i] * inv; b2 = W[i] * inv;
        } else {
            const __global Sphere* sph = &spheres[ref[i] - numTriangles];
            if (!Sphere_Intersect(sph, MotionBlur_RestOrigin(org, time, sph->motion.xyz), dir, *tMax, &t)) continue;
        }
        *tMax = t;
        hit->t = t; hit->prim = ref[i]; hit->u = b1; hit->v = b2;
        found = 1;
        if (flags & CLRT_RAY_ANY_HIT) return 1;
    }
    return found;
}

#ifdef CLRT_HAS_MOTION_BLUR
/* With motion blur every triangle has its own rest-frame origin: one at a time (Triangle_Intersect). */
inline int Leaf_BlockMoving(const __global int* prim, const __global Triangle* tris, const __global Sphere* spheres,
                            int numTriangles, float3 org, float3 dir, RayShear shear, float time, int flags,
                            float cullBefore, float* tMax, Hit* hit) {
    int found = 0;
    for (int i = 0; i < 4; ++i) {
        const int ref = prim[i];
        if (ref < 0) break;
        float t, b1 = 0.0f, b2 = 0.0f;
        int h;
        if (ref < numTriangles) {
            const __global Triangle* tri = &tris[ref];
            const float3 o = MotionBlur_RestOrigin(org, time, Triangle_Motion(tri));
            h = Triangle_Intersect(o, shear, tri->v0.xyz, tri->v1.xyz, tri->v2.xyz, *tMax, flags, cullBefore, &t, &b1, &b2);
        } else {
            const __global Sphere* sph = &spheres[ref - numTriangles];
            h = Sphere_Intersect(sph, MotionBlur_RestOrigin(org, time, sph->motion.xyz), dir, *tMax, &t);
        }
        if (!h) continue;
        *tMax = t;
        hit->t = t; hit->prim = ref; hit->u = b1; hit->v = b2;
        found = 1;
        if (flags & CLRT_RAY_ANY_HIT) return 1;
    }
    return found;
}
#endif

/* The leaf of stack entry ~(firstBlock << 4 | count): its blocks in order. Returns 1 if some
 * primitive hit (closer than *tMax, which it lowers; CLRT_RAY_ANY_HIT in flags: stops at the first). */
__attribute__((always_inline)) inline int Leaf_Intersect(const __global LeafBlock* leaves, int packed, const __global Triangle* tris,
                          const __global Sphere* spheres, int numTriangles, float3 org, float3 dir, float4 orgK,
                          RayShear shear, float time, int flags, float cullBefore, float* tMax,
                          Hit* hit) {
    const int firstBlock = packed >> 4, count = packed & 15;
    int found = 0;
    for (int b = firstBlock; b < firstBlock + ((count + 3) >> 2); ++b) {
        const __global LeafBlock* block = &leaves[b];
#ifdef CLRT_HAS_MOTION_BLUR
        found |= Leaf_BlockMoving((const __global int*)&block->prim, tris, spheres, numTriangles, org, dir, shear, time, flags, cullBefore, tMax, hit);
#else
        const int4 prim = block->prim;
        const int4 isTri = (prim >= (int4)(0)) & (prim < (int4)(numTriangles));
        float4 V, W, T, det;
        const int4 cand = Triangle4_Intersect(block->vertex, orgK, shear, isTri, *tMax, flags, cullBefore, &V, &W, &T, &det);
        /* Spheres are not compiled out without CLRT_HAS_SPHERES: with the sphere test gone, Intel's CPU
         * runtime traced the Audi TT's rays at about half the speed (measured). On every device, not a
         * quirk (docs/quirks.md "Not quirks"). */
        if (any(cand | (prim >= (int4)(numTriangles))))
            found |= Leaf_Block(block, prim, cand, V, W, T, det, spheres, numTriangles, org, dir, time, flags, tMax, hit);
#endif
        if (found && (flags & CLRT_RAY_ANY_HIT)) return 1;
    }
    return found;
}

/* ---- 8-wide nodes ---------------------------------------------------------------------------- */

/* The slab tests of node n's eight children: their entry distances (tEnter) and which are hit before
 * tEnd, the ray's tMax widened by CLRT_SLAB_WIDEN (*isHit); returns how many are. The near and far planes
 * of each axis are picked by the per-ray plane index near (minX 0 / maxX 1, minY 2 / maxY 3, minZ 4 / maxZ 5,
 * by the sign of the direction): an empty lane (min +inf, max -inf) is then never hit. */
__attribute__((always_inline)) inline int Bvh8_SlabTest(const __global Bvh8Node* n, float3 org, float3 invDir, int nearX,
                                                         int nearY, int nearZ, float tEnd, float8* tEnterOut, int8* isHit) {
    /* The node's planes as an array of float8 rows (minX, maxX, minY, maxY, minZ, maxZ): one aligned load each
     * (a node is 256 bytes, a buffer at least 128-byte aligned; vload8's unaligned loads were 3–5% slower). */
    const __global float8* planes = (const __global float8*)n->planes;
    const float8 tNx = (planes[nearX] - org.x) * invDir.x;
    const float8 tFx = (planes[nearX ^ 1] - org.x) * invDir.x;
    const float8 tNy = (planes[nearY] - org.y) * invDir.y;
    const float8 tFy = (planes[nearY ^ 1] - org.y) * invDir.y;
    const float8 tNz = (planes[nearZ] - org.z) * invDir.z;
    const float8 tFz = (planes[nearZ ^ 1] - org.z) * invDir.z;
    /* max(0, tNx, tNy, tNz) and min(tFx, tFy, tFz) that drop a NaN operand (0·inf: a ray lying in a
     * face's plane, whose slab is then unbounded), as fmax/fmin do, but written as compare-and-select
     * with the NaN candidate first, so that a CPU compiles each to one min/max instruction (x86
     * minps/maxps return their second operand when one is NaN). */
    float8 tEnter = (float8)(0.0f);
    tEnter = tNx > tEnter ? tNx : tEnter;
    tEnter = tNy > tEnter ? tNy : tEnter;
    tEnter = tNz > tEnter ? tNz : tEnter;
    float8 tExit = (float8)(INFINITY);
    tExit = tFx < tExit ? tFx : tExit;
    tExit = tFy < tExit ? tFy : tExit;
    tExit = tFz < tExit ? tFz : tExit;
    tExit = tExit * CLRT_SLAB_WIDEN; /* tEnd: the ray's tMax, widened the same (CLRT_SLAB_WIDEN) */
    tExit = tExit < tEnd ? tExit : (float8)(tEnd);
    *isHit = tEnter <= tExit;
    *tEnterOut = tEnter;
    const int4 h = -((*isHit).lo + (*isHit).hi);
    return h.x + h.y + h.z + h.w;
}

/* The nh > 0 hit children of node n: returns the one to visit next and pushes the others (stack entries:
 * Bvh8Node's lane entries). One hit child (most visits) is found by branches, which let the core start
 * loading the predicted child before the slab test ends (branch-free picks lost 4–20%). Any hit
 * (shadow rays, whose answer does not depend on the order): the first hit lane visited, the others pushed
 * in lane order, no sort. Closest hit: the hit lanes sorted by entry distance (insertion, stable: ties in
 * lane order), the nearest visited, the others pushed far first with their entry distance, so that pops
 * skip those beyond the best hit so far. */
__attribute__((always_inline)) inline int Bvh8_Children(const __global Bvh8Node* n, float8 tEnter, int8 isHit, int nh,
                                                         int flags, int* stackEntry, float* stackT, int* sp) {
    int e[8], h[8];
    vstore8(vload8(0, (const __global int*)n->entry), 0, e);
    vstore8(isHit, 0, h);
    if (nh == 1) {
        for (int i = 0; i < 7; ++i)
            if (h[i]) return e[i];
        return e[7];
    }
    if (*sp + nh - 1 > CLRT_BVH8_STACK_SIZE) return e[0]; /* never, by the host's bound */
    if (flags & CLRT_RAY_ANY_HIT) {
        int first = -1;
        for (int i = 7; i >= 0; --i)
            if (h[i]) {
                if (first >= 0) stackEntry[(*sp)++] = e[first];
                first = i;
            }
        return e[first];
    }
    float k[8], keys[8];
    int entries[8];
    vstore8(tEnter, 0, k);
    int m = 0;
    for (int i = 0; i < 8; ++i) {
        if (!h[i]) continue;
        const float key = k[i] < FLT_MAX ? k[i] : FLT_MAX;
        int j = m++;
        for (; j > 0 && keys[j - 1] > key; --j) { keys[j] = keys[j - 1]; entries[j] = entries[j - 1]; }
        keys[j] = key;
        entries[j] = e[i];
    }
    for (int j = m - 1; j >= 1; --j) { stackEntry[*sp] = entries[j]; stackT[*sp] = keys[j]; ++*sp; }
    return entries[0];
}

/* A ray as the traversal tests it: origin, direction and what the slab and triangle tests derive from
 * them once (inverse direction, shear, permuted origin, near planes). */
typedef struct {
    float3 org, dir, invDir;
    RayShear shear;
    float4 orgK;
    int nearX, nearY, nearZ;
} TraceRay;

inline TraceRay TraceRay_Make(float3 org, float3 dir) {
    TraceRay r;
    r.org = org;
    r.dir = dir;
    r.invDir = safeInverse(dir);
    r.shear = RayShear_Make(dir);
    r.orgK = RayShear_Permute(r.shear, org);
    r.nearX = signbit(r.invDir.x) ? 1 : 0;
    r.nearY = signbit(r.invDir.y) ? 3 : 2;
    r.nearZ = signbit(r.invDir.z) ? 5 : 4;
    return r;
}

#ifdef CLRT_HAS_INSTANCES
/* Two-level BVH (Instance): the top-level tree's leaf lanes are instances, lane entry ~((instance + 1) << 4):
 * as a stack entry, a "leaf" whose count bits are 0 (Bvh8Node). */
inline int Entry_Instance(int entry) { return ((~entry) & 15) == 0 ? ((~entry) >> 4) - 1 : CLRT_INVALID; }

/* Enters instance k: the ray in its object space (Instance), the stack height to leave it at. */
inline int Instance_Enter(const __global Instance* inst, float3 orgW, float3 dirW, float time, TraceRay* r) {
    const float3 orgObj = affinePoint(inst->worldToObject, MotionBlur_RestOrigin(orgW, time, inst->motion.xyz));
    *r = TraceRay_Make(orgObj, affineVector(inst->worldToObject, dirW));
    return inst->rootNode;
}
#endif

/* Traverses the 8-wide BVH (Bvh8Node, leaves in LeafBlock blocks) near-first from nodes[0], then, with
 * instances, the top-level tree from scene.instanceRoot, descending into an instance's bottom-level
 * tree in its object space (the stack holds both levels: popping back to the height at which the
 * instance was entered returns to the world ray). flags: CLRT_RAY_ANY_HIT stops at the first hit (shadow
 * rays); triangles seen from behind closer than cullBefore are skipped (under CLRT_HAS_BACKFACE_CULLING).
 * Returns 1 on a hit. time: the ray's shutter time (used only under CLRT_HAS_MOTION_BLUR). The
 * stack's size is the exact worst case the host computed. */
inline int Bvh_Traverse(const __global Bvh8Node* nodes, const __global LeafBlock* leaves,
                        const __global Triangle* tris, const __global Sphere* spheres,
                        const __global Instance* instances, SceneParams scene, float3 org, float3 dir,
                        float tMax, float time, int flags, float cullBefore, Hit* hit, int* hitInstance) {
    const int numTriangles = scene.numTriangles;
    TraceRay r = TraceRay_Make(org, dir);
    int stackEntry[CLRT_BVH8_STACK_SIZE];
    float stackT[CLRT_BVH8_STACK_SIZE];
    int sp = 0;
    int entry = 0;
    int found = 0;
    float tEnd = tMax * CLRT_SLAB_WIDEN; /* what boxes and popped entries are held against (CLRT_SLAB_WIDEN) */
#ifdef CLRT_HAS_INSTANCES
    int instance = CLRT_INVALID, instanceSp = 0; /* the instance being traversed, the stack height it began at */
    if (scene.numInstances > 0) { stackEntry[0] = scene.instanceRoot; stackT[0] = 0.0f; sp = 1; }
#endif
    for (;;) {
        if (entry >= 0) {
            const __global Bvh8Node* n = &nodes[entry];
            float8 tEnter;
            int8 isHit;
            const int nh = Bvh8_SlabTest(n, r.org, r.invDir, r.nearX, r.nearY, r.nearZ, tEnd, &tEnter, &isHit);
            if (nh > 0) {
                entry = Bvh8_Children(n, tEnter, isHit, nh, flags, stackEntry, stackT, &sp);
                continue;
            }
#ifdef CLRT_HAS_INSTANCES
        } else if (Entry_Instance(entry) != CLRT_INVALID) {
            instance = Entry_Instance(entry);
            instanceSp = sp;
            entry = Instance_Enter(&instances[instance], org, dir, time, &r);
            continue;
#endif
        } else if (Leaf_Intersect(leaves, ~entry, tris, spheres, numTriangles, r.org, r.dir, r.orgK, r.shear, time,
                                  flags, cullBefore, &tMax, hit)) {
            found = 1;
            tEnd = tMax * CLRT_SLAB_WIDEN;
#ifdef CLRT_HAS_INSTANCES
            *hitInstance = instance;
#endif
            if (flags & CLRT_RAY_ANY_HIT) return 1;
        }
        /* Pop the next entry that can still hold a closer hit (any hit: tMax never drops, so all can). */
        for (;;) {
#ifdef CLRT_HAS_INSTANCES
            if (instance != CLRT_INVALID && sp == instanceSp) { instance = CLRT_INVALID; r = TraceRay_Make(org, dir); }
#endif
            if (sp == 0) return found;
            --sp;
            if ((flags & CLRT_RAY_ANY_HIT) || stackT[sp] <= tEnd) { entry = stackEntry[sp]; break; }
        }
    }
}

/* Every plane against the ray (planes are unbounded, so not in the BVH). */
inline int Planes_Intersect(const __global Plane* planes, int numPlanes, int firstPlaneRef, float3 org, float3 dir,
                            float tMax, int anyHit, Hit* hit) {
    int found = 0;
    for (int k = 0; k < numPlanes; ++k) {
        float3 n = planes[k].normal.xyz;
        float denom = dot(n, dir);
        if (denom == 0.0f) continue;
        float t = dot(planes[k].point.xyz - org, n) / denom;
        if (t > 0.0f && t < tMax) {
            tMax = t;
            hit->t = t; hit->prim = firstPlaneRef + k; hit->u = 0.0f; hit->v = 0.0f;
            found = 1;
            if (anyHit) return 1;
        }
    }
    return found;
}

/* The closest hit of ray r (planes, then the BVH); prim CLRT_INVALID when it hits nothing. *instance:
 * the Instance hit, or CLRT_INVALID (Hit). */
inline Hit Ray_Closest(Ray r, SceneParams scene, const __global Bvh8Node* nodes, const __global LeafBlock* leaves,
                       const __global Triangle* tris, const __global Sphere* spheres, const __global Plane* planes,
                       const __global Instance* instances, int* instance) {
    const int numPlanes = scene.numPlanes;
    const int firstPlaneRef = scene.numTriangles + scene.numSpheres;
    Hit h;
    h.t = -1.0f; h.prim = CLRT_INVALID; h.u = 0.0f; h.v = 0.0f;
    *instance = CLRT_INVALID;
    float3 dir = r.direction.xyz;
    float tMax = r.direction.w;
    float cullBefore = 0.0f;
#ifdef CLRT_HAS_BACKFACE_CULLING
    if (tMax < 0.0f) { /* a ray that skips back faces closer than -tMax (Ray in device_types.h) */
        cullBefore = -tMax;
        tMax = INFINITY;
    }
#endif
    if (allFinite3(r.origin.xyz) && allFinite3(dir) && tMax > 0.0f) {
        if (numPlanes > 0 && Planes_Intersect(planes, numPlanes, firstPlaneRef, r.origin.xyz, dir, tMax, 0, &h)) tMax = h.t;
        Bvh_Traverse(nodes, leaves, tris, spheres, instances, scene, r.origin.xyz, dir, tMax, Ray_Time(r), 0, cullBefore, &h, instance);
    }
    return h;
}

/* Whether shadow ray s is blocked before its tMax (any hit). */
inline int Shadow_Occluded(ShadowRay s, SceneParams scene, const __global Bvh8Node* nodes, const __global LeafBlock* leaves,
                           const __global Triangle* tris, const __global Sphere* spheres, const __global Plane* planes,
                           const __global Instance* instances) {
    const int numPlanes = scene.numPlanes;
    const int firstPlaneRef = scene.numTriangles + scene.numSpheres;
    Hit h;
    int instance;
    return (numPlanes > 0 && Planes_Intersect(planes, numPlanes, firstPlaneRef, s.origin.xyz, s.direction.xyz, s.origin.w, 1, &h)) ||
           Bvh_Traverse(nodes, leaves, tris, spheres, instances, scene, s.origin.xyz, s.direction.xyz, s.origin.w,
                        s.direction.w, CLRT_RAY_ANY_HIT, 0.0f, &h, &instance);
}

/* Closest hit for each ray of the queue. */
/* Parameters of both kernels: src/shared/kernel_params.h. */
__kernel void intersect_closest(CLRT_KERNEL_PARAMS(intersect_closest)) {
    int i = get_global_id(0);
    if (i >= *queueCount) return;
    int instance;
    hits[i] = Ray_Closest(rays[i], scene, nodes, leaves, tris, spheres, planes, instances, &instance);
#ifdef CLRT_HAS_INSTANCES
    hitInstances[i] = instance;
#endif
}

/* Any hit for each shadow ray: an occluded ray's contribution is set to zero. */
__kernel void intersect_shadow(CLRT_KERNEL_PARAMS(intersect_shadow)) {
    int i = get_global_id(0);
    if (i >= *queueCount * raysPerPath) return;
    float4 c = shadows[i].contribution;
    if (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f) return;
    if (Shadow_Occluded(shadows[i], scene, nodes, leaves, tris, spheres, planes, instances)) shadows[i].contribution = (float4)(0.0f);
}

/* End of the FP_CONTRACT OFF scope: contraction back to ON, the OpenCL default, which every other
 * file is compiled with (shading gains from fma; tests/test_cl.cpp checks each file leaves it ON). */
#pragma OPENCL FP_CONTRACT ON

#endif /* CLRT_INTERSECT_CL */
