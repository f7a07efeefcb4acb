// worlds.glsl: a batch of worlds' per-view overrides (render/worlds.py, WorldFactors): each
// view of a compute batch of worlds names its world's block of WorldFactors by
// views[view_index].factor_base (0: none, every frame and plain batch). A block, in vec4s:
//   [header: uint bits (lights at, environment at, has lights, has environment)
//    | 3 a material: base colour; emissive, metallic; roughness
//    | 1 a light: rgb colour x intensity | 1 the environment: intensity, cos, sin of its turn]
// at factor_base - 1. Elsewhere (the fragment path, frames) the macros read the frame's own.
#ifndef WORLDS_GLSL
#define WORLDS_GLSL

#if BATCH && COMPUTE_SHADING
uint world_base() { return views[view_index].factor_base; }

MaterialRecord world_material(uint index) {
    MaterialRecord m = materials[index];
    uint base = world_base();
    if (base != 0u) {
        uint at = base + 3u * index;
        vec4 e = world_factors[at + 1u];
        m.base_color_factor = world_factors[at];
        m.emissive_factor = e.rgb;
        m.metallic_factor = e.a;
        m.roughness_factor = world_factors[at + 2u].x;
    }
    return m;
}

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
#define WORLD_LIGHT(light, i) (light)
#define ENV_INTENSITY lighting.env_intensity
#define ENV_ROTATION lighting.env_rotation.xy
#endif

#endif
