#version 450
// post_encode.comp: the last step of a frame with post steps (render/post.py): the frame's
// HDR radiance (already exposed: the shading multiplies by Settings.exposure) through its
// tone map (brdf.glsl tonemap, as frame_output.glsl applies it in frames without post
// steps), then stored into the output target's storage view: sRGB-encoded for an 8-bit sRGB
// image (whose view is UNORM), as is for a float one (brdf.glsl stored_color).
#extension GL_GOOGLE_include_directive : require
#define STRUCTS_ONLY 1
#include "generated.glsl"
#include "brdf.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D radiance;
layout(set = 0, binding = 1) uniform writeonly image2D target;  // WriteWithoutFormat

layout(push_constant) uniform Encode {
    int tonemap_mode;  // TONEMAP_*
    uint srgb;  // 1: the target is 8-bit sRGB (its view UNORM)
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(target)))) return;
    vec4 c = imageLoad(radiance, p);
    imageStore(target, p, stored_color(vec4(tonemap(c.rgb, pc.tonemap_mode), c.a), pc.srgb != 0u));
}
