#version 450
// ao_denoise.comp: XeGTAO's spatial denoise (XeGTAO_Denoise, MIT, Intel), a pixel an
// invocation: the 3x3 neighbourhood averaged with weights from the depth edges of ao_gtao.comp
// (made symmetric, a little leak where a pixel has 3 or 4 edges, diagonals through both of
// their paths), the centre weighted by the blur beta (a fifth of it on passes before the
// last). It runs on the working images (at 1 / scale of the frame's size): passes write the
// other working image, edges kept (ao_raw -> ao_mid -> ao_raw ...), except the last at full
// resolution, which writes the visibility the shading reads (ao_out; background pixels get
// 1). At half resolution ao_upsample.comp makes ao_out from the last pass's image.
#extension GL_GOOGLE_include_directive : require
#include "ao_common.glsl"

const float BLUR_BETA = 1.2;  // XeGTAO's DenoiseBlurBeta
const float DIAGONAL = 0.85 * 0.5;

uint load(ivec2 w, ivec2 wlo) {
    ivec2 q = ao_work_clamp(w, wlo);
    return pc.read_mid != 0u ? imageLoad(ao_mid, AO_AT(q)).r : imageLoad(ao_raw, AO_AT(q)).r;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);  // a working pixel
    uint view;
    ivec2 lo, wlo;
    if (any(greaterThanEqual(p, imageSize(ao_raw).xy)) || !ao_work_view(p, view, wlo, lo)) return;
    uint c = load(p, wlo);
    uint l = load(p + ivec2(-1, 0), wlo), r = load(p + ivec2(1, 0), wlo);
    uint t = load(p + ivec2(0, -1), wlo), b = load(p + ivec2(0, 1), wlo);
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
    float blur = pc.final_pass != 0u ? BLUR_BETA : BLUR_BETA / 5.0;
    float sum = blur * ao_visibility(c), weight = blur;
    sum += e.x * ao_visibility(l) + e.y * ao_visibility(r) + e.z * ao_visibility(t)
        + e.w * ao_visibility(b);
    weight += e.x + e.y + e.z + e.w;
    sum += w_tl * ao_visibility(load(p + ivec2(-1, -1), wlo))
        + w_tr * ao_visibility(load(p + ivec2(1, -1), wlo))
        + w_bl * ao_visibility(load(p + ivec2(-1, 1), wlo))
        + w_br * ao_visibility(load(p + ivec2(1, 1), wlo));
    weight += w_tl + w_tr + w_bl + w_br;
    float v = sum / weight;
    if (pc.final_pass == 0u || pc.scale > 1u) {  // into the other working image
        uint packed = ao_pack(v, c >> 16);
        if (pc.read_mid != 0u) imageStore(ao_raw, AO_AT(p), uvec4(packed));
        else imageStore(ao_mid, AO_AT(p), uvec4(packed));
    } else {
        bool background = texelFetch(depth_map, AO_AT(p), 0).r <= 0.0;
        imageStore(ao_out, AO_AT(p), vec4(background ? 1.0 : v, 0.0, 0.0, 0.0));
    }
}
