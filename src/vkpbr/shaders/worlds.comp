#version 450
// worlds.comp: a batch of worlds' draw records from poses on the GPU (render/worlds.py), the
// first step of a batch whose worlds' poses live in GPU memory (a simulator's torch tensors).
// One invocation per (world w, draw d): the draw's record in Instances at (1 + w) * D + d is
//     model = pose(w, anchor(d)) * relative(d)   (pose itself where relative is the identity)
// and its normal matrix (the inverse transpose: cofactors / determinant, a singular one kept),
// or the state's record (records 0..D-1, written by the host) for draws with no anchor; zero
// where the world hides a node that covers the draw or the state hides it. The NumPy mirror,
// and what the tests compare it with: vkpbr.scene.worlds.world_models.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

// Instances of the batch: the state's records, then every world's (model, normal) pairs.
layout(set = 0, binding = 0, std430) buffer WorldRecords { mat4 world_records[]; };
// Poses: per (world, slot) 7 floats (position, quaternion) or 16 (a row-major 4x4 matrix).
layout(set = 0, binding = 1, std430) readonly buffer WorldPoses { float world_poses[]; };
// Per (world, slot): nonzero where the world shows the slot node (unused without).
layout(set = 0, binding = 2, std430) readonly buffer WorldVisible { uint world_visible[]; };
struct WorldDraw {
    mat4 relative;  // model = pose * relative
    mat4 frame;  // local poses: the anchor's parent's world matrix in the state (model = frame * pose * relative)
    int anchor;  // the slot the draw hangs from, -1: none (the state's record in every world)
    uint identity;  // relative is the identity: model = pose
    uint covers_at;  // its first word in WorldCovers
    uint pad;
};
layout(set = 0, binding = 3, std430) readonly buffer WorldDraws { WorldDraw world_draws[]; };
// Per draw, covers_words words: bit n set where slot n is the draw's node or an ancestor.
layout(set = 0, binding = 4, std430) readonly buffer WorldCovers { uint world_covers[]; };
// Poses that are no pose (NaN, infinity, a zero quaternion; CUDA tensors are not read back
// before the batch): how many (world, draw) records met one, and the lowest such world. Their
// draws are hidden; the host reports the first after the batch (render/worlds.py).
layout(set = 0, binding = 5, std430) buffer WorldErrors { uint world_errors[2]; };

layout(push_constant, std430) uniform WorldsPush {
    uint worlds;
    uint slots;
    uint draws;
    uint pose_floats;  // 7 or 16
    uint wxyz;  // quaternion order: 1 w, x, y, z; 0 x, y, z, w
    uint has_visible;
    uint covers_words;
    uint local;  // poses relative to the node's parent (WorldDraw.frame), else world poses
} pc;

bool pose_valid(uint w, uint n) {
    uint at = (w * pc.slots + n) * pc.pose_floats;
    for (uint k = 0u; k < pc.pose_floats; ++k) {
        float x = world_poses[at + k];
        if (isnan(x) || isinf(x)) return false;
    }
    if (pc.pose_floats == 7u) {
        vec4 q = vec4(world_poses[at + 3u], world_poses[at + 4u], world_poses[at + 5u], world_poses[at + 6u]);
        return dot(q, q) >= 1e-24;
    }
    return true;
}

mat4 pose_of(uint w, uint n) {
    uint at = (w * pc.slots + n) * pc.pose_floats;
    if (pc.pose_floats == 16u) {  // row-major rows -> GLSL columns
        mat4 m;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m[c][r] = world_poses[at + uint(r * 4 + c)];
        return m;
    }
    vec3 t = vec3(world_poses[at], world_poses[at + 1u], world_poses[at + 2u]);
    vec4 q = vec4(world_poses[at + 3u], world_poses[at + 4u], world_poses[at + 5u], world_poses[at + 6u]);
    if (pc.wxyz != 0u) q = q.yzwx;
    float s = 2.0 / dot(q, q);  // normalises: 2 / |q|^2 (as scene/state.py quaternion_matrices)
    vec3 qs = q.xyz * s;
    float wx = q.w * qs.x, wy = q.w * qs.y, wz = q.w * qs.z;
    float xx = q.x * qs.x, xy = q.x * qs.y, xz = q.x * qs.z;
    float yy = q.y * qs.y, yz = q.y * qs.z, zz = q.z * qs.z;
    return mat4(vec4(1.0 - (yy + zz), xy + wz, xz - wy, 0.0),  // columns
                vec4(xy - wz, 1.0 - (xx + zz), yz + wx, 0.0),
                vec4(xz + wy, yz - wx, 1.0 - (xx + yy), 0.0),
                vec4(t, 1.0));
}

mat4 normal_of(mat4 model) {
    vec3 a0 = model[0].xyz, a1 = model[1].xyz, a2 = model[2].xyz;
    vec3 c0 = cross(a1, a2), c1 = cross(a2, a0), c2 = cross(a0, a1);
    float det = dot(a0, c0);
    mat3 n = abs(det) > 1e-30 ? mat3(c0, c1, c2) / det : mat3(model);
    return mat4(vec4(n[0], 0.0), vec4(n[1], 0.0), vec4(n[2], 0.0), vec4(0.0, 0.0, 0.0, 1.0));
}

bool shown(uint w, WorldDraw wd) {
    if (pc.has_visible == 0u) return true;
    for (uint k = 0u; k < pc.covers_words; ++k) {
        uint bits = world_covers[wd.covers_at + k];
        while (bits != 0u) {
            int b = findLSB(bits);
            bits &= bits - 1u;
            if (world_visible[w * pc.slots + k * 32u + uint(b)] == 0u) return false;
        }
    }
    return true;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.worlds * pc.draws) return;
    uint w = i / pc.draws, d = i - w * pc.draws;
    uint out_at = 2u * ((1u + w) * pc.draws + d);
    WorldDraw wd = world_draws[d];
    mat4 base = world_records[2u * d];
    bool hidden = base[0].xyz == vec3(0.0) && base[1].xyz == vec3(0.0) && base[2].xyz == vec3(0.0);
    if (hidden || !shown(w, wd)) {
        world_records[out_at] = mat4(0.0);
        world_records[out_at + 1u] = mat4(vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    if (wd.anchor < 0) {
        world_records[out_at] = base;
        world_records[out_at + 1u] = world_records[2u * d + 1u];
        return;
    }
    if (!pose_valid(w, uint(wd.anchor))) {  // hidden, and reported
        atomicAdd(world_errors[0], 1u);
        atomicMin(world_errors[1], w);
        world_records[out_at] = mat4(0.0);
        world_records[out_at + 1u] = mat4(vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    mat4 pose = pose_of(w, uint(wd.anchor));
    if (pc.local != 0u) pose = wd.frame * pose;
    mat4 model = wd.identity != 0u ? pose : pose * wd.relative;
    world_records[out_at] = model;
    world_records[out_at + 1u] = normal_of(model);
}
