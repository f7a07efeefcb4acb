#version 450
// post_fullscreen.vert: one triangle covering the target (post steps drawn as fragment passes:
// post_encode.frag into a window or a multisampled target, render/post_stage.py).
void main() {
    vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
