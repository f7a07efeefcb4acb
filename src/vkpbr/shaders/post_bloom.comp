#version 450
// post_bloom.comp: a physically based bloom in the manner of Filament's and pygfx's
// (PhysicalBasedBloomPass; Jimenez 2014, "Next generation post processing in Call of Duty:
// Advanced Warfare"): no threshold, every pixel's radiance spreads a little. The radiance is
// downsampled into a chain of half-size images (MODE_DOWN: a 4x4 tent, weights 1 3 3 1 per
// axis), upsampled back (MODE_UP: a bilinear tent of 3x3 taps, added to the level above),
// and the chain's top, the mean of every level, mixed into the radiance (MODE_MIX:
// color = mix(color, bloom, strength)). Each step keeps the image's mean (but at the last row
// or column of an odd size, which it counts twice), so the mix keeps the frame's total
// radiance: the bloom moves light, it does not make it. Over a frame, or a compute batch's
// atlas in one dispatch a step: every view's tile its own chain (reads clamped to the tile).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform image2D dst;

const uint MODE_DOWN = 0u, MODE_UP = 1u, MODE_MIX = 2u;
layout(push_constant) uniform Bloom {
    uint mode;
    float strength;  // MODE_MIX
    float weight;  // MODE_UP: 1 / the levels added so far (the result is their mean)
    uint views;  // a compute batch's views (1: a frame), their tiles column-major,
    uint rows;  // `rows` a column, in every image of the chain
    uint src_w, src_h;  // a view's pixels in src (a frame: its whole size)
    uint dst_w, dst_h;  // and in dst
} pc;

ivec2 src_lo;  // the view's first pixel in src: reads are clamped to its tile

vec3 load(ivec2 p) {
    return imageLoad(src, src_lo + clamp(p, ivec2(0), ivec2(pc.src_w, pc.src_h) - 1)).rgb;
}

// src at continuous texel position `x` (texel centres at integer + 0.5), bilinear, clamped.
vec3 bilinear(vec2 x) {
    vec2 t = x - 0.5;
    ivec2 i = ivec2(floor(t));
    vec2 f = t - vec2(i);
    return mix(mix(load(i), load(i + ivec2(1, 0)), f.x),
               mix(load(i + ivec2(0, 1)), load(i + ivec2(1, 1)), f.x), f.y);
}

vec3 down(ivec2 p) {
    const float w[4] = float[](1.0, 3.0, 3.0, 1.0);
    vec3 sum = vec3(0.0);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) sum += w[x] * w[y] * load(2 * p + ivec2(x - 1, y - 1));
    return sum / 64.0;
}

// The level below at this level's pixel p: a 3x3 tent (1 2 1) of bilinear taps one
// texel of the level below apart.
vec3 up(ivec2 p, vec2 scale) {
    vec2 c = (vec2(p) + 0.5) * scale;
    vec3 sum = vec3(0.0);
    for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x)
            sum += float((2 - abs(x)) * (2 - abs(y))) * bilinear(c + vec2(x, y));
    return sum / 16.0;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    // The view p belongs to (a frame: the one), p in its tile, and the tile's place in src.
    uvec2 dst_tile = uvec2(pc.dst_w, pc.dst_h), src_tile = uvec2(pc.src_w, pc.src_h);
    uvec2 t = uvec2(p) / dst_tile;
    if (t.y >= pc.rows || t.x * pc.rows + t.y >= pc.views) return;
    src_lo = ivec2(t * src_tile);
    ivec2 q = p - ivec2(t * dst_tile);
    vec2 scale = vec2(src_tile) / vec2(dst_tile);
    if (pc.mode == MODE_DOWN) {
        imageStore(dst, p, vec4(down(q), 1.0));
    } else if (pc.mode == MODE_UP) {  // the mean of this level and the ones below
        vec3 here = imageLoad(dst, p).rgb;
        imageStore(dst, p, vec4(mix(up(q, scale), here, pc.weight), 1.0));
    } else {
        vec4 c = imageLoad(dst, p);
        imageStore(dst, p, vec4(mix(c.rgb, up(q, scale), pc.strength), c.a));
    }
}
