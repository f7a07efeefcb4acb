#version 450
// pbr.frag: the fragment path's shading: the interpolated surface of pbr.vert shaded by
// shade.glsl (every frame path's one shading function), textures read from the draw's
// material set with hardware derivatives.
// ALPHA_MASK = 1 builds the masked-material variant that discards below the cutoff (report 1.3).
// VISIBILITY = 1 builds the compute path's visibility pass (render/compute_path.py): coverage
// decided exactly as here (the same alpha test), writing (draw index + 1, primitive index).
// DEPTH_ONLY = 1 (with ALPHA_MASK) builds the masked rows of the ambient occlusion's depth
// pre-pass (render/ao.py, frames without a visibility image): the same alpha test, no output.
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"

layout(location = 0) in vec3 v_world_pos;
layout(location = 1) in vec4 v_texcoords;  // xy: TEXCOORD_0, zw: TEXCOORD_1
layout(location = 2) in vec3 v_normal;
layout(location = 3) in vec3 v_tangent;
layout(location = 4) in vec3 v_bitangent;
layout(location = 5) in vec4 v_color;  // COLOR_0 (white when the mesh has none)
layout(location = 6) flat in uint v_draw;  // the draw's index (its firstInstance)
layout(location = 8) flat in float v_model_scale;  // the node's scale (shade.glsl s_model_scale)
#if BATCH  // a view of a batch (render/batch.py): the camera is views[v_view]
layout(location = 7) flat in uint v_view;
#endif

#if VISIBILITY
layout(location = 0) out uvec2 out_visibility;
#elif DEPTH_ONLY
#else
layout(location = 0) out vec4 out_color;
#endif

#define MAT material
#if BATCH  // the draw's material (the push's w), whose factors a world may set (worlds.glsl)
#define MATERIAL_INDEX draw.index.w
#endif
#define SAMPLE(name) texture(name##_map, texture_uv(MAT.name##_uv_row0, MAT.name##_uv_row1))
#include "shade.glsl"

void main() {
#if BATCH
    view_index = v_view;
    s_ao_layer = int(views[v_view].layer);  // the layer it draws into (render/ao.py)
#endif
    opaque_zero = uint(gl_FragCoord.x < 0.0);
    s_world_pos = v_world_pos;
    s_texcoords = v_texcoords;
    s_normal = v_normal;
    s_tangent = v_tangent;
    s_bitangent = v_bitangent;
    s_color = v_color;
    s_front_facing = gl_FrontFacing;
    s_model_scale = v_model_scale;
    s_pixel = ivec2(gl_FragCoord.xy);
#if DEPTH_ONLY
    if (surface_base_color().a < MAT.alpha_cutoff) discard;
#elif VISIBILITY
#if ALPHA_MASK
    if (surface_base_color().a < MAT.alpha_cutoff) discard;
#endif
    out_visibility = uvec2(v_draw + 1u, uint(gl_PrimitiveID));
#else
    out_color = shade_surface();
#endif
}
