/* material.cl — what the shading stages of shade.cl and path.cl share about a material: the Fresnel
 * factors of dielectrics and conductors, the glossy perturbation of a rough material's mirror and
 * refraction directions (Glossy_Perturb: Roughness), and Material_EvalDirect, the light a surface reflects per
 * unit of incident light (the classic Blinn-Phong terms, or the material's BRDF; reads Material,
 * ShadingPoint). */
#ifndef CLRT_MATERIAL_CL
#define CLRT_MATERIAL_CL

#include "../src/shared/device_types.h"
#include "common.cl"
#include "brdf.cl"

/* Dielectric Fresnel reflectance for unit cosines (course formulas: mean of r∥² and r⊥²). */
inline float Fresnel_Dielectric(float cosI, float cosT, float n1, float n2) {
    float rPar = (n2 * cosI - n1 * cosT) / (n2 * cosI + n1 * cosT);
    float rPerp = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    return 0.5f * (rPar * rPar + rPerp * rPerp);
}

/* Conductor Fresnel with refraction index n and absorption index k. */
inline float Fresnel_Conductor(float cosI, float n, float k) {
    float c2 = cosI * cosI, nk = n * n + k * k;
    float rs = (nk - 2.0f * n * cosI + c2) / (nk + 2.0f * n * cosI + c2);
    float rp = (nk * c2 - 2.0f * n * cosI + 1.0f) / (nk * c2 + 2.0f * n * cosI + 1.0f);
    return 0.5f * (rs + rp);
}

/* Glossy perturbation of a reflected or refracted direction (course hw3: r' = normalize(r + roughness·(ξ1·u
 * + ξ2·v)), ξ uniform in [-1/2, 1/2], u, v the course's orthonormal basis across r, courseBasis). A rough
 * dielectric perturbs both its reflected and its refracted ray, each with its own ξ. */
inline float3 Glossy_Perturb(float3 r, float roughness, float u1, float u2) {
    if (roughness <= 0.0f) return r;
    float3 a, b;
    courseBasis(r, &a, &b);
    return normalize(r + roughness * ((u1 - 0.5f) * a + (u2 - 0.5f) * b));
}

/* The light reflected towards sp.wo per unit of what Light_Sample returns from direction wi
 * (cosTheta = n·wi > 0): f(wo, wi)·cosθ. Materials without a BRDF keep the classic Blinn-Phong
 * terms kd·cosθ + ks·cos^p αh (bit for bit what sample_lights computed before BRDFs; ks = 0 adds
 * exactly 0, so the lobe is skipped then). */
inline float3 Material_EvalDirect(ShadingPoint sp, const __global Material* materials, float3 wi, float cosTheta) {
#ifdef CLRT_HAS_BRDFS
    const __global Material* m = &materials[sp.material];
    if (m->brdf != CLRT_INVALID) {
        BrdfParams b;
        Brdf_FromMaterial(&b, m, sp.kd.xyz, sp.ks.xyz);
        return Brdf_Eval(&b, sp.normal.xyz, sp.wo.xyz, wi) * cosTheta;
    }
#endif
    if (!(maxComponent(sp.ks.xyz) > 0.0f)) return sp.kd.xyz * cosTheta;
    float3 hv = normalize(wi + sp.wo.xyz);
    float spec = Math_PowNonNegative(fmax(0.0f, dot(sp.normal.xyz, hv)), sp.ks.w);
    return sp.kd.xyz * cosTheta + sp.ks.xyz * spec;
}

/* What shading one hit leaves (Shade_Hit in shade.cl, Path_ShadeHit in path.cl): the ShadingPoint for
 * light sampling, the radiance that needs no shadow ray (already times the path throughput) and up to
 * CLRT_SHADE_CHILDREN children (k = 0: reflection or the path tracer's one child, pathId·2; k = 1:
 * refraction, pathId·2 + 1; k = 2: only under the course's roulette rule, a specular material's lobe,
 * Path_CourseSpecularChildren). The wavefront writes them to its queues (SceneParams-independent
 * childSlots per path: 3 under the course rule, else 2), the fused kernel (fused.cl) keeps them. */
typedef struct {
    ShadingPoint sp;
    float4 radiance;
    PathState childPath[CLRT_SHADE_CHILDREN];
    Ray childRay[CLRT_SHADE_CHILDREN];
    int childValid[CLRT_SHADE_CHILDREN];
} ShadeResult;

#endif /* CLRT_MATERIAL_CL */
