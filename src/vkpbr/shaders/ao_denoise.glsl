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

// The denoise of a working pixel from its 3 x 3 neighbourhood's packed terms (c the centre;
// l, r, t, b its 4-neighbours; tl, tr, bl, br its diagonals, each already clamped to the tile).
float ao_denoise_of(uint c, uint l, uint r, uint t, uint b, uint tl, uint tr, uint bl, uint br,
                    bool final_pass) {
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
    sum += w_tl * ao_visibility(tl) + w_tr * ao_visibility(tr) + w_bl * ao_visibility(bl)
        + w_br * ao_visibility(br);
    weight += w_tl + w_tr + w_bl + w_br;
    return sum / weight;
}

// The denoised visibility at working pixel p (its tile's first working pixel wlo); `centre`:
// p's packed term (its edges go on with the result).
float ao_denoise(ivec2 p, ivec2 wlo, bool final_pass, out uint centre) {
    uint c = ao_load(p, wlo);
    centre = c;
    return ao_denoise_of(c, ao_load(p + ivec2(-1, 0), wlo), ao_load(p + ivec2(1, 0), wlo),
                         ao_load(p + ivec2(0, -1), wlo), ao_load(p + ivec2(0, 1), wlo),
                         ao_load(p + ivec2(-1, -1), wlo), ao_load(p + ivec2(1, -1), wlo),
                         ao_load(p + ivec2(-1, 1), wlo), ao_load(p + ivec2(1, 1), wlo),
                         final_pass);
}

// The last pass's denoise of the 2 x 2 working pixels from w0 (ao_upsample.comp with
// pc.fused), x first: their 4 x 4 neighbourhood loaded once (16 loads, not 36). A pixel past
// the tile's last column or row is the last one (clamped, as ao_load clamps): its value.
vec4 ao_denoise_block(ivec2 w0, ivec2 wlo) {
    uint n[16];  // n[j * 4 + i]: w0 + (i - 1, j - 1), clamped to the tile
    for (int k = 0; k < 16; ++k) n[k] = ao_load(w0 + ivec2(k & 3, k >> 2) - 1, wlo);
    ivec2 last = wlo + ao_work_tile() - 1;
    vec4 v;
    for (int k = 0; k < 4; ++k) {
        ivec2 d = min(w0 + ivec2(k & 1, k >> 1), last) - w0;  // (0 where clamped)
        int c = (d.y + 1) * 4 + d.x + 1;  // the centre's index
        v[k] = ao_denoise_of(n[c], n[c - 1], n[c + 1], n[c - 4], n[c + 4], n[c - 5], n[c - 3],
                             n[c + 3], n[c + 5], true);
    }
    return v;
}
#endif
