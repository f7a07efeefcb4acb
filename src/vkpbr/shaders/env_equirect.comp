#version 450
// Panorama -> level 0 of the source cube (bilinear, wrapping in u through the sampler).
#include "env_common.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0) uniform sampler2D panorama;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray cube;
layout(push_constant) uniform Push { uint size; } pc;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size) return;
    vec3 d = texel_direction(id, pc.size);
    imageStore(cube, ivec3(id), vec4(textureLod(panorama, equirect_uv(d), 0.0).rgb, 1.0));
}
