// lights.glsl: the radiance a punctual light sends to a point (KHR_lights_punctual), read from
// the frame's light records (render/layouts.py LIGHT_RECORD, written by render/frames.py).
// Mirrored in src/vkpbr/reference/lights.py.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL
#include "brdf.glsl"

// KHR_lights_punctual's spot falloff: t = clamp(cos(angle) * scale + offset, 0, 1), t^2, with
// scale = 1 / max(1e-3, cos inner - cos outer) and offset = -cos outer * scale.
float spot_falloff(LightRecord light, vec3 l) {
    float cd = dot(light.direction_kind.xyz, -l);
    float t = clamp(cd * light.cone.x + light.cone.y, 0.0, 1.0);
    return t * t;
}

// Radiance arriving at p from `light` (before n.l and shadows); l: unit direction to the light.
vec3 light_incident(LightRecord light, vec3 p, vec3 fallback, out vec3 l) {
    int kind = int(light.direction_kind.w);
    vec3 radiance = light.color_falloff.rgb;
    if (kind == LIGHT_DIRECTIONAL) {
        l = -light.direction_kind.xyz;
        return radiance;
    }
    vec3 to_light = light.position_range.xyz - p;
    float dist2 = dot(to_light, to_light);
    l = dist2 > 1e-16 ? to_light * inversesqrt(dist2) : fallback;
    radiance *= light_attenuation(dist2, uint(light.color_falloff.w), light.position_range.w);
    if (kind == LIGHT_SPOT) radiance *= spot_falloff(light, l);
    return radiance;
}

#endif
