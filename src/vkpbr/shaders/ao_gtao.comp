#version 450
// ao_gtao.comp: ground-truth ambient occlusion (Jimenez et al. 2016, "Practical Real-Time
// Strategies for Accurate Indirect Occlusion") as XeGTAO computes it (XeGTAO_MainPass, MIT,
// Intel): per pixel, `slices` directions in the screen, each searched `steps` samples to a side
// for the highest horizon within the effect radius, and the cosine-weighted visible arc
// between the two horizons integrated analytically about the normal projected into the
// slice, on the working pixels (render/ao.py PRESETS: at half resolution, the top-left pixel
// of each 2 x 2 block; ao_upsample.comp brings it back). The view-space normal is made from
// the full-resolution view-space depth in place
// (XE_GTAO_GENERATE_NORMALS_INPLACE: of the four neighbour pairs, those not across a depth
// edge), so one kernel serves every frame path. Slice angles and sample offsets are jittered
// by a 64x64 Hilbert-curve R2 sequence (XeGTAO's spatio-temporal noise at frame 0), which the
// denoise (ao_denoise.comp) averages away. The result is the visibility, 1 unoccluded; with
// the depth edges it is packed into ao_raw. Depths come from ao_prefilter.comp's MIPs of the
// view-space depth: the pixel and its neighbours from level 0 (the depth buffer's own values),
// the samples far along a slice from coarser levels (XeGTAO's choice: the far samples of
// neighbouring pixels scatter over the frame, and a coarse level keeps them in a few cache
// lines). The final value's power is 1 (XeGTAO's default 2.2
// is a look, not the integral: tests/gpu/test_ao.py checks this one against ray casting).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "ao_common.glsl"

// The preset's slices and samples a side, fixed at build time (render/codegen.py builds one
// kernel per preset, as XeGTAO does): the loops unroll, so that a pixel's samples are all
// fetched before their results are needed (a loop over push constants waited on each pair).
#ifndef AO_SLICES
#define AO_SLICES 3
#endif
#ifndef AO_STEPS
#define AO_STEPS 3
#endif
const uint SLICES = AO_SLICES, STEPS = AO_STEPS;

const float PI = 3.14159265358979;
const float PI_HALF = 1.57079632679490;

// XeGTAO_CalculateEdges: 1 where the neighbour continues the centre's surface, 0 across an
// edge (its depth differs by more than about 1.1% of the centre's beyond the slope).
vec4 calculate_edges(float z, float l, float r, float t, float b) {
    vec4 e = vec4(l, r, t, b) - z;
    float slope_lr = (e.y - e.x) * 0.5;
    float slope_tb = (e.w - e.z) * 0.5;
    vec4 adjusted = e + vec4(slope_lr, -slope_lr, slope_tb, -slope_tb);
    e = min(abs(e), abs(adjusted));
    return clamp(1.25 - e / (z * 0.011), 0.0, 1.0);
}

uint pack_edges(vec4 e) {  // XeGTAO_PackEdges: 2 bits an edge
    uvec4 q = uvec4(round(clamp(e, 0.0, 1.0) * 2.9));
    return (q.x << 6) | (q.y << 4) | (q.z << 2) | q.w;
}

vec3 safe_normalize(vec3 v) {
    float l2 = dot(v, v);
    return l2 > 1e-30 ? v * inversesqrt(l2) : vec3(0.0);
}

// XeGTAO_CalculateNormal: the neighbour pairs' cross products, weighted by their edges.
vec3 calculate_normal(vec4 e, vec3 c, vec3 l, vec3 r, vec3 t, vec3 b) {
    vec4 accepted = clamp(vec4(e.x * e.z, e.z * e.y, e.y * e.w, e.w * e.x) + 0.01, 0.0, 1.0);
    l = safe_normalize(l - c);
    r = safe_normalize(r - c);
    t = safe_normalize(t - c);
    b = safe_normalize(b - c);
    vec3 n = accepted.x * cross(l, t) + accepted.y * cross(t, r) + accepted.z * cross(r, b)
        + accepted.w * cross(b, l);
    return safe_normalize(n);
}

uint hilbert_index(uint x, uint y) {  // XeGTAO's HilbertIndex, 64 x 64
    uint index = 0u;
    for (uint level = 32u; level > 0u; level /= 2u) {
        uint rx = (x & level) > 0u ? 1u : 0u;
        uint ry = (y & level) > 0u ? 1u : 0u;
        index += level * level * ((3u * rx) ^ ry);
        if (ry == 0u) {
            if (rx == 1u) { x = 63u - x; y = 63u - y; }
            uint tmp = x; x = y; y = tmp;
        }
    }
    return index;
}

float fast_acos(float x) {  // XeGTAO_FastACos (Lagarde), [-1, 1] -> [0, pi]
    float a = abs(x);
    float res = (-0.156583 * a + PI_HALF) * sqrt(max(1.0 - a, 0.0));
    return x >= 0.0 ? res : PI - res;
}

// The view-space depth at pixel p of the tile whose first pixel is lo (p in it) from `level`
// of the depth MIPs (ao_prefilter.comp).
float mip_z(ivec2 p, ivec2 lo, int level) {
    return texelFetch(depth_mips, AO_AT((ao_mip_base(lo) + p - lo) >> level), level).r;
}

// The depth at a sample, as a view-space point; `inside`: whether the sample is in the tile
// (one outside is unknown: it gets no weight, as a sample beyond the radius. Clamped to the
// border, as a clamping sampler would, it sat beside the slice, not in it, and on a plane
// receding past the frame's edge made a horizon higher than the plane's: false occlusion).
vec3 sample_pos(ivec2 p, ivec2 lo, int level, vec4 intr, out bool inside) {
    ivec2 q = ao_clamp(p, lo);
    inside = q == p;
    return ao_view_pos(vec2(q - lo) + 0.5, mip_z(q, lo, level), intr);
}

float gtao(ivec2 p, ivec2 lo, uvec2 tile_p, vec3 center, vec3 n, vec4 intr) {
    vec3 view_vec = normalize(-center);
    // World radius in pixels at this depth: sx * size.x / 2 pixels a unit of x / z.
    float px_per_unit = intr.x * float(pc.tile_w) * 0.5 / center.z;
    float screen_radius = pc.radius * px_per_unit;
    float visibility = clamp((10.0 - screen_radius) / 100.0, 0.0, 1.0) * 0.5;
    float falloff_range = max(pc.falloff * pc.radius, 1e-6 * pc.radius);
    float falloff_mul = -1.0 / falloff_range;
    float falloff_add = pc.radius * (1.0 - pc.falloff) / falloff_range + 1.0;
    const float too_close = 1.3;  // pixels: samples nearer than this are pushed out
    float min_s = too_close / screen_radius;
    vec2 noise = fract(0.5 + float(hilbert_index(tile_p.x % 64u, tile_p.y % 64u))
                       * vec2(0.75487766624669276005, 0.5698402909980532659114));
    const float slices = float(SLICES), steps = float(STEPS);
    [[unroll]] for (uint slice = 0u; slice < SLICES; ++slice) {
        float phi = (float(slice) + noise.x) / slices * PI;
        vec2 omega = vec2(cos(phi), -sin(phi)) * screen_radius;  // pixels
        vec3 dir = vec3(cos(phi), sin(phi), 0.0);
        vec3 ortho = dir - dot(dir, view_vec) * view_vec;
        vec3 axis = normalize(cross(ortho, view_vec));
        vec3 proj_n = n - axis * dot(n, axis);
        float sign_n = sign(dot(ortho, proj_n));
        float proj_len = length(proj_n);
        float cos_n = clamp(dot(proj_n, view_vec) / max(proj_len, 1e-8), 0.0, 1.0);
        float nn = sign_n * fast_acos(cos_n);
        float low0 = cos(nn + PI_HALF), low1 = cos(nn - PI_HALF);
        float h0c = low0, h1c = low1;
        [[unroll]] for (uint step = 0u; step < STEPS; ++step) {
            float step_noise = fract(noise.y + float(slice + step * STEPS) * 0.6180339887498948);
            float s = (float(step) + step_noise) / steps;
            s = s * s + min_s;  // XeGTAO's sample distribution power 2: more samples near
            vec2 offset = s * omega;
            // The MIP level it reads: log2(len) - pc.mip_offset, rounded (XeGTAO's
            // DepthMIPSamplingOffset, 3.3: render/ao.py MIP_OFFSET; its point-sampled
            // SampleLevel): level 0 within 13.9 pixels, 1 to 27.9, 2 to 55.7, 3 to 111, 4 beyond.
            int level = clamp(int(floor(log2(length(offset)) - pc.mip_offset + 0.5)), 0,
                              AO_MIPS - 1);
            offset = round(offset);
            bool in0, in1;
            vec3 d0 = sample_pos(p + ivec2(offset), lo, level, intr, in0) - center;
            vec3 d1 = sample_pos(p - ivec2(offset), lo, level, intr, in1) - center;
            float l0 = length(d0), l1 = length(d1);
            float w0 = in0 ? clamp(l0 * falloff_mul + falloff_add, 0.0, 1.0) : 0.0;
            float w1 = in1 ? clamp(l1 * falloff_mul + falloff_add, 0.0, 1.0) : 0.0;
            float shc0 = l0 > 0.0 ? dot(d0 / l0, view_vec) : low0;
            float shc1 = l1 > 0.0 ? dot(d1 / l1, view_vec) : low1;
            h0c = max(h0c, mix(low0, shc0, w0));
            h1c = max(h1c, mix(low1, shc1, w1));
        }
        proj_len = mix(proj_len, 1.0, 0.05);  // XeGTAO's fudge for high slopes
        float h0 = -fast_acos(h1c);
        float h1 = fast_acos(h0c);
        float iarc0 = (cos_n + 2.0 * h0 * sin(nn) - cos(2.0 * h0 - nn)) / 4.0;
        float iarc1 = (cos_n + 2.0 * h1 * sin(nn) - cos(2.0 * h1 - nn)) / 4.0;
        visibility += proj_len * (iarc0 + iarc1);
    }
    return max(visibility / slices, 0.03);
}

float neighbour_z(ivec2 p, ivec2 lo) {
    return mip_z(ao_clamp(p, lo), lo, 0);
}

void main() {
    ivec2 wp = ivec2(gl_GlobalInvocationID.xy);  // the working pixel
    uint view;
    ivec2 wlo, lo;
    if (any(greaterThanEqual(wp, imageSize(ao_raw).xy)) || !ao_work_view(wp, view, wlo, lo)) return;
    ivec2 p = ao_frame_pixel(wp, wlo, lo);  // the frame's pixel it stands for
    vec4 intr = views[view].intrinsics;
    float z = neighbour_z(p, lo);  // (p is in its tile)
    if (z >= AO_FAR) {  // nothing drawn: unoccluded, an edge all round
        imageStore(ao_raw, AO_AT(wp), uvec4(ao_pack(1.0, 0u)));
        return;
    }
    float zl = neighbour_z(p + ivec2(-1, 0), lo);
    float zr = neighbour_z(p + ivec2(1, 0), lo);
    float zt = neighbour_z(p + ivec2(0, -1), lo);
    float zb = neighbour_z(p + ivec2(0, 1), lo);
    vec4 edges = calculate_edges(z, zl, zr, zt, zb);
    // The tile's border is an edge: the denoise never mixes in another view.
    ivec2 q = p - lo;
    vec4 inside = vec4(q.x > 0, q.x < int(pc.tile_w) - 1, q.y > 0, q.y < int(pc.tile_h) - 1);
    edges *= inside;
    vec2 pix = vec2(q) + 0.5;
    vec3 c = ao_view_pos(pix, z, intr);
    // A neighbour past the border is the pixel itself (its depth, its position): a zero
    // vector, no part in the normal (XeGTAO's 0.01 floor would let a wrong point in).
    vec3 n = calculate_normal(edges, c, ao_view_pos(pix + vec2(-inside.x, 0), zl, intr),
                              ao_view_pos(pix + vec2(inside.y, 0), zr, intr),
                              ao_view_pos(pix + vec2(0, -inside.z), zt, intr),
                              ao_view_pos(pix + vec2(0, inside.w), zb, intr));
    if (dot(n, c) > 0.0) n = -n;  // facing the eye
    if (pc.scale > 1u) {
        // The denoise's edges at half resolution: to the neighbouring working pixels' frame
        // pixels (scale apart; past the working tile's border, an edge).
        int s = int(pc.scale);
        ivec2 wq = wp - wlo, wt = ao_work_tile();
        edges = calculate_edges(z, neighbour_z(p + ivec2(-s, 0), lo),
                                neighbour_z(p + ivec2(s, 0), lo),
                                neighbour_z(p + ivec2(0, -s), lo),
                                neighbour_z(p + ivec2(0, s), lo))
            * vec4(wq.x > 0, wq.x < wt.x - 1, wq.y > 0, wq.y < wt.y - 1);
    }
    // Nudged towards the eye against depth imprecision (XeGTAO's 0.99999 for 32-bit depths).
    vec3 center = ao_view_pos(pix, z * 0.99999, intr);
    float v = dot(n, n) > 0.0 ? gtao(p, lo, uvec2(wp - wlo), center, n, intr) : 1.0;
    imageStore(ao_raw, AO_AT(wp), uvec4(ao_pack(v, pack_edges(edges))));
}
