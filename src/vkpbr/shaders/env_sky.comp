#version 450
// The built-in Preetham sky (scene/sky.py computes the coefficients and mirrors this formula):
// Perez F(theta, gamma) per Y, x, y, scaled by the zenith values, xyY -> linear Rec. 709; the
// ground below the horizon.
#include "env_common.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray cube;
layout(push_constant) uniform Push {
    vec4 perez[4];   // 15 floats: rows Y, x, y of A..E, then one pad
    vec4 zenith;     // Y_z / F_Y(0, theta_s), x_z / F_x(0, theta_s), y_z / F_y(0, theta_s)
    vec4 to_sun;
    vec4 ground;
    uint size;
} pc;

float coef(int k) { return pc.perez[k / 4][k % 4]; }

float perez(float cos_t, float gamma, int row) {
    int o = row * 5;
    float cg = cos(gamma);
    return (1.0 + coef(o) * exp(coef(o + 1) / cos_t))
         * (1.0 + coef(o + 2) * exp(coef(o + 3) * gamma) + coef(o + 4) * cg * cg);
}

const mat3 XYZ_TO_SRGB = mat3(3.2404542, -0.9692660, 0.0556434,
                              -1.5371385, 1.8760108, -0.2040259,
                              -0.4985314, 0.0415560, 1.0572252);

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size) return;
    vec3 d = texel_direction(id, pc.size);
    vec3 rgb = pc.ground.rgb;
    if (d.y >= 0.0) {
        float cos_t = max(d.y, 0.01);
        float gamma = acos(clamp(dot(d, pc.to_sun.xyz), -1.0, 1.0));
        float Y = pc.zenith.x * perez(cos_t, gamma, 0);
        float x = pc.zenith.y * perez(cos_t, gamma, 1);
        float y = pc.zenith.z * perez(cos_t, gamma, 2);
        vec3 XYZ = vec3(x / y * Y, Y, (1.0 - x - y) / y * Y);
        rgb = max(XYZ_TO_SRGB * XYZ, vec3(0.0));
    }
    imageStore(cube, ivec3(id), vec4(rgb, 1.0));
}
