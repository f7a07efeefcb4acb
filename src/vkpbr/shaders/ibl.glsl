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

struct IblTerms {
    vec3 diffuse;
    vec3 specular;
    vec3 diffuse_weight;  // k_d: what the specular lobe leaves the diffuse (and transmission)
};

// f0_dielectric, specular_weight: KHR_materials_ior / _specular (0.04 and 1 by default); the
// dielectric's and the metal's F0 and weight are mixed by metalness before the compensation,
// which for the defaults is the core material's formula exactly (and the Sample Viewer's
// getIBLGGXFresnel at metalness 0 or 1).
IblTerms ibl_evaluate(vec3 n, vec3 v, vec3 c, float metallic, float roughness,
                      vec3 f0_dielectric, float specular_weight) {
    vec2 rot = lighting.env_rotation.xy;
    float max_lod = lighting.env_rotation.z;
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 r = reflect(-v, n);
    vec3 radiance = textureLod(env_specular, env_rotate(r, rot), roughness * max_lod).rgb;
    vec3 irradiance = textureLod(env_irradiance, env_rotate(n, rot), 0.0).rgb;
    vec2 ab = textureLod(brdf_lut, vec2(n_dot_v, roughness), 0.0).rg;

    vec3 f0 = mix(f0_dielectric, c, metallic);
    float weight = mix(specular_weight, 1.0, metallic);
    vec3 diffuse_color = c * (1.0 - metallic);
    // Roughness-dependent Fresnel (Fdez-Aguera eq. in listing 3): F at the lobe's mean.
    vec3 fr = max(vec3(1.0 - roughness), f0) - f0;
    vec3 k_s = f0 + fr * pow(1.0 - n_dot_v, 5.0);
    vec3 fss_ess = weight * (k_s * ab.x + ab.y);  // single scattering, F-weighted
    float ess = ab.x + ab.y;                      // single-scattering albedo for F = 1
    float ems = 1.0 - ess;
    vec3 f_avg = weight * (f0 + (1.0 - f0) / 21.0);  // hemispherical mean of Schlick's F
    vec3 fms_ems = ems * fss_ess * f_avg / (1.0 - ems * f_avg);
    vec3 k_d = diffuse_color * (1.0 - fss_ess - fms_ems);

    IblTerms t;
    t.specular = (fss_ess * radiance + fms_ems * irradiance) * lighting.env_intensity;
    t.diffuse = k_d * irradiance * lighting.env_intensity;
    t.diffuse_weight = k_d;
    return t;
}

IblTerms ibl_evaluate(vec3 n, vec3 v, vec3 c, float metallic, float roughness) {
    return ibl_evaluate(n, v, c, metallic, roughness, vec3(0.04), 1.0);
}

// The pre-filtered environment's radiance along unit direction d at perceptual roughness
// `roughness` (the layers' lobes: the coat's reflection, sheen, refraction), scaled.
vec3 ibl_radiance(vec3 d, float roughness) {
    return textureLod(env_specular, env_rotate(d, lighting.env_rotation.xy),
                      roughness * lighting.env_rotation.z).rgb * lighting.env_intensity;
}

#endif
