#version 450
// pbr.vert: world-space position and TBN for pbr.frag (report 1.1). TBN_MODE picks how the
// tangent frame arrives: 0 normal + tangent vectors, 1 a float QTangent, 2 a packed uint32.
// The camera is views[view_index] (generated.glsl): the frame's one view, or with BATCH = 1
// a view of a batch (render/batch.py): instance i of a draw is the view visible_views[i]
// (the culling kernel lists the views that see the draw from its firstInstance on), drawn
// with that view's VP into its layer of the batch target. ATLAS = 1 (with BATCH) builds the
// compute batch's blended draws (render/batch_path.py): the view is drawn into its tile of
// the batch's one atlas image instead of a layer (views[].viewport; the atlas's size is the
// push's yz), its own frustum's sides clipping it to that tile.
#extension GL_GOOGLE_include_directive : require
#if BATCH && !ATLAS
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#include "generated.glsl"
#if TBN_MODE != 0
#include "tbn_decode.glsl"
#endif

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_texcoord0;
// TEXCOORD_1. Scenes without it bind the TEXCOORD_0 buffer here (render/gpu_scene.py), so
// one shader serves both and such scenes spend no vertex memory on a second set.
layout(location = 2) in vec2 in_texcoord1;
// glTF COLOR_0 (linear RGBA, multiplies the base colour). Scenes without vertex colours bind a
// single white value with stride 0 (render/gpu_scene.py), so they spend no memory on it.
layout(location = 3) in vec4 in_color;
#if TBN_MODE == 0
layout(location = 4) in vec3 in_normal;
layout(location = 5) in vec4 in_tangent;
#elif TBN_MODE == 1
layout(location = 4) in vec4 in_qtangent;
#else
layout(location = 4) in uint in_packed_frame;
#endif

// The depth pre-pass (render/passes.py) runs this shader too: its depths must be bit-equal.
invariant gl_Position;

layout(location = 0) out vec3 v_world_pos;
layout(location = 1) out vec4 v_texcoords;  // xy: TEXCOORD_0, zw: TEXCOORD_1 (one varying slot)
layout(location = 2) out vec3 v_normal;
layout(location = 3) out vec3 v_tangent;
layout(location = 4) out vec3 v_bitangent;
layout(location = 5) out vec4 v_color;
layout(location = 6) flat out uint v_draw;  // firstInstance of the draw: its index (the visibility pass)
#if BATCH
layout(location = 7) flat out uint v_view;  // the view of the batch (Views)
#endif
layout(location = 8) flat out float v_model_scale;  // |model x axis| (the volume's thickness)

#if ATLAS
out float gl_ClipDistance[4];

// `clip` (the view's own clip space) in the atlas's: the view's NDC square mapped onto its
// `tile` (x, y, width, height pixels) of an `atlas`-sized image, a linear map of the clip
// coordinates (so interpolation stays perspective-correct); the tile's edges are the view's
// frustum sides, w +- x and w +- y, as clip distances.
vec4 atlas_position(vec4 clip, uvec4 tile, vec2 atlas) {
    gl_ClipDistance[0] = clip.w + clip.x;
    gl_ClipDistance[1] = clip.w - clip.x;
    gl_ClipDistance[2] = clip.w + clip.y;
    gl_ClipDistance[3] = clip.w - clip.y;
    vec2 scale = vec2(tile.zw) / atlas;
    vec2 offset = (2.0 * vec2(tile.xy) + vec2(tile.zw)) / atlas - 1.0;
    return vec4(clip.xy * scale + offset * clip.w, clip.zw);
}
#endif

void main() {
#if TBN_MODE == 0
    vec3 n = in_normal;
    vec3 t = in_tangent.xyz;
    // glTF: bitangent = w * cross(n, t), w = +-1 the handedness.
    vec3 b = (in_tangent.w < 0.0 ? -1.0 : 1.0) * cross(n, t);
#else
#if TBN_MODE == 1
    mat3 tbn = tbn_from_qtangent(in_qtangent);
#else
    mat3 tbn = tbn_from_qtangent(qtangent_unpack(in_packed_frame));
#endif
    vec3 t = tbn[0];
    vec3 b = tbn[1];
    vec3 n = tbn[2];
#endif
#if BATCH  // one record a draw, pushed: the instance index is the view, and the view's
    // world's records start at its instance_base (0 but in a batch of worlds)
    view_index = visible_views[gl_InstanceIndex];
    uint record = 2u * (views[view_index].instance_base + draw.index.x);
    mat4 model = instance_matrices[record];
    mat3 normal_matrix = mat3(instance_matrices[record + 1u]);
#else  // a draw's instances are consecutive records (EXT_mesh_gpu_instancing: one draw call)
    mat4 model = instance_matrices[2u * uint(gl_InstanceIndex)];
    mat3 normal_matrix = mat3(instance_matrices[2u * uint(gl_InstanceIndex) + 1u]);
#endif
    vec4 world = model * vec4(in_position, 1.0);
    v_model_scale = length(model[0].xyz);
    v_world_pos = world.xyz;
    v_texcoords = vec4(in_texcoord0, in_texcoord1);
    v_color = in_color;
    v_draw = uint(gl_InstanceIndex);
    // Normals take the inverse transpose; tangent and bitangent are surface directions and
    // take the model matrix itself, which keeps the handedness right under mirroring.
    v_normal = normal_matrix * n;
    v_tangent = mat3(model) * t;
    v_bitangent = mat3(model) * b;
#if BATCH
    v_view = view_index;
#endif
#if ATLAS
    gl_Position = atlas_position(views[view_index].VP * world, views[view_index].viewport,
                                 vec2(draw.index.yz));
#else
#if BATCH
    gl_Layer = int(views[view_index].layer);
#endif
    gl_Position = views[view_index].VP * world;
#endif
}
