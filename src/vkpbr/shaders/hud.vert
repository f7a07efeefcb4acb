// HUD overlay (vkpbr view): textured, coloured quads in window pixels, drawn over the frame.
// Positions arrive in pixels from the top-left corner; the push constant maps them to clip
// space (Vulkan's clip-space Y points down, as window pixels do).
#version 450

layout(location = 0) in vec4 in_pos_uv;  // xy: window pixels, zw: atlas texture coordinates
layout(location = 1) in vec4 in_color;   // linear RGBA

layout(push_constant, std430) uniform Screen {
    vec2 scale;   // 2 / window size
    vec2 offset;  // -1, -1
} screen;

layout(location = 0) out vec2 v_uv;
layout(location = 1) out vec4 v_color;

void main() {
    v_uv = in_pos_uv.zw;
    v_color = in_color;
    gl_Position = vec4(in_pos_uv.xy * screen.scale + screen.offset, 0.0, 1.0);
}
