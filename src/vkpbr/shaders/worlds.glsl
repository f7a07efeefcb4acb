// worlds.glsl: a batch of worlds' per-view overrides (render/worlds.py, WorldFactors, set 0):
// each view of a batch of worlds names its world's block of WorldFactors by
// views[view_index].factor_base (0: none, every frame and plain batch), read by the compute
// batch's kernels and by the BATCH builds of pbr.frag (the layered batch's draws, the compute
// batch's blended ones) and background.frag. A block, in vec4s:
//   [header: uint bits (lights at, environment at, has lights, has environment)
//    | 3 a material: base colour; emissive, metallic; roughness
//    | 1 a light: rgb colour x intensity | 1 the environment: intensity, cos, sin of its turn]
// at factor_base - 1. Elsewhere (frames) the macros read the frame's own.
#ifndef WORLDS_GLSL
#define WORLDS_GLSL

#if BATCH
uint world_base() { return views[view_index].factor_base; }

// A world's four factors of the material MATERIAL_INDEX (the includer's), else the table's;
// only these fields are read (a copy of the whole record per use cost lavapipe 5x).
#ifdef MATERIAL_INDEX  // (the shading and rasterising kernels, pbr.frag; not the background's)
vec4 world_material_row(uint row) {
    return world_factors[world_base() + 3u * MATERIAL_INDEX + row];
}
#define MAT_BASE_COLOR_FACTOR (world_base() != 0u ? world_material_row(0u) : MAT.base_color_factor)
#define MAT_EMISSIVE_FACTOR (world_base() != 0u ? world_material_row(1u).rgb : MAT.emissive_factor)
#define MAT_METALLIC_FACTOR (world_base() != 0u ? world_material_row(1u).a : MAT.metallic_factor)
#define MAT_ROUGHNESS_FACTOR (world_base() != 0u ? world_material_row(2u).x : MAT.roughness_factor)
#endif

LightRecord world_light(LightRecord light, uint i) {
    uint base = world_base();
    if (base != 0u) {
        uvec4 h = floatBitsToUint(world_factors[base - 1u]);
        if (h.z != 0u) light.color_falloff.rgb = world_factors[base - 1u + h.x + i].rgb;
    }
    return light;
}

vec3 world_environment() {  // (intensity, cos, sin)
    uint base = world_base();
    if (base != 0u) {
        uvec4 h = floatBitsToUint(world_factors[base - 1u]);
        if (h.w != 0u) return world_factors[base - 1u + h.y].xyz;
    }
    return vec3(lighting.env_intensity, lighting.env_rotation.xy);
}
#define WORLD_LIGHT(light, i) world_light(light, i)
#define ENV_INTENSITY world_environment().x
#define ENV_ROTATION world_environment().yz
#else
#define MAT_BASE_COLOR_FACTOR MAT.base_color_factor
#define MAT_EMISSIVE_FACTOR MAT.emissive_factor
#define MAT_METALLIC_FACTOR MAT.metallic_factor
#define MAT_ROUGHNESS_FACTOR MAT.roughness_factor
#define WORLD_LIGHT(light, i) (light)
#define ENV_INTENSITY lighting.env_intensity
#define ENV_ROTATION lighting.env_rotation.xy
#endif

#endif
