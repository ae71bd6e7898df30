/* lights.cl — light sampling, one `case` per light kind. Light_Sample returns what the course's
 * shading model multiplies with the BRDF terms: the irradiance-like quantity E (point and spot:
 * I/d², directional: radiance, area: L·A·|cosθ_L|/d² for a uniformly drawn point (an AreaLight emits
 * from both faces: the course's hw3 box lights its ceiling above a downward light, the hw6 Veach Ajar
 * room is lit through the door by a light facing away from it), environment:
 * L(wi)/pdf(wi) for a direction drawn by the light's sampler) divided by the pdf of the chosen
 * direction, and the direction and distance (INFINITY: directional, environment) for the shadow ray.
 * LightMesh and LightSphere (object lights, also geometry): object_lights.cl.
 * Env strategies (SCENE_FORMAT.md): uniform (hemisphere around n by rejection, pdf 1/2π),
 * cosine (pdf cosθ/π), importance (the map's luminance distribution, envmap.cl), mis. MIS is
 * multi-sample (EnvLight_SampleMis): one importance and one cosine direction per shading point, two
 * shadow rays, each weighted by the power heuristic; the renderer gives such a light two shadow-ray
 * slots (sample_lights' lightSlots). EnvironmentLight_Sample's `mis` case is the one-sample form
 * (importance or cosine with probability 1/2 each, divided by the mixture pdf ½·p_imp + ½·p_cos),
 * kept for callers with one slot. */
#ifndef CLRT_LIGHTS_CL
#define CLRT_LIGHTS_CL

#include "../src/shared/device_types.h"
#include "common.cl"
#include "envmap.cl"
#include "object_lights.cl"

/* Spot fall-off (SCENE_FORMAT.md): 1 inside falloff/2, 0 outside coverage/2, smooth quartic between.
 * Guards coverage == falloff (a hard edge) without dividing by zero. */
inline float SpotLight_Falloff(const __global Light* light, float cosAlpha) {
    if (cosAlpha >= light->cosFalloffHalf) return 1.0f;
    if (cosAlpha <= light->cosCoverageHalf) return 0.0f;
    float denom = light->cosFalloffHalf - light->cosCoverageHalf;
    if (!(denom > 0.0f)) return 0.0f;
    float s = (cosAlpha - light->cosCoverageHalf) / denom;
    return s * s * s * s;
}

inline float3 PointLight_Sample(const __global Light* light, float3 p, float3* wi, float* dist) {
    float3 d = light->position.xyz - p;
    float d2 = dot(d, d);
    if (!(d2 > 0.0f)) return (float3)(0.0f);
    *dist = sqrt(d2);
    *wi = d / *dist;
    return light->radiance.xyz / d2;
}

inline float3 SpotLight_Sample(const __global Light* light, float3 p, float3* wi, float* dist) {
    float3 e = PointLight_Sample(light, p, wi, dist);
    float cosAlpha = dot(-*wi, light->direction.xyz);
    return e * SpotLight_Falloff(light, cosAlpha);
}

inline float3 DirectionalLight_Sample(const __global Light* light, float3* wi, float* dist) {
    *wi = -light->direction.xyz;
    *dist = INFINITY;
    return light->radiance.xyz;
}

inline float3 AreaLight_Sample(const __global Light* light, float3 p, float2 u, float3* wi, float* dist) {
    float3 q = light->position.xyz + (u.x - 0.5f) * light->edgeU.xyz + (u.y - 0.5f) * light->edgeV.xyz;
    float3 d = q - p;
    float d2 = dot(d, d);
    if (!(d2 > 0.0f)) return (float3)(0.0f);
    *dist = sqrt(d2);
    *wi = d / *dist;
    float cosLight = fabs(dot(light->direction.xyz, *wi)); /* two-sided (SCENE_FORMAT.md conventions) */
    if (!(cosLight > 0.0f)) return (float3)(0.0f);
    return light->radiance.xyz * (light->area * cosLight / d2);
}

/* Uniform direction in the hemisphere around n: a point drawn in [-1,1]^3 is kept if inside the unit
 * ball (course: rejection), then mirrored into n's side. The retries draw hashed uniforms; after 32
 * failures (probability ~1e-10) the uniform hemisphere warp is used: the density is 1/2π either way. */
inline float3 EnvSample_Uniform(float3 n, float2 u) {
    for (uint k = 0; k < 32u; ++k) {
        float2 a = Env_RetryUniforms(u.x, u.y, 64u + 2u * k), b = Env_RetryUniforms(u.x, u.y, 65u + 2u * k);
        float3 q = (float3)(2.0f * a.x - 1.0f, 2.0f * a.y - 1.0f, 2.0f * b.x - 1.0f);
        float l2 = dot(q, q);
        if (l2 > 1e-6f && l2 <= 1.0f) {
            q /= sqrt(l2);
            return dot(q, n) < 0.0f ? -q : q;
        }
    }
    float3 t, b;
    makeBasis(n, &t, &b);
    float3 l = Warp_UniformHemisphere(u.x, u.y);
    return l.x * t + l.y * b + l.z * n;
}

inline float3 EnvSample_Cosine(float3 n, float2 u) {
    float3 t, b;
    makeBasis(n, &t, &b);
    float3 l = Warp_CosineHemisphere(u.x, u.y);
    return normalize(l.x * t + l.y * b + l.z * n);
}

/* An environment light's map turned by its <Transformations> (a rotation R, read_lights.cpp): the map's
 * direction dMap shows in world direction R·dMap. The light's direction, edgeU and edgeV hold the rows of
 * R^T (world -> map). Sampling runs in map space (the distributions are the map's; dot products and
 * solid-angle densities are the same in both spaces), its directions leave it through EnvLight_ToWorld;
 * lookups of a world direction enter it through EnvLight_ToMap. Compiled only where some environment
 * light is turned (CLRT_HAS_ENV_ROTATION); elsewhere both are the identity. */
inline float3 EnvLight_ToMap(const __global Light* light, float3 dirWorld) {
#ifdef CLRT_HAS_ENV_ROTATION
    return (float3)(dot(light->direction.xyz, dirWorld), dot(light->edgeU.xyz, dirWorld), dot(light->edgeV.xyz, dirWorld));
#else
    return dirWorld;
#endif
}
inline float3 EnvLight_ToWorld(const __global Light* light, float3 dirMap) {
#ifdef CLRT_HAS_ENV_ROTATION
    return dirMap.x * light->direction.xyz + dirMap.y * light->edgeU.xyz + dirMap.z * light->edgeV.xyz;
#else
    return dirMap;
#endif
}

/* The importance distribution an env light samples at a shading point: the map's (own), and under the mis
 * strategy the cosine-weighted table (tab) with the bucket of the point's normal (envmap.cl, EnvCos_*; bucket
 * -1: the map's). The importance strategy keeps the map's: the path tracer's MIS evaluates its pdf without a
 * normal (path.cl, Path_EnvLightPdf). */
typedef struct {
    const __global float* own;
    const __global float* tab;
    int bucket;
} EnvLightDist;

inline EnvLightDist EnvLight_Distribution(const __global Light* light, const __global float* envDist, float3 n) {
    EnvLightDist d;
    d.own = envDist + (light->distribution == CLRT_INVALID ? 0 : light->distribution);
    d.tab = envDist + (light->envCosine == CLRT_INVALID ? 0 : light->envCosine);
    d.bucket = light->envStrategy == ENV_STRATEGY_MIS && light->envCosine != CLRT_INVALID ? EnvCos_Bucket(d.tab, n) : -1;
    return d;
}

inline int EnvLightDist_SampleUv(EnvLightDist d, float u1, float u2, float3* dir, float* pdf, float2* uv) {
    return d.bucket < 0 ? EnvDist_SampleUv(d.own, u1, u2, dir, pdf, uv) : EnvCos_SampleUv(d.own, d.tab, d.bucket, u1, u2, dir, pdf, uv);
}

inline float EnvLightDist_PdfUv(EnvLightDist d, float2 uv) {
    return d.bucket < 0 ? EnvDist_PdfUv(d.own, uv) : EnvCos_PdfUv(d.own, d.tab, d.bucket, uv);
}

inline float3 EnvironmentLight_Sample(const __global Light* light, float3 nWorld, float2 u, const __global ImageInfo* images,
                                      const __global float4* texels, const __global float* envDist, float3* wi,
                                      float* dist) {
    *dist = INFINITY;
    const float3 n = EnvLight_ToMap(light, nWorld); /* everything below in map space */
    int strategy = light->envStrategy;
    if (light->distribution == CLRT_INVALID && (strategy == ENV_STRATEGY_IMPORTANCE || strategy == ENV_STRATEGY_MIS))
        strategy = ENV_STRATEGY_COSINE;
    const EnvLightDist d = EnvLight_Distribution(light, envDist, n);
    const int mapping = light->mapping;
    float3 w = n;
    float pdf = 0.0f;
    float2 uv = (float2)(-1.0f); /* map coordinates of w when a branch knows them */
    switch (strategy) {
    case ENV_STRATEGY_UNIFORM:
        w = EnvSample_Uniform(n, u);
        pdf = 1.0f / (2.0f * CLRT_PI);
        break;
    case ENV_STRATEGY_COSINE:
        w = EnvSample_Cosine(n, u);
        pdf = fmax(dot(w, n), 0.0f) * CLRT_INV_PI;
        break;
    case ENV_STRATEGY_IMPORTANCE:
        if (!EnvLightDist_SampleUv(d, u.x, u.y, &w, &pdf, &uv)) return (float3)(0.0f);
        break;
    default: { /* ENV_STRATEGY_MIS */
        float pImp;
        if (u.x < 0.5f) {
            if (!EnvLightDist_SampleUv(d, 2.0f * u.x, u.y, &w, &pImp, &uv)) return (float3)(0.0f);
        } else {
            w = EnvSample_Cosine(n, (float2)(fmin(2.0f * u.x - 1.0f, CLRT_ONE_MINUS_EPS), u.y));
            uv = EnvMap_DirToUv(mapping, w); /* once, for the pdf and the lookup */
            pImp = EnvLightDist_PdfUv(d, uv);
        }
        pdf = 0.5f * pImp + 0.5f * fmax(dot(w, n), 0.0f) * CLRT_INV_PI;
        break;
    }
    }
    *wi = EnvLight_ToWorld(light, w);
    if (!(pdf > 0.0f) || !isfinite(pdf)) return (float3)(0.0f);
    if (uv.x < 0.0f) uv = EnvMap_DirToUv(mapping, w);
    float3 l = EnvMap_Lookup(texels, images[light->image], mapping, uv.x, uv.y) * light->radiance.xyz;
    return finiteOrZero(l / pdf);
}

/* Whether an environment light is sampled by multi-sample MIS (two shadow-ray slots). */
inline int EnvLight_UsesMis(const __global Light* light) {
    return light->kind == LIGHT_ENVIRONMENT && light->envStrategy == ENV_STRATEGY_MIS && light->distribution != CLRT_INVALID;
}

/* Power heuristic weight of a sample of density p drawn with expected count nP per shading point,
 * against the other strategy's density q and count nQ. */
inline float Mis_Power(float nP, float p, float nQ, float q) {
    if (!(p > 0.0f)) return 0.0f;
    float r = (nQ * q) / (nP * p);  /* r·r overflowing to +inf gives weight 0, the limit */
    return 1.0f / (1.0f + r * r);
}

/* One sample's value under multi-sample MIS: L·w/(nP·p), w the power-heuristic weight of a sample of
 * density p drawn nP times per shading point against the other strategy's density q drawn nQ times;
 * 0 where p is not a positive finite density. */
inline float3 EnvLight_MisValue(float3 l, float nP, float p, float nQ, float q) {
    if (!(p > 0.0f) || !isfinite(p)) return (float3)(0.0f);
    return finiteOrZero(l * (Mis_Power(nP, p, nQ, q) / (nP * p)));
}

/* Multi-sample MIS for an environment light: one sample from the map's importance distribution (uniforms
 * uLight; direction *wiL, value *eL) at every shading point, and one from the cosine lobe around n (uBsdf;
 * *wiB, *eB) where withCosine is set, which the caller sets at a fraction cosShare of the shading points
 * (1: all; ½: every other sample of a pixel), expected counts 1 and cosShare. Then eL + eB (each times its
 * sample's Blinn-Phong term) is an unbiased estimate of what Light_Sample's E estimates. Shadow rays go
 * to infinity; a direction not drawn is n, with value 0.
 * In steps, each a few dependent loads or a short chain of arithmetic, over an EnvMis state: both
 * directions first (EnvMis_Begin: the cosine direction and its map coordinates; EnvMis_Row, EnvMis_Column,
 * EnvMis_Texel, EnvMis_Point: the importance sample), then the reads of the map for both
 * (EnvMis_Footprints: the two bilinear lookups' texels; EnvMis_Reads: their loads and the cosine
 * direction's pdf), which miss the cache (an 8 MB map, random directions) and, issued together, overlap;
 * then the values (EnvMis_Values). EnvLight_SampleMis runs the steps in turn; the lanes (lanes.cl,
 * Lanes_EnvMisShadows) run each step for four shading points before the next, so that four points' chains
 * of loads overlap. */
typedef struct {
    EnvLightDist d;
    EnvCosCell cell;
    EnvTexels fL, fB; /* the two lookups' texels */
    float3 n, wL, wB, lL, lB; /* map space */
    float2 uLight, uvL, uvB;
    float pL, pB;
    int okL, withCosine;
} EnvMis;

inline void EnvMis_Begin(const __global Light* light, const __global float* envDist, float3 nWorld, float2 uLight,
                         float2 uBsdf, int withCosine, EnvMis* s) {
    s->n = EnvLight_ToMap(light, nWorld); /* everything below in map space */
    s->d = EnvLight_Distribution(light, envDist, s->n);
    s->uLight = uLight;
    s->withCosine = withCosine;
    s->wL = s->wB = s->n;
    s->lL = s->lB = (float3)(0.0f);
    s->uvL = s->uvB = (float2)(0.0f);
    s->pL = s->pB = 0.0f; /* pB: the map's pdf of the cosine direction */
    s->okL = 0;
    s->fL.i00 = s->fL.i10 = s->fL.i01 = s->fL.i11 = 0;
    s->fL.dx = s->fL.dy = 0.0f;
    s->fB = s->fL;
    if (withCosine) {
        s->wB = EnvSample_Cosine(s->n, (float2)(fmin(uBsdf.x, CLRT_ONE_MINUS_EPS), uBsdf.y));
        s->uvB = EnvMap_DirToUv(light->mapping, s->wB);
    }
}

inline void EnvMis_Row(EnvMis* s) {
    if (s->d.bucket >= 0) EnvCos_PickRow(s->d.tab, s->d.bucket, s->uLight.y, &s->cell);
}

inline void EnvMis_Column(EnvMis* s) {
    if (s->d.bucket >= 0) EnvCos_PickColumn(s->d.tab, s->d.bucket, s->uLight.x, &s->cell);
}

inline void EnvMis_Texel(EnvMis* s) {
    if (s->d.bucket < 0) s->okL = EnvDist_SampleUv(s->d.own, s->uLight.x, s->uLight.y, &s->wL, &s->pL, &s->uvL);
    else s->cell = EnvCos_PickTexel(s->d.own, s->d.tab, s->cell);
}

/* The point within the texel (a bucket's sample; the map's own distribution sampled it whole in EnvMis_Texel). */
inline void EnvMis_Point(EnvMis* s) {
    if (s->d.bucket < 0) return;
    const EnvCosCell t = s->cell;
    s->okL = EnvDist_CellSample(s->d.own, t.I, t.J, t.du, t.dv, t.p, s->uLight.x, s->uLight.y, &s->wL, &s->pL, &s->uvL);
}

inline void EnvMis_Footprints(const __global Light* light, const __global ImageInfo* images, EnvMis* s) {
    const ImageInfo img = images[light->image];
    if (s->okL) s->fL = EnvMap_Footprint(img, light->mapping, s->uvL.x, s->uvL.y);
    if (s->withCosine) s->fB = EnvMap_Footprint(img, light->mapping, s->uvB.x, s->uvB.y);
}

inline void EnvMis_Reads(const __global Light* light, const __global ImageInfo* images, const __global float4* texels,
                         EnvMis* s) {
    const ImageInfo img = images[light->image];
    if (s->okL) s->lL = EnvMap_Blend(texels, img, s->fL) * light->radiance.xyz;
    else s->wL = s->n;
    if (s->withCosine) {
        s->lB = EnvMap_Blend(texels, img, s->fB) * light->radiance.xyz;
        s->pB = EnvLightDist_PdfUv(s->d, s->uvB);
    }
}

inline void EnvMis_Values(const __global Light* light, float cosShare, const EnvMis* s, float3* wiL, float3* eL,
                          float3* wiB, float3* eB) {
    *wiL = EnvLight_ToWorld(light, s->wL);
    *wiB = EnvLight_ToWorld(light, s->wB);
    *eL = s->okL ? EnvLight_MisValue(s->lL, 1.0f, s->pL, cosShare, fmax(dot(s->wL, s->n), 0.0f) * CLRT_INV_PI) : (float3)(0.0f);
    *eB = s->withCosine ? EnvLight_MisValue(s->lB, cosShare, fmax(dot(s->wB, s->n), 0.0f) * CLRT_INV_PI, 1.0f, s->pB)
                        : (float3)(0.0f);
}

inline void EnvLight_SampleMis(const __global Light* light, float3 nWorld, float2 uLight, float2 uBsdf, float cosShare,
                               int withCosine, const __global ImageInfo* images, const __global float4* texels,
                               const __global float* envDist, float3* wiL, float3* eL, float3* wiB, float3* eB) {
    EnvMis s;
    EnvMis_Begin(light, envDist, nWorld, uLight, uBsdf, withCosine, &s);
    EnvMis_Row(&s);
    EnvMis_Column(&s);
    EnvMis_Texel(&s);
    EnvMis_Point(&s);
    EnvMis_Footprints(light, images, &s);
    EnvMis_Reads(light, images, texels, &s);
    EnvMis_Values(light, cosShare, &s, wiL, eL, wiB, eB);
}

/* The dispatcher. p: the shading point, n: its shading normal (env strategies), u: two uniform
 * numbers for lights that need them; images/texels/envDist: the texel atlas and the environment
 * distributions; lightData: the object lights' triangles and spheres (object_lights.cl). */
inline float3 Light_Sample(const __global Light* light, float3 p, float3 n, float2 u, const __global ImageInfo* images,
                           const __global float4* texels, const __global float* envDist,
                           const __global float4* lightData, float3* wi, float* dist) {
    *dist = 0.0f;
    *wi = (float3)(0.0f, 0.0f, 1.0f);
    switch (light->kind) {
#ifdef CLRT_HAS_POINT_LIGHT
    case LIGHT_POINT: return PointLight_Sample(light, p, wi, dist);
#endif
#ifdef CLRT_HAS_SPOT_LIGHT
    case LIGHT_SPOT: return SpotLight_Sample(light, p, wi, dist);
#endif
#ifdef CLRT_HAS_DIRECTIONAL_LIGHT
    case LIGHT_DIRECTIONAL: return DirectionalLight_Sample(light, wi, dist);
#endif
#ifdef CLRT_HAS_AREA_LIGHT
    case LIGHT_AREA: return AreaLight_Sample(light, p, u, wi, dist);
#endif
#ifdef CLRT_HAS_ENV_LIGHT
    case LIGHT_ENVIRONMENT: return EnvironmentLight_Sample(light, n, u, images, texels, envDist, wi, dist);
#endif
#ifdef CLRT_HAS_LIGHT_MESH
    case LIGHT_MESH: return MeshLight_Sample(light, lightData, p, u, wi, dist);
#endif
#ifdef CLRT_HAS_LIGHT_SPHERE
    case LIGHT_SPHERE: return SphereLight_Sample(light, lightData, p, u, wi, dist);
#endif
    default: return (float3)(0.0f);
    }
}

#endif /* CLRT_LIGHTS_CL */
