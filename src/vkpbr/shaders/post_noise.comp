#version 450
// post_noise.comp: a sensor's colour noise (render/post.py Noise) on the frame's linear
// radiance, before the tone map and encoding: Poisson-Gaussian per channel (Foi et al. 2008),
// y = x + sqrt(x / full_well + (read / full_well)^2) n, in units where 1 is the full well;
// shot noise as its Gaussian limit (variance = mean in electrons), clamped at 0. In place;
// over a frame, or a compute batch's atlas (one dispatch, each tile its view's key).
#extension GL_GOOGLE_include_directive : require
#include "noise.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

layout(push_constant) uniform ColourNoise {
    uint frame;  // the first key: a frame's slot (keys[frame]), 0 for a batch's own keys
    float full_well;  // electrons at x = 1
    float read_noise;  // electrons
    uint tile_w;  // a view's pixels: the frame's size, or a compute batch's tile
    uint tile_h;
    uint rows;  // tiles a column (column-major, as the batch's atlas); 1 for a frame
    uint views;  // views drawn (tiles past them are left alone)
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    // The view p belongs to and p in its tile: a batch's view draws the noise of the same
    // camera rendered alone (its key, its own pixel coordinates).
    uvec2 t = uvec2(p) / uvec2(pc.tile_w, pc.tile_h);
    uint view = t.x * pc.rows + t.y;
    if (t.y >= pc.rows || view >= pc.views) return;
    ivec2 q = p - ivec2(t * uvec2(pc.tile_w, pc.tile_h));
    vec4 c = imageLoad(src, p);
    uint key = keys[pc.frame + view].hash.x;
    vec2 n01 = gauss2(key, q, 0u), n2 = gauss2(key, q, 1u);
    vec3 n = vec3(n01, n2.x);
    float read = pc.read_noise / pc.full_well;
    vec3 sigma = sqrt(max(c.rgb, 0.0) / pc.full_well + read * read);
    imageStore(dst, p, vec4(max(c.rgb + sigma * n, 0.0), c.a));
}
