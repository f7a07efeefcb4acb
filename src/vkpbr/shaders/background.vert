#version 450
// The background pass (render/passes.py, "background"): one triangle covering the screen at
// the far plane (reversed-Z: depth 0), drawn after the opaque passes with depth test
// GREATER_OR_EQUAL and no depth write against the depth cleared to 0, so it reaches exactly
// the pixels no surface covered. `ray` is the world direction through the pixel: the
// difference of two points the inverse view-projection unprojects at NDC depths 1 (the near
// plane) and 0.5. Points of one NDC depth lie on a plane of the camera, affine in NDC xy, so
// the difference interpolates exactly across the triangle (every vertex has w = 1).
// The camera is views[view_index]: the frame's one view, or with BATCH = 1 instance i's,
// view i of the batch (render/batch.py), drawn into its layer.
#extension GL_GOOGLE_include_directive : require
#if BATCH
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#include "generated.glsl"

layout(location = 0) out vec3 ray;

void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
#if BATCH
    view_index = uint(gl_InstanceIndex);
    gl_Layer = int(views[view_index].layer);
#endif
    mat4 inv = inverse(views[view_index].VP);
    vec4 near = inv * vec4(p, 1.0, 1.0);
    vec4 mid = inv * vec4(p, 0.5, 1.0);
    ray = mid.xyz / mid.w - near.xyz / near.w;
}
