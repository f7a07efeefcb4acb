#version 450
// Diffuse irradiance cube: (1 / pi) * integral of L cos over the hemisphere around n, i.e. the
// cosine-weighted mean radiance (Lambert: outgoing radiance = albedo * this), by cosine-weighted
// importance sampling (pdf cos / pi, so each sample weighs 1) with mip-filtered samples.
#include "env_common.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0) uniform samplerCube source;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray irradiance;
layout(push_constant) uniform Push {
    uint samples;
    uint source_size;
    uint size;
} pc;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size) return;
    vec3 n = texel_direction(id, pc.size);
    mat3 frame = basis_around(n);
    float omega_p = 4.0 * ENV_PI / (6.0 * float(pc.source_size) * float(pc.source_size));
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < pc.samples; ++i) {
        vec2 xi = hammersley(i, pc.samples);
        float r = sqrt(xi.y);
        float phi = 2.0 * ENV_PI * xi.x;
        float cos_t = sqrt(max(1.0 - xi.y, 0.0));
        vec3 l = frame * vec3(r * cos(phi), r * sin(phi), cos_t);
        float pdf = max(cos_t, 1e-4) / ENV_PI;
        float lod = max(0.5 * log2(1.0 / (float(pc.samples) * pdf * omega_p)) + 1.0, 0.0);
        sum += textureLod(source, l, lod).rgb;
    }
    imageStore(irradiance, ivec3(id), vec4(sum / float(pc.samples), 1.0));
}
