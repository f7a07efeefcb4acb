#version 450
// The environment behind the scene: env_specular's sharpest level (the GGX pre-filter at
// roughness 0) in the direction of the pixel, rotated and scaled as image-based lighting sees
// it (Lighting.env_rotation, env_intensity; a batch's view: its world's, worlds.glsl), then the frame's exposure and tone map exactly as
// pbr.frag applies them (frame_output.glsl). Pixels are left to the clear colour when the
// frame has no background (Lighting.flags without LIGHTING_BACKGROUND: the course mode, env
// none, --env-background off) and in debug views other than final. OPAQUE_COPY: the
// transmission's copy of the opaque scene (render/transmission.py), linear radiance, with
// the environment behind wherever it lights the frame (--env-background off included).
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
#include "brdf.glsl"
#include "env_common.glsl"
#include "frame_output.glsl"
#include "worlds.glsl"  // BATCH: a batch of worlds' environment (ENV_ROTATION, ENV_INTENSITY)

layout(location = 0) in vec3 ray;
#if BATCH
layout(location = 1) flat in uint v_view;  // the view of a layered batch (background.vert)
#endif
layout(location = 0) out vec4 out_color;

void main() {
#if BATCH
    view_index = v_view;
#endif
    opaque_zero = uint(gl_FragCoord.x < 0.0);
#if OPAQUE_COPY  // through glass the environment is seen wherever it lights, drawn or not
    const uint drawn_when = LIGHTING_IBL;
#else
    const uint drawn_when = LIGHTING_BACKGROUND;
#endif
    if ((u(lighting.flags) & drawn_when) == 0u || frame_view() != VIEW_FINAL) {
        discard;
    }
    vec3 d = env_rotate(normalize(ray), ENV_ROTATION);
    vec3 radiance = textureLod(env_specular, d, 0.0).rgb * ENV_INTENSITY;
    out_color = vec4(radiance_output(radiance), 1.0);
}
