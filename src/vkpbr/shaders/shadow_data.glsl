// shadow_data.glsl: the shadow maps' per-frame data (set 3, binding 0), written by
// render/shadows.py (ShadowMaps.write; its HEADER_BYTES and MATRICES must match). std430:
// four vec4 then the matrices, 64-byte header.
#ifndef SHADOW_DATA_GLSL
#define SHADOW_DATA_GLSL

layout(set = 3, binding = 0, std430) readonly buffer ShadowData {
    vec4 cascade_far;    // view depth where cascade i ends (render/shadow_math.py CascadeFit.far)
    vec4 cascade_texel;  // world size of one texel in cascade i (normal offset)
    vec4 params;         // x: 2D map size, y: cube map size (texels), z: normal offset (texels), w: PCF radius (texels)
    // x, y: a batch of worlds' maps (render/world_shadows.py): texels a world, its cubes' start;
    // z: bit 0 where the frame's maps are the compute rasteriser's buffer (ShadowDepths), bit 1
    // where the maps' sampler filters linearly (the by-hand compare does too); w: the buffer's cubes' start
    uvec4 world_layout;
    mat4 layer_vp[];     // world -> clip: the 2D layers, then 6 per cube (+X -X +Y -Y +Z -Z)
} shadow_data;

#endif
