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
// dispatch and one barrier fewer, and no write and read of the working image between, for
// 2.25 denoises a pixel instead of a quarter of one: render/ao.py FUSE).
#extension GL_GOOGLE_include_directive : require
#include "ao_denoise.glsl"

// A neighbour's weight falls to a half where its depth differs from the pixel's by this
// share of the pixel's (surfaces continue within a pixel by far less, except at grazing
// angles, where every neighbour is down-weighted alike).
const float DEPTH_SHARE = 0.02;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    uint view;
    ivec2 lo;
    if (any(greaterThanEqual(p, imageSize(ao_out).xy)) || !ao_view(p, view, lo)) return;
    float znear = views[view].eye_near.w;
    float z = ao_view_z(p, znear);
    if (isinf(z)) {
        imageStore(ao_out, AO_AT(p), vec4(1.0, 0.0, 0.0, 0.0));
        return;
    }
    ivec2 q = p - lo;
    ivec2 wt = ao_work_tile();
    ivec2 wlo = (lo / ivec2(pc.tile_w, pc.tile_h)) * wt;
    ivec2 base = q >> 1;
    vec2 f = vec2(q & 1) * 0.5;  // 0 on a working pixel, 0.5 between two
    float sum = 0.0, weight = 0.0, nearest = 1.0, nearest_dz = 1.0 / 0.0;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            float bilinear = (i == 0 ? 1.0 - f.x : f.x) * (j == 0 ? 1.0 - f.y : f.y);
            if (bilinear == 0.0) continue;
            ivec2 w = wlo + min(base + ivec2(i, j), wt - 1);
            float v;
            if (pc.fused != 0u) {  // the last denoise pass here (no pass of its own)
                uint centre;
                v = ao_denoise(w, wlo, true, centre);
            } else {
                v = ao_visibility(pc.read_mid != 0u ? imageLoad(ao_mid, AO_AT(w)).r
                                                    : imageLoad(ao_raw, AO_AT(w)).r);
            }
            float dz = abs(ao_view_z(ao_frame_pixel(w, wlo, lo), znear) - z);  // inf: none
            float r = dz / (DEPTH_SHARE * z);
            float wgt = bilinear / (1.0 + r * r);
            sum += wgt * v;
            weight += wgt;
            if (dz < nearest_dz) { nearest_dz = dz; nearest = v; }
        }
    }
    float v = weight > 1e-6 ? sum / weight : nearest;
    imageStore(ao_out, AO_AT(p), vec4(v, 0.0, 0.0, 0.0));
}
