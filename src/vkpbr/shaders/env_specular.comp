#version 450
// One level of the GGX pre-filtered cube (Karis 2013, "Real Shading in Unreal Engine 4": the
// split sum's first factor, n = v = r), by importance sampling with mip-filtered samples
// (Colbert and Krivanek 2007, GPU Gems 3 ch. 20: the lod whose texel covers the sample's solid
// angle), which removes the fireflies of bright, small sources.
#include "env_common.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0) uniform samplerCube source;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray level;
layout(push_constant) uniform Push {
    float roughness;
    uint samples;
    uint source_size;  // texels per face of the source's level 0
    uint size;         // texels per face of this level
} pc;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size) return;
    vec3 n = texel_direction(id, pc.size);
    float texel_lod = log2(float(pc.source_size) / float(pc.size));
    if (pc.roughness <= 0.0) {  // a mirror: the source, filtered to this level's texels
        imageStore(level, ivec3(id), vec4(textureLod(source, n, texel_lod).rgb, 1.0));
        return;
    }
    float alpha = pc.roughness * pc.roughness;
    mat3 frame = basis_around(n);
    float omega_p = 4.0 * ENV_PI / (6.0 * float(pc.source_size) * float(pc.source_size));
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint i = 0u; i < pc.samples; ++i) {
        vec3 h = frame * ggx_half_vector(hammersley(i, pc.samples), alpha);
        vec3 l = reflect(-n, h);
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0) continue;
        float n_dot_h = clamp(dot(n, h), 0.0, 1.0);
        // pdf of l with v = n: D (n.h) / (4 (v.h)) = D / 4.
        float pdf = d_ggx(n_dot_h, alpha) * 0.25;
        float omega_s = 1.0 / (float(pc.samples) * pdf + 1e-6);
        float lod = max(0.5 * log2(omega_s / omega_p) + 1.0, texel_lod);
        sum += textureLod(source, l, lod).rgb * n_dot_l;  // Karis' n.l weighting
        weight += n_dot_l;
    }
    imageStore(level, ivec3(id), vec4(sum / max(weight, 1e-6), 1.0));
}
