#version 450
// The environment behind the scene: env_specular's sharpest level (the GGX pre-filter at
// roughness 0) in the direction of the pixel, rotated and scaled as image-based lighting sees
// it (Lighting.env_rotation, env_intensity), then the frame's exposure and tone map exactly as
// pbr.frag applies them (frame_output.glsl). Pixels are left to the clear colour when the
// frame has no background (Lighting.flags without LIGHTING_BACKGROUND: the course mode, env
// none, --env-background off) and in debug views other than final.
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
#include "brdf.glsl"
#include "env_common.glsl"
#include "frame_output.glsl"

layout(location = 0) in vec3 ray;
layout(location = 0) out vec4 out_color;

void main() {
    opaque_zero = uint(gl_FragCoord.x < 0.0);
    if ((u(lighting.flags) & LIGHTING_BACKGROUND) == 0u || u(settings.view) != VIEW_FINAL) {
        discard;
    }
    vec3 d = env_rotate(normalize(ray), lighting.env_rotation.xy);
    vec3 radiance = textureLod(env_specular, d, 0.0).rgb * lighting.env_intensity;
    out_color = vec4(radiance_output(radiance), 1.0);
}
