/* lanes.cl — the path tracer with four paths per work-item in float4 lanes (render_lanes; CPU devices,
 * compiled under CLRT_HAS_LANES: FeatureSet::lanes). A work-item takes its pixel's samples four at a
 * time (lane k: sample s0 + k) and steps their paths together, one depth per round:
 *   per lane, scalar: the closest hit (Ray_Closest) and the loads of what it hit (Lanes_Closest), the
 *     surface of any hit but a plain triangle (Lanes_ScalarSurface), the material's f, the samples of lights
 *     without a lane form (Lanes_ScalarLightSample), the
 *     shadow rays' occlusion (Shadow_Occluded), the specular pick and a mirror's, conductor's or
 *     dielectric's child (Path_SpecularBounce), roulette;
 *   in lanes: a plain triangle's surface, the facing and the emission the ray sees (Lanes_Surfaces: the
 *     path branch of Shade_Hit and the start of Path_ShadeHit), the sampler (Lanes_Stratified2D), the
 *     light samples of every kind but an environment's (Light_Sample: MeshLight_PickTriangle, MeshLight_Sample,
 *     SphereLight_Sample, AreaLight_Sample, ...; Shadow_Make,
 *     Path_LightSampleWeight, ObjectLight_AimShadow), a glossy or textured material's f, pdf and bounce
 *     (lanes_brdf.cl) and the bounce (Path_SampleBounce, Path_Child).
 * It computes what render_fused computes for the same random streams, up to rounding (tests/test_lanes.cpp):
 * one lane is one path of the fused kernel. Scenes of its family only (src/flatten/device_scene.h
 * lanesFamily, src/render/fused_renderer.h lanesUnsupported): every sampler (the lanes' stratified form,
 * or Sampler_2D per lane), no tree of paths, no motion blur or mip-maps; every surface (a plain world-space triangle's in lanes, the others per lane:
 * Lanes_ScalarSurface, textures and instances included), every material (a direction-free f,
 * CLRT_BRDF_LAMBERTIAN, in lanes; a glossy or textured one in lanes too, from its ShadingPoint:
 * Lanes_GlossyLightTerms, Lanes_GlossyBounces) and every light (in lanes, Lanes_LightDirection; an environment light per
 * lane: Lanes_ScalarLightSample). Classic (direct-lighting) cameras of a scene under an environment light
 * (Lanes_Direct): per lane render_fused's Fused_Path, but the environment light's multi-sample MIS at the camera
 * rays' hits in steps across the lanes (Lanes_EnvMisShadows); their children per lane as render_fused follows
 * them (Lanes_DirectChildren). Why lanes: a path's
 * shading is a chain of dependent sqrt, division, sin/cos and loads; four paths go through it as one
 * chain of vector instructions (docs/studies/2026-12-05-simd-lanes-prototype.md).
 * Reads: the scene's geometry, materials and lights; writes: image, and rayCounts[0] += the bounce rays. */
#ifndef CLRT_LANES_CL
#define CLRT_LANES_CL

#include "fused.cl"
#include "lanes_surface.cl"
#include "lanes_brdf.cl"

#ifdef CLRT_HAS_LANES

/* ---- the lanes' samples ---------------------------------------------------------------------------- */

/* The camera rays of samples s0 .. s0 + n - 1 (n <= 4) of pixel `pixel` (Camera_GenerateAt), lane k the sample
 * s0 + k (lanes past n repeat the last: every lane holds a valid path); returns the lanes' sample indices. */
inline LaneU Lanes_CameraRays(CameraParams cam, SceneParams scene, int pixel, int px, int py, int s0, int n,
                              PathState* path, Ray* ray) {
    int sampleIdx[CLRT_LANES];
    for (int k = 0; k < CLRT_LANES; ++k) {
        sampleIdx[k] = s0 + min(k, n - 1);
        Camera_GenerateAt(cam, scene, pixel, px, py, sampleIdx[k], &path[k], &ray[k]);
    }
    return as_uint4(vload4(0, sampleIdx));
}

/* The lanes' 2D sample of dimension dim, as Sampler_2D draws it for each lane's path: Lanes_Stratified2D
 * under the stratified sampler (and the correlated one, whose path dimensions are the stratified ones),
 * else Sampler_2D per lane (zsobol, independent). */
inline void Lanes_Sample2D(SceneParams scene, uint strat, LaneU sample, const PathState* path, int pixel, uint dim,
                           LaneF* u1, LaneF* u2) {
    if (scene.pixelSampler == CLRT_PIXEL_SAMPLER_STRATIFIED || scene.pixelSampler == CLRT_PIXEL_SAMPLER_CORRELATED) {
        Lanes_Stratified2D(strat, sample, dim, u1, u2);
        return;
    }
    float a[CLRT_LANES], b[CLRT_LANES];
    for (int k = 0; k < CLRT_LANES; ++k) {
        const float2 u = Sampler_2D(scene, path[k], Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId), dim);
        a[k] = u.x;
        b[k] = u.y;
    }
    *u1 = vload4(0, a);
    *u2 = vload4(0, b);
}

/* ---- an environment light's multi-sample MIS in steps across the lanes (both kinds of camera) ------ */

/* The lanes' 2D sample of light dimension dim at their depth-0 shading points, as Sampler_Light2D draws it:
 * under the correlated sampler a classic camera's light samples take its camera sample (per lane), else
 * Lanes_Sample2D. */
inline void Lanes_Light2D(SceneParams scene, uint strat, LaneU sample, const PathState* path, int pixel, uint dim,
                          LaneF* u1, LaneF* u2) {
    if (CLRT_SAMPLER_IS_CORRELATED(scene) && scene.pathMode == 0) {
        float a[CLRT_LANES], b[CLRT_LANES];
        for (int k = 0; k < CLRT_LANES; ++k) {
            const float2 u = Sampler_Light2D(scene, path[k], Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId), dim);
            a[k] = u.x;
            b[k] = u.y;
        }
        *u1 = vload4(0, a);
        *u2 = vload4(0, b);
        return;
    }
    Lanes_Sample2D(scene, strat, sample, path, pixel, dim, u1, u2);
}

#ifdef CLRT_HAS_ENV_LIGHT
/* EnvMis_Point of the lanes in `bits` under a lat-long map, in lanes: for those whose bucket drew a texel, the
 * point within it (EnvDist_CellSample's lat-long branch: u uniform, cos θ uniform between the row's bounds). */
inline void Lanes_EnvLatLongPoints(EnvMis* s, int bits) {
    float zTop[CLRT_LANES], zBottom[CLRT_LANES], x[CLRT_LANES], dv[CLRT_LANES], p[CLRT_LANES];
    int cells = 0, W = 1;
    for (int k = 0; k < CLRT_LANES; ++k) {
        zTop[k] = 1.0f; zBottom[k] = x[k] = dv[k] = p[k] = 0.0f;
        if (!((bits >> k) & 1) || s[k].d.bucket < 0) continue;
        const __global float* own = s[k].d.own;
        W = (int)own[0];
        const int H = (int)own[1];
        const __global float* zr = own + 4 + H + 1 + H * (W + 1) + W * H;
        zTop[k] = zr[s[k].cell.J];
        zBottom[k] = zr[s[k].cell.J + 1];
        x[k] = (float)s[k].cell.I + s[k].cell.du;
        dv[k] = s[k].cell.dv;
        p[k] = s[k].cell.p;
        cells |= 1 << k;
    }
    if (!cells) return;
    const LaneF z0 = vload4(0, zTop), z1 = vload4(0, zBottom), u = vload4(0, x) / (float)W;
    const LaneF z = z0 - vload4(0, dv) * (z0 - z1), st = sqrt(fmax(0.0f, 1.0f - z * z));
    LaneF c, sn;
    Lanes_SinCos2Pi(u, &c, &sn); /* φ = 2πu − π, as in EnvMap_UvToDir */
    const LaneF v = Lanes_Atan2(st, z) * CLRT_INV_PI; /* acos(z) */
    const LaneF omega = 2.0f * CLRT_PI / (float)W * (z0 - z1);
    const LaneF pdf = select((LaneF)(0.0f), vload4(0, p) / omega, omega > 0.0f);
    float3 dir[CLRT_LANES];
    float uo[CLRT_LANES], vo[CLRT_LANES], po[CLRT_LANES];
    LaneV3_Store(LaneV3_Make(-st * sn, z, st * c), dir);
    vstore4(u, 0, uo); vstore4(v, 0, vo); vstore4(pdf, 0, po);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((cells >> k) & 1)) continue;
        s[k].wL = dir[k];
        s[k].uvL = (float2)(uo[k], vo[k]);
        s[k].pL = po[k];
        s[k].okL = po[k] > 0.0f && isfinite(po[k]);
    }
}

/* Light l's multi-sample MIS (an environment light; Light_ShadowRays' first branch, dim its dimension there) at
 * the shading points sp of the lanes in `bits` (classic cameras, and the path tracer's nee lanes): their two
 * shadow rays each, sr and sr2, as Light_ShadowRays makes them, with EnvLight_SampleMis's steps (lights.cl,
 * EnvMis_*) run for every lane before the next step, so that the lanes' chains of dependent loads (the
 * bucket's row, column and texel CDFs, the map's texels) are in flight together; the arithmetic between them
 * (the cosine directions and their lat-long coordinates, the lat-long point in a drawn texel) in lanes. */
inline void Lanes_EnvMisShadows(SceneParams scene, const __global Material* materials, const __global Light* lights,
                                const __global ImageInfo* images, const __global float4* texels,
                                const __global float* envDist, int l, int bits, const PathState* path,
                                const ShadingPoint* sp, int pixel, uint strat, LaneU sample, uint dim, ShadowRay* sr,
                                ShadowRay* sr2) {
    const __global Light* light = &lights[l];
    int first = 0; /* a lane in bits (not empty), whose normal the others borrow */
    while (!((bits >> first) & 1)) ++first;
    LaneF a1, a2, b1, b2;
    Lanes_Light2D(scene, strat, sample, path, pixel, dim, &a1, &a2);
    Lanes_Sample2D(scene, strat, sample, path, pixel, dim + 0x8000u, &b1, &b2); /* the cosine sample's */
    float ua[CLRT_LANES], va[CLRT_LANES], ub[CLRT_LANES], vb[CLRT_LANES];
    vstore4(a1, 0, ua); vstore4(a2, 0, va); vstore4(b1, 0, ub); vstore4(b2, 0, vb);
    /* EnvMis_Begin's cosine directions (EnvSample_Cosine) and their lat-long coordinates (EnvMap_DirToUv) in
     * lanes, the rest of it per lane */
    float3 nMap[CLRT_LANES], wCos[CLRT_LANES];
    for (int k = 0; k < CLRT_LANES; ++k) nMap[k] = EnvLight_ToMap(light, sp[(bits >> k) & 1 ? k : first].normal.xyz);
    const LaneV3 n = LaneV3_Load(nMap);
    LaneV3 t, bt;
    Lanes_Basis(n, &t, &bt);
    const LaneF u1 = fmin(b1, CLRT_ONE_MINUS_EPS), r = sqrt(u1), z = sqrt(fmax(0.0f, 1.0f - u1));
    LaneF c, sn;
    Lanes_SinCos2Pi(b2, &c, &sn);
    LaneV3 w = LaneV3_Add(LaneV3_Add(LaneV3_Scale(t, r * c), LaneV3_Scale(bt, r * sn)), LaneV3_Scale(n, z));
    w = LaneV3_Scale(w, 1.0f / sqrt(LaneV3_Dot(w, w)));
    LaneV3_Store(w, wCos);
    float uCos[CLRT_LANES], vCos[CLRT_LANES];
    vstore4(0.5f * (1.0f + Lanes_Atan2(w.x, -w.z) / CLRT_PI), 0, uCos);
    vstore4(Lanes_Atan2(sqrt(w.x * w.x + w.z * w.z), w.y) / CLRT_PI, 0, vCos);
    EnvMis s[CLRT_LANES];
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((bits >> k) & 1)) continue;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        EnvMis_Begin(light, envDist, sp[k].normal.xyz, (float2)(ua[k], va[k]), (float2)(ub[k], vb[k]), 0, &s[k]);
        s[k].withCosine = EnvLight_MisWithCosine(path[k], key, l);
        if (!s[k].withCosine) continue;
        s[k].wB = wCos[k];
        s[k].uvB = light->mapping == ENV_LATLONG ? (float2)(uCos[k], vCos[k]) : EnvMap_DirToUv(light->mapping, wCos[k]);
    }
    for (int k = 0; k < CLRT_LANES; ++k) if ((bits >> k) & 1) EnvMis_Row(&s[k]);
    for (int k = 0; k < CLRT_LANES; ++k) if ((bits >> k) & 1) EnvMis_Column(&s[k]);
    for (int k = 0; k < CLRT_LANES; ++k) if ((bits >> k) & 1) EnvMis_Texel(&s[k]);
    if (light->mapping == ENV_LATLONG) Lanes_EnvLatLongPoints(s, bits);
    else for (int k = 0; k < CLRT_LANES; ++k) if ((bits >> k) & 1) EnvMis_Point(&s[k]);
    for (int k = 0; k < CLRT_LANES; ++k) if ((bits >> k) & 1) EnvMis_Footprints(light, images, &s[k]);
    for (int k = 0; k < CLRT_LANES; ++k) if ((bits >> k) & 1) EnvMis_Reads(light, images, texels, &s[k]);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((bits >> k) & 1)) continue;
        float3 wiL, eL, wiB, eB;
        EnvMis_Values(light, CLRT_ENV_MIS_COSINE_SHARE, &s[k], &wiL, &eL, &wiB, &eB);
        sr[k] = Shadow_Make(sp[k], materials, path[k].throughput.xyz, wiL, INFINITY, eL, scene.shadowEpsilon);
        sr2[k] = Shadow_Make(sp[k], materials, path[k].throughput.xyz, wiB, INFINITY, eB, scene.shadowEpsilon);
    }
}
#endif

#ifdef CLRT_HAS_PATH_TRACING /* ---- path-traced cameras: one depth of the lanes' paths (lights, bounces, children) ---- */

/* Which of the lanes in okBits see the shadow ray from org along unit dir unblocked up to tMax
 * (Shadow_Occluded, per lane). */
inline int Lanes_Unoccluded(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int okBits, LaneV3 org, LaneV3 dir, LaneF tMax) {
    if (!okBits) return 0;
    float tm[CLRT_LANES];
    float3 o[CLRT_LANES], d[CLRT_LANES];
    vstore4(tMax, 0, tm);
    LaneV3_Store(org, o);
    LaneV3_Store(dir, d);
    int open = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!(okBits & (1 << k))) continue;
        ShadowRay sr;
        sr.origin = (float4)(o[k], tm[k]);
        sr.direction = (float4)(d[k], 0.0f);
        sr.contribution = (float4)(0.0f);
        if (!Shadow_Occluded(sr, scene, nodes, leaves, tris, spheres, planes, instances)) open |= 1 << k;
    }
    return open;
}

#ifdef CLRT_HAS_LIGHT_MESH
/* MeshLight_PickTriangle for the lanes: the first of the light's n triangles whose cumulative area
 * fraction (the w of its first vertex) exceeds u (the last if none), by a binary search of fixed steps
 * (the count of those at or below u: the same triangle for a non-decreasing table); *uRest as there. */
inline LaneI Lanes_PickTriangle(const __global float4* tri, int n, LaneF u, LaneF* uRest) {
    LaneI pos = (LaneI)(0);
    int step = 1;
    while (step * 2 <= n - 1) step *= 2;
    for (; step > 0 && n > 1; step >>= 1) {
        const LaneI next = pos + step;
        int idx[CLRT_LANES];
        float c[CLRT_LANES];
        vstore4(min(next, (LaneI)(n - 1)) - 1, 0, idx); /* not min(int4, int): garbage on Oclgrind (docs/quirks.md) */
        for (int k = 0; k < CLRT_LANES; ++k) c[k] = tri[3 * idx[k]].w;
        pos = select(pos, next, (next <= n - 1) & (vload4(0, c) <= u));
    }
    int at[CLRT_LANES];
    float c0[CLRT_LANES], c1[CLRT_LANES];
    vstore4(pos, 0, at);
    for (int k = 0; k < CLRT_LANES; ++k) {
        const int i = at[k];
        c0[k] = i > 0 ? tri[3 * (i - 1)].w : 0.0f;
        c1[k] = tri[3 * i].w;
    }
    const LaneF lo = vload4(0, c0), hi = vload4(0, c1);
    *uRest = select((LaneF)(0.5f), clamp((u - lo) / (hi - lo), 0.0f, 0.99999994f), hi > lo);
    return pos;
}

/* MeshLight_Subtended of the lanes' triangles (a, b, c; n = (b − a)×(c − a)) at their points p, the same
 * operations in lanes. */
inline void Lanes_Subtended(LaneV3 a, LaneV3 b, LaneV3 c, LaneV3 n, LaneV3 p, LaneF* num, LaneF* den) {
    const LaneV3 ra = LaneV3_Sub(a, p), rb = LaneV3_Sub(b, p), rc = LaneV3_Sub(c, p);
    const LaneF la = sqrt(LaneV3_Dot(ra, ra)), lb = sqrt(LaneV3_Dot(rb, rb)), lc = sqrt(LaneV3_Dot(rc, rc));
    *num = fabs(LaneV3_Dot(ra, n));
    *den = la * lb * lc + LaneV3_Dot(ra, rb) * lc + LaneV3_Dot(ra, rc) * lb + LaneV3_Dot(rb, rc) * la;
}

/* MeshLight_Weight at the lanes' points p, the same operations in lanes; *num, *den: its Lanes_Subtended terms. */
inline LaneF Lanes_MeshLightWeight(float3 a, float3 b, float3 c, LaneV3 p, LaneF* num, LaneF* den) {
    Lanes_Subtended(LaneV3_Splat(a), LaneV3_Splat(b), LaneV3_Splat(c), LaneV3_Splat(cross(b - a, c - a)), p, num, den);
    const LaneF w = select((LaneF)(CLRT_MESHLIGHT_WEIGHT_CAP), *num / *den, *den * CLRT_MESHLIGHT_WEIGHT_CAP > *num);
    return select((LaneF)(0.0f), w, *num > 0.0f);
}

/* MeshLight_Facing of triangle (a, b, c) for the lanes' points p: the lanes that see its inner side, and those
 * outside the enclosed light's volume by it added to *outside. */
inline LaneI Lanes_MeshLightInner(float3 a, float3 b, float3 c, LaneV3 p, float3 inside, LaneI* outside) {
    const float3 n = cross(b - a, c - a);
    const LaneV3 ra = LaneV3_Sub(LaneV3_Splat(a), p);
    const LaneF dn = LaneV3_Dot(ra, LaneV3_Splat(n)), s = dot(a - inside, n) > 0.0f ? dn : -dn;
    *outside |= (s < 0.0f) & (s * s > 1e-10f * LaneV3_Dot(ra, ra) * dot(n, n));
    return s > 0.0f;
}

/* MeshLight_SphericalDirection in lanes (each lane its own spherical triangle a, b, c of half-area halfOmega). */
inline LaneV3 Lanes_SphericalDirection(LaneV3 a, LaneV3 b, LaneV3 c, LaneF halfOmega, LaneF u1, LaneF u2) {
    const LaneV3 ca = LaneV3_Sub(c, a), ba = LaneV3_Sub(b, a);
    const LaneV3 cPerp = LaneV3_Normalize(LaneV3_Sub(ca, LaneV3_Scale(a, LaneV3_Dot(ca, a))));
    const LaneF g = 1.0f + LaneV3_Dot(a, b), m = LaneV3_Dot(ba, cPerp), k = fabs(LaneV3_Dot(ba, LaneV3_Cross(cPerp, a)));
    LaneF cosH, sinH;
    Lanes_SinCos2Pi(u1 * halfOmega * (0.5f * CLRT_INV_PI), &cosH, &sinH);
    const LaneF n = sinH * g, d = fmax(k * cosH - sinH * m, 0.0f), r = n * n + d * d;
    const LaneV3 cHat = LaneV3_Add(LaneV3_Scale(a, (d * d - n * n) / r), LaneV3_Scale(cPerp, 2.0f * n * d / r));
    const LaneV3 bc = LaneV3_Sub(cHat, b);
    const LaneF oneMinusZ = u2 * 0.5f * LaneV3_Dot(bc, bc);
    const LaneF sinZ = sqrt(fmax(0.0f, oneMinusZ * (2.0f - oneMinusZ)));
    const LaneV3 bpRaw = LaneV3_Sub(bc, LaneV3_Scale(b, LaneV3_Dot(bc, b)));
    const LaneF lbp = LaneV3_Dot(bpRaw, bpRaw);
    const LaneV3 w = LaneV3_Add(LaneV3_Scale(b, 1.0f - oneMinusZ), LaneV3_Scale(bpRaw, select((LaneF)(0.0f), sinZ * rsqrt(lbp), lbp > 0.0f)));
    return LaneV3_Select(a, LaneV3_Normalize(w), r > 0.0f);
}

/* MeshLight_PickByWeight for the lanes (n <= CLRT_MESHLIGHT_PICK_MAX): the picked triangles, *uRest, and
 * *total (Σw) and *wPick (the pick's w) from which the caller makes A·Σw / w; *wPick 0 where nothing is picked.
 * *num, *den: the picked triangle's Lanes_Subtended terms (its solid angle's; 0 and 1 where its weight was not
 * computed: no lane sees it, and then it is not picked). */
inline LaneI Lanes_PickByWeight(const __global Light* light, const __global float4* tri, int n, LaneV3 p, LaneF u,
                                LaneF* uRest, LaneF* total, LaneF* wPick, LaneF* num, LaneF* den) {
    LaneF w[CLRT_MESHLIGHT_PICK_MAX > 0 ? CLRT_MESHLIGHT_PICK_MAX : 1];
    LaneI hidden[CLRT_MESHLIGHT_PICK_MAX > 0 ? CLRT_MESHLIGHT_PICK_MAX : 1], outside = (LaneI)(0);
    const int enclosed = light->position.w > 0.0f; /* MeshLight_Weights: hidden triangles weigh 0 */
    for (int i = 0; i < n; ++i)
        hidden[i] = enclosed ? Lanes_MeshLightInner(tri[3 * i].xyz, tri[3 * i + 1].xyz, tri[3 * i + 2].xyz, p,
                                                    light->position.xyz, &outside)
                             : (LaneI)(0);
    LaneF sum = (LaneF)(0.0f), nums[CLRT_MESHLIGHT_PICK_MAX > 0 ? CLRT_MESHLIGHT_PICK_MAX : 1],
                              dens[CLRT_MESHLIGHT_PICK_MAX > 0 ? CLRT_MESHLIGHT_PICK_MAX : 1];
    for (int i = 0; i < n; ++i) { /* a triangle no lane sees is not weighed */
        hidden[i] &= outside;
        nums[i] = (LaneF)(0.0f);
        dens[i] = (LaneF)(1.0f);
        w[i] = all(hidden[i]) ? (LaneF)(0.0f)
                              : select(Lanes_MeshLightWeight(tri[3 * i].xyz, tri[3 * i + 1].xyz, tri[3 * i + 2].xyz, p,
                                                             &nums[i], &dens[i]),
                                       (LaneF)(0.0f), hidden[i]);
        sum += w[i];
    }
    const LaneF x = u * sum;
    LaneF below = (LaneF)(0.0f), wk = w[0];
    LaneI k = (LaneI)(0), going = (LaneI)(-1);
    *num = nums[0];
    *den = dens[0];
    for (int i = 0; i < n - 1; ++i) { /* as the scalar loop: past triangle i while x is not below its end */
        going &= !(x < below + w[i]);
        below = select(below, below + w[i], going);
        k = select(k, (LaneI)(i + 1), going);
        wk = select(wk, w[i + 1], going);
        *num = select(*num, nums[i + 1], going);
        *den = select(*den, dens[i + 1], going);
    }
    const LaneI ok = (sum > 0.0f) & isfinite(sum) & (wk > 0.0f);
    *uRest = select((LaneF)(0.5f), clamp((x - below) / wk, 0.0f, 0.99999994f), ok);
    *total = sum;
    *wPick = select((LaneF)(0.0f), wk, ok);
    return k;
}

/* MeshLight_Sample's uniform point on the lanes' triangles (a, b, c; unit normal nL) seen from p: *wi, *dist
 * (MeshLight_ShadowLength's), and the value's scale invAreaPdf·cosθ_L/d² (0 where the sample fails). */
inline LaneF Lanes_MeshLightPoint(LaneV3 a, LaneV3 b, LaneV3 c, LaneV3 nL, LaneV3 p, LaneF ux, LaneF u2, LaneF invAreaPdf,
                                  LaneV3* wi, LaneF* dist) {
    const LaneF su = sqrt(ux);
    const LaneF b0 = 1.0f - su, b1 = u2 * su;
    const LaneV3 q = LaneV3_Add(LaneV3_Add(LaneV3_Scale(a, b0), LaneV3_Scale(b, b1)), LaneV3_Scale(c, 1.0f - b0 - b1));
    const LaneV3 d = LaneV3_Sub(q, p);
    const LaneF d2 = LaneV3_Dot(d, d);
    const LaneF len = sqrt(d2);
    *wi = LaneV3_Scale(d, 1.0f / len);
    const LaneF cosLight = fabs(LaneV3_Dot(nL, *wi));
    *dist = fmax(len - Lanes_OffsetDistance(q) / cosLight, 0.5f * len);
    return select((LaneF)(0.0f), invAreaPdf * cosLight / d2, (d2 > 0.0f) & (cosLight > 0.0f) & (invAreaPdf > 0.0f));
}

/* MeshLight_Sample's direction uniform in the solid angle (2·halfOmega) of the lanes' triangles from p: *wi,
 * *dist to the triangle's plane (MeshLight_ShadowLength's); returns whether the sample holds. */
inline LaneI Lanes_MeshLightDirection(LaneV3 a, LaneV3 b, LaneV3 c, LaneV3 nL, LaneV3 p, LaneF halfOmega, LaneF ux, LaneF u2,
                                      LaneV3* wi, LaneF* dist) {
    const LaneV3 ra = LaneV3_Sub(a, p);
    *wi = Lanes_SphericalDirection(LaneV3_Normalize(ra), LaneV3_Normalize(LaneV3_Sub(b, p)), LaneV3_Normalize(LaneV3_Sub(c, p)),
                                   halfOmega, ux, u2);
    const LaneF cosLight = fabs(LaneV3_Dot(nL, *wi)), t = fabs(LaneV3_Dot(nL, ra)) / cosLight; /* to the plane */
    *dist = fmax(t - Lanes_OffsetDistance(LaneV3_Add(p, LaneV3_Scale(*wi, t))) / cosLight, 0.5f * t);
    return (cosLight > 0.0f) & (t > 0.0f) & isfinite(t);
}

/* MeshLight_Sample for the lanes at p: *wi, *dist (MeshLight_ShadowLength's), the radiance estimate *e
 * (0 where the sample fails); u: the lanes' 2D sample. Each part only where some lane takes it. */
inline void Lanes_MeshLightSample(const __global Light* light, const __global float4* lightData, LaneV3 p, LaneF u1,
                                  LaneF u2, LaneV3* wi, LaneF* dist, LaneV3* e) {
    const __global float4* tri = lightData + light->objFirst;
    LaneF ux, total = (LaneF)(0.0f), wPick = (LaneF)(0.0f), num, den;
    const int byWeight = light->objCount <= CLRT_MESHLIGHT_PICK_MAX;
    const LaneI pick = byWeight ? Lanes_PickByWeight(light, tri, light->objCount, p, u1, &ux, &total, &wPick, &num, &den)
                                : Lanes_PickTriangle(tri, light->objCount, u1, &ux);
    int at[CLRT_LANES];
    float3 v0[CLRT_LANES], v1[CLRT_LANES], v2[CLRT_LANES];
    float areaK[CLRT_LANES];
    vstore4(pick, 0, at);
    for (int k = 0; k < CLRT_LANES; ++k) {
        const int t = at[k];
        v0[k] = tri[3 * t].xyz; v1[k] = tri[3 * t + 1].xyz; v2[k] = tri[3 * t + 2].xyz;
        areaK[k] = tri[3 * t + 1].w;
    }
    const LaneV3 a = LaneV3_Load(v0), b = LaneV3_Load(v1), c = LaneV3_Load(v2);
    const LaneV3 n = LaneV3_Cross(LaneV3_Sub(b, a), LaneV3_Sub(c, a));
    const LaneV3 nL = LaneV3_Normalize(n);
    /* 1 / P(pick): Σw / w by weight, A / A_k by area */
    const LaneF invPick = byWeight ? select((LaneF)(0.0f), total / wPick, wPick > 0.0f) : light->area / vload4(0, areaK);
    /* the lanes whose triangle's Ω is sampled uniformly (MeshLight_SolidAngle, _BySolidAngle); a pick by weight
     * has the picked triangle's terms already */
    if (!byWeight) Lanes_Subtended(a, b, c, n, p, &num, &den);
    const LaneF omega = 2.0f * atan2(num, den);
    const LaneI sph = (omega > CLRT_MESHLIGHT_SPHERICAL_MIN) & (omega < CLRT_MESHLIGHT_SPHERICAL_MAX);
    LaneF value = (LaneF)(0.0f);
    *wi = LaneV3_Splat((float3)(0.0f));
    *dist = (LaneF)(0.0f);
    if (!all(sph)) /* by area: MeshLight_TriangleArea · Σw / w, or the mesh's area */
        value = Lanes_MeshLightPoint(a, b, c, nL, p, ux, u2, byWeight ? 0.5f * sqrt(LaneV3_Dot(n, n)) * invPick : (LaneF)(light->area),
                                     wi, dist);
    if (any(sph)) { /* L·Ω / P(pick) */
        LaneV3 ws;
        LaneF ds;
        const LaneI ok = Lanes_MeshLightDirection(a, b, c, nL, p, 0.5f * omega, ux, u2, &ws, &ds);
        *wi = LaneV3_Select(*wi, ws, sph);
        *dist = select(*dist, ds, sph);
        value = select(value, select((LaneF)(0.0f), omega * invPick, ok), sph);
    }
    *e = LaneV3_Scale(LaneV3_Splat(light->radiance.xyz), value);
}
#endif

#ifdef CLRT_HAS_LIGHT_SPHERE
/* SphereLight_ConeDirection in lanes: a direction drawn uniformly (u1, u2) in the cone around unit axis n of a sphere
 * of radius R whose centre is d2 (squared) away; *oneMinusCosMax: 1 − cosθmax (the solid angle over 2π). */
inline LaneV3 Lanes_ConeDirection(LaneV3 n, float R, LaneF d2, LaneF u1, LaneF u2, LaneF* oneMinusCosMax) {
    const LaneF sin2Max = R * R / d2, cosMax = sqrt(fmax(0.0f, 1.0f - sin2Max));
    *oneMinusCosMax = sin2Max / (1.0f + cosMax); /* 1 − cosθmax without cancellation */
    const LaneF oneMinusCos = u1 * *oneMinusCosMax;
    const LaneF cosT = 1.0f - oneMinusCos, sinT = sqrt(fmax(0.0f, oneMinusCos * (2.0f - oneMinusCos)));
    LaneF cs, sn;
    Lanes_SinCos2Pi(u2, &cs, &sn);
    LaneV3 t, b;
    Lanes_Basis(n, &t, &b);
    return LaneV3_Normalize(LaneV3_Add(LaneV3_Add(LaneV3_Scale(t, sinT * cs), LaneV3_Scale(b, sinT * sn)), LaneV3_Scale(n, cosT)));
}

/* The affine map of rows m[0..2] (a 3×4 matrix) applied to the lanes' points p, and to their vectors v. */
inline LaneV3 Lanes_AffinePoint(const __global float4* m, LaneV3 p) {
    return LaneV3_Make(LaneV3_Dot(LaneV3_Splat(m[0].xyz), p) + m[0].w, LaneV3_Dot(LaneV3_Splat(m[1].xyz), p) + m[1].w,
                       LaneV3_Dot(LaneV3_Splat(m[2].xyz), p) + m[2].w);
}
inline LaneV3 Lanes_AffineVector(const __global float4* m, LaneV3 v) {
    return LaneV3_Make(LaneV3_Dot(LaneV3_Splat(m[0].xyz), v), LaneV3_Dot(LaneV3_Splat(m[1].xyz), v), LaneV3_Dot(LaneV3_Splat(m[2].xyz), v));
}

/* SphereLight_Sample of a LightSphere under a similarity (objCount 0) at the lanes' points p, the same operations
 * in lanes: a direction uniform in the cone the sphere subtends (SphereLight_ConeDirection), its distance to the
 * sphere's outside (SphereLight_Hit), *e = Radiance·Ω; nothing where p is inside the sphere or the direction
 * misses it. s: the light's lightData (object-space centre and radius, then the worldToObject rows). */
inline void Lanes_SphereLightSample(const __global Light* light, const __global float4* s, LaneV3 p, LaneF u1, LaneF u2,
                                    LaneV3* wi, LaneF* dist, LaneV3* e) {
    const LaneV3 axis = LaneV3_Sub(LaneV3_Splat(light->position.xyz), p);
    const float R = light->objRadius;
    const LaneF d2 = LaneV3_Dot(axis, axis);
    LaneF oneMinusCosMax;
    const LaneV3 w = Lanes_ConeDirection(LaneV3_Scale(axis, 1.0f / sqrt(d2)), R, d2, u1, u2, &oneMinusCosMax);
    /* SphereLight_Hit: in object space, the near root of the ray from p along w */
    const LaneV3 o = Lanes_AffinePoint(s + 1, p), d = Lanes_AffineVector(s + 1, w);
    const float r = s[0].w;
    const LaneV3 f = LaneV3_Sub(o, LaneV3_Splat(s[0].xyz));
    const LaneF cc = LaneV3_Dot(f, f) - r * r, a = LaneV3_Dot(d, d), bf = LaneV3_Dot(f, d);
    const LaneV3 l = LaneV3_Sub(f, LaneV3_Scale(d, bf / a));
    const LaneF disc = a * (r * r - LaneV3_Dot(l, l));
    const LaneF tHit = cc / -(bf - sqrt(disc));
    const LaneI ok = (d2 > R * R) & (cc > 0.0f) & (bf < 0.0f) & (a > 0.0f) & (disc >= 0.0f) & (tHit > 0.0f);
    *wi = w;
    *dist = tHit;
    *e = LaneV3_Select(LaneV3_Splat((float3)(0.0f)), LaneV3_Scale(LaneV3_Splat(light->radiance.xyz), 2.0f * CLRT_PI * oneMinusCosMax), ok);
}

/* SphereLight_SampleObjectCone in lanes (a LightSphere under a transform that is no similarity: an ellipsoid): p
 * in object space, a direction uniform in the cone the object-space sphere subtends there, its near hit carried
 * back to world space: *wi, *dist (MeshLight_ShadowLength's), *e = Radiance·Ω_obj; nothing from inside.
 * s: the light's lightData (centre and radius, worldToObject rows, objectToWorld rows). */
inline void Lanes_EllipsoidLightSample(const __global Light* light, const __global float4* s, LaneV3 p, LaneF u1, LaneF u2,
                                       LaneV3* wi, LaneF* dist, LaneV3* e) {
    const LaneV3 pObj = Lanes_AffinePoint(s + 1, p), c = LaneV3_Splat(s[0].xyz);
    const LaneV3 f = LaneV3_Sub(pObj, c);
    const float R = s[0].w;
    const LaneF d2 = LaneV3_Dot(f, f);
    LaneF oneMinusCosMax;
    const LaneF fl = sqrt(d2);
    const LaneV3 wObj = Lanes_ConeDirection(LaneV3_Make(-f.x / fl, -f.y / fl, -f.z / fl), R, d2, u1, u2, &oneMinusCosMax);
    const LaneF b = LaneV3_Dot(f, wObj), cc = d2 - R * R;
    const LaneF root = -b + sqrt(fmax(b * b - cc, 0.0f)); /* ≥ 0 inside the cone but for rounding */
    const LaneF tObj = select((LaneF)(0.0f), cc / root, root > 0.0f); /* the near root */
    const LaneV3 qObj = LaneV3_Add(pObj, LaneV3_Scale(wObj, tObj));
    const LaneV3 q = Lanes_AffinePoint(s + 4, qObj);
    const LaneV3 d = LaneV3_Sub(q, p);
    const LaneF dl = sqrt(LaneV3_Dot(d, d));
    *wi = LaneV3_Make(d.x / dl, d.y / dl, d.z / dl);
    const LaneV3 nObj = LaneV3_Sub(qObj, c); /* the world normal M⁻ᵀ·n_obj (SphereLight_NormalWorld) */
    const LaneV3 m = LaneV3_Add(LaneV3_Add(LaneV3_Scale(LaneV3_Splat(s[1].xyz), nObj.x), LaneV3_Scale(LaneV3_Splat(s[2].xyz), nObj.y)),
                                LaneV3_Scale(LaneV3_Splat(s[3].xyz), nObj.z));
    const LaneF ml = sqrt(LaneV3_Dot(m, m));
    const LaneF cosLight = select((LaneF)(1.0f), fmax(-LaneV3_Dot(m, *wi) / ml, 1e-4f), ml > 0.0f);
    *dist = fmax(dl - Lanes_OffsetDistance(q) / cosLight, 0.5f * dl); /* MeshLight_ShadowLength */
    const LaneI ok = (d2 > R * R) & (dl > 0.0f) & isfinite(dl);
    *e = LaneV3_Select(LaneV3_Splat((float3)(0.0f)),
                       LaneV3_FiniteOrZero(LaneV3_Scale(LaneV3_Splat(light->radiance.xyz), 2.0f * CLRT_PI * oneMinusCosMax)), ok);
}

/* SphereLight_DirectionScale in lanes: dω_obj/dω_world along the lanes' world directions w (1 under a similarity). */
inline LaneF Lanes_SphereLightDirectionScale(const __global Light* light, const __global float4* s, LaneV3 w) {
    if (light->objCount == 0) return (LaneF)(1.0f);
    const LaneV3 a = Lanes_AffineVector(s + 1, w);
    const LaneF l = sqrt(LaneV3_Dot(a, a));
    const LaneF j = 1.0f / (light->edgeU.x * l * l * l);
    return select((LaneF)(0.0f), j, (l > 0.0f) & isfinite(j));
}
#endif

/* f·cosθ towards wi and Path_BouncePdf's density of wi at the glossy lanes' hits, in lanes (lanes_brdf.cl:
 * Shadow_Make's Material_EvalDirect, Path_LightSampleWeight's pdf); the other lanes keep *fCos and *bouncePdf.
 * b: the BRDFs loaded for the vertex's glossy lanes (a superset of glossy; each lane computes on its own). */
inline void Lanes_GlossyLightTerms(const __global Material* materials, const LaneBrdf* b, int mode, int glossy,
                                   const ShadingPoint* sp, LaneV3 wi, LaneF cosTheta, LaneV3* fCos, LaneF* bouncePdf) {
    const LaneI g = Lane_FromBits(glossy);
    const LaneBrdfAt at = LaneBrdf_At(b, wi);
    const LaneV3 f = LaneV3_Select(LaneV3_Splat((float3)(0.0f)), LaneBrdf_EvalDirect(b, &at, cosTheta), cosTheta > 0.0f);
    *fCos = LaneV3_Select(*fCos, f, g);
    *bouncePdf = select(*bouncePdf, LaneBrdf_BouncePdf(b, mode, &at), g);
    const int scalar = b->scalar & glossy;
    if (!scalar) return;
    float3 w[CLRT_LANES], fc[CLRT_LANES]; /* a BRDF without a lane form: per lane */
    float c[CLRT_LANES], pdf[CLRT_LANES];
    LaneV3_Store(wi, w);
    LaneV3_Store(*fCos, fc);
    vstore4(cosTheta, 0, c);
    vstore4(*bouncePdf, 0, pdf);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((scalar >> k) & 1)) continue;
        fc[k] = c[k] > 0.0f ? Material_EvalDirect(sp[k], materials, w[k], c[k]) : (float3)(0.0f);
        pdf[k] = Path_BouncePdf(sp[k], materials, mode, w[k]);
    }
    *fCos = LaneV3_Load(fc);
    *bouncePdf = vload4(0, pdf);
}

/* SpotLight_Falloff in lanes. */
inline LaneF Lanes_SpotFalloff(const __global Light* light, LaneF cosAlpha) {
    const float denom = light->cosFalloffHalf - light->cosCoverageHalf;
    const LaneF s = denom > 0.0f ? (cosAlpha - light->cosCoverageHalf) / denom : (LaneF)(0.0f);
    const LaneF inner = select(s * s * s * s, (LaneF)(0.0f), cosAlpha <= light->cosCoverageHalf);
    return select(inner, (LaneF)(1.0f), cosAlpha >= light->cosFalloffHalf);
}

/* AreaLight_Sample in lanes: a uniform point of the square (u1, u2), seen from either side. */
inline void Lanes_AreaLightSample(const __global Light* light, LaneV3 p, LaneF u1, LaneF u2, LaneV3* wi, LaneF* dist, LaneV3* e) {
    const LaneV3 q = LaneV3_Add(LaneV3_Add(LaneV3_Splat(light->position.xyz), LaneV3_Scale(LaneV3_Splat(light->edgeU.xyz), u1 - 0.5f)),
                                LaneV3_Scale(LaneV3_Splat(light->edgeV.xyz), u2 - 0.5f));
    const LaneV3 d = LaneV3_Sub(q, p);
    const LaneF d2 = LaneV3_Dot(d, d);
    *dist = sqrt(d2);
    *wi = LaneV3_Make(d.x / *dist, d.y / *dist, d.z / *dist);
    const LaneF cosLight = fabs(LaneV3_Dot(LaneV3_Splat(light->direction.xyz), *wi)); /* two-sided */
    *e = LaneV3_Scale(LaneV3_Splat(light->radiance.xyz),
                      select((LaneF)(0.0f), light->area * cosLight / d2, (d2 > 0.0f) & (cosLight > 0.0f)));
}

/* Light_Sample of light `light` (a kind Lanes_HasLaneForm names) at the lanes' points p, in lanes: *wi, *dist
 * (INFINITY for a directional light) and the estimate *e, 0 where the sample fails. The lanes' 2D sample of
 * dimension dim (Sampler_Light2D's: path tracing's is Sampler_2D) is drawn for the lights that read one. */
inline void Lanes_LightDirection(const __global Light* light, const __global float4* lightData, SceneParams scene, uint strat,
                                 LaneU sample, const PathState* path, int pixel, uint dim, LaneV3 p, LaneV3* wi, LaneF* dist,
                                 LaneV3* e) {
    *wi = *e = LaneV3_Splat((float3)(0.0f));
    *dist = (LaneF)(0.0f);
    const int kind = light->kind;
    LaneF u1, u2;
    if (kind == LIGHT_MESH || kind == LIGHT_SPHERE || kind == LIGHT_AREA) Lanes_Sample2D(scene, strat, sample, path, pixel, dim, &u1, &u2);
#ifdef CLRT_HAS_LIGHT_MESH
    if (kind == LIGHT_MESH && light->objCount > 0 && light->area > 0.0f) Lanes_MeshLightSample(light, lightData, p, u1, u2, wi, dist, e);
#endif
#ifdef CLRT_HAS_LIGHT_SPHERE
    if (kind == LIGHT_SPHERE && light->objCount == 0)
        Lanes_SphereLightSample(light, lightData + light->objFirst, p, u1, u2, wi, dist, e);
    if (kind == LIGHT_SPHERE && light->objCount != 0)
        Lanes_EllipsoidLightSample(light, lightData + light->objFirst, p, u1, u2, wi, dist, e);
#endif
#ifdef CLRT_HAS_AREA_LIGHT
    if (kind == LIGHT_AREA) Lanes_AreaLightSample(light, p, u1, u2, wi, dist, e);
#endif
#ifdef CLRT_HAS_DIRECTIONAL_LIGHT
    if (kind == LIGHT_DIRECTIONAL) { /* DirectionalLight_Sample */
        *wi = LaneV3_Splat(-light->direction.xyz);
        *dist = (LaneF)(INFINITY);
        *e = LaneV3_Splat(light->radiance.xyz);
    }
#endif
    if (kind == LIGHT_POINT || kind == LIGHT_SPOT) { /* PointLight_Sample, SpotLight_Sample */
        const LaneV3 d = LaneV3_Sub(LaneV3_Splat(light->position.xyz), p);
        const LaneF d2 = LaneV3_Dot(d, d);
        *dist = sqrt(d2);
        *wi = LaneV3_Scale(d, 1.0f / *dist);
        LaneF scale = select((LaneF)(0.0f), 1.0f / d2, d2 > 0.0f);
#ifdef CLRT_HAS_SPOT_LIGHT
        if (kind == LIGHT_SPOT) scale *= Lanes_SpotFalloff(light, -LaneV3_Dot(*wi, LaneV3_Splat(light->direction.xyz)));
#endif
        *e = LaneV3_Scale(LaneV3_Splat(light->radiance.xyz), scale);
    }
}

/* The lanes' light samples of light `light` (any kind Lanes_HasLaneForm names) at their hits (those in hit->nee):
 * as Light_ShadowRays and Fused_Shadow, the unoccluded contributions (MIS-weighted, times the throughput). brdf: the
 * vertex's LaneBrdf_Load for hit->glossy (read only where that is non-zero). */
inline LaneV3 Lanes_LightSample(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) const __global Light* light, const LanesHit* hit,
                                const LaneBrdf* brdf, const PathState* path, int pixel, LaneV3 throughput, uint strat, LaneU sample, uint dim) {
    const LaneV3 zero = LaneV3_Splat((float3)(0.0f)), p = hit->p, ng = hit->ng, ns = hit->ns;
    LaneV3 wi, e;
    LaneF dist;
    const int shape = light->kind == LIGHT_MESH || light->kind == LIGHT_SPHERE; /* an object light */
    Lanes_LightDirection(light, lightData, scene, strat, sample, path, pixel, dim, p, &wi, &dist, &e);
    /* Shadow_Make */
    const int mode = scene.pathMode;
    const LaneF cosTheta = LaneV3_Dot(ns, wi);
    LaneI ok = Lane_FromBits(hit->nee) & (cosTheta > 0.0f) & (LaneV3_Max(e) > 0.0f);
    LaneV3 fCos = LaneV3_Scale(hit->f, cosTheta);
    LaneF bouncePdf = Path_UsesImportance(mode) ? cosTheta * CLRT_INV_PI : (LaneF)(0.5f * CLRT_INV_PI);
    if (hit->glossy & hit->nee)
        Lanes_GlossyLightTerms(materials, brdf, mode, hit->glossy & hit->nee, hit->sp, wi, cosTheta, &fCos, &bouncePdf);
    LaneV3 contrib = LaneV3_FiniteOrZero(LaneV3_Mul(LaneV3_Mul(throughput, fCos), e));
    if (shape && (mode & CLRT_PATH_MIS)) { /* Path_LightSampleWeight: a point light's weight is 1 */
        LaneF scale = 1.0f; /* an ellipsoid's dω_obj/dω_world */
#ifdef CLRT_HAS_LIGHT_SPHERE
        if (light->kind == LIGHT_SPHERE) scale = Lanes_SphereLightDirectionScale(light, lightData + light->objFirst, wi);
#endif
        const LaneF lightPdf = maxComponent(light->radiance.xyz) * scale / LaneV3_Max(e);
        contrib = LaneV3_Scale(contrib, Lanes_MisWeight(mode, lightPdf, select((LaneF)(0.0f), bouncePdf, cosTheta > 0.0f)));
    }
    /* The ray: from Ray_EpsilonOrigin aimed at the light's point, as long as from p (a mesh light's:
     * ObjectLight_AimShadow, short of its point) */
    const LaneV3 org = LaneV3_Add(p, LaneV3_Scale(ng, fmax(Lanes_OffsetDistance(p), scene.shadowEpsilon)));
    const LaneV3 toLight = LaneV3_Sub(LaneV3_Add(p, LaneV3_Scale(wi, dist)), org);
    const LaneF len = sqrt(LaneV3_Dot(toLight, toLight));
    const LaneV3 dir = LaneV3_Select(LaneV3_Scale(toLight, 1.0f / len), wi, isinf(dist)); /* a directional light's: wi */
    ok &= LaneV3_Max(contrib) > 0.0f; /* Fused_Shadow traces no ray of zero contribution */
    LaneF tMax = dist;
    if (shape) {
        ok &= (len > 0.0f) & isfinite(len);
        tMax = len * (1.0f - 1e-5f);
    }
    const int open = Lanes_Unoccluded(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) Lane_Bits(ok), org, dir, tMax);
    return LaneV3_Select(zero, contrib, Lane_FromBits(open));
}

/* Whether light l's samples have a lane form (Lanes_LightDirection): every kind but an environment light (whose
 * samples run per lane; so does a kind added without one). */
inline int Lanes_HasLaneForm(const __global Light* light) {
    const int kind = light->kind;
    return kind == LIGHT_MESH || kind == LIGHT_SPHERE || kind == LIGHT_POINT || kind == LIGHT_SPOT || kind == LIGHT_AREA ||
           kind == LIGHT_DIRECTIONAL;
}

/* Light l's samples at the lanes in hit->nee through clrt's scalar Light_ShadowRays and Fused_Shadow, per lane
 * (the light kinds without a lane form: environment maps, with
 * lightSlots shadow rays each: 2 for an environment light's MIS pair, made in steps across the lanes by
 * Lanes_EnvMisShadows), added to the lanes' sum in render_fused's order: each lane's path, ShadingPoint and
 * random stream as there. dim: the light's dimension (Light_ShadowRays'). */
inline LaneV3 Lanes_ScalarLightSample(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int l, int lightSlots, const LanesHit* hit,
                                      const PathState* path, int pixel, uint strat, LaneU sample, uint dim, LaneV3 sum) {
    float3 out[CLRT_LANES];
    LaneV3_Store(sum, out);
    ShadowRay sr[CLRT_LANES], sr2[CLRT_LANES];
    int envMis = 0;
#ifdef CLRT_HAS_ENV_LIGHT
    envMis = lightSlots == 2 && EnvLight_UsesMis(&lights[l]);
    if (envMis)
        Lanes_EnvMisShadows(scene, materials, lights, images, texels, envDist, l, hit->nee, path, hit->sp, pixel, strat,
                            sample, dim, sr, sr2);
#endif
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((hit->nee >> k) & 1)) continue;
        if (!envMis) {
            sr2[k].origin = sr2[k].direction = sr2[k].contribution = (float4)(0.0f); /* a light with one sample leaves it untraced */
            Light_ShadowRays(scene, path[k], hit->sp[k], l, lightSlots, Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId),
                             materials, lights, images, texels, envDist, lightData, &sr[k], &sr2[k]);
        }
        out[k] += Fused_Shadow(sr[k], scene, nodes, leaves, tris, spheres, planes, instances).xyz;
        if (lightSlots == 2) out[k] += Fused_Shadow(sr2[k], scene, nodes, leaves, tris, spheres, planes, instances).xyz;
    }
    return LaneV3_Load(out);
}

/* Path_SampleBounce at the glossy lanes' hits, in lanes (lanes_brdf.cl), with the lanes' sample u (c2, s2: the
 * cosine and sine of 2π·u2) and, in *dir
 * and *pdf, the hemisphere warp Lanes_Bounce drew from it (what a material without a BRDF, or every material
 * without importance sampling, takes): their *dir, *pdf and *fCos (0 where the sample carries nothing); the
 * other lanes keep theirs. */
inline void Lanes_GlossyBounces(const __global Material* materials, const LaneBrdf* b, int mode, int glossy,
                                const ShadingPoint* sp, LaneF u1, LaneF u2, LaneF c2, LaneF s2, LaneV3* dir, LaneF* pdf,
                                LaneV3* fCos) {
    const int scalar = b->scalar & glossy;
    const LaneI g = Lane_FromBits(glossy);
    LaneV3 wi = *dir;
    LaneF pd = *pdf;
    LaneI ok = (LaneI)(-1), okB = (LaneI)(-1);
    const LaneI brdf = Path_UsesImportance(mode) ? b->kind != CLRT_INVALID : (LaneI)(0);
    if (any(brdf)) { /* Brdf_Sample where there is a BRDF; its density once the lanes' wi are known */
        LaneV3 wB;
        okB = LaneBrdf_Sample(b, u1, c2, s2, &wB);
        wi = LaneV3_Select(wi, wB, brdf);
    }
    const LaneBrdfAt at = LaneBrdf_At(b, wi); /* f and the density share its power */
    if (any(brdf)) {
        const LaneF pB = LaneBrdf_MixturePdf(b, &at);
        pd = select(pd, pB, brdf);
        ok = select(ok, okB & (pB > 0.0f), brdf);
    }
    const LaneF c = at.cosI;
    ok &= (c > 0.0f) & (LaneV3_Dot(b->ng, wi) > 0.0f) & (pd > 0.0f);
    const LaneV3 f = LaneV3_Select(LaneV3_Splat((float3)(0.0f)), LaneBrdf_EvalDirect(b, &at, c), ok);
    float3 d[CLRT_LANES], fc[CLRT_LANES]; /* a BRDF without a lane form: per lane, from the lanes' warp */
    float a[CLRT_LANES], bb[CLRT_LANES], pdfs[CLRT_LANES];
    if (scalar) {
        LaneV3_Store(*dir, d);
        LaneV3_Store(*fCos, fc);
        vstore4(u1, 0, a);
        vstore4(u2, 0, bb);
        vstore4(*pdf, 0, pdfs);
    }
    *dir = LaneV3_Select(*dir, wi, g);
    *pdf = select(*pdf, pd, g);
    *fCos = LaneV3_Select(*fCos, f, g);
    if (!scalar) return;
    for (int k = 0; k < CLRT_LANES; ++k)
        if ((scalar >> k) & 1) fc[k] = Path_SampleBounce(sp[k], materials, mode, (float2)(a[k], bb[k]), &d[k], &pdfs[k]);
    const LaneI sc = Lane_FromBits(scalar);
    *dir = LaneV3_Select(*dir, LaneV3_Load(d), sc);
    *fCos = LaneV3_Select(*fCos, LaneV3_Load(fc), sc);
    *pdf = select(*pdf, vload4(0, pdfs), sc);
}

/* The lanes' non-specular bounces (Path_SampleBounce; the glossy lanes' by Lanes_GlossyBounces, from brdf as in
 * Lanes_LightSample) for the lanes in bounceBits, picked with probability 1 − pSpecular: *dir, *pdf and the new
 * throughput; the lanes in the returned bits carry a child. */
inline int Lanes_Bounce(const __global Material* materials, const LaneBrdf* brdf, int mode, int bounceBits, const LanesHit* hit,
                        LaneF pSpecular, LaneF u1, LaneF u2, LaneV3* throughput, LaneV3* dir, LaneF* pdf) {
    const int cosine = Path_UsesImportance(mode);
    const LaneV3 ng = hit->ng, ns = hit->ns;
    LaneF c2, s2;
    Lanes_SinCos2Pi(u2, &c2, &s2);
    LaneF lx, ly, lz;
    if (cosine) { /* Warp_CosineHemisphere (also Brdf_Sample's diffuse lobe when ks = 0) */
        const LaneF r = sqrt(u1);
        lx = r * c2; ly = r * s2; lz = sqrt(fmax(0.0f, 1.0f - u1));
    } else { /* Warp_UniformHemisphere */
        const LaneF r = sqrt(fmax(0.0f, 1.0f - u1 * u1));
        lx = r * c2; ly = r * s2; lz = u1;
    }
    LaneV3 t, bt;
    Lanes_Basis(ns, &t, &bt);
    *dir = LaneV3_Normalize(LaneV3_Add(LaneV3_Add(LaneV3_Scale(t, lx), LaneV3_Scale(bt, ly)), LaneV3_Scale(ns, lz)));
    *pdf = cosine ? lz * CLRT_INV_PI : (LaneF)(0.5f * CLRT_INV_PI);
    LaneV3 fCos = LaneV3_Scale(hit->f, LaneV3_Dot(ns, *dir));
    if (hit->glossy & bounceBits)
        Lanes_GlossyBounces(materials, brdf, mode, hit->glossy & bounceBits, hit->sp, u1, u2, c2, s2, dir, pdf, &fCos);
    const LaneI ok = Lane_FromBits(bounceBits) & (LaneV3_Dot(ns, *dir) > 0.0f) & (LaneV3_Dot(ng, *dir) > 0.0f) &
                     (*pdf > 0.0f) & LaneV3_Finite(*dir);
    const LaneF q = *pdf * (1.0f - pSpecular);
    const LaneV3 weight = LaneV3_Make(fCos.x / q, fCos.y / q, fCos.z / q); /* f·cosθ / (pdf·(1 − pSpecular)) */
    *throughput = LaneV3_Mul(*throughput, weight);
    return Lane_Bits(ok & (LaneV3_Max(weight) > 0.0f));
}

/* Path_ShadeHit's pick at the live lanes' hits: a specular child with probability pSpecular (½ beside a
 * diffuse part, else 1; *pSpec per lane, 0 where no specular material); returns the lanes that take it.
 * A pick at the last vertex ends the lane's path (its only child there is the BSDF sample). */
inline int Lanes_PickSpecular(SceneParams scene, int pixel, const PathState* path, const LanesHit* hit, uint dim, int* live,
                              float* pSpec) {
    int specBits = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        pSpec[k] = 0.0f;
        if (!(*live & hit->specular & (1 << k))) continue;
        pSpec[k] = (hit->diffuse >> k) & 1 ? 0.5f : 1.0f;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        if (!(Sampler_Other1D(scene, path[k], key, dim + 3u) < pSpec[k])) continue;
        if ((hit->lastVertex >> k) & 1) *live &= ~(1 << k);
        else specBits |= 1 << k;
    }
    return specBits;
}

/* Path_SpecularBounce for the lanes in specBits (their hits: hit, p, ns, ng per lane): *org, dirs and
 * *weight per lane; a lane whose bounce fails leaves specBits (returned). */
inline int Lanes_SpecularBounces(SceneParams scene, const __global Material* materials, int pixel, uint dim, int specBits,
                                 const LanesHit* hit, const PathState* path, const Ray* ray, float3* org, float3* dirs,
                                 float3* weight) {
    float3 p[CLRT_LANES], ns[CLRT_LANES], ng[CLRT_LANES];
    LaneV3_Store(hit->p, p);
    LaneV3_Store(hit->ns, ns);
    LaneV3_Store(hit->ng, ng);
    for (int k = 0; k < CLRT_LANES; ++k) {
        if (!((specBits >> k) & 1)) continue;
        const RngKey key = Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId);
        const float2 uGlossy = Sampler_Other2D(scene, path[k], key, dim);
        if (!Path_SpecularBounce(materials[hit->material[k]], -ray[k].direction.xyz, ns[k], ng[k], p[k], hit->t[k],
                                 (hit->inside >> k) & 1, Sampler_Other1D(scene, path[k], key, dim + 2u), uGlossy, &weight[k], &org[k], &dirs[k]))
            specBits &= ~(1 << k);
    }
    return specBits;
}

/* Path_Child (child 0) of each live lane, after Path_RussianRoulette: the specular lanes' child from
 * Path_SpecularBounce (specWeight), the others' from the lanes' bounce (org, dirs, next3, pdfs). Every
 * lane's path id moves on (they share it). Returns the children made; *live keeps the lanes that have one. */
inline uint Lanes_Children(SceneParams scene, int pixel, int depth, int specBits, const float* pSpec, const float3* org,
                           const float3* dirs, const float3* next3, const float3* specWeight, const float* pdfs,
                           PathState* path, Ray* ray, int* live) {
    const int mode = scene.pathMode;
    const uint dim = 4u + 32u * (uint)depth;
    uint children = 0;
    for (int k = 0; k < CLRT_LANES; ++k) { /* Path_Child (child 0), after Path_RussianRoulette */
        const uint id = path[k].pathId;
        path[k].pathId = id < 0x80000000u ? id * 2u : id; /* every lane: they share it */
        if (!(*live & (1 << k))) continue;
        const int spec = (specBits >> k) & 1, roulette = (mode & CLRT_PATH_RR) && depth >= scene.rrMinDepth;
        float3 next = spec ? path[k].throughput.xyz * (specWeight[k] / pSpec[k]) : next3[k];
        PathState drawn = path[k]; /* the path id the depth's numbers were drawn with */
        drawn.pathId = id;
        if (roulette && !Path_RussianRoulette(&next, Sampler_Other1D(scene, drawn, Rng_Key(scene.seed, pixel, drawn.sample, id), dim + 4u))) {
            *live &= ~(1 << k);
            continue;
        }
        if (!(maxComponent(next) > 0.0f) || !allFinite3(next) || !allFinite3(dirs[k])) { *live &= ~(1 << k); continue; }
        path[k].throughput = (float4)(next, spec ? 0.0f : pdfs[k]);
        path[k].depth = depth + 1;
        ray[k].origin = (float4)(org[k], 0.0f);
        ray[k].direction = (float4)(dirs[k], INFINITY);
        ++children;
    }
    return children;
}

/* Samples s0 .. s0 + n - 1 (n <= 4) of pixel `pixel`: their radiance summed in sample order per depth
 * into levelSum (as render_fused's per-depth sums). Returns the bounce rays traced. */
inline uint Lanes_Paths(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int lightSlots, int pixel, int px, int py, int s0,
                        int n, int levels, float3* levelSum) {
    PathState path[CLRT_LANES];
    Ray ray[CLRT_LANES];
    const LaneU sample = Lanes_CameraRays(cam, scene, pixel, px, py, s0, n, path, ray);
    int live = (1 << n) - 1;
    const int mode = scene.pathMode;
    int scalarLights = 0;
    for (int l = 0; l < scene.numLights; ++l) scalarLights |= !Lanes_HasLaneForm(&lights[l]);
    uint secondary = 0;
    for (int depth = 0; live; ++depth) {
        LanesGather g;
        Lanes_Closest(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) live, path, ray, &g);
        LanesHit hit;
        Lanes_Surfaces(scene, materials, lights, lightData, scalarLights, &g, depth, path, ray, &hit);
        float3 thr[CLRT_LANES];
        for (int k = 0; k < CLRT_LANES; ++k) thr[k] = path[k].throughput.xyz;
        LaneV3 throughput = LaneV3_Load(thr);
        const uint strat = Rng_Key(scene.seed, pixel, 0, path[0].pathId).strat; /* the lanes' shared path id */
        const uint dim = 4u + 32u * (uint)depth;
        LaneV3 sum = hit.radiance;
        LaneBrdf brdf; /* the glossy lanes' BRDFs, for every light's sample and the bounce */
        if (hit.glossy) brdf = LaneBrdf_Load(materials, hit.glossy, hit.sp);
        for (int l = 0; l < scene.numLights && hit.nee; ++l)
            sum = Lanes_HasLaneForm(&lights[l])
                      ? LaneV3_Add(sum, Lanes_LightSample(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) & lights[l], &hit, &brdf, path,
                                                          pixel, throughput, strat, sample, dim + 8u + 2u * (uint)l))
                      : Lanes_ScalarLightSample(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) l, lightSlots, &hit, path, pixel, strat,
                                                sample, dim + 8u + 2u * (uint)l, sum);
        float3 out[CLRT_LANES];
        LaneV3_Store(sum, out);
        for (int k = 0; k < CLRT_LANES; ++k) /* as render_fused: per depth, in sample order */
            if (live & (1 << k)) levelSum[min(depth, levels - 1)] += finiteOrZero(out[k]);
        live &= hit.bounce;
        if (!live) break;
        float pSpec[CLRT_LANES];
        float3 org[CLRT_LANES], dirs[CLRT_LANES], next3[CLRT_LANES], specWeight[CLRT_LANES];
        int specBits = Lanes_PickSpecular(scene, pixel, path, &hit, dim, &live, pSpec);
        LaneF u1, u2, pdf;
        Lanes_Sample2D(scene, strat, sample, path, pixel, dim + 5u, &u1, &u2);
        LaneV3 dir;
        const int diffuseBits = Lanes_Bounce(materials, &brdf, mode, live & ~specBits, &hit, vload4(0, pSpec), u1, u2, &throughput,
                                             &dir, &pdf);
        float pdfs[CLRT_LANES];
        LaneV3_Store(LaneV3_Add(hit.p, LaneV3_Scale(hit.ng, Lanes_OffsetDistance(hit.p))), org); /* Ray_OffsetOrigin */
        LaneV3_Store(dir, dirs);
        LaneV3_Store(throughput, next3);
        vstore4(pdf, 0, pdfs);
        if (specBits) {
            const int ok = Lanes_SpecularBounces(scene, materials, pixel, dim, specBits, &hit, path, ray, org, dirs, specWeight);
            live &= ~(specBits & ~ok);
            specBits = ok;
        }
        live &= diffuseBits | specBits;
        secondary += Lanes_Children(scene, pixel, depth, specBits, pSpec, org, dirs, next3, specWeight, pdfs, path, ray, &live);
    }
    return secondary;
}

#endif /* CLRT_HAS_PATH_TRACING */

/* ---- classic (direct-lighting) cameras ----------------------------------------------------------- */

#ifdef CLRT_FUSED_BOUNCES
/* The children of a classic camera ray's shaded hit (res) and theirs, as render_fused follows them: each path's
 * radiance (Fused_Path) added to levelSum[min(depth, levels - 1)]; returns how many were traced. */
inline uint Lanes_DirectChildren(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int lightSlots, const ShadeResult* res, int levels,
                                 float3* levelSum) {
    FusedEntry stack[CLRT_FUSED_STACK_SIZE];
    int top = 0;
    uint secondary = 0;
    PathState path;
    Ray ray;
    int more = Fused_NextPath(res, stack, &top, &path, &ray, &secondary);
    while (more) {
        ShadeResult child;
        levelSum[min(path.depth, levels - 1)] += Fused_Path(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) lightSlots, path, ray, &child);
        more = Fused_NextPath(&child, stack, &top, &path, &ray, &secondary);
    }
    return secondary;
}
#endif

/* Samples s0 .. s0 + n - 1 (n <= 4) of pixel `pixel` under a classic (direct-lighting) camera (no tree of paths:
 * lanesUnsupported): per lane render_fused's Fused_Path (the closest hit, Shade_Hit, each light's shadow rays,
 * Fused_Shadow), except an environment light's multi-sample MIS at the camera rays' hits, made in steps across
 * the lanes (Lanes_EnvMisShadows); then each lane's children (mirror, conductor, dielectric) as render_fused
 * follows them (Lanes_DirectChildren). Their radiance added to levelSum[min(depth, levels - 1)], the camera
 * rays' in sample order; returns how many children were traced. */
inline uint Lanes_Direct(CLRT_GROUP_PARAMS(CLRT_PARAMS_FUSED_SCENE) int lightSlots, int pixel, int px, int py, int s0,
                         int n, int levels, float3* levelSum) {
    PathState path[CLRT_LANES];
    Ray ray[CLRT_LANES];
    ShadeResult res[CLRT_LANES];
    ShadingPoint sp[CLRT_LANES];
    float4 sum[CLRT_LANES];
    const LaneU sample = Lanes_CameraRays(cam, scene, pixel, px, py, s0, n, path, ray);
    int shaded = 0;
    for (int k = 0; k < CLRT_LANES; ++k) {
        sum[k] = (float4)(0.0f);
        for (int c = 0; c < CLRT_SHADE_CHILDREN; ++c) res[k].childValid[c] = 0;
        if (k >= n) continue;
        int instance;
        const Hit h = Ray_Closest(ray[k], scene, nodes, leaves, tris, spheres, planes, instances, &instance);
        Shade_Hit(scene, cam, path[k], ray[k], h, instance, tris, triShading, triAttributes, spheres, planes, instances,
                  materials, textureSets, textures, images, texels, lights, envDist, lightData, &res[k]);
        sum[k] = res[k].radiance;
        sp[k] = res[k].sp;
        if (sp[k].position.w > 0.0f) shaded |= 1 << k;
        else if (scene.numLights > 0) sum[k] += (float4)(0.0f); /* as Fused_Path */
    }
    const uint strat = Rng_Key(scene.seed, pixel, 0, path[0].pathId).strat; /* the lanes' shared path id */
    for (int l = 0; l < scene.numLights && shaded; ++l) {
        ShadowRay sr[CLRT_LANES], sr2[CLRT_LANES];
        for (int k = 0; k < CLRT_LANES; ++k) /* a slot a light does not use: zero contribution, not traced */
            sr[k].origin = sr[k].direction = sr[k].contribution = sr2[k].origin = sr2[k].direction = sr2[k].contribution =
                (float4)(0.0f);
#ifdef CLRT_HAS_ENV_LIGHT
        if (lightSlots == 2 && EnvLight_UsesMis(&lights[l]))
            Lanes_EnvMisShadows(scene, materials, lights, images, texels, envDist, l, shaded, path, sp, pixel, strat, sample,
                                4u + 8u + 2u * (uint)l, sr, sr2); /* Light_ShadowRays' dimension at depth 0 */
        else
#endif
            for (int k = 0; k < CLRT_LANES; ++k)
                if ((shaded >> k) & 1)
                    Light_ShadowRays(scene, path[k], sp[k], l, lightSlots, Rng_Key(scene.seed, pixel, path[k].sample, path[k].pathId),
                                     materials, lights, images, texels, envDist, lightData, &sr[k], &sr2[k]);
        for (int k = 0; k < CLRT_LANES; ++k) {
            if (!((shaded >> k) & 1)) continue;
            sum[k] += Fused_Shadow(sr[k], scene, nodes, leaves, tris, spheres, planes, instances);
            if (lightSlots == 2) sum[k] += Fused_Shadow(sr2[k], scene, nodes, leaves, tris, spheres, planes, instances);
        }
    }
    for (int k = 0; k < n; ++k) levelSum[0] += finiteOrZero(sum[k].xyz);
    uint secondary = 0;
#ifdef CLRT_FUSED_BOUNCES
    for (int k = 0; k < n; ++k)
        secondary += Lanes_DirectChildren(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) lightSlots, &res[k], levels, levelSum);
#endif
    return secondary;
}

/* Parameters: src/shared/kernel_params.h (CLRT_KERNEL_render_lanes: render_fused's). A work-item: its
 * pixel's passes × samples samples of the launch, four at a time (the host gives a launch at least four
 * where the render has them), summed per depth in sample order, then added to the image. */
__kernel CLRT_KERNEL_VEC_HINT void render_lanes(CLRT_KERNEL_PARAMS(render_lanes)) {
    const int i = get_global_id(0);
    if (i >= count) return;
    const int pixel = firstPixel + i;
    const int levels = min(CLRT_LAST_DEPTH(scene.maxDepth, scene.pathMode) + 1, CLRT_FUSED_MAX_LEVELS);
    float3 levelSum[CLRT_FUSED_MAX_LEVELS];
    for (int d = 0; d < levels; ++d) levelSum[d] = (float3)(0.0f);
    float4 acc = image[pixel];
    uint secondary = 0;
    const int px = pixel % cam.width, py = pixel / cam.width;
    const int total = passes * samples;
    for (int s = 0; s < total; s += CLRT_LANES)
#ifdef CLRT_HAS_PATH_TRACING
        if (scene.pathMode != 0)
            secondary += Lanes_Paths(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) lightSlots, pixel, px, py, firstSample + s,
                                     min(CLRT_LANES, total - s), levels, levelSum);
        else
#endif
            secondary += Lanes_Direct(CLRT_GROUP_ARGS(CLRT_PARAMS_FUSED_SCENE) lightSlots, pixel, px, py, firstSample + s,
                                      min(CLRT_LANES, total - s), levels, levelSum);
    for (int d = 0; d < levels; ++d) acc.xyz += levelSum[d];
    image[pixel] = acc;
    if (secondary > 0) atomic_add(&rayCounts[0], secondary);
}

#endif /* CLRT_HAS_LANES */
#endif /* CLRT_LANES_CL */
