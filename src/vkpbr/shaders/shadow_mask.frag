#version 450
// shadow_mask.frag: alpha-masked (and blended) casters cut out of the shadow maps where the
// base colour's alpha is below the cutoff, as pbr.frag's masked variant discards them: a
// leaf's shadow has the leaf's shape. Writes no colour.
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"

layout(location = 0) in vec4 v_texcoords;
layout(location = 1) in float v_alpha;

// See pbr.frag: keeps Mesa 22.3's lavapipe from compiling (and leaking) a variant per material.
uint opaque_zero;
float u(float x) { return x + float(opaque_zero); }

void main() {
    opaque_zero = uint(gl_FragCoord.x < 0.0);
    vec4 row0 = material.base_color_uv_row0, row1 = material.base_color_uv_row1;
    vec3 uv_h = vec3(u(row0.w) > 0.5 ? v_texcoords.zw : v_texcoords.xy, 1.0);
    vec2 uv = vec2(dot(row0.xyz, uv_h), dot(row1.xyz, uv_h));
    float alpha = texture(base_color_map, uv).a * material.base_color_factor.a * v_alpha;
    if (alpha < u(material.alpha_cutoff)) discard;
}
