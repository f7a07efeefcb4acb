// Shared by the environment compute shaders, ibl.glsl and the background pass: the cube's
// face directions, the panorama mapping (scene/environment.py mirrors it), the rotation about
// +Y, and GGX importance sampling. Pure functions, no bindings.
#ifndef ENV_COMMON_GLSL
#define ENV_COMMON_GLSL
#include "brdf_lobes.glsl"

const float ENV_PI = 3.14159265358979;

// Direction through texel (x, y) of cube face `face` (Vulkan's +X, -X, +Y, -Y, +Z, -Z order;
// Vulkan spec 16.5.4 "Cube Map Face Selection"), uv in [-1, 1] with y growing downwards.
vec3 cube_direction(uint face, vec2 uv) {
    vec3 d;
    if (face == 0u) d = vec3(1.0, -uv.y, -uv.x);
    else if (face == 1u) d = vec3(-1.0, -uv.y, uv.x);
    else if (face == 2u) d = vec3(uv.x, 1.0, uv.y);
    else if (face == 3u) d = vec3(uv.x, -1.0, -uv.y);
    else if (face == 4u) d = vec3(uv.x, -uv.y, 1.0);
    else d = vec3(-uv.x, -uv.y, -1.0);
    return normalize(d);
}

vec3 texel_direction(uvec3 id, uint size) {
    vec2 uv = (vec2(id.xy) + 0.5) / float(size) * 2.0 - 1.0;
    return cube_direction(id.z, uv);
}

// The panorama's (u, v) of a unit direction: u = 0.5 + atan(x, -z) / 2 pi, v = acos(y) / pi.
vec2 equirect_uv(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) / (2.0 * ENV_PI), acos(clamp(d.y, -1.0, 1.0)) / ENV_PI);
}

// World direction -> environment direction for an environment rotated by theta about +Y
// (cs = (cos theta, sin theta)): the inverse rotation, R_y(-theta) d.
vec3 env_rotate(vec3 d, vec2 cs) {
    return vec3(cs.x * d.x - cs.y * d.z, d.y, cs.y * d.x + cs.x * d.z);
}

// Hammersley point i of n (Holger Dammertz, "Hammersley Points on the Hemisphere", 2012).
vec2 hammersley(uint i, uint n) {
    uint b = bitfieldReverse(i);
    return vec2(float(i) / float(n), float(b) * 2.3283064365386963e-10);
}

// An orthonormal basis around n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
mat3 basis_around(vec3 n) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
    return mat3(t, bt, n);
}

// GGX half vector for xi in [0,1)^2 (Walter et al. 2007, eq. 35-36), in the frame of +Z.
vec3 ggx_half_vector(vec2 xi, float alpha) {
    float cos_t = sqrt((1.0 - xi.y) / (1.0 + (alpha * alpha - 1.0) * xi.y));
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    float phi = 2.0 * ENV_PI * xi.x;
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// GGX D and Smith V: brdf_lobes.glsl's, the shading's own.

#endif
