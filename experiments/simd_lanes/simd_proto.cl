/* simd_proto.cl — EXPERIMENT (session 27; docs/studies/2026-12-05-simd-lanes-prototype.md), not part of clrt.
 * A render_fused kernel that carries PW paths (4, 8 or 16) of one pixel in float vector lanes: structure of
 * arrays (V3W: x, y, z lane vectors), masks for the paths still alive, per-lane gathers of the hit's
 * surface and of the light triangle. It renders only what the hw6 diffuse box needs: triangles and
 * spheres (flattened), diffuse materials (kd/π), one two-sided LightMesh (lights[0]), MIS with the power
 * heuristic, cosine bounces, no roulette, depth as clrt's (light samples at depths 0..maxDepth, an
 * emission-only last segment). Everything else is wrong with it, silently. Its random numbers are a
 * per-lane PCG-style hash keyed by pixel and sample (not clrt's stratified sampler), its triangle test in
 * packets is Möller–Trumbore (not clrt's watertight test), and it guards NaN only at the end.
 * simd_variant.h (make_variants.sh) chooses: PW; LANE_TRACE (clrt's scalar traversal, one lane at a
 * time, instead of packet traversal); HYBRID N (packet traversal, a lane alone through a subtree that at
 * most N lanes enter); ONE_PATH (one live lane per packet: the scalar control); REAL_SAMPLER (clrt's
 * stratified sampler's streams, per lane: Sampler_2D at clrt's dimensions, MeshLight_PickTriangle);
 * REAL_SAMPLER with LANE_SAMPLER: the same streams, computed for all lanes at once (Lane_Stratified2D);
 * CAMERA_PACKETS with LANE_TRACE: packet traversal for the camera rays only. */
#include "simd_variant.h"
#ifndef PW
#define PW 4
#endif
#if PW == 16
#define vstore_int(v, a) vstore16(v, 0, a)
#define ldWi(a) vload16(0, a)
typedef float16 fW;
typedef int16 iW;
typedef uint16 uW;
#define ldW(a) vload16(0, a)
#define stW(v, a) vstore16(v, 0, a)
#define convert_uW convert_uint16
#define as_uW as_uint16
#define convert_fW convert_float16
#define LANES (iW)(0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15)
#elif PW == 8
#define vstore_int(v, a) vstore8(v, 0, a)
#define ldWi(a) vload8(0, a)
typedef float8 fW;
typedef int8 iW;
typedef uint8 uW;
#define ldW(a) vload8(0, a)
#define stW(v, a) vstore8(v, 0, a)
#define convert_uW convert_uint8
#define as_uW as_uint8
#define convert_fW convert_float8
#define LANES (iW)(0,1,2,3,4,5,6,7)
#else
#define vstore_int(v, a) vstore4(v, 0, a)
#define ldWi(a) vload4(0, a)
typedef float4 fW;
typedef int4 iW;
typedef uint4 uW;
#define ldW(a) vload4(0, a)
#define stW(v, a) vstore4(v, 0, a)
#define convert_uW convert_uint4
#define as_uW as_uint4
#define convert_fW convert_float4
#define LANES (iW)(0,1,2,3)
#endif
typedef struct { fW x, y, z; } V3W;
inline V3W V3(fW x, fW y, fW z) { V3W r; r.x = x; r.y = y; r.z = z; return r; }
inline V3W V3b(float3 p) { return V3((fW)(p.x), (fW)(p.y), (fW)(p.z)); }
inline V3W V3sub(V3W a, V3W b) { return V3(a.x - b.x, a.y - b.y, a.z - b.z); }
inline V3W V3add(V3W a, V3W b) { return V3(a.x + b.x, a.y + b.y, a.z + b.z); }
inline V3W V3mul(V3W a, fW s) { return V3(a.x * s, a.y * s, a.z * s); }
inline V3W V3mulv(V3W a, V3W b) { return V3(a.x * b.x, a.y * b.y, a.z * b.z); }
inline fW V3dot(V3W a, V3W b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3W V3cross(V3W a, V3W b) { return V3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
inline V3W V3sel(V3W a, V3W b, iW m) { return V3(select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m)); }
inline float hmin8(fW v) { float a[PW]; stW(v, a); float m = a[0]; for (int i = 1; i < PW; ++i) m = fmin(m, a[i]); return m; }
inline float hmax8(fW v) { float a[PW]; stW(v, a); float m = a[0]; for (int i = 1; i < PW; ++i) m = fmax(m, a[i]); return m; }
inline int mask8(iW m) { int a[PW]; vstore_int(m, a); int r = 0; for (int i = 0; i < PW; ++i) r |= a[i] ? 1 << i : 0; return r; }

/* per-lane PCG-style hash RNG */
inline uW RngW_Next(uW* s) {
    uW st = *s;
    *s = st * 747796405u + 2891336453u;
    uW w = ((st >> ((st >> 28u) + 4u)) ^ st) * 277803737u;
    return (w >> 22u) ^ w;
}
inline fW RngW_U(uW* s) { return convert_fW(RngW_Next(s) >> 8) * 0x1p-24f; }

/* Möller-Trumbore, 8 rays against one triangle; updates t/prim of lanes hit closer. */
inline void TriW(float3 v0, float3 v1, float3 v2, int ref, V3W o, V3W d, fW* tMax, iW* prim) {
    const V3W e1 = V3b(v1 - v0), e2 = V3b(v2 - v0);
    const V3W p = V3cross(d, e2);
    const fW det = V3dot(e1, p);
    const fW inv = 1.0f / det;
    const V3W tv = V3sub(o, V3b(v0));
    const fW u = V3dot(tv, p) * inv;
    const V3W q = V3cross(tv, e1);
    const fW v = V3dot(d, q) * inv;
    const fW t = V3dot(e2, q) * inv;
    const iW hit = (det != 0.0f) & (u >= 0.0f) & (v >= 0.0f) & (u + v <= 1.0f) & (t > 0.0f) & (t < *tMax);
    *tMax = select(*tMax, t, hit);
    *prim = select(*prim, (iW)(ref), hit);
}

inline void SphW(const __global Sphere* sp, int ref, V3W oW, V3W dW, fW* tMax, iW* prim) {
    const float4 r0 = sp->worldToObject[0], r1 = sp->worldToObject[1], r2 = sp->worldToObject[2];
    V3W o = V3(r0.x * oW.x + r0.y * oW.y + r0.z * oW.z + r0.w, r1.x * oW.x + r1.y * oW.y + r1.z * oW.z + r1.w,
               r2.x * oW.x + r2.y * oW.y + r2.z * oW.z + r2.w);
    V3W d = V3(r0.x * dW.x + r0.y * dW.y + r0.z * dW.z, r1.x * dW.x + r1.y * dW.y + r1.z * dW.z,
               r2.x * dW.x + r2.y * dW.y + r2.z * dW.z);
    const V3W f = V3sub(o, V3b(sp->centerRadius.xyz));
    const float r = sp->centerRadius.w;
    const fW a = V3dot(d, d), b = V3dot(f, d), c = V3dot(f, f) - r * r;
    const fW disc = b * b - a * c;
    const fW sq = sqrt(fmax(disc, 0.0f));
    fW t = (-b - sq) / a;
    t = select(t, (-b + sq) / a, t <= 1e-4f);
    const iW hit = (disc >= 0.0f) & (t > 1e-4f) & (t < *tMax);
    *tMax = select(*tMax, t, hit);
    *prim = select(*prim, (iW)(ref), hit);
}


#ifdef HYBRID
/* One lane's ray through the subtree at entry (clrt's scalar node and leaf tests); lowers *tMax, sets *prim. */
inline int SubtreeTrace(const __global Bvh4Node* nodes, const __global Bvh4Leaf* leaves, const __global Triangle* tris,
                        const __global Sphere* spheres, int numTriangles, int entry, float3 org, float3 dir,
                        int anyHit, float* tMax, int* prim) {
    TraceRay r = TraceRay_Make(org, dir);
    int stackEntry[CLRT_BVH4_STACK_SIZE];
    float stackT[CLRT_BVH4_STACK_SIZE];
    int sp = 0, found = 0;
    const int flags = anyHit ? CLRT_RAY_ANY_HIT : 0;
    Hit h;
    for (;;) {
        if (entry >= 0) {
            const __global Bvh4Node* n = &nodes[entry];
            float4 tEnter; int4 isHit;
            const int nh = Bvh4_SlabTest(n, r.org, r.invDir, r.nearX, r.nearY, r.nearZ, *tMax, &tEnter, &isHit);
            if (nh > 0) { entry = Bvh4_Children(n, tEnter, isHit, nh, flags, stackEntry, stackT, &sp); continue; }
        } else if (Leaf_Intersect(leaves, ~entry, tris, spheres, numTriangles, r.org, r.dir, r.orgK, r.shear, 0.0f,
                                  flags, 0.0f, tMax, &h)) {
            found = 1; *prim = h.prim;
            if (anyHit) return 1;
        }
        for (;;) {
            if (sp == 0) return found;
            --sp;
            if (anyHit || stackT[sp] <= *tMax) { entry = stackEntry[sp]; break; }
        }
    }
}
#endif
/* Packet traversal of the 4-wide BVH: closest hit (anyHit 0) or occlusion (anyHit 1: returns the
 * lanes blocked). Lanes not in active are ignored. */
inline iW PacketTraceImpl(const __global Bvh4Node* nodes, const __global Bvh4Leaf* leaves, const __global Triangle* tris,
                      const __global Sphere* spheres, int numTriangles, V3W o, V3W d, fW tMaxIn, iW active,
                      int anyHit, fW* tOut, iW* primOut) {
    const V3W inv = V3(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
    fW tMax = select((fW)(-INFINITY), tMaxIn, active);
    iW prim = (iW)(-1);
    iW blocked = (iW)(0);
    int stackE[64];
    float stackT[64];
    int sp = 0, entry = 0;
#ifdef HYBRID
    int blockedA[PW];
    for (int l = 0; l < PW; ++l) blockedA[l] = 0;
#endif
    for (;;) {
        if (entry >= 0) {
            const __global float* nf = (const __global float*)&nodes[entry];
            const __global int* ni = (const __global int*)&nodes[entry].child;
            int ce[4]; float ck[4]; int nh = 0;
            for (int c = 0; c < 4; ++c) {
                const int child = ni[c], cnt = ni[4 + c];
                if (child == CLRT_INVALID) continue;
                const fW t0x = (nf[c] - o.x) * inv.x, t1x = (nf[4 + c] - o.x) * inv.x;
                const fW t0y = (nf[8 + c] - o.y) * inv.y, t1y = (nf[12 + c] - o.y) * inv.y;
                const fW t0z = (nf[16 + c] - o.z) * inv.z, t1z = (nf[20 + c] - o.z) * inv.z;
                const fW tn = fmax(fmax(fmin(t0x, t1x), fmin(t0y, t1y)), fmax(fmin(t0z, t1z), 0.0f));
                const fW tf = fmin(fmin(fmax(t0x, t1x), fmax(t0y, t1y)), fmin(fmax(t0z, t1z), tMax)) * 1.0000004f;
                const iW h = tn <= tf;
                if (!any(h)) continue;
#ifdef HYBRID
                {
                    const int hm = mask8(h);
                    if (popcount(hm) <= HYBRID) { /* few lanes: each alone through this subtree */
                        float ta[PW], oxa[PW], oya[PW], oza[PW], dxa[PW], dya[PW], dza[PW]; int pa[PW];
                        stW(tMax, ta); stW(o.x, oxa); stW(o.y, oya); stW(o.z, oza); stW(d.x, dxa); stW(d.y, dya); stW(d.z, dza);
                        vstore_int(prim, pa);
                        const int e = cnt > 0 ? ~((child << 4) | cnt) : child;
                        for (int l = 0; l < PW; ++l) {
                            if (!(hm & (1 << l))) continue;
                            float tl = ta[l]; int pl = pa[l];
                            if (SubtreeTrace(nodes, leaves, tris, spheres, numTriangles, e, (float3)(oxa[l], oya[l], oza[l]),
                                             (float3)(dxa[l], dya[l], dza[l]), anyHit, &tl, &pl)) {
                                if (anyHit) { ta[l] = -INFINITY; blockedA[l] = -1; } else { ta[l] = tl; pa[l] = pl; }
                            }
                        }
                        tMax = ldW(ta); prim = ldWi(pa);
                        continue;
                    }
                }
#endif
                ce[nh] = cnt > 0 ? ~((child << 4) | cnt) : child;
                ck[nh] = hmin8(select((fW)(INFINITY), tn, h));
                ++nh;
            }
#ifdef HYBRID
            if (anyHit && !any(tMax > 0.0f)) break;
#endif
            if (nh > 0) {
                /* insertion sort ascending by key, push far first */
                for (int a = 1; a < nh; ++a) {
                    int e = ce[a]; float k = ck[a]; int b = a - 1;
                    while (b >= 0 && ck[b] > k) { ce[b + 1] = ce[b]; ck[b + 1] = ck[b]; --b; }
                    ce[b + 1] = e; ck[b + 1] = k;
                }
                for (int a = nh - 1; a >= 1; --a) { stackE[sp] = ce[a]; stackT[sp] = ck[a]; ++sp; }
                entry = ce[0];
                continue;
            }
        } else {
            const int packed = ~entry, first = packed >> 4, cnt = packed & 15;
            for (int bk = first; bk < first + ((cnt + 3) >> 2); ++bk) {
                const __global Bvh4Leaf* blk = &leaves[bk];
                const __global float* vf = (const __global float*)blk->vertex;
                const __global int* pr = (const __global int*)&blk->prim;
                for (int i = 0; i < 4; ++i) {
                    const int ref = pr[i];
                    if (ref < 0) break;
                    fW tPrev = tMax;
                    if (ref < numTriangles) {
                        const float3 v0 = (float3)(vf[i], vf[4 + i], vf[8 + i]);
                        const float3 v1 = (float3)(vf[12 + i], vf[16 + i], vf[20 + i]);
                        const float3 v2 = (float3)(vf[24 + i], vf[28 + i], vf[32 + i]);
                        TriW(v0, v1, v2, ref, o, d, &tMax, &prim);
                    } else {
                        SphW(&spheres[ref - numTriangles], ref, o, d, &tMax, &prim);
                    }
                    if (anyHit) {
                        const iW hb = tMax < tPrev;
                        blocked |= hb;
                        tMax = select(tMax, (fW)(-INFINITY), hb); /* lane done */
                    }
                }
            }
            if (anyHit && !any(tMax > 0.0f)) break;
        }
        const float tm = hmax8(tMax);
        int found = 0;
        while (sp > 0) {
            --sp;
            if (anyHit || stackT[sp] <= tm) { entry = stackE[sp]; found = 1; break; }
        }
        if (!found) break;
    }
    *tOut = tMax;
    *primOut = prim;
#ifdef HYBRID
    blocked |= ldWi(blockedA);
#endif
    return blocked;
}

#ifndef LANE_TRACE
#define PacketTrace PacketTraceImpl
#endif

#ifdef LANE_TRACE
/* the scalar traversal, one lane at a time */
inline iW LaneTrace(const __global Bvh4Node* nodes, const __global Bvh4Leaf* leaves, const __global Triangle* tris,
                    const __global Sphere* spheres, const __global Plane* planes, const __global Instance* instances, SceneParams scene,
                    V3W o, V3W d, fW tMaxIn, iW active, int anyHit, fW* tOut, iW* primOut) {
    float ox[PW], oy[PW], oz[PW], dx[PW], dy[PW], dz[PW], tm[PW], to[PW]; int po[PW], bo[PW];
    stW(o.x, ox); stW(o.y, oy); stW(o.z, oz); stW(d.x, dx); stW(d.y, dy); stW(d.z, dz); stW(tMaxIn, tm);
    const int am = mask8(active);
    for (int l = 0; l < PW; ++l) {
        to[l] = -INFINITY; po[l] = -1; bo[l] = 0;
        if (!(am & (1 << l))) continue;
        if (anyHit) {
            ShadowRay sr; sr.origin = (float4)(ox[l], oy[l], oz[l], tm[l]); sr.direction = (float4)(dx[l], dy[l], dz[l], 0.0f);
            bo[l] = Shadow_Occluded(sr, scene, nodes, leaves, tris, spheres, planes, instances) ? -1 : 0;
        } else {
            Ray r; r.origin = (float4)(ox[l], oy[l], oz[l], 0.0f); r.direction = (float4)(dx[l], dy[l], dz[l], INFINITY);
            int inst;
            Hit h = Ray_Closest(r, scene, nodes, leaves, tris, spheres, planes, instances, &inst);
            to[l] = h.t; po[l] = h.prim;
        }
    }
    *tOut = ldW(to);
    int dummy[PW];
    *primOut = PW == 16 ? (iW)(0) : (iW)(0);
    { iW p; vstore_int((iW)(0), dummy); p = ldWi(po); *primOut = p; }
    return ldWi(bo);
}
#define PacketTrace(nodes, leaves, tris, spheres, numTriangles, o, d, tMax, act, any_, t, p) \
    LaneTrace(nodes, leaves, tris, spheres, planes, instances, scene, o, d, tMax, act, any_, t, p)
#endif

#ifdef LANE_SAMPLER
/* clrt's stratified sampler (common.cl Rng_Stratified2D) for the PW samples of one pixel at once: the
 * lanes share the pixel and the path id (every lane's path takes child 0), so the per-dimension hashes
 * are computed once; only the sample index differs per lane. */
inline uW ProtoBits_Reverse(uW v) { CLRT_BITS_REVERSE_NETWORK(v); return v; }  /* common.cl's bodies */
inline uW ProtoBits_LaineKarras(uW x, uint seed) { CLRT_LAINE_KARRAS(x, seed); return x; }
inline uW ProtoSobol_Dim1Reversed(uW i) { CLRT_SOBOL_DIM1_REVERSED(i); return i; }
inline void Lane_Stratified2D(uint strat, uW sample, uint dim, fW* ux, fW* uy) {
    const uint sIdx = Rng_Hash(strat ^ dim * 0x9e3779b1u);
    const uint sX = Rng_Hash(sIdx ^ 0xa54ff53au), sY = Rng_Hash(sIdx ^ 0x510e527fu);
    const uW idx = ProtoBits_Reverse(ProtoBits_LaineKarras(ProtoBits_Reverse(sample), sIdx));
    const uW x = ProtoBits_Reverse(ProtoBits_LaineKarras(idx, sX));
    const uW y = ProtoBits_Reverse(ProtoBits_LaineKarras(ProtoSobol_Dim1Reversed(idx), sY));
    *ux = convert_fW(x >> 8) * (1.0f / 16777216.0f);
    *uy = convert_fW(y >> 8) * (1.0f / 16777216.0f);
}
#endif
#define PW_GATHER_BEGIN float gx[PW], gy[PW], gz[PW]


__kernel CLRT_KERNEL_VEC_HINT void render_fused(CLRT_KERNEL_PARAMS(render_fused)) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const int pixel = firstPixel + i;
    const int px = pixel % cam.width, py = pixel / cam.width;
    const int numTriangles = scene.numTriangles;
    const int depthMax = CLRT_LAST_DEPTH(scene.maxDepth, scene.pathMode); /* NEE at depths 0..depthMax-1 */
    const __global Light* ml = &lights[0];
    const __global float4* ltri = lightData + ml->objFirst;
    const int nl = ml->objCount;
    const float3 Le = ml->radiance.xyz;
    const float lightArea = ml->area;
    float4 acc = image[pixel];
    uint secondary = 0;
    const int total = passes * samples;
    #ifdef ONE_PATH
#define PSTEP 1
#else
#define PSTEP PW
#endif
    for (int s0 = 0; s0 < total; s0 += PSTEP) {
        float ox[PW], oy[PW], oz[PW], dx[PW], dy[PW], dz[PW];
#ifdef REAL_SAMPLER
        PathState lanePath[PW];
#endif
        for (int l = 0; l < PW; ++l) {
            PathState path; Ray ray;
            const int s = firstSample + min(s0 + l, total - 1);
            Camera_GenerateAt(cam, scene, pixel, px, py, s, &path, &ray);
#ifdef REAL_SAMPLER
            lanePath[l] = path;
#endif
            ox[l] = ray.origin.x; oy[l] = ray.origin.y; oz[l] = ray.origin.z;
            dx[l] = ray.direction.x; dy[l] = ray.direction.y; dz[l] = ray.direction.z;
        }
        const iW laneId = LANES;
        iW active = (iW)(s0) + laneId < (iW)(total);
#ifdef ONE_PATH
        active &= laneId == (iW)(0);
#endif
        V3W o = V3(ldW(ox), ldW(oy), ldW(oz)), d = V3(ldW(dx), ldW(dy), ldW(dz));
        uW rng = (uW)(scene.seed * 0x9E3779B9u ^ (uint)pixel * 0x85EBCA6Bu) + convert_uW((iW)(firstSample + s0) + laneId) * 0xC2B2AE35u;
        RngW_Next(&rng); RngW_Next(&rng);
        V3W L = V3b((float3)(0.0f)), beta = V3b((float3)(1.0f));
        fW pdfPrev = (fW)(0.0f); /* bsdf pdf (solid angle) of the ray that led here; 0: camera */
        for (int depth = 0; depth <= depthMax && any(active); ++depth) {
            fW t; iW prim;
#ifdef CAMERA_PACKETS
            if (depth == 0) /* camera rays as a packet (the function itself, not LANE_TRACE's macro) */
                PacketTraceImpl(nodes, leaves, tris, spheres, numTriangles, o, d, (fW)(INFINITY), active, 0, &t, &prim);
            else
#endif
            PacketTrace(nodes, leaves, tris, spheres, numTriangles, o, d, (fW)(INFINITY), active, 0, &t, &prim);
            active &= prim >= 0;
            if (!any(active)) break;
            /* gather the surface */
            float nx[PW], ny[PW], nz[PW], kr[PW], kg[PW], kb[PW], em[PW];
            const int am = mask8(active);
            for (int l = 0; l < PW; ++l) {
                nx[l] = 0.0f; ny[l] = 0.0f; nz[l] = 1.0f; kr[l] = kg[l] = kb[l] = 0.0f; em[l] = 0.0f;
                if (!(am & (1 << l))) continue;
                const int ref = ((int*)&prim)[l];
                float3 n; int mat, light;
                if (ref < numTriangles) {
                    const __global Triangle* tr = &tris[ref];
                    n = cross(tr->v1.xyz - tr->v0.xyz, tr->v2.xyz - tr->v0.xyz);
                    mat = triShading[ref].material; light = triShading[ref].light;
                } else {
                    const __global Sphere* sph = &spheres[ref - numTriangles];
                    const float tl = ((float*)&t)[l];
                    const float3 pw = (float3)(ox[l], oy[l], oz[l]) + tl * (float3)(dx[l], dy[l], dz[l]);
                    const float3 po = affinePoint(sph->worldToObject, pw) - sph->centerRadius.xyz;
                    n = po.x * sph->worldToObject[0].xyz + po.y * sph->worldToObject[1].xyz + po.z * sph->worldToObject[2].xyz;
                    mat = sph->material; light = sph->light;
                }
                n = normalize(n);
                nx[l] = n.x; ny[l] = n.y; nz[l] = n.z;
                const float4 kd = materials[mat].diffuse;
                kr[l] = kd.x; kg[l] = kd.y; kb[l] = kd.z;
                em[l] = light >= 0 ? 1.0f : 0.0f;
            }
            V3W n = V3(ldW(nx), ldW(ny), ldW(nz));
            const V3W p = V3add(o, V3mul(d, t));
            const fW cosO = V3dot(n, d);
            n = V3sel(n, V3mul(n, (fW)(-1.0f)), cosO > 0.0f); /* facing the ray */
            /* emission (two-sided light), MIS against the light sample of the previous vertex */
            const iW emit = active & (ldW(em) > 0.0f);
            if (any(emit)) {
                const fW pdfL = t * t / (lightArea * fabs(cosO));
                const fW w = select(pdfPrev * pdfPrev / (pdfPrev * pdfPrev + pdfL * pdfL), (fW)(1.0f), pdfPrev == 0.0f);
                const fW wl = select((fW)(0.0f), w, emit);
                L = V3add(L, V3mul(V3mulv(beta, V3b(Le)), wl));
            }
            if (depth == depthMax) break;
            const V3W kd = V3(ldW(kr), ldW(kg), ldW(kb));
            active &= (kd.x + kd.y + kd.z) > 0.0f;
            if (!any(active)) break;
            const V3W pOff = V3add(p, V3mul(n, (fW)(1e-4f)));
            /* light sample: triangle by the area CDF (linear scan), uniform point */
#ifdef REAL_SAMPLER
            /* clrt's streams: the light sample at dimension 4 + 32·depth + 8 (light 0), the bounce at + 5 */
            float a1[PW], a2[PW], aB0[PW], aB1[PW]; int ak[PW];
#ifdef LANE_SAMPLER
            {
                const uint strat = Rng_Key(scene.seed, pixel, 0, lanePath[0].pathId).strat; /* shared by the lanes */
                int smp[PW];
                for (int l = 0; l < PW; ++l) smp[l] = lanePath[l].sample;
                const uW sampleW = as_uW(ldWi(smp));
                const uint dim = 4u + 32u * (uint)depth;
                fW uLx, uLy, uBx, uBy;
                Lane_Stratified2D(strat, sampleW, dim + 8u, &uLx, &uLy);
                Lane_Stratified2D(strat, sampleW, dim + 5u, &uBx, &uBy);
                float lx[PW];
                stW(uLx, lx); stW(uLy, a2); stW(uBx, aB0); stW(uBy, aB1);
                for (int l = 0; l < PW; ++l) {
                    float ux;
                    ak[l] = MeshLight_PickTriangle(ltri, nl, lx[l], &ux);
                    a1[l] = ux;
                    lanePath[l].pathId = lanePath[l].pathId < 0x80000000u ? lanePath[l].pathId * 2u : lanePath[l].pathId;
                }
            }
            if (0)
#endif
            for (int l = 0; l < PW; ++l) {
                PathState ps = lanePath[l];
                ps.depth = depth;
                const RngKey key = Rng_Key(scene.seed, ps.pixel, ps.sample, ps.pathId);
                const uint dim = 4u + 32u * (uint)depth;
                const float2 uL = Sampler_2D(scene, ps, key, dim + 8u);
                const float2 uB = Sampler_2D(scene, ps, key, dim + 5u);
                float ux;
                ak[l] = MeshLight_PickTriangle(ltri, nl, uL.x, &ux);
                a1[l] = ux; a2[l] = uL.y; aB0[l] = uB.x; aB1[l] = uB.y;
                lanePath[l].pathId = ps.pathId < 0x80000000u ? ps.pathId * 2u : ps.pathId;
            }
            const iW k = ldWi(ak);
            const fW u1 = ldW(a1), u2 = ldW(a2);
#else
            const fW u0 = RngW_U(&rng), u1 = RngW_U(&rng), u2 = RngW_U(&rng);
            iW k = (iW)(0);
            for (int j = 0; j < nl - 1; ++j) k += ((fW)(ltri[3 * j].w) < u0) ? (iW)(1) : (iW)(0);
#endif
            float qx[PW], qy[PW], qz[PW], lnx[PW], lny[PW], lnz[PW];
            const fW su = sqrt(u1);
            const fW b0 = 1.0f - su, b1 = u2 * su;
            for (int l = 0; l < PW; ++l) {
                const int kk = ((int*)&k)[l];
                const float3 v0 = ltri[3 * kk].xyz, v1 = ltri[3 * kk + 1].xyz, v2 = ltri[3 * kk + 2].xyz;
                const float bb0 = ((float*)&b0)[l], bb1 = ((float*)&b1)[l];
                const float3 q = bb0 * v0 + bb1 * v1 + (1.0f - bb0 - bb1) * v2;
                const float3 nn = normalize(cross(v1 - v0, v2 - v0));
                qx[l] = q.x; qy[l] = q.y; qz[l] = q.z; lnx[l] = nn.x; lny[l] = nn.y; lnz[l] = nn.z;
            }
            V3W wi = V3sub(V3(ldW(qx), ldW(qy), ldW(qz)), pOff);
            const fW dist2 = V3dot(wi, wi), dist = sqrt(dist2);
            wi = V3mul(wi, 1.0f / dist);
            const fW cosL = fabs(V3dot(V3(ldW(lnx), ldW(lny), ldW(lnz)), wi));
            const fW cosS = V3dot(n, wi);
            const iW lv = active & (cosS > 0.0f) & (cosL > 0.0f);
            if (any(lv)) {
                const fW pdfL = dist2 / (lightArea * cosL);
                const fW pdfB = cosS * M_1_PI_F;
                const fW w = pdfL * pdfL / (pdfL * pdfL + pdfB * pdfB);
                fW tS; iW pS;
                const iW blocked = PacketTrace(nodes, leaves, tris, spheres, numTriangles, pOff, wi, dist * 0.999f, lv, 1, &tS, &pS);
                const fW f = select((fW)(0.0f), cosS * M_1_PI_F * w / pdfL, lv & ~blocked);
                L = V3add(L, V3mulv(V3mulv(beta, kd), V3mul(V3b(Le), f)));
            }
            /* bounce: cosine-weighted */
#ifdef REAL_SAMPLER
            const fW v0r = ldW(aB0), v1r = ldW(aB1);
#else
            const fW v0r = RngW_U(&rng), v1r = RngW_U(&rng);
#endif
            const fW r = sqrt(v0r);
            fW cph; const fW sph = sincos(2.0f * M_PI_F * v1r, &cph);
            const fW lx = r * cph, ly = r * sph, lz = sqrt(fmax(0.0f, 1.0f - v0r));
            const fW sgn = copysign((fW)(1.0f), n.z);
            const fW a = -1.0f / (sgn + n.z);
            const fW bb = n.x * n.y * a;
            const V3W tt = V3(1.0f + sgn * n.x * n.x * a, sgn * bb, -sgn * n.x);
            const V3W bt = V3(bb, sgn + n.y * n.y * a, -n.y);
            d = V3add(V3add(V3mul(tt, lx), V3mul(bt, ly)), V3mul(n, lz));
            o = pOff;
            pdfPrev = lz * M_1_PI_F;
            beta = V3mulv(beta, kd);
            secondary += popcount(mask8(active));
            stW(o.x, ox); stW(o.y, oy); stW(o.z, oz);
            stW(d.x, dx); stW(d.y, dy); stW(d.z, dz);
        }
        iW valid = (iW)(s0) + laneId < (iW)(total);
#ifdef ONE_PATH
        valid &= laneId == (iW)(0);
#endif
        const fW lr = select((fW)(0.0f), L.x, valid & isfinite(L.x)), lg = select((fW)(0.0f), L.y, valid & isfinite(L.y)),
                 lb = select((fW)(0.0f), L.z, valid & isfinite(L.z));
        { float ar[PW], ag[PW], ab[PW]; stW(lr, ar); stW(lg, ag); stW(lb, ab);
          for (int l = 0; l < PW; ++l) { acc.x += ar[l]; acc.y += ag[l]; acc.z += ab[l]; } }
    }
    image[pixel] = acc;
    if (secondary > 0) atomic_add(&rayCounts[0], secondary);
}
