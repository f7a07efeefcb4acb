#version 450
// post_encode.frag: post_encode.comp as a fragment pass, for targets a compute shader cannot
// store into (a window's swapchain image, a multisampled target): the frame's HDR radiance at
// this pixel through its tone map; an sRGB attachment encodes in hardware.
#extension GL_GOOGLE_include_directive : require
#define STRUCTS_ONLY 1
#include "generated.glsl"
#include "brdf.glsl"

layout(set = 0, binding = 0, rgba32f) uniform readonly image2D radiance;
layout(push_constant) uniform Encode {
    int tonemap_mode;  // TONEMAP_*
    uint srgb;  // unused here (the attachment's format encodes)
} pc;
layout(location = 0) out vec4 out_color;

void main() {
    vec4 c = imageLoad(radiance, ivec2(gl_FragCoord.xy));
    out_color = vec4(tonemap(c.rgb, pc.tonemap_mode), c.a);
}
