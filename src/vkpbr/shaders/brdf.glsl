// brdf.glsl: the shading equations of renderer-spec section 2 (the course's Cook-Torrance) and
// of the glTF 2.0 specification's Appendix B, as pure functions of scalars and colours.
// Mirrored function for function, with the same names, in src/vkpbr/reference/brdf.py; the
// GPU tests compare the two.
// Notation: x+ = max(0, x); n, l, v, h unit vectors; c base colour, M metalness, r roughness.
#ifndef BRDF_GLSL
#define BRDF_GLSL
#include "brdf_lobes.glsl"  // PI, EPS, d_ggx, v_smith_ggx_correlated



// The course's Blinn-Phong distribution: (ap + 2) / (2 pi) (n.h)+^ap, ap = 2 / alpha^2 - 2.
float d_blinn_phong(float n_dot_h, float alpha) {
    float ap = 2.0 / (alpha * alpha) - 2.0;
    return (ap + 2.0) / (2.0 * PI) * pow(n_dot_h, ap);
}

// Schlick's Fresnel approximation (Schlick 1994): F0 + (1 - F0)(1 - h.v)^5. h.v of unit
// vectors rounds above 1 where l = v (a light at the eye: a headlight), and pow of a
// negative base is NaN: the base is kept >= 0.
vec3 f_schlick(vec3 f0, float v_dot_h) {
    return f0 + (1.0 - f0) * pow(max(1.0 - v_dot_h, 0.0), 5.0);
}

// Cook-Torrance masking (Cook & Torrance 1982): min(1, 2(n.h)(n.v)/(v.h), 2(n.h)(n.l)/(v.h)).
float g_cook_torrance(float n_dot_h, float n_dot_v, float n_dot_l, float v_dot_h) {
    float k = 2.0 * n_dot_h / max(v_dot_h, EPS);
    return min(1.0, min(k * n_dot_v, k * n_dot_l));
}


// Lambert diffuse weighted by what neither the specular lobe nor the metal takes:
// (c / pi)(1 - F)(1 - M).
vec3 diffuse_lambert(vec3 c, vec3 f, float metallic) {
    return c / PI * (1.0 - f) * (1.0 - metallic);
}

// F0 = (1 - M) 0.04 + M c.
vec3 f0_from_metallic(vec3 c, float metallic) {
    return mix(vec3(0.04), c, metallic);
}

struct BrdfTerms {
    float D;
    vec3 F;
    float G;
    vec3 specular;  // D F G / (4 (n.v)+ (n.l)+), the specular BRDF value
    vec3 diffuse;   // the diffuse BRDF value
};

// The glTF 2.0 BRDF (Appendix B.3): mix(dielectric, metal, M), where the dielectric is
// fresnel_mix(ior 1.5: F0 = 0.04) of Lambert c/pi under GGX D V, the metal the same specular
// lobe with F0 = c. Schlick's F is linear in F0, so the mixed specular is F(mix(0.04, c, M)) D V;
// the diffuse keeps the dielectric's own Fresnel: (1 - M)(1 - F(0.04)) c / pi.
BrdfTerms evaluate_gltf_brdf(float n_dot_l, float n_dot_v, float n_dot_h, float v_dot_h, vec3 c,
                             float metallic, float alpha) {
    BrdfTerms t;
    t.D = d_ggx(n_dot_h, alpha);
    t.F = f_schlick(f0_from_metallic(c, metallic), v_dot_h);
    float vis = v_smith_ggx_correlated(n_dot_l, n_dot_v, alpha);
    t.G = vis * 4.0 * n_dot_l * n_dot_v;
    t.specular = t.F * (t.D * vis);
    t.diffuse = (1.0 - metallic) * (1.0 - f_schlick(vec3(0.04), v_dot_h)) * c / PI;
    return t;
}

// Every term at one shading point. brdf: BRDF_GLTF, or the course's with D = BRDF_GGX or
// BRDF_BLINN_PHONG.
BrdfTerms evaluate_brdf(vec3 n, vec3 v, vec3 l, vec3 c, float metallic, float roughness, int brdf) {
    vec3 h = normalize(l + v);
    float n_dot_l = max(dot(n, l), 0.0);
    float n_dot_v = max(dot(n, v), 0.0);
    float n_dot_h = max(dot(n, h), 0.0);
    float v_dot_h = max(dot(v, h), 0.0);
    float alpha = roughness * roughness;
    if (brdf == BRDF_GLTF) return evaluate_gltf_brdf(n_dot_l, n_dot_v, n_dot_h, v_dot_h, c, metallic, alpha);
    BrdfTerms t;
    t.D = brdf == BRDF_BLINN_PHONG ? d_blinn_phong(n_dot_h, alpha) : d_ggx(n_dot_h, alpha);
    t.F = f_schlick(f0_from_metallic(c, metallic), v_dot_h);
    t.G = g_cook_torrance(n_dot_h, n_dot_v, n_dot_l, v_dot_h);
    t.specular = t.D * t.F * t.G / max(4.0 * n_dot_v * n_dot_l, EPS);
    t.diffuse = diffuse_lambert(c, t.F, metallic);
    return t;
}

// --- The KHR_materials_* layers (the glTF BRDF only; the course's BRDFs are the seed's) -----

float max3(vec3 x) { return max(x.r, max(x.g, x.b)); }

// KHR_materials_ior and _specular: the dielectric's F0 = min(((ior - 1)/(ior + 1))^2 * specular
// colour, 1) (ior 1.5: 0.04).
vec3 dielectric_f0(float ior, vec3 specular_color) {
    float r = (ior - 1.0) / (ior + 1.0);
    return min(vec3(r * r) * specular_color, vec3(1.0));
}

// KHR_materials_sheen's "Charlie" distribution (Conty & Kulla 2017), alpha_g = sheen roughness:
// (2 + 1/alpha_g) sin(theta_h)^(1/alpha_g) / (2 pi).
float d_charlie(float n_dot_h, float alpha_g) {
    float inv_r = 1.0 / alpha_g;
    float sin2h = max(1.0 - n_dot_h * n_dot_h, 0.0);
    return (2.0 + inv_r) * pow(sin2h, inv_r * 0.5) / (2.0 * PI);
}

// The fit l(x) of the Charlie visibility (the extension's README).
float sheen_l(float x, float alpha_g) {
    float w = (1.0 - alpha_g) * (1.0 - alpha_g);
    float a = mix(21.5473, 25.3245, w);
    float b = mix(3.82987, 3.32435, w);
    float c = mix(0.19823, 0.16801, w);
    float d = mix(-1.97760, -1.27393, w);
    float e = mix(-4.32054, -4.85967, w);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

float sheen_lambda(float cos_theta, float alpha_g) {
    return cos_theta < 0.5 ? exp(sheen_l(cos_theta, alpha_g))
                           : exp(2.0 * sheen_l(0.5, alpha_g) - sheen_l(1.0 - cos_theta, alpha_g));
}

// The Charlie visibility 1 / ((1 + lambda(n.v) + lambda(n.l)) 4 n.v n.l); 0 below the horizon.
float v_charlie(float n_dot_l, float n_dot_v, float alpha_g) {
    if (n_dot_l <= 0.0 || n_dot_v <= 0.0) return 0.0;
    return 1.0 / ((1.0 + sheen_lambda(n_dot_v, alpha_g) + sheen_lambda(n_dot_l, alpha_g))
                  * (4.0 * n_dot_v * n_dot_l));
}

// The sheen lobe's directional albedo E(n.v, alpha_g): the fitted polynomial of
// vkpbr.shading (generated.glsl sheen_albedo_fit), in x = cbrt(n.v), y = sqrt(alpha_g).
float sheen_albedo(float n_dot_v, float alpha_g) {
    float x = pow(clamp(n_dot_v, SHEEN_FIT_MIN_N_DOT_V, 1.0), 1.0 / 3.0);
    float y = sqrt(clamp(alpha_g, MIN_SHEEN_ROUGHNESS, 1.0));
    return clamp(sheen_albedo_fit(x, y), 0.0, 1.0);
}

// KHR_materials_volume: Beer-Lambert transmittance over `dist`, attenuation colour ^
// (dist / attenuation distance); attenuation distance 0 = infinite (no absorption).
vec3 volume_transmittance(float dist, vec3 attenuation_color, float attenuation_distance) {
    if (attenuation_distance <= 0.0 || dist <= 0.0) return vec3(1.0);
    return pow(attenuation_color, vec3(dist / attenuation_distance));
}

// KHR_materials_anisotropy's GGX (Burley 2012; the extension's README and the glTF Sample
// Viewer's D_GGX_anisotropic / V_GGX_anisotropic): alpha_t along the anisotropy direction t,
// alpha_b along b = ng x t; t.h, b.h, t.v, ... the directions' components in that frame.
float d_ggx_anisotropic(float n_dot_h, float t_dot_h, float b_dot_h, float at, float ab) {
    float a2 = at * ab;
    vec3 f = vec3(ab * t_dot_h, at * b_dot_h, a2 * n_dot_h);
    float w2 = a2 / dot(f, f);
    return a2 * w2 * w2 / PI;
}

float v_ggx_anisotropic(float n_dot_l, float n_dot_v, float b_dot_v, float t_dot_v,
                        float t_dot_l, float b_dot_l, float at, float ab) {
    float ggx_v = n_dot_l * length(vec3(at * t_dot_v, ab * b_dot_v, n_dot_v));
    float ggx_l = n_dot_v * length(vec3(at * t_dot_l, ab * b_dot_l, n_dot_l));
    return clamp(0.5 / (ggx_v + ggx_l), 0.0, 1.0);
}

// The anisotropic roughnesses of strength s: alpha_t = mix(alpha, 1, s^2) along the
// direction, alpha_b = alpha (at least 0.001) across it.
vec2 anisotropic_alphas(float alpha, float s) {
    return vec2(mix(alpha, 1.0, s * s), clamp(alpha, 0.001, 1.0));
}

// KHR_materials_iridescence: the Fresnel reflectance of a thin film (index eta2, thickness
// in nm) between the outside (index 1) and a base of reflectance base_f0, at cos(theta1) =
// n.v: Belcour and Barla 2017's airy summation (two orders) with the spectral sensitivity
// fitted in XYZ, as the extension's README and the glTF Sample Viewer's evalIridescence.
const mat3 XYZ_TO_REC709 = mat3(3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108,
                                -0.2040259, -0.4985314, 0.0415560, 1.0572252);

float sq(float x) { return x * x; }
vec3 sq(vec3 x) { return x * x; }

vec3 fresnel0_to_ior(vec3 f0) {
    vec3 s = sqrt(f0);
    return (1.0 + s) / (1.0 - s);
}

vec3 ior_to_fresnel0(vec3 transmitted, float incident) {
    return sq((transmitted - incident) / (transmitted + incident));
}

float ior_to_fresnel0(float transmitted, float incident) {
    return sq((transmitted - incident) / (transmitted + incident));
}

// The XYZ sensitivity's Fourier transform at optical path difference opd (nm), phase shift
// `shift`, as linear Rec. 709 (sRGB primaries).
vec3 eval_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1.0e-9;
    const vec3 val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    const vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
    const vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
    vec3 xyz = val * sqrt(2.0 * PI * var) * cos(pos * phase + shift) * exp(-sq(phase) * var);
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift[0])
        * exp(-4.5282e+09 * sq(phase));
    return XYZ_TO_REC709 * (xyz / 1.0685e-7);
}

vec3 eval_iridescence(float outside_ior, float eta2, float cos_theta1, float thickness,
                      vec3 base_f0) {
    // The film fades into the outside medium as it thins to nothing.
    float film_ior = mix(outside_ior, eta2, smoothstep(0.0, 0.03, thickness));
    float sin_theta2_sq = sq(outside_ior / film_ior) * (1.0 - sq(cos_theta1));
    float cos_theta2_sq = 1.0 - sin_theta2_sq;
    if (cos_theta2_sq < 0.0) return vec3(1.0);  // total internal reflection
    float cos_theta2 = sqrt(cos_theta2_sq);
    // First interface (outside | film).
    float r0 = ior_to_fresnel0(film_ior, outside_ior);
    float r12 = r0 + (1.0 - r0) * pow(1.0 - cos_theta1, 5.0);
    float t121 = 1.0 - r12;
    float phi12 = film_ior < outside_ior ? PI : 0.0;
    float phi21 = PI - phi12;
    // Second interface (film | base).
    vec3 base_ior = fresnel0_to_ior(clamp(base_f0, 0.0, 0.9999));
    vec3 r1 = ior_to_fresnel0(base_ior, film_ior);
    vec3 r23 = r1 + (1.0 - r1) * pow(1.0 - cos_theta2, 5.0);
    vec3 phi23 = mix(vec3(0.0), vec3(PI), lessThan(base_ior, vec3(film_ior)));
    float opd = 2.0 * film_ior * thickness * cos_theta2;
    vec3 phi = vec3(phi21) + phi23;
    vec3 r123 = clamp(r12 * r23, 1e-5, 0.9999);
    vec3 r123_sqrt = sqrt(r123);
    vec3 rs = sq(t121) * r23 / (1.0 - r123);
    vec3 intensity = r12 + rs;  // order 0
    vec3 cm = rs - t121;
    for (int m = 1; m <= 2; ++m) {
        cm *= r123_sqrt;
        intensity += cm * 2.0 * eval_sensitivity(float(m) * opd, float(m) * phi);
    }
    return max(intensity, vec3(0.0));
}

// The layers' parameters at a shading point (scene.types.Material documents each).
struct Layers {
    float ior;
    vec3 specular_color;
    float specular;        // weight of the dielectric lobe
    float clearcoat;
    float clearcoat_roughness;
    vec3 sheen_color;
    float sheen_roughness;  // alpha_g, clamped to MIN_SHEEN_ROUGHNESS
    float transmission;
    float thickness;
    vec3 attenuation_color;
    float attenuation_distance;
    float anisotropy;       // strength (0: the isotropic lobe)
    float anisotropy_rotation;
    vec3 anisotropic_t;     // the anisotropy direction in world space (shade.glsl)
    vec3 anisotropic_b;     // ng x anisotropic_t
    float iridescence;      // factor (0: no film)
    float iridescence_ior;
    float iridescence_thickness;  // nm
    vec3 iridescence_dielectric;  // the film's Fresnel over the dielectric's F0 at n.v
    vec3 iridescence_metal;       // and over the base colour (shade.glsl)
    float diffuse_transmission;   // the share of the diffuse lobe passing through
    vec3 diffuse_transmission_color;
    float dispersion;             // KHR_materials_dispersion (a volume's refraction)
};

// One punctual light's layered glTF BRDF (values before the light's radiance and shadow).
struct LayeredTerms {
    BrdfTerms base;    // D, F (the mixed specular Fresnel), G; specular and diffuse * n.l
    vec3 transmission; // the transmitted lobe (no n.l), weighted like the diffuse
    vec3 diffuse_transmission;  // the diffuse lobe's share through the surface (in base.diffuse)
    vec3 sheen;        // sheen colour D_charlie V_charlie n.l
    float clearcoat;   // the coat's D V (n_c.l): its Fresnel is in the blend (shade.glsl)
};

// The glTF BRDF with KHR_materials_ior / _specular / _transmission / _volume / _sheen /
// _clearcoat, as the specification's layering composes it: base = mix(dielectric, metal, M)
// with the dielectric fresnel_mix(ior, specular colour, specular) of (Lambert mixed with the
// transmitted lobe by transmission) and GGX; then sheen + base * albedo scaling, then the
// coat's fresnel_coat (shade.glsl, the blend is per view direction). `nc`: the coat's normal.
// The transmitted lobe is the Sample Viewer's getPunctualRadianceTransmission: GGX of the
// light mirrored through the surface, alpha scaled by clamp(2 ior - 2, 0, 1); the volume's
// transmittance over `thickness` applies to it.
LayeredTerms evaluate_layered_brdf(vec3 n, vec3 nc, vec3 v, vec3 l, vec3 c, float metallic,
                                   float roughness, Layers m) {
    vec3 h = normalize(l + v);
    float n_dot_l = max(dot(n, l), 0.0);
    float n_dot_v = max(dot(n, v), 0.0);
    float n_dot_h = max(dot(n, h), 0.0);
    float v_dot_h = max(dot(v, h), 0.0);
    float alpha = roughness * roughness;
    LayeredTerms t;
    t.base.D = d_ggx(n_dot_h, alpha);
    float vis = v_smith_ggx_correlated(n_dot_l, n_dot_v, alpha);
    if (m.anisotropy > 0.0) {  // KHR_materials_anisotropy: the specular lobe only
        vec2 a = anisotropic_alphas(alpha, m.anisotropy);
        vec3 at = m.anisotropic_t, ab = m.anisotropic_b;
        t.base.D = d_ggx_anisotropic(clamp(dot(n, h), 0.001, 1.0), dot(at, h), dot(ab, h), a.x, a.y);
        vis = v_ggx_anisotropic(n_dot_l, n_dot_v, dot(ab, v), dot(at, v), dot(at, l), dot(ab, l),
                                a.x, a.y);
    }
    t.base.G = vis * 4.0 * n_dot_l * n_dot_v;
    vec3 f_dielectric = m.specular * f_schlick(dielectric_f0(m.ior, m.specular_color), v_dot_h);
    vec3 f_metal = f_schlick(c, v_dot_h);
    float f_max = max3(f_dielectric);
    if (m.iridescence > 0.0) {  // KHR_materials_iridescence: the film's Fresnel mixed in
        f_dielectric = mix(f_dielectric, m.iridescence_dielectric, m.iridescence);
        f_metal = mix(f_metal, m.iridescence_metal, m.iridescence);
        f_max = mix(f_max, max3(m.iridescence_dielectric), m.iridescence);
    }
    t.base.F = (1.0 - metallic) * f_dielectric + metallic * f_metal;
    t.base.specular = t.base.F * (t.base.D * vis) * n_dot_l;
    float diffuse_weight = (1.0 - metallic) * (1.0 - f_max);
    t.base.diffuse = diffuse_weight * (1.0 - m.transmission) * c / PI * n_dot_l;
    t.diffuse_transmission = vec3(0.0);
    if (m.diffuse_transmission > 0.0) {
        // KHR_materials_diffuse_transmission: mix(Lambert of c on this side, Lambert of the
        // transmission colour on the other, factor), the volume's transmittance on the latter
        // (the Sample Viewer's diffuse_btdf).
        vec3 btdf = m.diffuse_transmission_color / PI * max(-dot(n, l), 0.0)
            * volume_transmittance(m.thickness, m.attenuation_color, m.attenuation_distance);
        t.diffuse_transmission = diffuse_weight * (1.0 - m.transmission) * m.diffuse_transmission
            * btdf;
        t.base.diffuse = t.base.diffuse * (1.0 - m.diffuse_transmission) + t.diffuse_transmission;
    }
    t.transmission = vec3(0.0);
    if (m.transmission > 0.0) {
        vec3 l_mirror = normalize(l - 2.0 * n * dot(l, n));
        vec3 ht = normalize(l_mirror + v);
        float alpha_t = alpha * clamp(m.ior * 2.0 - 2.0, 0.0, 1.0);
        float d_t = d_ggx(max(dot(n, ht), 0.0), alpha_t);
        float v_t = v_smith_ggx_correlated(max(dot(n, l_mirror), 0.0), n_dot_v, alpha_t);
        t.transmission = diffuse_weight * m.transmission * c * (d_t * v_t)
            * volume_transmittance(m.thickness, m.attenuation_color, m.attenuation_distance);
    }
    t.sheen = vec3(0.0);
    if (max3(m.sheen_color) > 0.0) {
        t.sheen = m.sheen_color * (d_charlie(n_dot_h, m.sheen_roughness)
                                   * v_charlie(n_dot_l, n_dot_v, m.sheen_roughness) * n_dot_l);
    }
    t.clearcoat = 0.0;
    if (m.clearcoat > 0.0) {
        float a_c = m.clearcoat_roughness * m.clearcoat_roughness;
        float nc_dot_l = max(dot(nc, l), 0.0);
        t.clearcoat = d_ggx(max(dot(nc, h), 0.0), a_c)
            * v_smith_ggx_correlated(nc_dot_l, max(dot(nc, v), 0.0), a_c) * nc_dot_l;
    }
    return t;
}

// Point-light attenuation: none (the course) or inverse square with glTF's range window.
float light_attenuation(float dist2, uint falloff, float range) {
    if (falloff == 0u) return 1.0;
    float att = 1.0 / max(dist2, 1e-4);
    if (range > 0.0) {
        float r = dist2 / (range * range);
        att *= clamp(1.0 - r * r, 0.0, 1.0);
    }
    return att;
}

// Khronos PBR Neutral (Khronos 3D Commerce, 2024): base colours under normal light pass
// unchanged, highlights compress towards white. The reference GLSL of the specification.
vec3 tonemap_pbr_neutral(vec3 color) {
    const float start_compression = 0.8 - 0.04;
    const float desaturation = 0.15;
    float x = min(color.r, min(color.g, color.b));
    float offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
    color -= offset;
    float peak = max(color.r, max(color.g, color.b));
    if (peak < start_compression) return color;
    const float d = 1.0 - start_compression;
    float new_peak = 1.0 - d * d / (peak + d - start_compression);
    color *= new_peak / peak;
    float g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(color, vec3(new_peak), g);
}

// Stephen Hill's ACES fit (BakingLab): sRGB -> ACES AP1-ish input matrix, the RRT+ODT rational
// fit, the output matrix back (matrices column-major, as the Sample Viewer writes them).
vec3 tonemap_aces_hill(vec3 color) {
    const mat3 input_mat = mat3(0.59719, 0.07600, 0.02840, 0.35458, 0.90834, 0.13383,
                                0.04823, 0.01566, 0.83777);
    const mat3 output_mat = mat3(1.60475, -0.10208, -0.00327, -0.53108, 1.10813, -0.07276,
                                 -0.07367, -0.00605, 1.07602);
    color = input_mat * color;
    vec3 a = color * (color + 0.0245786) - 0.000090537;
    vec3 b = color * (0.983729 * color + 0.4329510) + 0.238081;
    return clamp(output_mat * (a / b), 0.0, 1.0);
}

// Tone mapping (vkpbr.shading.Tonemap documents each curve): Reinhard x / (1 + x); ACES
// (Narkowicz 2015, no pre-scale); ACES (Hill); Khronos PBR Neutral.
vec3 tonemap(vec3 x, int mode) {
    if (mode == TONEMAP_REINHARD) return x / (1.0 + x);
    if (mode == TONEMAP_ACES) {
        return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    }
    if (mode == TONEMAP_ACES_HILL) return tonemap_aces_hill(x);
    if (mode == TONEMAP_PBR_NEUTRAL) return tonemap_pbr_neutral(x);
    return x;
}

// sRGB EOTF (IEC 61966-2-1): encoded value -> linear.
vec3 srgb_to_linear(vec3 e) {
    return mix(e / 12.92, pow((e + 0.055) / 1.055, vec3(2.4)), greaterThan(e, vec3(0.04045)));
}

// sRGB inverse EOTF (IEC 61966-2-1): linear -> encoded (the compute path writes UNORM views of
// sRGB images, so it encodes here what the attachment's hardware encoding does).
vec3 linear_to_srgb(vec3 x) {
    x = clamp(x, 0.0, 1.0);
    return mix(x * 12.92, 1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, greaterThan(x, vec3(0.0031308)));
}

// A linear colour as the compute path stores it into the target's storage view: encoded for
// an sRGB image (whose view is UNORM), as it is otherwise.
vec4 stored_color(vec4 c, bool srgb) { return srgb ? vec4(linear_to_srgb(c.rgb), c.a) : c; }

#endif
