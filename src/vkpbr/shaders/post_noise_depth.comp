#version 450
// post_noise_depth.comp: a stereo depth sensor's noise (render/post.py Noise) on the dataset
// outputs' depth and range (src: "out_depth_range"; dst: a transient, copied back by
// post_noise_copy.comp): lateral jitter (the depth of a texel lateral_sigma pixels off,
// nearest), dropouts (grazing angles, depth discontinuities, beyond max_range), Gaussian
// disparity noise d' = d + sigma_d n on d = f b / Z, quantised to disparity_step, Z' = f b / d'.
// Invalid depth is 0 (depth and range), as the sensors' images write it.
#extension GL_GOOGLE_include_directive : require
#include "noise.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rg32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;  // a transient
layout(set = 0, binding = 2, rgba32f) uniform readonly image2D normals;  // world, unit

layout(push_constant) uniform DepthNoise {
    uint frame;
    float baseline;  // metres
    float sigma_d;  // pixels of disparity
    float step_d;  // pixels of disparity (0: none)
    float lateral;  // pixels
    float grazing_start;  // degrees
    float grazing_end;
    float edge_jump;  // relative depth difference to a 4-neighbour
    float edge_rate;
    float max_range;  // metres (inf: none)
} pc;

float depth_at(ivec2 q) { return imageLoad(src, clamp(q, ivec2(0), imageSize(src) - 1)).x; }

// The angle (degrees) between the pixel's ray and the surface: its ray from the angle off
// the axis (depth / range) and the azimuth of its offset from the principal point.
float grazing_angle(ivec2 q, vec2 dr, FrameKey key) {
    vec3 n = imageLoad(normals, q).xyz;
    vec3 nc = vec3(dot(key.r0.xyz, n), dot(key.r1.xyz, n), dot(key.r2.xyz, n));
    float c = clamp(dr.x / dr.y, -1.0, 1.0), s = sqrt(max(1.0 - c * c, 0.0));
    vec2 off = (vec2(q) - key.k.zw) / key.k.xy;
    float phi = atan(off.y, off.x);
    vec3 ray = vec3(s * cos(phi), s * sin(phi), c);
    return degrees(acos(clamp(abs(dot(nc, ray)), 0.0, 1.0)));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    FrameKey key = keys[pc.frame];
    ivec2 q = clamp(p + ivec2(round(pc.lateral * gauss2(key.hash.x, p, 2u))), ivec2(0), size - 1);
    vec2 dr = imageLoad(src, q).xy;
    float z = dr.x;
    float drop = 0.0;  // the probability this pixel drops out
    if (isinf(z) || z <= 0.0) drop = 1.0;
    else {
        float a = grazing_angle(q, dr, key);
        float width = pc.grazing_end - pc.grazing_start;
        drop = width > 0.0 ? clamp((a - pc.grazing_start) / width, 0.0, 1.0)
                           : float(a >= pc.grazing_start);
        float jump = 0.0;
        for (int i = 0; i < 4; ++i) {
            ivec2 o = ivec2(i == 0 ? 1 : i == 1 ? -1 : 0, i == 2 ? 1 : i == 3 ? -1 : 0);
            float zn = depth_at(q + o);
            jump = max(jump, isinf(zn) ? 1e30 : abs(zn - z) / z);
        }
        if (jump > pc.edge_jump) drop = max(drop, pc.edge_rate);
    }
    float u = uniform01(hash4(uvec4(key.hash.x, uint(p.x), uint(p.y), 7u)));
    vec2 out_dr = vec2(0.0);
    if (u >= drop) {
        float fb = key.k.y * pc.baseline;
        float d = fb / z + pc.sigma_d * gauss2(key.hash.x, p, 3u).x;
        if (pc.step_d > 0.0) d = round(d / pc.step_d) * pc.step_d;
        float z2 = d > 0.0 ? fb / d : 0.0;
        if (z2 > 0.0 && z2 <= pc.max_range) out_dr = vec2(z2, z2 * dr.y / dr.x);
    }
    imageStore(dst, p, vec4(out_dr, 0.0, 0.0));
}
