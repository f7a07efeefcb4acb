// ibl.glsl: image-based lighting from the environment's pre-filtered maps (set 2, bindings
// 2-4). STUB until the environment lands: no image-based light.
#ifndef IBL_GLSL
#define IBL_GLSL

struct IblTerms {
    vec3 diffuse;   // radiance, before occlusion
    vec3 specular;  // radiance, before occlusion
};

IblTerms ibl_evaluate(vec3 n, vec3 v, vec3 c, float metallic, float roughness) {
    return IblTerms(vec3(0.0), vec3(0.0));
}

#endif
