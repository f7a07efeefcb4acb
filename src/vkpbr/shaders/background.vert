#version 450
// The background pass (render/passes.py, "background"): one triangle covering the screen at
// the far plane (reversed-Z: depth 0), drawn after the opaque passes with depth test
// GREATER_OR_EQUAL and no depth write against the depth cleared to 0, so it reaches exactly
// the pixels no surface covered. `ray` is the world direction through the pixel: the point
// the inverse view-projection unprojects at NDC depth 0, the infinite far plane, is a
// direction (w = 0; its xyz is affine in NDC xy, so it interpolates exactly across the
// triangle), with no eye to cancel (the compute path's pixel rays: surface_fetch.glsl).
// The camera is views[view_index]: the frame's one view, or with BATCH = 1 instance i's,
// view i of the batch (render/batch.py), drawn into its layer.
#extension GL_GOOGLE_include_directive : require
#if BATCH
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#include "generated.glsl"

layout(location = 0) out vec3 ray;
#if BATCH
layout(location = 1) flat out uint v_view;  // (its world's environment: background.frag)
#endif

void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
#if BATCH
    view_index = uint(gl_InstanceIndex);
    v_view = view_index;
    gl_Layer = int(views[view_index].layer);
#endif
    ray = (views[view_index].inv_VP * vec4(p, 0.0, 1.0)).xyz;
}
