#version 450
// The split-sum BRDF table (Karis 2013) for the glTF BRDF's specular lobe (GGX D,
// height-correlated Smith V): x = n.v, y = roughness at texel centres; R = A, G = B with
// integral of f_spec cos = F0 A + B (F = F0 + (1 - F0)(1 - v.h)^5). A + B is the lobe's
// directional albedo E_ss(n.v) for F = 1, which the multiple-scattering compensation uses.
#include "env_common.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray lut;
layout(push_constant) uniform Push { uint samples; uint size; } pc;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size) return;
    float n_dot_v = (float(id.x) + 0.5) / float(pc.size);
    float roughness = (float(id.y) + 0.5) / float(pc.size);
    float alpha = roughness * roughness;
    vec3 v = vec3(sqrt(1.0 - n_dot_v * n_dot_v), 0.0, n_dot_v);
    float a = 0.0, b = 0.0;
    for (uint i = 0u; i < pc.samples; ++i) {
        vec3 h = ggx_half_vector(hammersley(i, pc.samples), alpha);
        float v_dot_h = dot(v, h);
        vec3 l = 2.0 * v_dot_h * h - v;
        float n_dot_l = l.z;
        if (n_dot_l <= 0.0 || v_dot_h <= 0.0) continue;
        // f cos / pdf_l with pdf_l = D (n.h) / (4 v.h): V (n.l) 4 (v.h) / (n.h).
        float w = v_smith_ggx_correlated(n_dot_l, n_dot_v, alpha) * n_dot_l * 4.0 * v_dot_h / h.z;
        float fc = pow(max(1.0 - v_dot_h, 0.0), 5.0);  // (v.h rounds above 1 where h = v)
        a += (1.0 - fc) * w;
        b += fc * w;
    }
    imageStore(lut, ivec3(id.xy, 0), vec4(a, b, 0.0, 1.0) / vec4(vec3(float(pc.samples)), 1.0));
}
