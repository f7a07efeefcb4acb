// ao_denoise.glsl: XeGTAO's spatial denoise (XeGTAO_Denoise, MIT, Intel) of one working pixel:
// the 3x3 neighbourhood averaged with weights from the depth edges of ao_gtao.comp (made
// symmetric, a little leak where a pixel has 3 or 4 edges, diagonals through both of their
// paths), the centre weighted by the blur beta (a fifth of it on passes before the last).
// ao_denoise.comp runs it a pass at a time; ao_upsample.comp, where the last pass is fused
// into it (render/ao.py), runs it on the working pixels it blends.
#ifndef AO_DENOISE_GLSL
#define AO_DENOISE_GLSL
#include "ao_common.glsl"

const float BLUR_BETA = 1.2;  // XeGTAO's DenoiseBlurBeta
const float DIAGONAL = 0.85 * 0.5;

uint ao_load(ivec2 w, ivec2 wlo) {
    ivec2 q = ao_work_clamp(w, wlo);
    return pc.read_mid != 0u ? imageLoad(ao_mid, AO_AT(q)).r : imageLoad(ao_raw, AO_AT(q)).r;
}

// The denoised visibility at working pixel p (its tile's first working pixel wlo); `centre`:
// p's packed term (its edges go on with the result).
float ao_denoise(ivec2 p, ivec2 wlo, bool final_pass, out uint centre) {
    uint c = ao_load(p, wlo);
    centre = c;
    uint l = ao_load(p + ivec2(-1, 0), wlo), r = ao_load(p + ivec2(1, 0), wlo);
    uint t = ao_load(p + ivec2(0, -1), wlo), b = ao_load(p + ivec2(0, 1), wlo);
    vec4 el = ao_edges(l), er = ao_edges(r), et = ao_edges(t), eb = ao_edges(b);
    vec4 e = ao_edges(c) * vec4(el.y, er.x, et.w, eb.z);
    const float leak_threshold = 2.5, leak_strength = 0.5;
    float edginess = clamp(4.0 - leak_threshold - dot(e, vec4(1.0)), 0.0, 1.0)
        / (4.0 - leak_threshold) * leak_strength;
    e = clamp(e + edginess, 0.0, 1.0);
    float w_tl = DIAGONAL * (e.x * el.z + e.z * et.x);
    float w_tr = DIAGONAL * (e.z * et.y + e.y * er.z);
    float w_bl = DIAGONAL * (e.w * eb.x + e.x * el.w);
    float w_br = DIAGONAL * (e.y * er.w + e.w * eb.y);
    float blur = final_pass ? BLUR_BETA : BLUR_BETA / 5.0;
    float sum = blur * ao_visibility(c), weight = blur;
    sum += e.x * ao_visibility(l) + e.y * ao_visibility(r) + e.z * ao_visibility(t)
        + e.w * ao_visibility(b);
    weight += e.x + e.y + e.z + e.w;
    sum += w_tl * ao_visibility(ao_load(p + ivec2(-1, -1), wlo))
        + w_tr * ao_visibility(ao_load(p + ivec2(1, -1), wlo))
        + w_bl * ao_visibility(ao_load(p + ivec2(-1, 1), wlo))
        + w_br * ao_visibility(ao_load(p + ivec2(1, 1), wlo));
    weight += w_tl + w_tr + w_bl + w_br;
    return sum / weight;
}
#endif
