#version 450
// post_lens_cube_outputs.comp: a wide fisheye's dataset outputs from its cube faces
// (render/lens_cube.py), through the same mapping as its colour (post_lens_cube.comp) and
// as post_lens_outputs.comp maps a pinhole source's: ids never blended (the nearest face
// texel's); where the four taps show one instance the face's depth bilinear in 1/z (exact
// on a plane: 1/z is affine in a pinhole's pixels) and the normals bilinear, renormalised,
// else the nearest texel's. The face's depth z_f is along the face's axis; the point's
// range is z_f / l.z (l: the pixel's unit ray in the face's axes) and the model's depth its
// z along the lens's optical axis, range * ray.z: negative for points behind the camera's
// image plane (theta > 90 degrees), which a fisheye this wide sees. Motion: the face's
// (where the point was in the previous frame's image of the same face, lens_cube.py keeps
// each face's previous view), its ray back in the lens's axes, through the model's forward
// projection (lens_project). Background, pixels without a ray: ids 0, depth infinite.
#extension GL_GOOGLE_include_directive : require
#define LENS_CUBE 1
#include "lens.glsl"
#include "lens_cube.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rg32ui) uniform readonly uimage2D ids0;
layout(set = 0, binding = 1, rg32ui) uniform readonly uimage2D ids1;
layout(set = 0, binding = 2, rg32ui) uniform readonly uimage2D ids2;
layout(set = 0, binding = 3, rg32ui) uniform readonly uimage2D ids3;
layout(set = 0, binding = 4, rg32ui) uniform readonly uimage2D ids4;
layout(set = 0, binding = 5, rg32ui) uniform readonly uimage2D ids5;
layout(set = 0, binding = 6, rgba32f) uniform readonly image2D depth0;
layout(set = 0, binding = 7, rgba32f) uniform readonly image2D depth1;
layout(set = 0, binding = 8, rgba32f) uniform readonly image2D depth2;
layout(set = 0, binding = 9, rgba32f) uniform readonly image2D depth3;
layout(set = 0, binding = 10, rgba32f) uniform readonly image2D depth4;
layout(set = 0, binding = 11, rgba32f) uniform readonly image2D depth5;
layout(set = 0, binding = 12, rgba32f) uniform readonly image2D normal0;
layout(set = 0, binding = 13, rgba32f) uniform readonly image2D normal1;
layout(set = 0, binding = 14, rgba32f) uniform readonly image2D normal2;
layout(set = 0, binding = 15, rgba32f) uniform readonly image2D normal3;
layout(set = 0, binding = 16, rgba32f) uniform readonly image2D normal4;
layout(set = 0, binding = 17, rgba32f) uniform readonly image2D normal5;
layout(set = 0, binding = 18, rgba32f) uniform readonly image2D geometric0;
layout(set = 0, binding = 19, rgba32f) uniform readonly image2D geometric1;
layout(set = 0, binding = 20, rgba32f) uniform readonly image2D geometric2;
layout(set = 0, binding = 21, rgba32f) uniform readonly image2D geometric3;
layout(set = 0, binding = 22, rgba32f) uniform readonly image2D geometric4;
layout(set = 0, binding = 23, rgba32f) uniform readonly image2D geometric5;
layout(set = 0, binding = 24, rg32ui) uniform writeonly uimage2D dst_ids;
layout(set = 0, binding = 25, rgba32f) uniform writeonly image2D dst_depth;
layout(set = 0, binding = 26, rgba32f) uniform writeonly image2D dst_normal;
layout(set = 0, binding = 27, rgba32f) uniform writeonly image2D dst_geometric;

const float INF = 1.0 / 0.0;

uvec4 load_ids(int slot, ivec2 q) {
    switch (slot) {
        case 0: return imageLoad(ids0, q);
        case 1: return imageLoad(ids1, q);
        case 2: return imageLoad(ids2, q);
        case 3: return imageLoad(ids3, q);
        case 4: return imageLoad(ids4, q);
        default: return imageLoad(ids5, q);
    }
}

vec4 load_depth(int slot, ivec2 q) {
    switch (slot) {
        case 0: return imageLoad(depth0, q);
        case 1: return imageLoad(depth1, q);
        case 2: return imageLoad(depth2, q);
        case 3: return imageLoad(depth3, q);
        case 4: return imageLoad(depth4, q);
        default: return imageLoad(depth5, q);
    }
}

vec4 load_normal(int slot, ivec2 q) {
    switch (slot) {
        case 0: return imageLoad(normal0, q);
        case 1: return imageLoad(normal1, q);
        case 2: return imageLoad(normal2, q);
        case 3: return imageLoad(normal3, q);
        case 4: return imageLoad(normal4, q);
        default: return imageLoad(normal5, q);
    }
}

vec4 load_geometric(int slot, ivec2 q) {
    switch (slot) {
        case 0: return imageLoad(geometric0, q);
        case 1: return imageLoad(geometric1, q);
        case 2: return imageLoad(geometric2, q);
        case 3: return imageLoad(geometric3, q);
        case 4: return imageLoad(geometric4, q);
        default: return imageLoad(geometric5, q);
    }
}

vec4 normal_at(int slot, ivec2 t[4], vec4 w, bool blend, int n, bool geometric) {
    if (!blend) return geometric ? load_geometric(slot, t[n]) : load_normal(slot, t[n]);
    vec4 s = vec4(0.0);
    for (int k = 0; k < 4; ++k)
        s += w[k] * (geometric ? load_geometric(slot, t[k]) : load_normal(slot, t[k]));
    float len = length(s.xyz);
    return vec4(len > 0.0 ? s.xyz / len : s.xyz, s.w);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst_ids)))) return;
    vec4 ray = lens_ray(vec2(p));
    int face = cube_face(ray.xyz);
    int slot = face_slot(face);
    if (ray.w == 0.0 || slot < 0) {
        imageStore(dst_ids, p, uvec4(0u));
        imageStore(dst_depth, p, vec4(INF, INF, 0.0, 0.0));  // (no motion)
        imageStore(dst_normal, p, vec4(0.0));
        imageStore(dst_geometric, p, vec4(0.0));
        return;
    }
    vec3 l = face_local(face, ray.xyz);
    vec2 s = face_texel(l);
    ivec2 i = ivec2(floor(s));
    vec2 f = s - vec2(i);
    ivec2 hi = ivec2(lens.size - 1);
    ivec2 t[4] = ivec2[](clamp(i, ivec2(0), hi), clamp(i + ivec2(1, 0), ivec2(0), hi),
                         clamp(i + ivec2(0, 1), ivec2(0), hi), clamp(i + ivec2(1, 1), ivec2(0), hi));
    vec4 w = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    int n = int(f.x >= 0.5) + 2 * int(f.y >= 0.5);  // the nearest texel
    uvec2 ids[4];
    vec4 z[4];  // the face's depth, range, motion
    bool blend = true;
    for (int k = 0; k < 4; ++k) {
        ids[k] = load_ids(slot, t[k]).xy;
        z[k] = load_depth(slot, t[k]);
        blend = blend && ids[k].x == ids[0].x && ids[k].x != 0u && !isinf(z[k].x);
    }
    float zf = z[n].x;
    vec2 moved = z[n].zw;
    if (blend) {
        zf = 1.0 / (w.x / z[0].x + w.y / z[1].x + w.z / z[2].x + w.w / z[3].x);
        moved = w.x * z[0].zw + w.y * z[1].zw + w.z * z[2].zw + w.w * z[3].zw;
    }
    float range = isinf(zf) ? INF : zf / l.z;
    vec2 motion = vec2(0.0);
    if (moved != vec2(0.0) && !isinf(zf)) {
        vec2 was = s + moved;  // in the face's previous image
        vec3 d = face_to_lens(face, vec3((was - lens.k_src.zw) / lens.k_src.xy, 1.0));
        motion = lens_project(d) - vec2(p);
    }
    imageStore(dst_ids, p, uvec4(ids[n], 0u, 0u));
    imageStore(dst_depth, p, vec4(isinf(range) ? INF : range * ray.z, range, motion));
    imageStore(dst_normal, p, normal_at(slot, t, w, blend, n, false));
    imageStore(dst_geometric, p, normal_at(slot, t, w, blend, n, true));
}
