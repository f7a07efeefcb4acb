#version 450
// shadow.vert: depth-only shadow-map passes (render/shadows.py). One draw fills all layers of
// its pass, one instance per layer: instance i of a draw with firstInstance b (the pass's
// first matrix) uses matrix b + i and writes layer i of the pass's attachment; PUSH names the
// draw's record of Instances (the scene state's model matrices). (Multiview was tried first: Mesa 22.3's lavapipe draws perspective
// views of one pass into the wrong layers.)
// ALPHA_MASK = 1: also passes the base colour's coordinates and alpha for shadow_mask.frag.
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require
#extension GL_ARB_shader_viewport_layer_array : require
#include "generated.glsl"
#include "shadow_data.glsl"

layout(location = 0) in vec3 in_position;
#if ALPHA_MASK
layout(location = 1) in vec2 in_texcoord0;
layout(location = 2) in vec2 in_texcoord1;
layout(location = 3) in vec4 in_color;
layout(location = 0) out vec4 v_texcoords;  // xy: TEXCOORD_0, zw: TEXCOORD_1
layout(location = 1) out float v_alpha;  // COLOR_0's alpha
#endif

void main() {
    vec4 world = instance_matrices[2u * draw.index.x] * vec4(in_position, 1.0);
    gl_Position = shadow_data.layer_vp[gl_InstanceIndex] * world;
    gl_Layer = gl_InstanceIndex - gl_BaseInstanceARB;
#if ALPHA_MASK
    v_texcoords = vec4(in_texcoord0, in_texcoord1);
    v_alpha = in_color.a;
#endif
}
