// shadows.glsl: the shadow factor of a light at a point (set 3). STUB until the shadow maps
// land: everything is lit.
#ifndef SHADOWS_GLSL
#define SHADOWS_GLSL

// 1 = lit, 0 = shadowed; view_depth: distance along the camera's forward axis.
float shadow_factor(LightRecord light, vec3 world_pos, vec3 ng, vec3 l, float view_depth) {
    return 1.0;
}

#endif
