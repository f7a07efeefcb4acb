// brdf_lobes.glsl: the GGX lobe's D and height-correlated Smith V, needing nothing else:
// brdf.glsl shades with them and the environment pre-filter (env_common.glsl) samples
// them, so both use one definition. Mirrored in src/vkpbr/reference/brdf.py.
#ifndef BRDF_LOBES_GLSL
#define BRDF_LOBES_GLSL

const float PI = 3.14159265358979;
const float EPS = 1e-6;

// GGX / Trowbridge-Reitz (Disney GTR, gamma = 2), alpha = r^2 (Burley 2012, eq. 8).
float d_ggx(float n_dot_h, float alpha) {
    float a2 = alpha * alpha;
    float k = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

// Height-correlated Smith visibility V = G / (4 (n.l)(n.v)) for GGX (Heitz 2014, eq. 99; the
// glTF specification's Appendix B.3.2 and the Khronos Sample Viewer's V_GGX).
float v_smith_ggx_correlated(float n_dot_l, float n_dot_v, float alpha) {
    float a2 = alpha * alpha;
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    float s = gv + gl;
    return s > 0.0 ? 0.5 / s : 0.0;
}

#endif
