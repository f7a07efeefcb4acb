#version 450
// post_lens_batch.comp: post_lens.comp over a compute batch's atlas in one dispatch
// (render/post.py lens_batch_steps): each output pixel's view (its tile of the output
// atlas), that view's lens constants (a buffer, LensParams), its ray, then the view's source
// tile of the HDR atlas there, bilinear, clamped to the tile (a view never reads another's).
#extension GL_GOOGLE_include_directive : require
#define LENS_BATCH 1
#include "lens.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

layout(push_constant) uniform Tiles {
    uint tile_w;  // the output's tile (a view's pixels)
    uint tile_h;
    uint rows;  // tiles a column, in both atlases (column-major)
    uint views;
    uint src_w;  // the source's tile
    uint src_h;
} pc;

ivec2 src_lo;

vec4 load(ivec2 p) {
    return imageLoad(src, src_lo + clamp(p, ivec2(0), ivec2(pc.src_w, pc.src_h) - 1));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    uvec2 t = uvec2(p) / uvec2(pc.tile_w, pc.tile_h);
    uint view = t.x * pc.rows + t.y;
    if (t.y >= pc.rows || view >= pc.views) return;
    lens = view_lens[view];
    src_lo = ivec2(t * uvec2(pc.src_w, pc.src_h));
    ivec2 q = p - ivec2(t * uvec2(pc.tile_w, pc.tile_h));
    vec4 ray = lens_ray(vec2(q));
    if (ray.w == 0.0 || ray.z <= 0.0) {
        imageStore(dst, p, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec2 s = source_texel(ray.xyz);
    ivec2 i = ivec2(floor(s));
    vec2 f = s - vec2(i);
    vec4 c = mix(mix(load(i), load(i + ivec2(1, 0)), f.x),
                 mix(load(i + ivec2(0, 1)), load(i + ivec2(1, 1)), f.x), f.y);
    imageStore(dst, p, c);
}
