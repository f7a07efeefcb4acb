#version 450
// raster.comp: the compute rasteriser (render/compute_path.py, `raster="compute"`): the
// compute path's visibility buffer made on all SMs instead of the few that rasterise. Every
// covered pixel centre takes one 64-bit atomicMax of (reversed depth bits << 32 | triangle +
// 1) in `raster` (depth >= 0, so its float bits order as the depths: the nearest wins, and on
// a tie the later triangle, as GREATER_OR_EQUAL does for later draws). Triangles are clipped
// to the near and far planes (z <= w, z >= 0: the shading re-intersects the pixel's ray with
// the whole triangle, so only coverage and depth come from here). No plain load guards the
// atomic: on the H200 that "skip when nearer is stored" test cost more (1.57 -> 2.13 ms at
// 1080p) than the atomics it saved.
// KERNEL 1 (raster_small): one invocation a triangle of the opaque draws; triangles whose
//   screen box exceeds pc.big_area pixels are listed in raster_big instead, one entry for
//   each band of rows of about pc.big_chunk box pixels (a wall filling the screen is ~130
//   work groups' work, not one). Each row is covered where its edges' spans allow.
// KERNEL 4 (raster_args): one invocation: raster_big's dispatch size for KERNEL 2.
// KERNEL 2 (raster_big): one work group a listed band, set up once, its rows over the subgroups.
// KERNEL 5 (raster_masked): one invocation a triangle of one masked draw (alpha masking on),
//   with its material's set 1 bound; its triangles over pc.masked_area box pixels are listed
//   in the draw's segment of raster_masked_big, a band of about pc.masked_chunk box pixels an
//   entry (what does not fit: by the whole group afterwards). A pixel is covered where the
//   surface's base-colour alpha (surface_fetch.glsl + shade.glsl, exactly as the shading
//   samples it) reaches the cutoff;
//   pixels where a nearer surface is already stored skip that test (a plain load: the opaque
//   draws are done; unlike the opaque atomics, the alpha test costs more than the load).
// KERNEL 6 (raster_masked_big): one work group an entry of one masked draw's segment (an
//   indirect dispatch a masked draw, its set 1 bound, after every draw's KERNEL 5).
// KERNEL 3 (raster_resolve): per pixel, the visibility image's (draw + 1, primitive) from the
//   winning triangle (0: nothing, and the clear colour) -- what shade.comp and classify.comp
//   read -- counted in its material's bin (bin_tiles.glsl: classify.comp's count), and its depth
//   into raster_depths (copied into the depth buffer: a copy, where a screen-filling
//   fragment pass writing gl_FragDepth cost 0.30 ms at 1080p on the H200's few raster SMs).
// KERNEL 7 (raster_clear): invocation i zeroes element i of raster and of the bins, and of
//   the lists' heads (raster_big's count and dispatch size, each masked segment's): what is
//   read before it is written (a list's entries are written below its count first; clearing
//   the whole lists had cost Sponza 5.6 MB of writes a frame at 1080p). A kernel, not vkCmdFillBuffer,
//   so that what follows waits for shaders only, not for the frame before's readback copy
//   (gpu/graph.py: validation layers before 1.3.275 count a fill as a copy).
// BATCH = 1 (render/batch_path.py's compute batch): `views` views tiled `rows` to a column in
// one atlas (column-major, so a column of tiles is one copy into view-major memory), each `tile` pixels, each with its view's VP; the work's z index is the view.
// One view (BATCH 0) is the same with the frame's view and the whole target as the tile.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#if KERNEL == 3  // the resolve's material bins (bin_tiles.glsl)
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_shuffle : require
#endif
#define RASTER_INT64 1  // generated.glsl declares the 64-bit buffer
#include "generated.glsl"
#include "frustum.glsl"
#include "raster_clip.glsl"
#if KERNEL == 3
#include "brdf.glsl"  // stored_color
#define TILE_COUNTER x
#include "bin_tiles.glsl"
#endif

#define ALPHA_TESTED (KERNEL == 5 || KERNEL == 6)  // masked draws, their material bound
#if KERNEL == 2 || KERNEL == 6
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;  // 256 invocations
#elif KERNEL == 3
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;  // compute_path.CLASSIFY_GROUP
#elif KERNEL == 4
layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;
#elif KERNEL == 7
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;  // compute_path.CLEAR_GROUP
#elif KERNEL == 5
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;  // compute_path.RASTER_SMALL_GROUP
#else
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;  // compute_path.RASTER_SMALL_GROUP
#endif

layout(push_constant) uniform Raster {
    uint triangles;  // over every draw, in the order below (raster_draws[k].x: row k's first)
    uint draws;
    uint alpha_mask;  // 1: masked materials are left to the visibility pass's mask draws
    uint big_capacity;  // entries raster_big's list holds (from BIG_LIST on)
    uint width;
    uint height;
    uint draw;  // raster_masked: the masked draw's row of raster_draws
    uint material;  // raster_masked: its material (set 1 bound)
    uint views;  // the tiles: views, their width and height, tiles a column of the atlas
    uint tile_w;
    uint tile_h;
    uint rows;
    uint masked_draws;  // raster_masked_big's segments, one a masked draw
    uint segment;  // raster_masked(_big): this masked draw's
    uint masked_capacity;  // entries a segment holds
    // compute_path.RasterTuning (measured on the H200: BENCHMARKS.md): box pixels above
    // which work groups take a triangle, a listed band's box pixels; opaque, then masked.
    uint big_area;
    uint big_chunk;
    uint masked_area;
    uint masked_chunk;
    uint clear_srgb;  // raster_resolve: the colour target stores sRGB (encode the clear colour)
    vec4 clear_color;  // raster_resolve: linear, where nothing covers a pixel
} pc;

#if ALPHA_TESTED
#define MATERIAL_INDEX pc.material
#include "surface_fetch.glsl"
#endif


// raster_big: [0] the count, [1..3] KERNEL 2's dispatch size (indirect), from 4 the list of
// (triangle, view, chunk) entries.
const uint BIG_LIST = 4u, BIG_ENTRY = 3u;
// raster_masked_big: per masked draw m, [4m] its entries' count, [4m+1..4m+3] KERNEL 6's
// dispatch size (indirect); from 4 * pc.masked_draws on, each draw's segment of
// pc.masked_capacity (triangle, view, chunk) entries.
const uint MAX_GROUPS = 65535u;  // maxComputeWorkGroupCount[0] of every device
const uint DOUBLE_SIDED = 1u, MASKED = 2u, BLENDED = 4u;  // raster_draws[k].y (compute_path.py)
// raster_draws' rows follow the raster units' submission order (the opaque pass's draws, the
// two-sided pass's, the masked ones; each in draw order), .z the row's draw: so that a tie in
// depth goes to the later triangle in that order, as GREATER_OR_EQUAL gives it to the later
// draw (coincident surfaces pick what the fragment path picks).

// The draw holding triangle g: the last k whose first triangle is <= g (draws in order).
uint draw_of(uint g) {
    uint lo = 0u, hi = pc.draws;
    for (uint step = 0u; step < 32u && hi - lo > 1u; ++step) {
        uint mid = (lo + hi) >> 1u;
        if (raster_draws[mid].x <= g) lo = mid; else hi = mid;
    }
    return lo;
}

#if KERNEL == 5
shared uint group_big[64];  // this group's big triangles not listed (raster_masked)
shared uint group_big_count;
#endif
#if ALPHA_TESTED
uint masked_entry(uint segment, uint k) {
    return 4u * pc.masked_draws + BIG_ENTRY * (segment * pc.masked_capacity + k);
}
#endif

#if KERNEL != 3
vec3 position(uint i) { uint k = 3u * i; return vec3(positions[k], positions[k + 1u], positions[k + 2u]); }

// Triangle g's clip-space corners; false when its draw is not rasterised here.
bool fetch(uint g, out vec4 c[3], out bool double_sided) {
#if ALPHA_TESTED
    uint k = pc.draw;  // this dispatch's masked draw's row: always drawn
#else
    uint k = draw_of(g);
#endif
    uvec4 rd = raster_draws[k];
    double_sided = (rd.y & DOUBLE_SIDED) != 0u;
#if !ALPHA_TESTED
    if ((rd.y & BLENDED) != 0u || ((rd.y & MASKED) != 0u && pc.alpha_mask != 0u)) return false;
#endif
    // The draw's bounding sphere outside the view: none of its triangles is seen (one test
    // instead of three vertices; most of a scene's draws, for most of a batch's views).
    mat4 model = instance_matrices[2u * (views[view_index].instance_base + rd.z)];
    // A hidden draw (the scene state's zero matrix): its vertices would all be (0, 0, 0, 0),
    // whose division by w = 0 a GPU turns into pixel (0, 0)'s coverage.
    if (model[3][3] == 0.0) return false;
    if (!sphere_visible(views[view_index].VP, world_sphere(model, raster_spheres[rd.z]))) return false;
    DrawRecord dr = draws[rd.z];
    uint base = dr.info.x + 3u * (g - rd.x);
    for (int j = 0; j < 3; ++j) {
        uint v = indices[base + uint(j)] + dr.info.y;
        c[j] = views[view_index].VP * (model * vec4(position(v), 1.0));  // as pbr.vert's
    }
    return true;
}

// The view's tile: its first pixel in the target and its size.
ivec2 tile_origin() {
#if BATCH
    return ivec2(view_index / pc.rows, view_index % pc.rows) * ivec2(pc.tile_w, pc.tile_h);
#else
    return ivec2(0);
#endif
}

// Position in the view's tile (pixels, y down as the viewport maps it) and depth of a clip
// corner. In the tile, not the atlas: a batch's view is then covered with the very numbers
// its frame alone is (edge functions at the same pixel centres, the same depths), whichever
// tile it lands in; at the atlas's larger coordinates they rounded apart on the H200 (up to
// 9/255 at tile edges, and GTAO's depths 7e-7 apart).
vec3 screen(vec4 c) {
    vec3 ndc = c.xyz / c.w;
    return vec3((ndc.xy * 0.5 + 0.5) * vec2(pc.tile_w, pc.tile_h), ndc.z);
}

// Cover the screen triangle (s0, s1, s2), positive area, in its box [lo, hi): rows y0,
// y0 + ystep, ... below y1, and in each row the candidates (the three edges' span) from the
// span's start + lane on, every `lanes`. A row's span, not its box: a sliver across the
// screen tests its own pixels, not the box's.
void cover(vec3 s0, vec3 s1, vec3 s2, uint id, ivec2 lo, ivec2 hi, int y0, int y1, int ystep,
           int lane, int lanes) {
#if ALPHA_TESTED
    uint draw = raster_draws[pc.draw].z, prim = id - raster_draws[pc.draw].x;
#endif
#if KERNEL == 5
    // A small triangle's surface data fetched once for all its candidate pixels. (Not in
    // raster_masked_big: held across its bands' loops it took 80 -> 128 registers there,
    // 0.127 -> 0.148 ms at 1080p on the H200, where raster_masked went 0.100 -> 0.088.)
    SurfaceTriangle tri = surface_triangle(draw, prim);
#endif
    float area = edge(s0.xy, s1.xy, s2.xy);
    for (int y = y0; y < y1; y += ystep) {
        float py = float(y) + 0.5, xl = float(lo.x), xr = float(hi.x - 1);
        edge_span(s1.xy, s2.xy, py, xl, xr);
        edge_span(s2.xy, s0.xy, py, xl, xr);
        edge_span(s0.xy, s1.xy, py, xl, xr);
        // Clamped as integers: a NaN span (corners at w ~ 0) converts to anything.
        int xa = clamp(int(clamp(xl, float(lo.x), float(hi.x))), lo.x, hi.x) + lane;
        int xb = clamp(int(clamp(xr, float(lo.x - 1), float(hi.x - 1))), lo.x - 1, hi.x - 1);
        for (int x = xa; x <= xb; x += lanes) {
            ivec2 px = ivec2(x, y);
            vec2 p = vec2(px) + 0.5;
            float e0 = edge(s1.xy, s2.xy, p), e1 = edge(s2.xy, s0.xy, p), e2 = edge(s0.xy, s1.xy, p);
            if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) continue;
            float depth = clamp((e0 * s0.z + e1 * s1.z + e2 * s2.z) / area, 0.0, 1.0);
            ivec2 atlas = px + tile_origin();
            uint at = uint(atlas.y) * pc.width + uint(atlas.x);
#if ALPHA_TESTED
            // Nearer already stored (an equal depth loses to this later triangle): no test.
            if (uint(raster[at] >> 32) > floatBitsToUint(depth)) continue;
#if KERNEL == 5
            surface_point(tri, uvec2(px), vec2(pc.tile_w, pc.tile_h));
#else
            surface_point(surface_triangle(draw, prim), uvec2(px), vec2(pc.tile_w, pc.tile_h));
#endif
            if (surface_base_color().a < MAT.alpha_cutoff) continue;  // as pbr.frag's ALPHA_MASK
#endif
            uint64_t packed = (uint64_t(floatBitsToUint(depth)) << 32) | uint64_t(id + 1u);
            atomicMax(raster[at], packed);
        }
    }
}

// A big triangle's box is listed as bands of whole rows of about pc.big_chunk box pixels
// each (pc.masked_chunk for masked draws; at least a row).
#if ALPHA_TESTED
#define CHUNK pc.masked_chunk
#define BIG_AREA pc.masked_area
#else
#define CHUNK pc.big_chunk
#define BIG_AREA pc.big_area
#endif
int chunk_rows(ivec2 lo, ivec2 hi) { return max(1, int(CHUNK) / (hi.x - lo.x)); }

// Which rows of a band and which pixels of each an invocation covers (cover's first row
// after the band's start, ystep, lane, lanes): ALONE, all of them.
struct Share {
    int y_offset, ystep, lane, lanes;
};
const Share ALONE = Share(0, 1, 0, 1);
const uint ALL_CHUNKS = 0xffffffffu;

// Triangle g on the screen: its clipped polygon (at most 5 corners: pixels, depth), the
// polygon's `edge` area (its sign: which way it faces) and its box of pixel centres [lo, hi).
struct Screen {
    vec3 s[5];
    int n;
    float area;
    ivec2 lo, hi;
};

// Triangle g's Screen; false when none of it is drawn: its draw is not rasterised here, it
// is clipped away, degenerate, a back face, or its box holds no pixel centre. Vulkan's front
// faces (counter-clockwise: positive area by its formula, which is minus this `edge` in
// these y-down coordinates) have negative `edge` area here; a single-sided triangle with
// positive area is a back face, culled as the pipelines' cull="back" does.
bool on_screen(uint g, out Screen t) {
    vec4 c[3];
    bool double_sided;
    if (!fetch(g, c, double_sided)) return false;
    if (unclipped(c)) {  // most triangles: no clipping, no arrays indexed at run time
        t.n = 3;
        t.s[0] = screen(c[0]);
        t.s[1] = screen(c[1]);
        t.s[2] = screen(c[2]);
    } else {
        vec4 poly[5];
        t.n = clip(c, poly);
        if (t.n < 3) return false;
        for (int j = 0; j < t.n; ++j) t.s[j] = screen(poly[j]);
    }
    t.area = 0.0;
    for (int j = 1; j + 1 < t.n; ++j) t.area += edge(t.s[0].xy, t.s[j].xy, t.s[j + 1].xy);
    if (t.area == 0.0 || (t.area > 0.0 && !double_sided)) return false;
    vec2 lo2 = t.s[0].xy, hi2 = t.s[0].xy;
    for (int j = 1; j < t.n; ++j) { lo2 = min(lo2, t.s[j].xy); hi2 = max(hi2, t.s[j].xy); }
    // Pixel centres inside the box: from ceil(lo - 0.5) to floor(hi - 0.5), within the tile
    // (tile pixels: cover adds the tile's origin where it stores).
    t.lo = max(ivec2(ceil(lo2 - 0.5)), ivec2(0));
    t.hi = min(ivec2(floor(hi2 - 0.5)) + 1, ivec2(pc.tile_w, pc.tile_h));
    return all(lessThan(t.lo, t.hi));
}

float box_area(Screen t) { return float(t.hi.x - t.lo.x) * float(t.hi.y - t.lo.y); }
uint band_count(Screen t) { int r = chunk_rows(t.lo, t.hi); return uint((t.hi.y - t.lo.y + r - 1) / r); }

// Cover the row bands [chunk0, chunk1) of t's box (chunk_rows rows each) as `share` says:
// its polygon as a fan of screen triangles, each turned to positive `edge` area for cover.
void draw_screen(Screen t, uint g, uint chunk0, uint chunk1, Share share) {
    int rows = chunk_rows(t.lo, t.hi);
    uint chunks = band_count(t);
    int y0 = t.lo.y + int(min(chunk0, chunks)) * rows + share.y_offset;
    int y1 = chunk1 >= chunks ? t.hi.y : t.lo.y + int(chunk1) * rows;
    for (int j = 1; j + 1 < t.n; ++j) {
        vec3 a = t.s[0], b = t.s[j], d = t.s[j + 1];
        if (t.area < 0.0) { vec3 x = b; b = d; d = x; }  // a front face: `cover` wants area > 0
        cover(a, b, d, g, t.lo, t.hi, y0, y1, share.ystep, share.lane, share.lanes);
    }
}

// Triangle g alone: the whole of it by this invocation or the share given.
void raster_triangle(uint g, uint chunk0, uint chunk1, Share share) {
    Screen t;
    if (on_screen(g, t)) draw_screen(t, g, chunk0, chunk1, share);
}

#if KERNEL == 1 || KERNEL == 5
// A big triangle's row bands listed for work groups (raster_big, or this masked draw's
// segment of raster_masked_big), a band an entry.
void list_bands(Screen t, uint g) {
    uint chunks = band_count(t);
#if KERNEL == 5
    // The dispatch size kept at the entries listed; what does not fit is left to the group.
    uint segment = pc.segment;
    uint slot = atomicAdd(raster_masked_big[4u * segment], chunks);
    uint listed = slot < pc.masked_capacity ? min(chunks, pc.masked_capacity - slot) : 0u;
    for (uint c = 0u; c < listed; ++c) {
        uint e = masked_entry(segment, slot + c);
        raster_masked_big[e] = g;
        raster_masked_big[e + 1u] = view_index;
        raster_masked_big[e + 2u] = c;
    }
    if (listed > 0u) atomicMax(raster_masked_big[4u * segment + 1u], slot + listed);
    if (listed < chunks) group_big[atomicAdd(group_big_count, 1u)] = g;  // one an invocation
#else
    // Bands past the list's end (a batch's worst case) are drawn here.
    uint slot = atomicAdd(raster_big[0], chunks);
    uint listed = slot < pc.big_capacity ? min(chunks, pc.big_capacity - slot) : 0u;
    for (uint c = 0u; c < listed; ++c) {
        uint e = BIG_LIST + BIG_ENTRY * (slot + c);
        raster_big[e] = g;
        raster_big[e + 1u] = view_index;
        raster_big[e + 2u] = c;
    }
    if (listed < chunks) draw_screen(t, g, listed, ALL_CHUNKS, ALONE);
#endif
}

// One triangle an invocation: drawn alone where its box is at most BIG_AREA pixels, else
// listed in row bands for work groups.
void raster_one(uint g) {
    Screen t;
    if (!on_screen(g, t)) return;
    if (box_area(t) > float(BIG_AREA)) list_bands(t, g);
    else draw_screen(t, g, 0u, ALL_CHUNKS, ALONE);
}
#endif

// A work group's share: its subgroups take rows in turn, a subgroup's invocations the
// pixels of its row.
Share group_share() {
    return Share(int(gl_SubgroupID), int(gl_NumSubgroups), int(gl_SubgroupInvocationID),
                 int(gl_SubgroupSize));
}

#if KERNEL == 2 || KERNEL == 6
shared Screen entry_screen;  // the work group's entry, set up once
shared bool entry_drawn;

// One listed band (`chunk`) of triangle g by the whole work group: its first invocation sets
// the triangle up (fetch, transform, clip) for all of them.
void raster_entry(uint g, uint chunk) {
    if (gl_LocalInvocationIndex == 0u) {
        Screen t;
        entry_drawn = on_screen(g, t);
        entry_screen = t;
    }
    barrier();
    Screen t = entry_screen;
    bool drawn = entry_drawn;
    barrier();  // read before the next entry's set-up
    if (drawn) draw_screen(t, g, chunk, chunk + 1u, group_share());
}
#endif
#endif

void main() {
#if BATCH
    view_index = KERNEL == 2 || KERNEL == 6 ? 0u : gl_GlobalInvocationID.z;
#endif
#if KERNEL == 1
    uint g = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    if (g < pc.triangles) raster_one(g);
#elif KERNEL == 7
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u;
    if (i < uint(raster.length())) raster[i] = 0ul;
    if (i < BIG_LIST) raster_big[i] = 0u;
    if (i < 4u * pc.masked_draws) raster_masked_big[i] = 0u;
    if (i < uint(bins.length())) bins[i] = uvec4(0u);
#elif KERNEL == 5
    uint first = raster_draws[pc.draw].x;
    uint count = (pc.draw + 1u < pc.draws ? raster_draws[pc.draw + 1u].x : pc.triangles) - first;
    uint t = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    opaque_zero = 0u;  // shade.glsl's leak guard: a plain 0 here (no uniform block is read)
    if (gl_LocalInvocationIndex == 0u) group_big_count = 0u;
    barrier();
    if (t < count) raster_one(first + t);
    barrier();
    for (uint k = 0u; k < group_big_count; ++k)
        raster_triangle(group_big[k], 0u, ALL_CHUNKS, group_share());
#elif KERNEL == 4
    raster_big[1] = max(min(raster_big[0], MAX_GROUPS), 1u);
    raster_big[2] = 1u;
    raster_big[3] = 1u;
    for (uint m = 0u; m < pc.masked_draws; ++m) {  // (0, 1, 1): raster_masked counts x up
        raster_masked_big[4u * m + 2u] = 1u;
        raster_masked_big[4u * m + 3u] = 1u;
    }
#elif KERNEL == 6
    opaque_zero = 0u;  // shade.glsl's leak guard: a plain 0 here (no uniform block is read)
    uint listed = min(raster_masked_big[4u * pc.segment], pc.masked_capacity);
    for (uint k = gl_WorkGroupID.x; k < listed; k += gl_NumWorkGroups.x) {
        uint e = masked_entry(pc.segment, k);
#if BATCH
        view_index = raster_masked_big[e + 1u];
#endif
        uint chunk = raster_masked_big[e + 2u];
        raster_entry(raster_masked_big[e], chunk);
    }
#elif KERNEL == 2
    uint listed = min(raster_big[0], pc.big_capacity);
    for (uint k = gl_WorkGroupID.x; k < listed; k += gl_NumWorkGroups.x) {
        uint e = BIG_LIST + BIG_ENTRY * k;
#if BATCH
        view_index = raster_big[e + 1u];
#endif
        uint chunk = raster_big[e + 2u];
        raster_entry(raster_big[e], chunk);
    }
#else
    uvec2 p = gl_GlobalInvocationID.xy;
    uvec2 vis = uvec2(0u);
    if (p.x < pc.width && p.y < pc.height) {  // (no return: the tile's barriers follow)
        uint at = p.y * pc.width + p.x;
        uint64_t v = raster[at];
        raster_depths[at] = uintBitsToFloat(uint(v >> 32));  // 0 (the far plane): nothing
        if (v != 0ul) {
            uint g = uint(v & 0xffffffffUL) - 1u;
            uint k = draw_of(g);
            vis = uvec2(raster_draws[k].z + 1u, g - raster_draws[k].x);
        } else {  // classify.comp's count would write the clear colour here
            imageStore(out_image, ivec2(p), stored_color(pc.clear_color, pc.clear_srgb != 0u));
        }
        imageStore(visibility, ivec2(p), uvec4(vis, 0u, 0u));
    }
    // The material bins counted here, so that the classification starts at the offsets.
    uint slot, offset;
    tile_bins_begin();
    tile_bins_add(vis.x != 0u, vis.x != 0u ? draws[vis.x - 1u].info.z : NO_MATERIAL, slot, offset);
    tile_bins_commit();
#endif
}
