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
// then each job's frame (centre, 1 / radius) from pc.frames_at. Read as vec4s: a joint
// matrix is 4 16-byte loads, not 16 scalar ones (each job's joints start at a multiple of
// 16 floats, its frame at a multiple of 4: render/deform.py DeformLayout).
layout(set = 0, binding = 6, std430) readonly buffer DeformState { vec4 deform_state[]; };
// The posed positions the previous frame drew (the motion output), from first_posed on.
layout(set = 0, binding = 7, std430) writeonly buffer DeformPrev { float deform_prev[]; };

layout(push_constant, std430) uniform DeformPush {
    uint first_posed;  // the first posed vertex (GpuScene.posed_offsets[0])
    uint frames_at;  // the first frame float in DeformState
} pc;

float state_float(uint i) {  // float i of DeformState
    return deform_state[i >> 2u][i & 3u];
}

mat4 joint_matrix(uint at) {  // `at`: the matrix's first float, a multiple of 16
    uint q = at >> 2u;
    return mat4(deform_state[q], deform_state[q + 1u], deform_state[q + 2u], deform_state[q + 3u]);
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
        float w = state_float(b.w + k);
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
    vec4 frame = deform_state[(pc.frames_at >> 2u) + gl_WorkGroupID.y];  // (centre, 1 / radius)
    p = (p - frame.xyz) * frame.w;
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
