#version 450
// deform.comp: skins and morph targets on the GPU (render/deform.py), the frame's first step.
// One invocation per vertex of a deformed mesh instance (work group row y = the instance's
// job): it reads the mesh's rest vertex (the scene streams at the mesh's offset), adds the
// morph targets' displacements weighted by the instance's weights, blends its joints'
// matrices by the vertex's weights (glTF 3.7.3: up to 8 influences, JOINTS_0/1 + WEIGHTS_0/1)
// and writes the posed vertex into the instance's own region of the same streams, which every
// later step (both frame paths, shadow maps, batches, outputs) draws from like any vertex.
// Skinned positions are world positions (the skinned node's own transform is ignored, as the
// specification says), morphed ones mesh positions; either is written relative to the job's
// frame, (p - c) / r, a sphere (c, r) that holds every posed vertex of the job, so that the
// record's model matrix (translate(c) x scale(r) after the node's) places the unit sphere the
// culling kernels test (render/deform.py). Normals take the inverse transpose of the blended
// matrix, tangents the matrix itself (as pbr.vert's model matrix).
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) buffer DeformPositions { float d_positions[]; };  // 3 a vertex
layout(set = 0, binding = 1, std430) buffer DeformNormals { float d_normals[]; };  // 3 a vertex
layout(set = 0, binding = 2, std430) buffer DeformTangents { vec4 d_tangents[]; };
// Per rest vertex of a skinned mesh: its 8 joints as uint16 pairs (uvec4), then its 8 weights.
layout(set = 0, binding = 3, std430) readonly buffer SkinVertices { uvec4 skin_vertices[]; };
// Per morphed mesh, [target][vertex][9]: position, normal and tangent displacements.
layout(set = 0, binding = 4, std430) readonly buffer MorphDeltas { float morph_deltas[]; };
// Per job, two uvec4: (rest vertex, posed vertex, vertex count, skin vertex or ~0u) and
// (first delta, targets, first joint matrix, first weight) in DeformState's floats.
layout(set = 0, binding = 5, std430) readonly buffer DeformJobs { uvec4 deform_jobs[]; };
// The frame slot's: the joint matrices (16 floats each, column-major), then the weights,
// then each job's frame (centre, 1 / radius) from pc.frames_at.
layout(set = 0, binding = 6, std430) readonly buffer DeformState { float deform_state[]; };
// The posed positions the previous frame drew (the motion output), from first_posed on.
layout(set = 0, binding = 7, std430) writeonly buffer DeformPrev { float deform_prev[]; };

layout(push_constant, std430) uniform DeformPush {
    uint first_posed;  // the first posed vertex (GpuScene.posed_offsets[0])
    uint frames_at;  // the first frame float in DeformState
} pc;

vec3 vec3_of(float a[1], uint i);  // (declared for clarity; the reads below index directly)

mat4 joint_matrix(uint at) {
    return mat4(deform_state[at + 0u], deform_state[at + 1u], deform_state[at + 2u], deform_state[at + 3u],
                deform_state[at + 4u], deform_state[at + 5u], deform_state[at + 6u], deform_state[at + 7u],
                deform_state[at + 8u], deform_state[at + 9u], deform_state[at + 10u], deform_state[at + 11u],
                deform_state[at + 12u], deform_state[at + 13u], deform_state[at + 14u], deform_state[at + 15u]);
}

void main() {
    uvec4 a = deform_jobs[2u * gl_WorkGroupID.y];
    uvec4 b = deform_jobs[2u * gl_WorkGroupID.y + 1u];
    uint v = gl_GlobalInvocationID.x;
    if (v >= a.z) return;
    uint src = a.x + v, dst = a.y + v;
    vec3 p = vec3(d_positions[3u * src], d_positions[3u * src + 1u], d_positions[3u * src + 2u]);
    vec3 n = vec3(d_normals[3u * src], d_normals[3u * src + 1u], d_normals[3u * src + 2u]);
    vec4 t = d_tangents[src];
    for (uint k = 0u; k < b.y; ++k) {  // morph targets: p + sum w_k d_k (glTF 3.7.2.2)
        float w = deform_state[b.w + k];
        if (w == 0.0) continue;
        uint m = b.x + (k * a.z + v) * 9u;
        p += w * vec3(morph_deltas[m], morph_deltas[m + 1u], morph_deltas[m + 2u]);
        n += w * vec3(morph_deltas[m + 3u], morph_deltas[m + 4u], morph_deltas[m + 5u]);
        t.xyz += w * vec3(morph_deltas[m + 6u], morph_deltas[m + 7u], morph_deltas[m + 8u]);
    }
    if (a.w != 0xFFFFFFFFu) {  // skinning: sum w_i J_i over the vertex's 8 influences
        uvec4 packed = skin_vertices[3u * (a.w + v)];
        vec4 w0 = uintBitsToFloat(skin_vertices[3u * (a.w + v) + 1u]);
        vec4 w1 = uintBitsToFloat(skin_vertices[3u * (a.w + v) + 2u]);
        float weights[8] = float[](w0.x, w0.y, w0.z, w0.w, w1.x, w1.y, w1.z, w1.w);
        mat4 s = mat4(0.0);
        for (int i = 0; i < 8; ++i) {
            if (weights[i] == 0.0) continue;
            uint joint = (packed[i >> 1] >> (16u * uint(i & 1))) & 0xFFFFu;
            s += weights[i] * joint_matrix(b.z + 16u * joint);
        }
        p = (s * vec4(p, 1.0)).xyz;
        mat3 m3 = mat3(s);
        n = transpose(inverse(m3)) * n;
        t.xyz = m3 * t.xyz;
    }
    uint f = pc.frames_at + 4u * gl_WorkGroupID.y;
    p = (p - vec3(deform_state[f], deform_state[f + 1u], deform_state[f + 2u])) * deform_state[f + 3u];
    float nl = length(n), tl = length(t.xyz);
    n = nl > 0.0 ? n / nl : vec3(0.0, 0.0, 1.0);
    t.xyz = tl > 0.0 ? t.xyz / tl : vec3(1.0, 0.0, 0.0);
    uint prev = 3u * (dst - pc.first_posed);  // what the region held: the previous frame's
    deform_prev[prev] = d_positions[3u * dst];
    deform_prev[prev + 1u] = d_positions[3u * dst + 1u];
    deform_prev[prev + 2u] = d_positions[3u * dst + 2u];
    d_positions[3u * dst] = p.x;
    d_positions[3u * dst + 1u] = p.y;
    d_positions[3u * dst + 2u] = p.z;
    d_normals[3u * dst] = n.x;
    d_normals[3u * dst + 1u] = n.y;
    d_normals[3u * dst + 2u] = n.z;
    d_tangents[dst] = t;
}
