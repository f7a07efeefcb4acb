#version 450
// post_lens_cube.comp: a wide fisheye's colour from its cube faces (render/lens_cube.py):
// each output pixel's ray (lens.glsl lens_ray), the face its major axis picks, then that
// face image's radiance there, bilinear. A face image is CUBE_MARGIN texels wider than its
// 90 degrees each side, so the four taps always lie in the one face: no seam is sampled
// across. Pixels without a ray are black, alpha 1.
#extension GL_GOOGLE_include_directive : require
#define LENS_CUBE 1
#include "lens.glsl"
#include "lens_cube.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
// The faces' images by slot (unused slots bind slot 0's).
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D face0;
layout(set = 0, binding = 1, rgba32f) uniform readonly image2D face1;
layout(set = 0, binding = 2, rgba32f) uniform readonly image2D face2;
layout(set = 0, binding = 3, rgba32f) uniform readonly image2D face3;
layout(set = 0, binding = 4, rgba32f) uniform readonly image2D face4;
layout(set = 0, binding = 5, rgba32f) uniform readonly image2D face5;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D dst;

vec4 load(int slot, ivec2 q) {
    q = clamp(q, ivec2(0), ivec2(lens.size - 1));
    switch (slot) {
        case 0: return imageLoad(face0, q);
        case 1: return imageLoad(face1, q);
        case 2: return imageLoad(face2, q);
        case 3: return imageLoad(face3, q);
        case 4: return imageLoad(face4, q);
        default: return imageLoad(face5, q);
    }
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    vec4 ray = lens_ray(vec2(p));
    int face = cube_face(ray.xyz);
    int slot = face_slot(face);
    if (ray.w == 0.0 || slot < 0) {
        imageStore(dst, p, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec2 s = face_texel(face_local(face, ray.xyz));
    ivec2 i = ivec2(floor(s));
    vec2 f = s - vec2(i);
    vec4 c = mix(mix(load(slot, i), load(slot, i + ivec2(1, 0)), f.x),
                 mix(load(slot, i + ivec2(0, 1)), load(slot, i + ivec2(1, 1)), f.x), f.y);
    imageStore(dst, p, c);
}
