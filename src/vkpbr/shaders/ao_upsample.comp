#version 450
// ao_upsample.comp: the full-resolution visibility (ao_out) from GTAO at half resolution
// (render/ao.py, pc.scale 2), a frame pixel an invocation. Working pixel w holds the GTAO of
// the frame pixel 2w (the top-left of its 2 x 2 block), so a frame pixel lies on one working
// pixel (even row and column), between two or among four. Their visibilities are blended
// bilinearly, each weighted by how close its pixel's depth is to this pixel's (a bilateral
// upsample, as half-resolution SSAO is usually brought back: the pixel takes the values of
// its own surface, never those across a depth edge). Where no neighbour is of its surface
// (a feature thinner than a block) it takes the nearest in depth; background pixels get 1.
// With pc.fused the last denoise pass runs here, on each working pixel it blends (one
// dispatch and one barrier fewer, and no write and read of the working image between; the
// 2 x 2 working pixels' 4 x 4 neighbourhood loaded once: render/ao.py AoImages.fuse).
#extension GL_GOOGLE_include_directive : require
#include "ao_denoise.glsl"

// A neighbour's weight falls to a half where its depth differs from the pixel's by this
// share of the pixel's (surfaces continue within a pixel by far less, except at grazing
// angles, where every neighbour is down-weighted alike).
const float DEPTH_SHARE = 0.02;

// The visibility at frame pixel p (its view-axis distance z) from the 2 x 2 working pixels
// around it (`v`, `wz`: their visibilities and their frame pixels' distances, x first; the
// pixel lies on the first, between it and the next or among all four): its bilinear weights
// (f: 0 on a working pixel, 0.5 between two), each times the depth weight.
float upsample(vec2 f, float z, vec4 v, vec4 wz) {
    float sum = 0.0, weight = 0.0, nearest = 1.0, nearest_dz = 1.0 / 0.0;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            float bilinear = (i == 0 ? 1.0 - f.x : f.x) * (j == 0 ? 1.0 - f.y : f.y);
            if (bilinear == 0.0) continue;
            float dz = abs(wz[j * 2 + i] - z);  // inf: none
            float r = dz / (DEPTH_SHARE * z);
            float wgt = bilinear / (1.0 + r * r);
            sum += wgt * v[j * 2 + i];
            weight += wgt;
            if (dz < nearest_dz) { nearest_dz = dz; nearest = v[j * 2 + i]; }
        }
    }
    return weight > 1e-6 ? sum / weight : nearest;
}

// An invocation a working pixel: the 2 x 2 frame pixels of its block, which all blend the
// same 2 x 2 working pixels (each loaded, and with pc.fused denoised, once for the four).
void main() {
    ivec2 wp = ivec2(gl_GlobalInvocationID.xy);  // a working pixel
    uint view;
    ivec2 wlo, lo;
    if (any(greaterThanEqual(wp, imageSize(ao_raw).xy)) || !ao_work_view(wp, view, wlo, lo)) return;
    ivec2 wt = ao_work_tile();
    vec4 v, wz;
    // (with pc.fused, the last denoise pass here: no pass of its own)
    if (pc.fused != 0u) v = ao_denoise_block(wp, wlo);
    for (int k = 0; k < 4; ++k) {
        ivec2 w = wlo + min(wp - wlo + ivec2(k & 1, k >> 1), wt - 1);
        if (pc.fused == 0u) {
            v[k] = ao_visibility(pc.read_mid != 0u ? imageLoad(ao_mid, AO_AT(w)).r
                                                   : imageLoad(ao_raw, AO_AT(w)).r);
        }
        wz[k] = ao_view_z(ao_frame_pixel(w, wlo, lo), lo);
    }
    ivec2 first = lo + (wp - wlo) * 2, hi = lo + ivec2(pc.tile_w, pc.tile_h);
    for (int k = 0; k < 4; ++k) {
        ivec2 d = ivec2(k & 1, k >> 1), p = first + d;
        if (any(greaterThanEqual(p, hi))) continue;  // (the last block of an odd size)
        float z = ao_view_z(p, lo);
        float out_v = isinf(z) ? 1.0 : upsample(vec2(d) * 0.5, z, v, wz);
        imageStore(ao_out, AO_AT(p), vec4(out_v, 0.0, 0.0, 0.0));
    }
}
