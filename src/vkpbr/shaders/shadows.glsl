// shadows.glsl: the shadow factor of a light at a point (set 3, render/shadows.py):
//   float shadow_factor(LightRecord light, vec3 world_pos, vec3 ng, vec3 l, float view_depth)
// 1 = lit, 0 = shadowed; view_depth: distance along the camera's forward axis. The maps, the
// bias and the filtering are shadow_sampling.glsl's.
#ifndef SHADOWS_GLSL
#define SHADOWS_GLSL
#include "shadow_sampling.glsl"
#endif
