// Image-based lighting (helper A, issue 12): the split-sum approximation (Karis 2013) with
// Fdez-Aguera's multiple-scattering energy compensation ("A Multiple-Scattering Microfacet
// Model for Real-Time Image-based Lighting", JCGT 8(1), 2019, listing 3), as the
// glTF-Sample-Viewer evaluates it. Reads set 2: env_specular (GGX pre-filtered cube, lod =
// roughness * max lod), env_irradiance (cosine-weighted mean radiance), brdf_lut (RG = A, B of
// F0), and the Lighting block's env_intensity and env_rotation (x = cos, y = sin of the
// environment's rotation about +Y, z = max lod of env_specular). The includer declares them
// (generated.glsl); radiance out, before occlusion.
#ifndef IBL_GLSL
#define IBL_GLSL

#include "env_common.glsl"
#ifndef ENV_INTENSITY  // the frame's environment (worlds.glsl defines a batch of worlds' first)
#define ENV_INTENSITY lighting.env_intensity
#define ENV_ROTATION lighting.env_rotation.xy
#endif

struct IblTerms {
    vec3 diffuse;
    vec3 specular;
    vec3 diffuse_weight;  // k_d: (1 - metallic) c times what the dielectric's specular lobe
                          // leaves its diffuse (and transmission)
    vec3 diffuse_leaves;  // k_d without c: (1 - metallic) times what that lobe leaves
};

// One specular lobe's split-sum weights (Fdez-Aguera listing 3; the Sample Renderer's
// getIBLGGXFresnel returns their sum) for Schlick's F of `f0` scaled by `weight`. For a
// white lobe (f0 = weight = 1) FssEss + FmsEms = 1: no energy is lost.
struct IblLobe {
    vec3 fss_ess;  // single scattering, F-weighted: radiance's weight
    vec3 fms_ems;  // multiple scattering: irradiance's weight
};

IblLobe ibl_lobe(vec3 f0, float weight, float n_dot_v, float roughness, vec2 ab) {
    // Roughness-dependent Fresnel: F at the lobe's mean.
    vec3 fr = max(vec3(1.0 - roughness), f0) - f0;
    vec3 k_s = f0 + fr * pow(1.0 - n_dot_v, 5.0);
    IblLobe lobe;
    lobe.fss_ess = weight * (k_s * ab.x + ab.y);
    float ems = 1.0 - (ab.x + ab.y);  // what single scattering loses for F = 1
    vec3 f_avg = weight * (f0 + (1.0 - f0) / 21.0);  // hemispherical mean of Schlick's F
    lobe.fms_ems = ems * lobe.fss_ess * f_avg / (1.0 - ems * f_avg);
    return lobe;
}

// glTF 2.0 Appendix B's material under the environment: the dielectric BRDF (specular lobe of
// F0 f0_dielectric, KHR_materials_ior / _specular: 0.04 and 1 by default, over the diffuse c
// weighted by what that lobe leaves) and the metal BRDF (specular lobe of F0 c), each with its
// own energy compensation, mixed by metallic: mix(dielectric, metal, metallic), as the
// punctual lights mix them (brdf.glsl) and the glTF Sample Renderer mixes its
// f_dielectric_brdf_ibl and f_metal_brdf_ibl. Both lobes read the same three texels. (Mixing
// F0 = mix(f0_dielectric, c, metallic) into one lobe instead loses energy at fractional
// metallic: a white sphere in a white furnace returned 0.66-0.84 at metallic 0.25-0.75,
// issue 34.)
// `r`: the direction the pre-filtered environment is read along (the reflection of v about
// n, or about KHR_materials_anisotropy's bent normal: shade.glsl). KHR_materials_iridescence
// (`iridescence` > 0, the Sample Viewer's composition): each lobe mixed by the factor with
// the film's Fresnel times the radiance alone, the dielectric's diffuse with 1 - max3 of it.
IblTerms ibl_evaluate(vec3 n, vec3 v, vec3 r, vec3 c, float metallic, float roughness,
                      vec3 f0_dielectric, float specular_weight, float iridescence,
                      vec3 iridescence_dielectric, vec3 iridescence_metal) {
    vec2 rot = ENV_ROTATION;
    float max_lod = lighting.env_rotation.z;
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 radiance = textureLod(env_specular, env_rotate(r, rot), roughness * max_lod).rgb;
    vec3 irradiance = textureLod(env_irradiance, env_rotate(n, rot), 0.0).rgb;
    vec2 ab = textureLod(brdf_lut, vec2(n_dot_v, roughness), 0.0).rg;

    IblLobe dielectric = ibl_lobe(f0_dielectric, specular_weight, n_dot_v, roughness, ab);
    IblLobe metal = ibl_lobe(c, 1.0, n_dot_v, roughness, ab);
    // The dielectric's diffuse: c under what its own specular lobe leaves.
    vec3 leaves = 1.0 - dielectric.fss_ess - dielectric.fms_ems;
    if (iridescence > 0.0) {
        vec3 fi = iridescence_dielectric;
        leaves = mix(leaves, vec3(1.0 - max(fi.r, max(fi.g, fi.b))), iridescence);
        dielectric.fss_ess = mix(dielectric.fss_ess, iridescence_dielectric, iridescence);
        dielectric.fms_ems *= 1.0 - iridescence;
        metal.fss_ess = mix(metal.fss_ess, iridescence_metal, iridescence);
        metal.fms_ems *= 1.0 - iridescence;
    }
    vec3 fss_ess = mix(dielectric.fss_ess, metal.fss_ess, metallic);
    vec3 fms_ems = mix(dielectric.fms_ems, metal.fms_ems, metallic);
    vec3 k_d = (1.0 - metallic) * c * leaves;

    IblTerms t;
    t.specular = (fss_ess * radiance + fms_ems * irradiance) * ENV_INTENSITY;
    t.diffuse = k_d * irradiance * ENV_INTENSITY;
    t.diffuse_weight = k_d;
    t.diffuse_leaves = (1.0 - metallic) * leaves;
    return t;
}

IblTerms ibl_evaluate(vec3 n, vec3 v, vec3 c, float metallic, float roughness,
                      vec3 f0_dielectric, float specular_weight) {
    return ibl_evaluate(n, v, reflect(-v, n), c, metallic, roughness, f0_dielectric,
                        specular_weight, 0.0, vec3(0.0), vec3(0.0));
}

IblTerms ibl_evaluate(vec3 n, vec3 v, vec3 c, float metallic, float roughness) {
    return ibl_evaluate(n, v, c, metallic, roughness, vec3(0.04), 1.0);
}

// The environment's irradiance about unit direction d (cosine-weighted mean radiance), scaled:
// KHR_materials_diffuse_transmission's light from behind (about -n).
vec3 ibl_irradiance(vec3 d) {
    return textureLod(env_irradiance, env_rotate(d, ENV_ROTATION), 0.0).rgb * ENV_INTENSITY;
}

// The pre-filtered environment's radiance along unit direction d at perceptual roughness
// `roughness` (the layers' lobes: the coat's reflection, sheen, refraction), scaled.
vec3 ibl_radiance(vec3 d, float roughness) {
    return textureLod(env_specular, env_rotate(d, ENV_ROTATION),
                      roughness * lighting.env_rotation.z).rgb * ENV_INTENSITY;
}

#endif
