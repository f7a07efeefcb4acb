// noise.glsl: counter-based random numbers for the sensor noise (render/post.py Noise):
// every draw is a hash of (the frame's key: seed and view, the pixel, a stream number), so
// the same seed and camera give the same noise whatever else the GPU runs, in any order.
// PCG's output permutation as a hash (Jarzynski and Olano 2020, "Hash Functions for GPU
// Rendering"), Box-Muller for Gaussians.
#ifndef NOISE_GLSL
#define NOISE_GLSL

// The frame's key (render/post_stage.py PostKernels.write_key), one 128-byte record a
// frame slot: hash of (seed, view); the output's fx, fy, cx, cy; camera-from-world rows
// (OpenCV camera axes).
struct FrameKey {
    uvec4 hash;
    vec4 k;
    vec4 r0;
    vec4 r1;
    vec4 r2;
    vec4 pad0;
    vec4 pad1;
    vec4 pad2;
};
layout(set = 1, binding = 0, std430) readonly buffer FrameKeys { FrameKey keys[]; };

uint pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

uint hash4(uvec4 v) { return pcg(v.x ^ pcg(v.y ^ pcg(v.z ^ pcg(v.w)))); }

// A uniform number in (0, 1) from 24 bits of a hash.
float uniform01(uint h) { return (float(h >> 8u) + 0.5) * (1.0 / 16777216.0); }

// Two independent standard Gaussians for (frame key, pixel, stream).
vec2 gauss2(uint key, ivec2 p, uint stream) {
    float u1 = uniform01(hash4(uvec4(key, uint(p.x), uint(p.y), 2u * stream)));
    float u2 = uniform01(hash4(uvec4(key, uint(p.x), uint(p.y), 2u * stream + 1u)));
    float r = sqrt(-2.0 * log(u1));
    return r * vec2(cos(6.28318530718 * u2), sin(6.28318530718 * u2));
}

#endif
