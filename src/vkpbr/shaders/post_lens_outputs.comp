#version 450
// post_lens_outputs.comp: a camera model's dataset outputs (render/post.py Lens), through the
// same mapping as its colour (post_lens.comp). Ids are never blended: the nearest source
// texel's. Where the four source texels around the ray show one instance, the depth is
// bilinear in 1/z (exact on a plane: 1/z is affine in a pinhole's pixels) and the normals
// bilinear, renormalised; elsewhere (edges, background) the nearest texel's. The model's
// depth is the distance along its optical axis (the source's: same pose), its range the
// distance along the pixel's own ray: range = z / ray.z. The motion (the depth image's zw:
// where the point was in the previous frame's image, from where it is, in pixels) is mapped
// too: the source's motion (bilinear within one instance, as the depth, else the nearest
// texel's) gives where the point was in the previous source image; its ray there, through
// the model's forward projection (lens_project), where it was in the previous model image.
// The previous frame is taken to have had the same model and size (a sequence's frames: its
// source pinhole had the same intrinsics). Background, and a renderer's first frame: 0.
#extension GL_GOOGLE_include_directive : require
#include "lens.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rg32ui) uniform readonly uimage2D src_ids;
layout(set = 0, binding = 1, rgba32f) uniform readonly image2D src_depth;  // depth, range, motion
layout(set = 0, binding = 2, rgba32f) uniform readonly image2D src_normal;
layout(set = 0, binding = 3, rgba32f) uniform readonly image2D src_geometric;
layout(set = 0, binding = 4, rg32ui) uniform writeonly uimage2D dst_ids;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image2D dst_depth;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D dst_normal;
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2D dst_geometric;

const float INF = 1.0 / 0.0;

ivec2 clamped(ivec2 q) { return clamp(q, ivec2(0), imageSize(src_ids) - 1); }

vec4 normal_at(ivec2 t[4], vec4 w, bool blend, int n, bool geometric) {
    if (!blend) return geometric ? imageLoad(src_geometric, t[n]) : imageLoad(src_normal, t[n]);
    vec4 s = vec4(0.0);
    for (int k = 0; k < 4; ++k)
        s += w[k] * (geometric ? imageLoad(src_geometric, t[k]) : imageLoad(src_normal, t[k]));
    float len = length(s.xyz);
    return vec4(len > 0.0 ? s.xyz / len : s.xyz, s.w);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst_ids)))) return;
    vec4 ray = lens_ray(vec2(p));
    if (ray.w == 0.0 || ray.z <= 0.0) {
        imageStore(dst_ids, p, uvec4(0u));
        imageStore(dst_depth, p, vec4(INF, INF, 0.0, 0.0));  // (no motion)
        imageStore(dst_normal, p, vec4(0.0));
        imageStore(dst_geometric, p, vec4(0.0));
        return;
    }
    vec2 s = source_texel(ray.xyz);
    ivec2 i = ivec2(floor(s));
    vec2 f = s - vec2(i);
    ivec2 t[4] = ivec2[](clamped(i), clamped(i + ivec2(1, 0)), clamped(i + ivec2(0, 1)),
                         clamped(i + ivec2(1, 1)));
    vec4 w = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    int n = int(f.x >= 0.5) + 2 * int(f.y >= 0.5);  // the nearest texel
    uvec2 ids[4];
    vec4 z[4];  // depth, range, motion
    bool blend = true;
    for (int k = 0; k < 4; ++k) {
        ids[k] = imageLoad(src_ids, t[k]).xy;
        z[k] = imageLoad(src_depth, t[k]);
        blend = blend && ids[k].x == ids[0].x && ids[k].x != 0u && !isinf(z[k].x);
    }
    float depth = z[n].x;
    vec2 moved = z[n].zw;
    if (blend) {
        depth = 1.0 / (w.x / z[0].x + w.y / z[1].x + w.z / z[2].x + w.w / z[3].x);
        moved = w.x * z[0].zw + w.y * z[1].zw + w.z * z[2].zw + w.w * z[3].zw;
    }
    vec2 motion = vec2(0.0);
    if (moved != vec2(0.0) && !isinf(depth)) {
        vec2 was = s + moved;  // in the previous source image
        motion = lens_project(vec3((was - lens.k_src.zw) / lens.k_src.xy, 1.0)) - vec2(p);
    }
    imageStore(dst_ids, p, uvec4(ids[n], 0u, 0u));
    imageStore(dst_depth, p, vec4(depth, isinf(depth) ? INF : depth / ray.z, motion));
    imageStore(dst_normal, p, normal_at(t, w, blend, n, false));
    imageStore(dst_geometric, p, normal_at(t, w, blend, n, true));
}
