#version 450
// ao_denoise.comp: a pass of XeGTAO's spatial denoise (shaders/ao_denoise.glsl), a working
// pixel an invocation. It runs on the working images (at 1 / scale of the frame's size):
// passes write the other working image, edges kept (ao_raw -> ao_mid -> ao_raw ...), except
// the last at full resolution, which writes the visibility the shading reads (ao_out;
// background pixels get 1). At half resolution ao_upsample.comp makes ao_out from the last
// pass's image (or runs the last pass itself: render/ao.py fuses it there).
#extension GL_GOOGLE_include_directive : require
#include "ao_denoise.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);  // a working pixel
    uint view;
    ivec2 lo, wlo;
    if (any(greaterThanEqual(p, imageSize(ao_raw).xy)) || !ao_work_view(p, view, wlo, lo)) return;
    uint c;
    float v = ao_denoise(p, wlo, pc.final_pass != 0u, c);
    if (pc.final_pass == 0u || pc.scale > 1u) {  // into the other working image
        uint packed = ao_pack(v, c >> 16);
        if (pc.read_mid != 0u) imageStore(ao_raw, AO_AT(p), uvec4(packed));
        else imageStore(ao_mid, AO_AT(p), uvec4(packed));
    } else {
        bool background = isinf(ao_view_z(p, lo));  // (scale 1: p is the frame's pixel)
        imageStore(ao_out, AO_AT(p), vec4(background ? 1.0 : v, 0.0, 0.0, 0.0));
    }
}
