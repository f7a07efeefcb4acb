// surface_fetch.glsl: the surface point a pixel sees on one triangle, for the compute
// shaders (shade.comp, raster.comp's masked kernel): the triangle's vertices fetched from the
// scene's storage buffers, the pixel-centre ray intersected with it (perspective-correct
// barycentrics) and the rays of its 2x2 quad's pixels (the texture gradients a rasteriser's
// quads take, so mip levels agree), then shade.glsl's surface globals set from them.
// The includer defines MATERIAL_INDEX (the material whose set 1 is bound) and includes
// generated.glsl (COMPUTE_SHADING) and, for TBN_MODE != 0, tbn_decode.glsl first.
// The rays come from the camera views[view_index] (generated.glsl): its inverse
// view-projection and eye (a compute batch's includer sets the index first).
#ifndef SURFACE_FETCH_GLSL
#define SURFACE_FETCH_GLSL

vec4 g_dtex_dx, g_dtex_dy;  // d(TEXCOORD_0, TEXCOORD_1) per pixel step in x and y

vec2 texture_grad(vec4 row0, vec4 row1, vec4 d) {
    vec2 duv = row0.w > 0.5 ? d.zw : d.xy;  // the derivative of the texture's own UV set...
    return vec2(dot(row0.xy, duv), dot(row1.xy, duv));  // ...through its transform's 2x2 part
}

// The material from the compute path's table (the frame's blocks, too, are storage buffers
// here: generated.glsl, COMPUTE_SET); its textures from its own set 1. A batch's view of a
// world with its own material factors (views[].factor_base > 0: render/worlds.py) takes
// the record with those four factors replaced; every other view reads the table as is.
#define MAT materials[MATERIAL_INDEX]
#include "worlds.glsl"  // a batch of worlds' factors (MAT_*_FACTOR)
#define SAMPLE(name) textureGrad(name##_map, texture_uv(MAT.name##_uv_row0, MAT.name##_uv_row1), \
    texture_grad(MAT.name##_uv_row0, MAT.name##_uv_row1, g_dtex_dx), \
    texture_grad(MAT.name##_uv_row0, MAT.name##_uv_row1, g_dtex_dy))
#include "shade.glsl"

vec3 vec3_at(uint i, bool normal) {
    uint k = 3u * i;
    return normal ? vec3(normals[k], normals[k + 1u], normals[k + 2u])
                  : vec3(positions[k], positions[k + 1u], positions[k + 2u]);
}

vec4 color_at(uint i) {
    uint lo = colors[2u * i], hi = colors[2u * i + 1u];
    return vec4(unpackUnorm2x16(lo), unpackUnorm2x16(hi));
}

// The pixel's ray through pixel position `p` (in pixels, y down): origin at the camera, unit
// direction, from the inverse view-projection (any intrinsics included). Unprojected at NDC
// depth 0, the infinite far plane (reversed-Z), whose point is a direction (w = 0): inv_VP's
// columns x, y and w (render/views.py) hold no eye, so nothing cancels. A near-plane point
// minus the eye loses float32 digits as |eye| / znear grows: with znear 1e-5 of the scene's
// radius (a camera inside Sponza: 1.9e-4) the rays were off by a median 1.3 pixels at 1080p,
// and the texture gradients (differences of neighbouring rays) by more than a mip level
// (issue 34; docs/fidelity.md).
vec3 ray_dir(vec2 p, vec2 extent) {
    vec2 ndc = p / extent * 2.0 - 1.0;
    return normalize((views[view_index].inv_VP * vec4(ndc, 0.0, 1.0)).xyz);
}

// Barycentrics (b1, b2) of the ray's hit on the plane of triangle (a, b, c); b0 = 1 - b1 - b2.
vec2 barycentrics(vec3 o, vec3 d, vec3 a, vec3 b, vec3 c) {
    vec3 e1 = b - a, e2 = c - a;
    vec3 pv = cross(d, e2);
    float det = dot(e1, pv);
    float inv = abs(det) > 1e-30 ? 1.0 / det : 0.0;
    vec3 tv = o - a;
    vec3 qv = cross(tv, e1);
    return vec2(dot(tv, pv), dot(d, qv)) * inv;
}

// One triangle of a draw as the surface fetch needs it: its vertices' indices, world
// positions and TEXCOORD_0/1 (a column each), and whether the scene has COLOR_0.
struct SurfaceTriangle {
    uvec3 vi;
    vec3 w0, w1, w2;
    mat3x4 tex;
    bool colors;
};

// Primitive `prim` of draw `draw` (fetched once for all the pixels that see it: the
// compute rasteriser's alpha test walks a triangle's pixels).
SurfaceTriangle surface_triangle(uint draw, uint prim) {
    SurfaceTriangle t;
    DrawRecord dr = draws[draw];
    mat4 model = instance_matrices[2u * (views[view_index].instance_base + draw)];
    uint base = dr.info.x + 3u * prim;
    t.vi = uvec3(indices[base], indices[base + 1u], indices[base + 2u]) + dr.info.y;
    t.w0 = (model * vec4(vec3_at(t.vi.x, false), 1.0)).xyz;
    t.w1 = (model * vec4(vec3_at(t.vi.y, false), 1.0)).xyz;
    t.w2 = (model * vec4(vec3_at(t.vi.z, false), 1.0)).xyz;
    t.tex = mat3x4(vec4(texcoords0[t.vi.x], texcoords1[t.vi.x]),
                   vec4(texcoords0[t.vi.y], texcoords1[t.vi.y]),
                   vec4(texcoords0[t.vi.z], texcoords1[t.vi.z]));
    t.colors = dr.info.w != 0u;
    return t;
}

// shade.glsl's s_texcoords, s_world_pos, s_color and the gradients for the centre of `pixel`
// (of a target `extent` pixels) on triangle `t`; returns the barycentrics.
vec3 surface_point(SurfaceTriangle t, uvec2 pixel, vec2 extent) {
    vec3 eye = views[view_index].eye_near.xyz;
    vec2 centre = vec2(pixel) + 0.5;
    vec2 b = barycentrics(eye, ray_dir(centre, extent), t.w0, t.w1, t.w2);
    // Texture derivatives as a rasteriser's 2x2 quads take them (fine: across the quad's
    // pixel pair in this row and in this column), so mip levels agree at their boundaries.
    vec2 quad = vec2(pixel & ~1u) + 0.5;
    vec2 qx = barycentrics(eye, ray_dir(vec2(quad.x, centre.y), extent), t.w0, t.w1, t.w2);
    vec2 qy = barycentrics(eye, ray_dir(vec2(centre.x, quad.y), extent), t.w0, t.w1, t.w2);
    vec2 bx = barycentrics(eye, ray_dir(vec2(quad.x + 1.0, centre.y), extent), t.w0, t.w1, t.w2) - qx;
    vec2 by = barycentrics(eye, ray_dir(vec2(centre.x, quad.y + 1.0), extent), t.w0, t.w1, t.w2) - qy;
    vec3 bary = vec3(1.0 - b.x - b.y, b.x, b.y);
    vec3 dbx = vec3(-bx.x - bx.y, bx.x, bx.y), dby = vec3(-by.x - by.y, by.x, by.y);
    s_texcoords = t.tex * bary;
    g_dtex_dx = t.tex * dbx;
    g_dtex_dy = t.tex * dby;
    s_world_pos = mat3(t.w0, t.w1, t.w2) * bary;
    s_color = t.colors ? mat3x4(color_at(t.vi.x), color_at(t.vi.y), color_at(t.vi.z)) * bary
                       : vec4(1.0);  // no COLOR_0 in the scene: white, as pbr.vert reads
    return bary;
}

// surface_triangle and surface_point for one pixel of primitive `prim` of draw `draw`;
// returns the draw, and the vertices' indices, world positions and the barycentrics for
// `surface_frame_at`.
DrawRecord surface_at(uint draw, uint prim, uvec2 pixel, vec2 extent, out uvec3 vi,
                      out vec3 w0, out vec3 w1, out vec3 w2, out vec3 bary) {
    DrawRecord dr = draws[draw];
    SurfaceTriangle t = surface_triangle(draw, prim);
    bary = surface_point(t, pixel, extent);
    vi = t.vi;
    w0 = t.w0;
    w1 = t.w1;
    w2 = t.w2;
    return dr;
}

// The rest of the surface globals: the interpolated normal, tangent and bitangent through
// the draw's matrices (TBN_MODE's stream), which side faces the camera, the node's scale.
void surface_frame_at(uint draw, uvec3 vi, vec3 w0, vec3 w1, vec3 w2, vec3 bary) {
    mat4 model = instance_matrices[2u * (views[view_index].instance_base + draw)];
    mat3 normal_matrix = mat3(instance_matrices[2u * (views[view_index].instance_base + draw) + 1u]);
    vec3 eye = views[view_index].eye_near.xyz;
    vec3 n[3], t[3], bt[3];
    for (int k = 0; k < 3; ++k) {
#if TBN_MODE == 0
        n[k] = vec3_at(vi[k], true);
        vec4 tg = tangents[vi[k]];
        t[k] = tg.xyz;
        bt[k] = (tg.w < 0.0 ? -1.0 : 1.0) * cross(n[k], t[k]);
#else
#if TBN_MODE == 1
        mat3 tbn = tbn_from_qtangent(qtangents[vi[k]]);
#else
        mat3 tbn = tbn_from_qtangent(qtangent_unpack(packed_frames[vi[k]]));
#endif
        t[k] = tbn[0];
        bt[k] = tbn[1];
        n[k] = tbn[2];
#endif
    }
    // As pbr.vert: normals through the inverse transpose, tangents through the model matrix.
    s_normal = normal_matrix * (mat3(n[0], n[1], n[2]) * bary);
    s_tangent = mat3(model) * (mat3(t[0], t[1], t[2]) * bary);
    s_bitangent = mat3(model) * (mat3(bt[0], bt[1], bt[2]) * bary);
    // Counter-clockwise in the image is the front (the pipelines' front face), i.e. the
    // triangle's world normal facing the camera; mirrored transforms are handled by the world
    // positions themselves.
    s_front_facing = dot(cross(w1 - w0, w2 - w0), eye - w0) > 0.0;
    s_model_scale = length(model[0].xyz);
}

#endif
