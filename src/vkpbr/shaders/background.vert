#version 450
// The background (sky) pass: one fullscreen triangle at the far plane (reversed-Z: depth 0),
// drawn with depth test EQUAL / GREATER_OR_EQUAL against a cleared-to-0 depth buffer, so only
// pixels no surface covered get the environment. The view ray comes from the inverse of the
// view-projection without translation (push constant).
layout(push_constant) uniform Background {
    mat4 inv_view_proj;  // world-from-clip of the camera with its translation removed
    vec4 rotation;       // x = cos, y = sin of the environment's rotation about +Y; z = lod
    vec4 scale;          // rgb = env_intensity * 2^exposure-free factor, w = unused
} bg;
layout(location = 0) out vec3 ray;

void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
    vec4 w = bg.inv_view_proj * vec4(p, 1.0, 1.0);  // any depth: the ray's direction only
    ray = w.xyz / w.w;
}
