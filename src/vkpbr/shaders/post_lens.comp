#version 450
// post_lens.comp: a camera model's colour (render/post.py Lens): each output pixel's ray
// through the model's inverse (lens.glsl), then the wide source pinhole's HDR radiance there,
// bilinear. Pixels without a ray (outside the model's image) are black, alpha 1.
#extension GL_GOOGLE_include_directive : require
#include "lens.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

vec4 load(ivec2 p) { return imageLoad(src, clamp(p, ivec2(0), imageSize(src) - 1)); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    vec4 ray = lens_ray(vec2(p));
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
