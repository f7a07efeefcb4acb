// shade.glsl: a surface point shaded as every frame path shades it -- the material inputs,
// the shading normal from the TBN and the normal map, brdf.glsl summed over the frame's
// punctual lights (lights.glsl; the course's mode has one, report 1.1-1.2) with their shadows
// (shadows.glsl), the image-based light (ibl.glsl) or the course's ambient, then the selected
// debug view (Settings.view) as the target stores it. One function for the fragment path
// (pbr.frag) and the compute path (shade.comp), which differ only in where the inputs come from.
//
// The including shader defines, before including this file:
//   MAT            the material block (the draw's set 1, in both paths)
//   SAMPLE(name)   the texel of material texture `name` (base_color, metallic, roughness,
//                  normal, occlusion, emissive) at that texture's UV (texture_uv below): with
//                  hardware derivatives in pbr.frag, ray-differential gradients in shade.comp
// and sets opaque_zero and the surface globals s_* before calling shade_surface().
// ALPHA_MASK (fragment path) discards below the material's cutoff.
// The camera (eye, view direction, far plane, VP) is views[view_index] (generated.glsl),
// which a batch's includer sets first.
#ifndef SHADE_GLSL
#define SHADE_GLSL
#include "brdf.glsl"
#include "worlds.glsl"  // a batch of worlds' lights and environment (render/worlds.py)
#include "lights.glsl"
#include "shadows.glsl"
#include "ibl.glsl"
#include "ao.glsl"  // the image-based light's occlusion: material and GTAO (render/ao.py)
#include "frame_output.glsl"  // opaque_zero / u() (the lavapipe leak guard), radiance_output

// Specialisation (the compute path's shading kernels: render/compute_path.py ShadeVariant):
// the frame's lighting flags and BRDF as constants, and whether the material has any layer
// (KHR_materials_*) other than the defaults, so that the driver compiles out what the frame
// and the material never take (on the H200 the uber-shader's 128 registers a thread held its
// occupancy to a quarter). The defaults -- every flag, the frame's BRDF, the material's
// layers -- are the general shader (the fragment path's pipelines set none of them).
layout(constant_id = 0) const uint SHADE_LIGHTING_FLAGS = 0xFFFFFFFFu;  // ANDed with the frame's
layout(constant_id = 1) const int SHADE_BRDF = -1;  // >= 0: the frame's Settings.brdf
layout(constant_id = 2) const bool SHADE_LAYERS = true;  // false: the default layers
// (constant 3, SHADOW_HAND_READS: whether any shadow map is read by hand, shadow_sampling.glsl)
// A layer factor of the material, or (SHADE_LAYERS false) the default material's
// (generated.glsl MATERIAL_DEFAULT_*: the defaults of scene/material_table.py's rows).
#define LAYER_FACTOR(field) (SHADE_LAYERS ? MAT.field : MATERIAL_DEFAULT_##field)

// The surface point: world position, TEXCOORD_0 (xy) and _1 (zw), interpolated (unnormalised)
// normal, tangent and bitangent, COLOR_0, and which side of the triangle faces the camera.
vec3 s_world_pos;
vec4 s_texcoords;
vec3 s_normal;
vec3 s_tangent;
vec3 s_bitangent;
vec4 s_color;
bool s_front_facing;
// The node's scale along its model's x axis: KHR_materials_volume's thickness is given in
// the mesh's space and scales with the node (as the glTF-Sample-Viewer does).
float s_model_scale = 1.0;

vec3 safe_normalize(vec3 x, vec3 fallback) {
    float len2 = dot(x, x);
    return len2 > 1e-16 ? x * inversesqrt(len2) : fallback;
}

vec3 encode_dir(vec3 d) { return d * 0.5 + 0.5; }

// One texture's coordinates: its own UV set (row0.w, 0 or 1) through its own
// KHR_texture_transform, a 2x3 matrix given as two rows (render/layouts.py, MATERIAL).
vec2 texture_uv(vec4 row0, vec4 row1) {
    vec3 uv_h = vec3(u(row0.w) > 0.5 ? s_texcoords.zw : s_texcoords.xy, 1.0);
    return vec2(dot(row0.xyz, uv_h), dot(row1.xyz, uv_h));
}

// The base colour and its alpha (texture x factor x COLOR_0): alpha masking and the
// visibility pass decide coverage from this one function.
vec4 surface_base_color() {
    return SAMPLE(base_color) * MAT_BASE_COLOR_FACTOR * s_color;
}

// The surface's frame: ng the interpolated vertex normal, t and b the tangent and bitangent
// (back faces of double-sided materials see the whole frame flipped), n the shading normal
// (normal-mapped when the material and the settings say so). The outputs kernel writes them.
void surface_frame(uint settings_flags, uint material_flags, out vec3 ng, out vec3 t,
                   out vec3 b, out vec3 n) {
    ng = safe_normalize(s_normal, vec3(0.0, 0.0, 1.0));
    t = safe_normalize(s_tangent, vec3(1.0, 0.0, 0.0));
    b = safe_normalize(s_bitangent, cross(ng, t));
    if ((material_flags & MATERIAL_DOUBLE_SIDED) != 0u && !s_front_facing) {
        ng = -ng; t = -t; b = -b;
    }
    n = ng;
    if ((settings_flags & SETTINGS_NORMAL_MAPPING) != 0u && (material_flags & MATERIAL_HAS_NORMAL_MAP) != 0u) {
        vec3 tn = SAMPLE(normal).xyz * 2.0 - 1.0;  // linear (UNORM) texture
        tn.xy *= MAT.normal_scale;
        n = safe_normalize(mat3(t, b, ng) * tn, ng);
    }
}

// The material's KHR_materials_* layers: factors times their textures (white when absent;
// scalar maps arrive in R, swizzled by the view: gpu_scene.py).
// A layer texture's value, or the white default's (1.0) for a material with none of them
// (MATERIAL_HAS_LAYER_MAPS): most materials, which then skip eight texture reads a pixel.
#define LAYER_MAP(name, channels) (maps ? SAMPLE(name).channels : vec4(1.0).channels)
Layers material_layers(uint material_flags) {
    // Through u() (frame_output.glsl): branches depend on these, which lavapipe would inline.
    // (The specialised default layers are constants: there is no uniform to inline.)
    vec3 zero = SHADE_LAYERS ? vec3(float(opaque_zero)) : vec3(0.0);
    float zero1 = zero.x;
    bool maps = SHADE_LAYERS && (material_flags & MATERIAL_HAS_LAYER_MAPS) != 0u;
    Layers m;
    m.ior = max(LAYER_FACTOR(ior) + zero1, 1.0);
    m.specular_color = LAYER_FACTOR(specular_color_factor) * LAYER_MAP(specular_color, rgb) + zero;
    m.specular = clamp((LAYER_FACTOR(specular_factor) + zero1) * LAYER_MAP(specular, r), 0.0, 1.0);
    m.clearcoat = clamp((LAYER_FACTOR(clearcoat_factor) + zero1) * LAYER_MAP(clearcoat, r), 0.0, 1.0);
    m.clearcoat_roughness = clamp((LAYER_FACTOR(clearcoat_roughness_factor) + zero1)
                                  * LAYER_MAP(clearcoat_roughness, r), MIN_ROUGHNESS, 1.0);
    m.sheen_color = LAYER_FACTOR(sheen_color_factor) * LAYER_MAP(sheen_color, rgb) + zero;
    m.sheen_roughness = clamp((LAYER_FACTOR(sheen_roughness_factor) + zero1) * LAYER_MAP(sheen_roughness, r),
                              MIN_SHEEN_ROUGHNESS, 1.0);
    m.transmission = clamp((LAYER_FACTOR(transmission_factor) + zero1) * LAYER_MAP(transmission, r),
                           0.0, 1.0);
    m.thickness = max((LAYER_FACTOR(thickness_factor) + zero1) * LAYER_MAP(thickness, r), 0.0) * s_model_scale;
    m.attenuation_color = LAYER_FACTOR(attenuation_color) + zero;
    m.attenuation_distance = LAYER_FACTOR(attenuation_distance) + zero1;
    m.anisotropy = clamp(LAYER_FACTOR(anisotropy_strength) + zero1, 0.0, 1.0);
    m.anisotropy_rotation = LAYER_FACTOR(anisotropy_rotation) + zero1;
    m.anisotropic_t = vec3(1.0, 0.0, 0.0);
    m.anisotropic_b = vec3(0.0, 1.0, 0.0);
    m.iridescence = clamp((LAYER_FACTOR(iridescence_factor) + zero1) * LAYER_MAP(iridescence, r),
                          0.0, 1.0);
    m.iridescence_ior = max(LAYER_FACTOR(iridescence_ior) + zero1, 1.0);
    m.iridescence_thickness = max(mix(LAYER_FACTOR(iridescence_thickness_minimum),
                                      LAYER_FACTOR(iridescence_thickness_maximum),
                                      LAYER_MAP(iridescence_thickness, r)) + zero1, 0.0);
    m.iridescence_dielectric = vec3(0.0);
    m.iridescence_metal = vec3(0.0);
    m.diffuse_transmission = clamp((LAYER_FACTOR(diffuse_transmission_factor) + zero1)
                                   * LAYER_MAP(diffuse_transmission, r), 0.0, 1.0);
    m.diffuse_transmission_color = clamp(LAYER_FACTOR(diffuse_transmission_color_factor)
                                         * LAYER_MAP(diffuse_transmission_color, rgb) + zero,
                                         0.0, 1.0);
    m.dispersion = max(LAYER_FACTOR(dispersion) + zero1, 0.0);
    return m;
}

// KHR_materials_iridescence's Fresnel at n.v over the dielectric's F0 and over the base colour
// (the metal's), once a pixel; a film of thickness 0 is none (the Sample Viewer's).
void iridescence_fresnel(float n_dot_v, vec3 c, inout Layers m) {
    if (!SHADE_LAYERS || m.iridescence <= 0.0) return;
    if (m.iridescence_thickness <= 0.0) { m.iridescence = 0.0; return; }
    m.iridescence_dielectric = eval_iridescence(1.0, m.iridescence_ior, n_dot_v,
                                                m.iridescence_thickness,
                                                dielectric_f0(m.ior, m.specular_color));
    m.iridescence_metal = eval_iridescence(1.0, m.iridescence_ior, n_dot_v,
                                           m.iridescence_thickness, c);
}

// KHR_materials_anisotropy's frame, as the glTF Sample Viewer's getAnisotropyInfo: the
// direction (the texture's RG * 2 - 1, else +x) rotated by the material's rotation, in the
// tangent frame (t, b, n) of the mapped normal; b_a = ng x t_a; the strength times the
// texture's B. A material without anisotropy keeps its isotropic lobe (strength 0).
void anisotropy_frame(uint material_flags, vec3 t, vec3 b, vec3 n, vec3 ng, inout Layers m) {
    if (!SHADE_LAYERS || m.anisotropy <= 0.0) return;
    vec2 direction = vec2(1.0, 0.0);
    if ((material_flags & MATERIAL_HAS_ANISOTROPY_MAP) != 0u) {
        vec3 texel = SAMPLE(anisotropy).rgb;
        direction = texel.rg * 2.0 - 1.0;
        m.anisotropy *= texel.b;
    }
    vec2 cs = vec2(cos(m.anisotropy_rotation), sin(m.anisotropy_rotation));
    direction = mat2(cs.x, cs.y, -cs.y, cs.x) * direction;
    m.anisotropic_t = mat3(t, b, n) * normalize(vec3(direction, 0.0));
    m.anisotropic_b = cross(ng, m.anisotropic_t);
}

// The direction the environment is read along: the reflection about n, or for an anisotropic
// material about the Sample Viewer's bent normal (getIBLRadianceAnisotropy): the normal of
// the plane through the anisotropy's b_a and v, mixed back to n by (1 - s (1 - r))^4.
vec3 ibl_reflection(vec3 n, vec3 v, float roughness, Layers m) {
    if (!SHADE_LAYERS || m.anisotropy <= 0.0) return reflect(-v, n);
    vec3 anisotropic_tangent = cross(m.anisotropic_b, v);
    vec3 anisotropic_normal = cross(anisotropic_tangent, m.anisotropic_b);
    float bend = 1.0 - m.anisotropy * (1.0 - roughness);
    bend *= bend;
    vec3 bent = normalize(mix(anisotropic_normal, n, bend * bend));
    return normalize(reflect(-v, bent));
}

// The coat's normal: the interpolated one, or its own normal map (clearcoatNormalTexture)
// in the surface's tangent frame.
vec3 clearcoat_normal(uint settings_flags, uint material_flags, vec3 ng, vec3 t, vec3 b) {
    if (!SHADE_LAYERS || (settings_flags & SETTINGS_NORMAL_MAPPING) == 0u
        || (material_flags & MATERIAL_HAS_CLEARCOAT_NORMAL_MAP) == 0u) return ng;
    vec3 tn = SAMPLE(clearcoat_normal).xyz * 2.0 - 1.0;
    tn.xy *= MAT.clearcoat_normal_scale;
    return safe_normalize(mat3(t, b, ng) * tn, ng);
}

// KHR_materials_transmission through the opaque scene, as the glTF-Sample-Viewer's
// getTransmissionSample: the radiance the copy of the opaque scene (render/transmission.py,
// linear, mip-mapped) holds where `exit_point` projects, blurred by lod log2(1024) x
// `roughness` at the copy's largest size, 1024 (the same share of the screen at any size:
// log2(size) - log2(1024) (1 - roughness)); false where it projects off the screen or
// behind the eye. Single frames only:
// a batch's views share one copy slot, so they keep the environment; the copy's own pass
// must not read the image it is writing.
#define SCREEN_TRANSMISSION (!OPAQUE_COPY && !BATCH)
#if SCREEN_TRANSMISSION
bool opaque_copy_radiance(vec3 exit_point, float roughness, out vec3 radiance) {
    vec4 clip = views[view_index].VP * vec4(exit_point, 1.0);
    radiance = vec3(0.0);
    if (clip.w <= 1e-6) return false;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;  // NDC to the copy's texels (same viewport maps)
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return false;
    float lod = max(log2(float(textureSize(opaque_copy, 0).x))
                    - log2(OPAQUE_COPY_MAX_SIZE) * (1.0 - roughness), 0.0);
    radiance = textureLod(opaque_copy, uv, lod).rgb;
    return true;
}
#endif

// The light a transmissive surface lets through along `d` (unit, into the surface) from its
// exit point: the opaque copy's where the frame has one and the point is on screen, else the
// pre-filtered environment (when the frame has image-based light), else none.
vec3 transmitted_radiance(vec3 d, float thickness, float roughness, bool screen, bool ibl_on) {
    vec3 radiance = vec3(0.0);
#if SCREEN_TRANSMISSION
    if (screen && opaque_copy_radiance(s_world_pos + d * thickness, roughness, radiance)) {
        return radiance;
    }
#endif
    return ibl_on ? ibl_radiance(d, roughness) : radiance;
}

// The light behind, refracted through the surface at index `ior`: straight through a thin
// wall, refracted into a volume (leaving it `thickness` further on); rougher by
// clamp(2 ior - 2, 0, 1) (the Sample Viewer's applyIorToRoughness).
vec3 refracted_radiance(vec3 v, vec3 n, float ior, float thickness, float roughness,
                        bool screen, bool ibl_on) {
    vec3 d = thickness > 0.0 ? refract(-v, n, 1.0 / ior) : -v;
    if (dot(d, d) < 1e-8) d = -v;  // no total internal reflection entering
    float r_t = roughness * clamp(ior * 2.0 - 2.0, 0.0, 1.0);
    return transmitted_radiance(normalize(d), thickness, r_t, screen, ibl_on);
}

// What refraction brings; KHR_materials_dispersion spreads a volume's ior over the channels,
// each read along its own refracted ray (the Sample Viewer's getIBLVolumeRefraction: red at
// ior - s, green at ior, blue at ior + s, s = (ior - 1) 0.025 dispersion).
vec3 refracted_behind(vec3 v, vec3 n, Layers m, float roughness, bool screen, bool ibl_on) {
    if (!SHADE_LAYERS || m.dispersion <= 0.0 || m.thickness <= 0.0) {
        return refracted_radiance(v, n, m.ior, m.thickness, roughness, screen, ibl_on);
    }
    float spread = (m.ior - 1.0) * 0.025 * m.dispersion;
    vec3 behind;
    for (int i = 0; i < 3; ++i) {
        float ior = max(m.ior + float(i - 1) * spread, 1.0);
        behind[i] = refracted_radiance(v, n, ior, m.thickness, roughness, screen, ibl_on)[i];
    }
    return behind;
}

vec4 shade_surface() {
    uint settings_flags = u(settings.flags);
    uint material_flags = u(MAT.flags);
    int view = frame_view();
    vec2 uv = texture_uv(MAT.base_color_uv_row0, MAT.base_color_uv_row1);
    vec4 base = surface_base_color();
#if ALPHA_MASK && !COMPUTE_SHADING
    if (base.a < MAT.alpha_cutoff) discard;
#endif
    vec3 c = base.rgb;
    // glTF's packed metallic-roughness texture: one sample (its metallic view's R and G).
    vec2 mr = (material_flags & MATERIAL_SHARED_METALLIC_ROUGHNESS) != 0u
        ? SAMPLE(metallic).rg : vec2(SAMPLE(metallic).r, SAMPLE(roughness).r);
    float metallic = clamp(mr.x * MAT_METALLIC_FACTOR, 0.0, 1.0);
    float roughness_map = mr.y * MAT_ROUGHNESS_FACTOR;
    // KHR_materials_pbrSpecularGlossiness: the factor and texel are glossiness.
    if ((material_flags & MATERIAL_GLOSSINESS) != 0u) roughness_map = 1.0 - roughness_map;
    // The environment's level and split-sum row take the roughness as it is: a mirror reads
    // the sharpest level (the Sample Viewer's too). The punctual lights' D needs the floor.
    float roughness_ibl = clamp(roughness_map, 0.0, 1.0);
    float roughness = max(roughness_ibl, MIN_ROUGHNESS);
    float occlusion = 1.0;
    if ((settings_flags & SETTINGS_OCCLUSION) != 0u && (material_flags & MATERIAL_HAS_OCCLUSION_MAP) != 0u) {
        occlusion = 1.0 + MAT.occlusion_strength * (SAMPLE(occlusion).r - 1.0);
    }
    vec3 emissive = ((material_flags & MATERIAL_HAS_EMISSIVE_MAP) != 0u ? SAMPLE(emissive).rgb
                                                                        : vec3(1.0)) * MAT_EMISSIVE_FACTOR;

    vec3 ng, t, b, n;
    surface_frame(settings_flags, material_flags, ng, t, b, n);

    vec3 eye = views[view_index].eye_near.xyz;
    vec3 v = safe_normalize(eye - s_world_pos, ng);
    float view_depth = dot(s_world_pos - eye, views[view_index].forward_far.xyz);
    uint lighting_flags = u(lighting.flags) & SHADE_LIGHTING_FLAGS;
    int brdf = SHADE_BRDF >= 0 ? SHADE_BRDF : u(settings.brdf);
    uint light_count = min(u(lighting.light_count), MAX_LIGHTS);
    Layers layers = material_layers(material_flags);
    anisotropy_frame(material_flags, t, b, n, ng, layers);
    iridescence_fresnel(clamp(dot(n, v), 0.0, 1.0), c, layers);
    // The layers shade the glTF BRDF only (the course's BRDFs are the seed's).
    bool layered = brdf == BRDF_GLTF;
    vec3 nc = clearcoat_normal(settings_flags, material_flags, ng, t, b);
    vec3 specular = vec3(0.0), diffuse = vec3(0.0), transmission = vec3(0.0), sheen = vec3(0.0);
    vec3 diffuse_transmission = vec3(0.0);
    vec3 clearcoat = vec3(0.0);
    BrdfTerms first_terms = BrdfTerms(0.0, vec3(0.0), 0.0, vec3(0.0), vec3(0.0));
    vec3 first_l = ng;
    float first_shadow = 1.0;
    bool shadow_seen = false;
    for (uint i = 0u; i < light_count; ++i) {
        LightRecord light = WORLD_LIGHT(lights[i], i);
        vec3 l;
        vec3 light_in = light_incident(light, s_world_pos, ng, l);
        float shadow = 1.0;
        if ((lighting_flags & LIGHTING_SHADOWS) != 0u && light.shadow.x >= 0.0) {
            shadow = shadow_factor(light, s_world_pos, ng, l, view_depth);
            if (!shadow_seen) { first_shadow = shadow; shadow_seen = true; }
        }
        vec3 incident = light_in * shadow;
        if (layered) {
            LayeredTerms lt = evaluate_layered_brdf(n, nc, v, l, c, metallic, roughness, layers);
            if (i == 0u) { first_terms = lt.base; first_l = l; }
            specular += lt.base.specular * incident;
            diffuse += lt.base.diffuse * incident;
            transmission += lt.transmission * incident;
            diffuse_transmission += lt.diffuse_transmission * incident;
            sheen += lt.sheen * incident;
            clearcoat += vec3(lt.clearcoat) * incident;
        } else {
            BrdfTerms terms = evaluate_brdf(n, v, l, c, metallic, roughness, brdf);
            if (i == 0u) { first_terms = terms; first_l = l; }
            float n_dot_l = max(dot(n, l), 0.0);
            specular += terms.specular * incident * n_dot_l;
            diffuse += terms.diffuse * incident * n_dot_l;
        }
    }
    vec3 ambient = lighting.ambient_color.rgb * c * occlusion;
    IblTerms ibl = IblTerms(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 f0_dielectric = dielectric_f0(layers.ior, layers.specular_color);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    bool ibl_on = (lighting_flags & LIGHTING_IBL) != 0u;
    bool screen = (lighting_flags & LIGHTING_SCREEN_TRANSMISSION) != 0u;
    // Transmission needs the split sum's weights with or without an environment: the opaque
    // copy shows what is behind under punctual lights alone too.
    bool refracts = layered && layers.transmission > 0.0 && (ibl_on || screen);
    if (ibl_on || refracts) {
        ibl = ibl_evaluate(n, v, ibl_reflection(n, v, roughness_ibl, layers), c, metallic,
                           roughness_ibl, f0_dielectric, layers.specular, layers.iridescence,
                           layers.iridescence_dielectric, layers.iridescence_metal);
        if (!ibl_on) { ibl.diffuse = vec3(0.0); ibl.specular = vec3(0.0); }
        if (layered && ibl_on && layers.diffuse_transmission > 0.0) {
            // KHR_materials_diffuse_transmission: the irradiance from behind (about -n) in the
            // colour of the transmission, mixed with the front's by the factor.
            vec3 behind = ibl.diffuse_leaves * layers.diffuse_transmission_color
                * ibl_irradiance(-n) * volume_transmittance(layers.thickness,
                                                            layers.attenuation_color,
                                                            layers.attenuation_distance);
            ibl.diffuse = mix(ibl.diffuse, behind, layers.diffuse_transmission);
            // (The view's share, before occlusion.)
            diffuse_transmission += behind * layers.diffuse_transmission * (1.0 - layers.transmission);
        }
        bool ssao = (lighting_flags & LIGHTING_AO) != 0u;
        IblOcclusion ao = ibl_occlusion(occlusion, screen_occlusion(lighting_flags, material_flags),
                                        ssao, c * (1.0 - metallic),
                                        mix(f0_dielectric, c, metallic), n_dot_v, roughness);
        ibl.diffuse *= ao.diffuse;
        ibl.specular *= ao.specular;
        if (refracts) {
            transmission += layers.transmission * ibl.diffuse_weight * occlusion
                * refracted_behind(v, n, layers, roughness, screen, ibl_on)
                * volume_transmittance(layers.thickness, layers.attenuation_color,
                                       layers.attenuation_distance);
            ibl.diffuse *= 1.0 - layers.transmission;
        }
        if (layered && ibl_on) {
            if (max3(layers.sheen_color) > 0.0) {
                // The GGX pre-filtered environment stands in for a Charlie pre-filtered one.
                sheen += occlusion * layers.sheen_color
                    * sheen_albedo(n_dot_v, layers.sheen_roughness)
                    * ibl_radiance(reflect(-v, n), layers.sheen_roughness);
            }
            if (layers.clearcoat > 0.0) {
                clearcoat += occlusion * ibl_radiance(reflect(-v, nc), layers.clearcoat_roughness);
            }
        }
    }
    // Sheen's albedo scaling of the base (the README's simplified form, by n.v) and the coat's
    // blend clearcoat * F_coat(n_c.v) with F0 0.04 (ior 1.5), emission included.
    float sheen_scaling = 1.0;
    float coat_blend = 0.0;
    if (layered) {
        float sheen_max = max3(layers.sheen_color);
        if (sheen_max > 0.0) sheen_scaling = 1.0 - sheen_max * sheen_albedo(n_dot_v, layers.sheen_roughness);
        float nc_dot_v = clamp(dot(nc, v), 0.0, 1.0);
        coat_blend = layers.clearcoat * f_schlick(vec3(0.04), nc_dot_v).r;
        clearcoat *= coat_blend;
    }
    vec3 base_radiance = diffuse + specular + transmission + ibl.diffuse + ibl.specular;
    vec3 final_value = (emissive + ambient + sheen + base_radiance * sheen_scaling)
        * (1.0 - coat_blend) + clearcoat;
    if ((material_flags & MATERIAL_UNLIT) != 0u) final_value = c;  // KHR_materials_unlit

    vec3 value;
    switch (view) {
        case VIEW_D: value = vec3(first_terms.D); break;
        case VIEW_F: value = first_terms.F; break;
        case VIEW_G: value = vec3(first_terms.G); break;
        case VIEW_SPECULAR: value = specular; break;
        case VIEW_DIFFUSE: value = diffuse; break;
        case VIEW_AMBIENT: value = ambient; break;
        case VIEW_GEOMETRIC_NORMAL: value = encode_dir(ng); break;
        case VIEW_MAPPED_NORMAL: value = encode_dir(n); break;
        case VIEW_VIEW_DIR: value = encode_dir(v); break;
        case VIEW_LIGHT_DIR: value = encode_dir(first_l); break;
        case VIEW_BASE_COLOR: value = c; break;
        case VIEW_METALLIC: value = vec3(metallic); break;
        case VIEW_ROUGHNESS: value = vec3(roughness); break;
        case VIEW_OCCLUSION: value = vec3(occlusion); break;
        case VIEW_ALPHA: value = vec3(base.a); break;
        case VIEW_TEXCOORDS: value = vec3(fract(uv), 0.0); break;
        case VIEW_DEPTH: value = vec3(view_depth / views[view_index].forward_far.w); break;
        case VIEW_EMISSIVE: value = emissive; break;
        case VIEW_TANGENT: value = encode_dir(t); break;
        case VIEW_BITANGENT: value = encode_dir(b); break;
        case VIEW_SHADOW: value = vec3(first_shadow); break;
        case VIEW_IBL_DIFFUSE: value = ibl.diffuse; break;
        case VIEW_IBL_SPECULAR: value = ibl.specular; break;
        case VIEW_IOR: value = vec3(layers.ior - 1.0); break;
        case VIEW_DIELECTRIC_F0: value = f0_dielectric * layers.specular; break;
        case VIEW_CLEARCOAT: value = clearcoat; break;
        case VIEW_SHEEN: value = sheen; break;
        case VIEW_TRANSMISSION: value = transmission; break;
        case VIEW_ANISOTROPY:
            value = layers.anisotropy > 0.0
                ? vec3(vec2(dot(layers.anisotropic_t, t), dot(layers.anisotropic_t, b)) * 0.5 + 0.5,
                       layers.anisotropy)
                : vec3(1.0, 0.5, 0.0);
            break;
        case VIEW_IRIDESCENCE: value = layers.iridescence_dielectric * layers.iridescence; break;
        case VIEW_DIFFUSE_TRANSMISSION: value = diffuse_transmission; break;
        case VIEW_AO: value = vec3(screen_occlusion(lighting_flags, material_flags)); break;
        case VIEW_VOLUME:
            value = volume_transmittance(layers.thickness, layers.attenuation_color,
                                         layers.attenuation_distance);
            break;
        default: value = final_value; break;
    }

    int kind = VIEW_KINDS[clamp(view, 0, VIEW_KINDS.length() - 1)];
    bool srgb_target = (settings_flags & SETTINGS_SRGB_TARGET) != 0u;
    if (kind == VIEW_KIND_RADIANCE) {
        value = radiance_output(value);
    } else if (kind == VIEW_KIND_DATA) {
        // Raw data: on an sRGB target, pre-linearise so that the stored byte is the value.
        value = clamp(value, 0.0, 1.0);
        if (srgb_target) value = srgb_to_linear(value);
    }
    float alpha = (material_flags & MATERIAL_BLEND) != 0u ? base.a : 1.0;
    return vec4(value, alpha);
}

#endif
