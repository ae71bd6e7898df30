/* lights.cl — light sampling, one `case` per light kind. Light_Sample returns what the course's
 * shading model multiplies with the BRDF terms: the irradiance-like quantity E (point and spot:
 * I/d², directional: radiance, area: L·A·cosθ_L/d² for a uniformly drawn point) divided by the pdf
 * of the chosen direction, and the direction and distance for the shadow ray. */

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
    float cosLight = dot(light->direction.xyz, -*wi);
    if (cosLight <= 0.0f) return (float3)(0.0f); /* one-sided */
    return light->radiance.xyz * (light->area * cosLight / d2);
}

/* The dispatcher. u: two uniform numbers for lights that need them. */
inline float3 Light_Sample(const __global Light* light, float3 p, float2 u, float3* wi, float* dist) {
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
    default: return (float3)(0.0f);
    }
}
