#version 450
// batch_cull.comp: per-view frustum culling of a batch (render/batch.py). One invocation per
// (view, draw): when the draw's world bounding sphere touches the view's frustum, the view is
// appended to the draw's list of its chunk and the draw's indirect command counts one more
// instance. The batch's passes then draw each draw once per chunk, instanced over exactly
// the views that see it (pbr.vert BATCH reads visible_views[gl_InstanceIndex]).
//
// Commands: per (chunk k, draw d), a VkDrawIndexedIndirectCommand at k * draw_count + d,
// zeroed before this kernel; the first view of each chunk writes its constant fields, and
// its firstInstance is the start of its list, (k * draw_count + d) * chunk_views.
// The frustum test: frustum.glsl.
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
#include "frustum.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std140) readonly buffer CullViews {
    ViewRecord cull_views[];
};
// Per draw: xyz centre, w radius of its mesh (placed by the draw's model matrix, below), then
// (index count, first index, vertex offset, 0).
layout(set = 0, binding = 1, std430) readonly buffer DrawBounds {
    vec4 spheres_and_ranges[];  // 2 vec4 a draw: the sphere, then the range as uint bits
};
layout(set = 0, binding = 2, std430) buffer Commands {
    uint commands[];
};
layout(set = 0, binding = 3, std430) writeonly buffer CullVisible {
    uint cull_visible[];
};
// The scene state's matrices (Instances: model, normal matrix a draw; render/scene_state.py).
layout(set = 0, binding = 4, std430) readonly buffer CullInstances {
    mat4 cull_matrices[];
};

layout(push_constant, std430) uniform CullPush {
    uint view_count;
    uint draw_count;
    uint chunk_views;  // views per chunk (layers of the batch target)
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.view_count * pc.draw_count) return;
    uint view = i / pc.draw_count;
    uint d = i - view * pc.draw_count;
    uint chunk = view / pc.chunk_views;
    uint command = chunk * pc.draw_count + d;
    uint base = command * 5u;
    vec4 range = spheres_and_ranges[2u * d + 1u];
    if (view == chunk * pc.chunk_views) {  // the chunk's first view: the constant fields
        commands[base + 0u] = floatBitsToUint(range.x);
        commands[base + 2u] = floatBitsToUint(range.y);
        commands[base + 3u] = floatBitsToUint(range.z);
        commands[base + 4u] = command * pc.chunk_views;
    }
    mat4 model = cull_matrices[2u * (cull_views[view].instance_base + d)];
    vec4 sphere = world_sphere(model, spheres_and_ranges[2u * d]);
    if (model[3][3] != 0.0 && sphere_visible(cull_views[view].VP, sphere)) {  // (0: hidden)
        uint k = atomicAdd(commands[base + 1u], 1u);
        cull_visible[command * pc.chunk_views + k] = view;
    }
}
