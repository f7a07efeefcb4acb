#version 450
// post_bloom.comp: a physically based bloom in the manner of Filament's and pygfx's
// (PhysicalBasedBloomPass; Jimenez 2014, "Next generation post processing in Call of Duty:
// Advanced Warfare"): no threshold, every pixel's radiance spreads a little. The radiance is
// downsampled into a chain of half-size images (MODE_DOWN: at even sizes a 4x4 tent, weights
// 1 3 3 1 per axis), upsampled back (MODE_UP: at even sizes a bilinear tent, added to the
// level above), and the chain's top, the mean of every level, mixed into the radiance
// (MODE_MIX: color = mix(color, bloom, strength)). Each step keeps the image's mean at every
// size (below: odd sizes too), so the mix keeps the frame's total radiance: the bloom moves
// light, it does not make it. Over a frame, or a compute batch's
// atlas in one dispatch a step: every view's tile its own chain (reads clamped to the tile).
#extension GL_GOOGLE_include_directive : require

// 1: the build for steps between levels of other than 2:1 in an axis (odd sizes, render/
// post.py); 0: every step 2:1, where the general weights reduce to constant ones.
#ifndef ODD_LEVELS
#define ODD_LEVELS 0
#endif

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

// The chain's resampling, exact in the mean at every size (an odd level's last row or column
// had counted twice, losing up to ~4% of a frame's light). Per axis, a level of n texels
// maps onto the `s` = (level above)/n times as many texels of the level above, each of its
// texels the footprint [j s, (j+1) s) there. MODE_DOWN: the level above blurred by T (1 2 1,
// reads clamped: every texel keeps a total weight of 1), then averaged over each footprint
// by area; at even sizes (s = 2) this is the 1 3 3 1 tent of Jimenez 2014 exactly. MODE_UP:
// the level below blurred by T, then spread back by the transpose of that average times s
// (each texel below gives away s, each texel above is a normalised mix): in the interior
// the bilinear tent of Jimenez 2014. Both keep the mean; 5 taps an axis at most.
#if ODD_LEVELS  // the general weights
const float T[3] = float[](0.25, 0.5, 0.25);  // the blur, at offsets -1, 0, +1

// Overlap of footprint j ([j s, (j+1) s), clipped to [0, n_above)) with texel k ([k, k+1)).
float overlap(int j, int k, float s, int n_above) {
    float lo = float(j) * s, hi = min(float(j + 1) * s, float(n_above));
    return max(0.0, min(hi, float(k + 1)) - max(lo, float(k)));
}

// MODE_DOWN, one axis: dst texel q's weights of the level above's texels first - 1 + m (m in
// 0..4), `first` the footprint's first texel, `n` the level above's size, `s` n / dst size.
float[5] down_weights(int q, float s, int n, out int first) {
    float w[5] = float[](0.0, 0.0, 0.0, 0.0, 0.0);
    first = int(floor(float(q) * s));
    for (int k = 0; k < 3; ++k) {
        float o = overlap(q, first + k, s, n) / s;
        for (int d = 0; d < 3; ++d) w[k + d] += o * T[d];  // texel first + k + d - 1
    }
    return w;
}

// MODE_UP, one axis: the level above's texel i's weights (the transpose of down_weights, times
// s) of the blurred level below's texels first + m (m in 0..2), `n` the level above's size,
// `s` n / the level below's size; clamped reads at i's edges count as i's.
float[3] up_weights(int i, float s, int n, out int first) {
    float w[3] = float[](0.0, 0.0, 0.0);
    first = int(floor(float(max(i - 1, 0)) / s));
    for (int m = 0; m < 3; ++m) {
        int j = first + m;
        // texel k's blur reads i at offset i - k: k = i + 1, i, i - 1 (T[0], T[1], T[2])
        float u = overlap(j, i + 1, s, n) * T[0] + overlap(j, i, s, n) * T[1]
                + overlap(j, i - 1, s, n) * T[2];
        if (i == 0) u += overlap(j, 0, s, n) * T[0];  // texel 0's read at -1
        if (i == n - 1) u += overlap(j, n - 1, s, n) * T[2];  // texel n-1's read at n
        w[m] = u;
    }
    return w;
}

// The level above's (MODE_DOWN) or below's (MODE_UP) texels first - 1 + m, m in 0..4 an
// axis, weighted by wx and wy (zero weights not read).
vec3 taps5(ivec2 first, float wx[5], float wy[5]) {
    vec3 sum = vec3(0.0);
    for (int y = 0; y < 5; ++y) {
        if (wy[y] == 0.0) continue;
        vec3 row = vec3(0.0);
        for (int x = 0; x < 5; ++x)
            if (wx[x] != 0.0) row += wx[x] * load(first + ivec2(x - 1, y - 1));
        sum += wy[y] * row;
    }
    return sum;
}

vec3 down(ivec2 p) {
    ivec2 first;
    vec2 s = vec2(pc.src_w, pc.src_h) / vec2(pc.dst_w, pc.dst_h);
    float wx[5] = down_weights(p.x, s.x, int(pc.src_w), first.x);
    float wy[5] = down_weights(p.y, s.y, int(pc.src_h), first.y);
    return taps5(first, wx, wy);
}

// One axis of up: up_weights of the blurred texels first + m (m in 0..2) as weights of the
// level below's texels first - 1 + m (m in 0..4), the blur T folded in.
float[5] up_taps(int i, float s, int n, out int first) {
    float u[3] = up_weights(i, s, n, first);
    float w[5] = float[](0.0, 0.0, 0.0, 0.0, 0.0);
    for (int m = 0; m < 3; ++m)
        for (int d = 0; d < 3; ++d) w[m + d] += u[m] * T[d];
    return w;
}

// The level below (src) at this level's pixel p (dst): blurred by T there (clamped reads),
// then spread by up_weights.
vec3 up(ivec2 p) {
    ivec2 first;
    vec2 s = vec2(pc.dst_w, pc.dst_h) / vec2(pc.src_w, pc.src_h);
    float wx[5] = up_taps(p.x, s.x, int(pc.dst_w), first.x);
    float wy[5] = up_taps(p.y, s.y, int(pc.dst_h), first.y);
    return taps5(first, wx, wy);
}

#else  // every step 2:1 (render/post.py picks this build then): constant weights
// At even sizes (s = 2) the resampling above has constant weights: MODE_DOWN's 1 3 3 1 tent, MODE_UP's
// bilinear tent (1 5 7 3 or 3 7 5 1 by parity, / 16; its edge texels 12 4 and 4 12).
vec3 down_even(ivec2 p) {
    const float w[4] = float[](1.0, 3.0, 3.0, 1.0);
    vec3 sum = vec3(0.0);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) sum += w[x] * w[y] * load(2 * p + ivec2(x - 1, y - 1));
    return sum / 64.0;
}

// One axis of up_even: the weights (/ 16) of the level below's texels first .. first + 3 for
// this level's texel i of n (at its two edges up_weights' sums, the clamped reads folded in).
vec4 up_even_weights(int i, int n) {
    if (i == 0) return vec4(0.0, 0.0, 12.0, 4.0);
    if (i == n - 1) return vec4(4.0, 12.0, 0.0, 0.0);
    return (i & 1) == 0 ? vec4(1.0, 5.0, 7.0, 3.0) : vec4(3.0, 7.0, 5.0, 1.0);
}

vec3 up_even(ivec2 p) {
    ivec2 first = (p >> 1) - 2 + (p & 1);  // even i = 2j: j - 2; odd i = 2j + 1: j - 1
    vec4 wx = up_even_weights(p.x, int(pc.dst_w)), wy = up_even_weights(p.y, int(pc.dst_h));
    vec3 sum = vec3(0.0);
    for (int y = 0; y < 4; ++y) {
        vec3 row = vec3(0.0);
        for (int x = 0; x < 4; ++x) row += wx[x] * load(first + ivec2(x, y));
        sum += wy[y] * row;
    }
    return sum / 256.0;
}

vec3 down(ivec2 p) { return down_even(p); }
vec3 up(ivec2 p) { return up_even(p); }
#endif

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    // The view p belongs to (a frame: the one), p in its tile, and the tile's place in src.
    uvec2 dst_tile = uvec2(pc.dst_w, pc.dst_h), src_tile = uvec2(pc.src_w, pc.src_h);
    uvec2 t = uvec2(p) / dst_tile;
    if (t.y >= pc.rows || t.x * pc.rows + t.y >= pc.views) return;
    src_lo = ivec2(t * src_tile);
    ivec2 q = p - ivec2(t * dst_tile);
    if (pc.mode == MODE_DOWN) {
        imageStore(dst, p, vec4(down(q), 1.0));
    } else if (pc.mode == MODE_UP) {  // the mean of this level and the ones below
        vec3 here = imageLoad(dst, p).rgb;
        imageStore(dst, p, vec4(mix(up(q), here, pc.weight), 1.0));
    } else {
        vec4 c = imageLoad(dst, p);
        imageStore(dst, p, vec4(mix(c.rgb, up(q), pc.strength), c.a));
    }
}
