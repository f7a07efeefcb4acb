#version 450
// shade.comp: the compute path's shading (render/compute_path.py). Dispatched once per
// material with that material's set 1 bound (classify.comp binned the pixels); one invocation
// per pixel of the bin reads the visibility buffer (draw index + 1, primitive index) that the
// raster pass wrote, fetches the triangle's three vertices from the scene's storage buffers, intersects the pixel-centre
// ray with it for perspective-correct barycentrics (and the rays of its 2x2 quad's pixels for
// the texture derivatives the fragment path's quads take), and shades the point with
// shade.glsl -- the fragment path's own function -- on all SMs of the GPU, not only those that
// run fragment shaders. Pixels nothing covers were cleared by classify.comp.
// TBN_MODE: the tangent-frame stream, as in pbr.vert.
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
#if TBN_MODE != 0
#include "tbn_decode.glsl"
#endif

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;  // compute_path.SHADE_GROUP

layout(push_constant) uniform Shade {
    uint material;  // the bin this dispatch shades (its set 1 is bound)
} pc;

vec4 g_dtex_dx, g_dtex_dy;  // d(TEXCOORD_0, TEXCOORD_1) per pixel step in x and y

vec2 texture_grad(vec4 row0, vec4 row1, vec4 d) {
    vec2 duv = row0.w > 0.5 ? d.zw : d.xy;  // the derivative of the texture's own UV set...
    return vec2(dot(row0.xy, duv), dot(row1.xy, duv));  // ...through its transform's 2x2 part
}

// The material from the compute path's table (the frame's blocks, too, are storage buffers
// here: generated.glsl, COMPUTE_SET); its textures from its own set 1.
#define MAT materials[pc.material]
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
// direction, from the inverse view-projection (any intrinsics included).
vec3 ray_dir(vec2 p, vec2 extent) {
    vec2 ndc = p / extent * 2.0 - 1.0;
    vec4 near = camera.inv_VP * vec4(ndc, 1.0, 1.0);  // reversed-Z: the near plane is depth 1
    return normalize(near.xyz / near.w - lighting.view_pos.xyz);
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

void main() {
    uvec4 bin = bins[pc.material];
    if (gl_GlobalInvocationID.x >= bin.x) return;
    ivec2 size = imageSize(out_image);
    uint index = pixel_list[bin.y + gl_GlobalInvocationID.x];
    uvec2 pixel = uvec2(index % uint(size.x), index / uint(size.x));
    // The leak guard's zero (frame_output.glsl) may be a plain 0 here: this shader reads no
    // uniform block for lavapipe to inline (COMPUTE_SET).
    opaque_zero = 0u;
    uvec2 vis = imageLoad(visibility, ivec2(pixel)).xy;
    bool srgb_target = (u(settings.flags) & SETTINGS_SRGB_TARGET) != 0u;
    DrawRecord dr = draws[vis.x - 1u];
    uint base = dr.info.x + 3u * vis.y;
    uvec3 vi = uvec3(indices[base], indices[base + 1u], indices[base + 2u]) + dr.info.y;

    vec3 w0 = (dr.model * vec4(vec3_at(vi.x, false), 1.0)).xyz;
    vec3 w1 = (dr.model * vec4(vec3_at(vi.y, false), 1.0)).xyz;
    vec3 w2 = (dr.model * vec4(vec3_at(vi.z, false), 1.0)).xyz;
    vec3 eye = lighting.view_pos.xyz;
    vec2 extent = vec2(size);
    vec2 centre = vec2(pixel) + 0.5;
    vec2 b = barycentrics(eye, ray_dir(centre, extent), w0, w1, w2);
    // Texture derivatives as a rasteriser's 2x2 quads take them (fine: across the quad's
    // pixel pair in this row and in this column), so mip levels agree at their boundaries.
    vec2 quad = vec2(pixel & ~1u) + 0.5;
    vec2 qx = barycentrics(eye, ray_dir(vec2(quad.x, centre.y), extent), w0, w1, w2);
    vec2 qy = barycentrics(eye, ray_dir(vec2(centre.x, quad.y), extent), w0, w1, w2);
    vec2 bx = barycentrics(eye, ray_dir(vec2(quad.x + 1.0, centre.y), extent), w0, w1, w2) - qx;
    vec2 by = barycentrics(eye, ray_dir(vec2(centre.x, quad.y + 1.0), extent), w0, w1, w2) - qy;
    vec3 bary = vec3(1.0 - b.x - b.y, b.x, b.y);
    vec3 dbx = vec3(-bx.x - bx.y, bx.x, bx.y), dby = vec3(-by.x - by.y, by.x, by.y);

    mat3x4 tex = mat3x4(vec4(texcoords0[vi.x], texcoords1[vi.x]),
                        vec4(texcoords0[vi.y], texcoords1[vi.y]),
                        vec4(texcoords0[vi.z], texcoords1[vi.z]));
    s_texcoords = tex * bary;
    g_dtex_dx = tex * dbx;
    g_dtex_dy = tex * dby;
    s_world_pos = mat3(w0, w1, w2) * bary;
    s_color = dr.info.w != 0u ? mat3x4(color_at(vi.x), color_at(vi.y), color_at(vi.z)) * bary
                              : vec4(1.0);  // no COLOR_0 in the scene: white, as pbr.vert reads

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
    s_normal = mat3(dr.normal_matrix) * (mat3(n[0], n[1], n[2]) * bary);
    s_tangent = mat3(dr.model) * (mat3(t[0], t[1], t[2]) * bary);
    s_bitangent = mat3(dr.model) * (mat3(bt[0], bt[1], bt[2]) * bary);
    // Counter-clockwise in the image is the front (the pipelines' front face), i.e. the
    // triangle's world normal facing the camera; mirrored transforms are handled by the world
    // positions themselves.
    s_front_facing = dot(cross(w1 - w0, w2 - w0), eye - w0) > 0.0;
    s_model_scale = length(dr.model[0].xyz);

#if OUTPUTS
    // Dataset outputs (Renderer.render(outputs=...)): ids, normals, distances of this point.
    vec3 frame_ng, frame_t, frame_b, frame_n;
    surface_frame(u(settings.flags), u(MAT.flags), frame_ng, frame_t, frame_b, frame_n);
    ivec2 at = ivec2(pixel);
    imageStore(out_ids, at, uvec4(dr.ids.xy, 0u, 0u));
    imageStore(out_normal, at, vec4(frame_n, 0.0));
    imageStore(out_normal_geometric, at, vec4(frame_ng, 0.0));
    vec3 to_point = s_world_pos - eye;
    imageStore(out_depth_range, at, vec4(dot(to_point, settings.camera_forward.xyz),
                                         length(to_point), 0.0, 0.0));
#else
    vec4 value = shade_surface();
    // The storage view is UNORM: encode sRGB here, as the attachment would (shade_surface
    // pre-linearised data views for an sRGB target, exactly as for the fragment path).
    imageStore(out_image, ivec2(pixel), srgb_target ? vec4(linear_to_srgb(value.rgb), value.a) : value);
#endif
}
