#version 450
// Test harness for shaders/ibl.glsl (tests/gpu/test_ibl.py): evaluates ibl_evaluate at the
// points of an input buffer. Declares what ibl.glsl reads under the names generated.glsl gives.
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, std140) uniform Lighting {
    float env_intensity;
    vec4 env_rotation;
} lighting;
layout(set = 0, binding = 2) uniform samplerCube env_specular;
layout(set = 0, binding = 3) uniform samplerCube env_irradiance;
layout(set = 0, binding = 4) uniform sampler2D brdf_lut;
struct Point { vec4 n_metallic; vec4 v_roughness; vec4 color; };
layout(set = 0, binding = 5, std430) readonly buffer Points { Point points[]; };
layout(set = 0, binding = 6, std430) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform Push { uint count; } pc;

#include "ibl.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Point p = points[i];
    IblTerms t = ibl_evaluate(p.n_metallic.xyz, p.v_roughness.xyz, p.color.rgb,
                              p.n_metallic.w, p.v_roughness.w);
    results[2u * i] = vec4(t.diffuse, 0.0);
    results[2u * i + 1u] = vec4(t.specular, 0.0);
}
