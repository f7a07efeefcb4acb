// ao.glsl: how the frame's screen-space ambient occlusion (render/ao.py: GTAO) and the
// material's occlusion texture occlude the image-based light, as Filament does
// (light_indirect.fs): the smaller of the two (min, not the product: both see the same
// cavities, and a product would darken them twice). GTAO's visibility first takes its
// multi-bounce approximation for the diffuse light (Jimenez et al. 2016, XeGTAO_MultiBounce:
// light bounced inside the cavity by the albedo brightens it) and Lagarde's specular
// occlusion (Lagarde & de Rousiers 2014, Filament's specularAO) with the multi-bounce on F0
// for the specular; the material's occlusion is taken as it is, so that turning GTAO on
// never brightens a surface (Filament applies the multi-bounce after the min, which lifts
// the texture's own occlusion). Direct light takes none (its shadows occlude it). Without
// screen-space occlusion the material's occlusion alone multiplies both, as before.
#ifndef AO_GLSL
#define AO_GLSL

// The pixel being shaded (pbr.frag: gl_FragCoord; shade.comp: its pixel of the target or
// the batch's atlas), where the frame's GTAO is read.
ivec2 s_pixel = ivec2(0);
// Its layer of ao_map (an array: the layered batch's views are its layers; frames and the
// compute batch's atlas use layer 0): pbr.frag's BATCH build sets its view's.
int s_ao_layer = 0;

// The frame's GTAO visibility at s_pixel: 1 without it (LIGHTING_AO off), for blended
// surfaces (GTAO saw what is behind them) and in the transmission's copy (another size).
float screen_occlusion(uint lighting_flags, uint material_flags) {
#if OPAQUE_COPY
    return 1.0;
#else
    if ((lighting_flags & LIGHTING_AO) == 0u || (material_flags & MATERIAL_BLEND) != 0u) return 1.0;
    return texelFetch(ao_map, ivec3(s_pixel, s_ao_layer), 0).r;
#endif
}

vec3 gtao_multi_bounce(float visibility, vec3 albedo) {
    vec3 a = 2.0404 * albedo - 0.3324;
    vec3 b = -4.7951 * albedo + 0.6417;
    vec3 c = 2.7552 * albedo + 0.6903;
    float x = visibility;
    return max(vec3(x), ((x * a + b) * x + c) * x);
}

float specular_occlusion(float n_dot_v, float visibility, float roughness) {
    return clamp(pow(n_dot_v + visibility, exp2(-16.0 * roughness - 1.0)) - 1.0 + visibility,
                 0.0, 1.0);
}

struct IblOcclusion {
    vec3 diffuse;
    vec3 specular;
};

// `material`: the occlusion texture's value; `screen`: screen_occlusion's; `ssao`: whether
// the frame has screen-space occlusion.
IblOcclusion ibl_occlusion(float material, float screen, bool ssao, vec3 diffuse_albedo,
                           vec3 f0, float n_dot_v, float roughness) {
    if (!ssao) return IblOcclusion(vec3(material), vec3(material));
    vec3 diffuse = gtao_multi_bounce(screen, diffuse_albedo);
    vec3 specular = gtao_multi_bounce(specular_occlusion(n_dot_v, screen, roughness), f0);
    return IblOcclusion(min(vec3(material), diffuse), min(vec3(material), specular));
}
#endif
