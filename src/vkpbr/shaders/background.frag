#version 450
// The environment as background: env_specular at `lod` (0: the sharp sky), rotated, times
// env_intensity; linear radiance (the frame's tone map and exposure follow in the same pass
// as for surfaces when the includer wires it so; this standalone shader writes radiance).
#include "env_common.glsl"
layout(push_constant) uniform Background {
    mat4 inv_view_proj;
    vec4 rotation;
    vec4 scale;
} bg;
layout(set = 0, binding = 0) uniform samplerCube environment;
layout(location = 0) in vec3 ray;
layout(location = 0) out vec4 color;

void main() {
    vec3 d = env_rotate(normalize(ray), bg.rotation.xy);
    color = vec4(textureLod(environment, d, bg.rotation.z).rgb * bg.scale.rgb, 1.0);
}
