#version 450
// ao_prefilter.comp: XeGTAO's depth prefilter (XeGTAO_PrefilterDepths16x16, MIT, Intel): the
// frame's view-space depth (level 0: znear / depth, exactly what the main pass computed from
// the depth buffer before) and 4 coarser MIP levels, in one dispatch: an invocation takes a
// 2 x 2 block of pixels (one gather), a work group 16 x 16, levels 2 to 4 made through
// shared memory. ao_gtao.comp reads its far samples from the coarser levels (fewer cache lines for
// the samples far along a slice, the main pass's cost). A coarser texel is XeGTAO's weighted
// average of its four children (XeGTAO_DepthMIPFilter): a child nearer than the farthest by
// more than 0.75 of the search radius gets no weight (an occluder in front does not pull a
// texel of the surface behind it towards the eye: the texel keeps the farther surface's
// depth, as XeGTAO's, which errs towards less occlusion).
// A compute batch's atlas of views: each tile's levels are made in a block of their own
// (ao_common.glsl ao_mip_base: the tile rounded up to a multiple of 16, so a work group lies
// in one tile), its texels grouping the tile's pixels as a frame's alone (a texel past the
// tile's edge takes only the children inside).
#extension GL_GOOGLE_include_directive : require
#include "ao_common.glsl"
#ifndef AO_DEPTH_BUFFER
#define AO_DEPTH_BUFFER 0
#endif

shared float scratch[8][8];

// The filter over the children present (a weight of 0 for the others; the first, the texel's
// own first pixel's, always is).
float mip_filter(vec4 d, bvec4 present) {
    vec4 z = mix(vec4(0.0), d, present);
    float far = max(max(z.x, z.y), max(z.z, z.w));
    float radius = 0.75 * pc.radius;
    float range = max(pc.falloff * radius, 1e-6 * radius);
    float mul = -1.0 / range, add = radius * (1.0 - pc.falloff) / range + 1.0;
    vec4 w = clamp((far - d) * mul + add, 0.0, 1.0) * vec4(present);
    // far - d is 0 for the farthest child: its weight is 1, the sum never 0. Relative to the
    // farthest, the sum stays finite where children are AO_FAR (nothing drawn).
    return min(far + dot(w, d - far) / dot(w, vec4(1.0)), AO_FAR);
}

// Whether the texel of `level` at c (its first pixel c << level) is in the tile's block
// [base, hi): a level-0 pixel of the MIPs, or past the tile (the block's padding).
bool in_tile(ivec2 c, int level, ivec2 hi) {
    return all(lessThan(c << level, hi));
}

float view_z(float d, bool valid, float znear) {
    return valid && d > 0.0 ? min(znear / d, AO_FAR) : AO_FAR;
}

// The depth buffer's 2 x 2 pixels from p in one fetch (XeGTAO's GatherRed): at the corner
// they share, x first ((x, y) of gather's w, z, x, y components).
// AO_DEPTH_BUFFER = 1: from the compute rasteriser's depths (the same floats the depth image
// would hold after a copy); reads past the buffer's end clamped to its last pixel (like the
// gather's clamped texels, those pixels are past the tile: `present` drops them).
vec4 gather_depths(ivec2 p) {
#if AO_DEPTH_BUFFER
    uint i = uint(p.y) * pc.depth_row + uint(p.x), n = uint(raster_depth.length());
    return vec4(raster_depth[min(i, n - 1u)], raster_depth[min(i + 1u, n - 1u)],
                raster_depth[min(i + pc.depth_row, n - 1u)],
                raster_depth[min(i + pc.depth_row + 1u, n - 1u)]);
#else
    vec2 uv = vec2(p + 1) / vec2(textureSize(depth_map, 0).xy);
#if AO_LAYERED
    vec4 g = textureGather(depth_map, vec3(uv, float(gl_GlobalInvocationID.z)));
#else
    vec4 g = textureGather(depth_map, uv);
#endif
    return g.wzxy;
#endif
}

void main() {
    ivec2 t = ivec2(gl_LocalInvocationID.xy);
    ivec2 c1 = ivec2(gl_GlobalInvocationID.xy);  // this invocation's texel of level 1
    ivec2 m = c1 * 2;  // its first pixel of level 0
    ivec2 size = ivec2(pc.tile_w, pc.tile_h);
    ivec2 tile = m / ao_mip_tile(), base = tile * ao_mip_tile();
    ivec2 p = tile * size + (m - base);  // the frame's (the atlas's) pixel of m
    uint index = uint(tile.x) * pc.rows + uint(tile.y), view = ao_view_of(index);
    bool valid = uint(tile.y) < pc.rows && index < pc.views && all(lessThan(m - base, size));
    float znear = views[valid ? view : pc.first_view].eye_near.w;
    ivec2 hi = base + size;
    bvec4 present = bvec4(true, in_tile(m + ivec2(1, 0), 0, hi), in_tile(m + ivec2(0, 1), 0, hi),
                          in_tile(m + ivec2(1, 1), 0, hi));
    vec4 g = gather_depths(p);
    vec4 d = vec4(view_z(g.x, valid, znear), view_z(g.y, valid && present.y, znear),
                  view_z(g.z, valid && present.z, znear), view_z(g.w, valid && present.w, znear));
    imageStore(depth_mip0, AO_AT(m), vec4(d.x));
    imageStore(depth_mip0, AO_AT(m + ivec2(1, 0)), vec4(d.y));
    imageStore(depth_mip0, AO_AT(m + ivec2(0, 1)), vec4(d.z));
    imageStore(depth_mip0, AO_AT(m + ivec2(1, 1)), vec4(d.w));
    float mean = mip_filter(d, present);
    imageStore(depth_mip1, AO_AT(c1), vec4(mean));
    scratch[t.x][t.y] = mean;
    // Levels 2 to 4: the invocations at multiples of 2, 4, 8 of the group take the 2 x 2 of
    // the level above from shared memory (their children: stride / 2 apart).
    for (int level = 2; level < AO_MIPS; ++level) {
        barrier();
        int stride = 1 << (level - 1), half_stride = stride >> 1;
        bool takes = all(equal(t % stride, ivec2(0)));
        if (takes) {
            ivec2 c = c1 >> (level - 1);  // the texel of `level`
            ivec2 child = c * 2;  // its first child, of level - 1
            vec4 cd = vec4(scratch[t.x][t.y], scratch[t.x + half_stride][t.y],
                           scratch[t.x][t.y + half_stride],
                           scratch[t.x + half_stride][t.y + half_stride]);
            bvec4 cp = bvec4(true, in_tile(child + ivec2(1, 0), level - 1, hi),
                             in_tile(child + ivec2(0, 1), level - 1, hi),
                             in_tile(child + ivec2(1, 1), level - 1, hi));
            mean = mip_filter(cd, cp);
            if (level == 2) imageStore(depth_mip2, AO_AT(c), vec4(mean));
            else if (level == 3) imageStore(depth_mip3, AO_AT(c), vec4(mean));
            else imageStore(depth_mip4, AO_AT(c), vec4(mean));
        }
        barrier();
        if (takes) scratch[t.x][t.y] = mean;
    }
}
