#version 450
// shadow_raster.comp: shadow maps drawn by compute shaders (render/shadow_raster.py,
// RenderOptions.shadow_raster): every caster triangle x every redrawn layer of a light
// (cascades, a spot map, a cube's six faces) in one dispatch, on all SMs instead of the few
// that rasterise. A layer is named by its matrix in ShadowData (render/shadows.py): matrix m
// < pc.max_layers is 2D layer m of the maps, else cube layer m - pc.max_layers. Each covered
// texel centre takes one 32-bit atomicMax of its reversed depth's float bits in `depths`
// (depths are >= 0, so their bits order as the depths: the nearest to the light wins), then
// the redrawn layers are copied into the shadow images the lighting samples (a transfer: the
// sampling keeps its hardware compare and 2x2 filter). The depth carries the raster
// pipelines' DEPTH_BIAS: Vulkan's slope-scaled bias m * slope + r * constant, m the largest
// of |dz/dx| and |dz/dy| in texels, r 2^(e - 23) for the primitive's largest depth exponent
// e (D32_SFLOAT), then clamped to [0, 1] as a float attachment's depth is.
// Triangles are clipped to 0 <= z <= w (the pipelines clip depth: no depth clamp); no face is
// culled (the shadow pipelines' cull "none").
// A batch of worlds whose poses move casters (render/world_shadows.py) draws every world's
// maps in the same dispatches: invocation z is (world, layer) = (pc.world_at.x + z / pc.world.w,
// z % pc.world.w) (KERNEL 1: the world, its layers in a loop), a caster's record in Instances is pc.world.y + world * pc.world.x + its draw
// (the world's records, as views[].instance_base names them for the main rasteriser) and its
// texels are its world's, pc.world.z texels a world (no copy: the shading reads them). A
// frame's maps are world 0 of one: pc.world = (0, 0, 0, layers).
// KERNEL 1 (shadow_small): one invocation an opaque caster triangle (in every layer of the
//   dispatch: z is the world alone), a work group a chunk of up to 64 triangles of one
//   caster row (the table's chunk list: the row is the group's, so its bounding-sphere tests
//   are uniform and no invocation searches the rows);
//   triangles whose box exceeds pc.big_area texels are listed as bands of rows of
//   ~pc.big_chunk box texels.
// KERNEL 3 (shadow_args): the listed bands' dispatch size.
// KERNEL 2 (shadow_big): one subgroup a listed band, its triangle's set-up read from the
//   list as KERNEL 1 stored it (every lane alike: broadcasts), no shared memory and no
//   barrier: a work group's subgroups take their bands independently (one work group a
//   band, set up again by one invocation behind two barriers, left Sponza's 111 k bands to
//   wait on it).
// KERNEL 4 (shadow_masked): one invocation a (triangle of one masked caster draw, layer),
//   its material's set 1 bound; a texel counts where the base colour's alpha (texture x
//   factor x COLOR_0, as shadow_mask.frag) reaches the cutoff, sampled at the texel's
//   perspective-correct texture coordinates with their per-texel differences as gradients
//   (the quad differences the fragment shader's texture() takes). Triangles over
//   pc.masked_area box texels are covered by the whole work group afterwards.
// KERNEL 5 (shadow_save) and KERNEL 6 (shadow_move): a redrawn layer's start (one
//   invocation a texel, layer z), as its row after the matrices says (`clip_row`, written by
//   render/shadows.py ShadowMaps.stale): CLIP_FULL cleared (depth 0, the farthest under
//   reversed-Z); CLIP_KEEP left as it is; CLIP_SCROLL (a cascade the camera moved by whole
//   texels) saved into `scratch` by KERNEL 5, then moved by (dx, dy) by KERNEL 6, the texels
//   that came into view cleared; CLIP_COPY (the moving casters drawn over the still ones'
//   kept map; a batch of worlds' maps over the map of what no world moves) copied from
//   `scratch`, bound to that map. KERNELs 1, 2 and 4 then
//   draw only the row's [lo, hi) texels of the layer (`screen`), and none where it is kept.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#include "generated.glsl"
#include "frustum.glsl"
#include "raster_clip.glsl"

#if KERNEL == 2
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;
#elif KERNEL == 5 || KERNEL == 6
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;  // shadow_raster.TEXEL_GROUP / TEXEL_RUN
#elif KERNEL == 3 || KERNEL == 7
layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;
#else
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;  // shadow_raster.SMALL_GROUP
#endif

// Set 4 (render/shadow_raster.py SET_ROWS): the scene's streams where generated.glsl declares
// them for the compute path (Indices, Positions, Texcoords0/1, Colors: bindings 3-7), and
// the shadow raster's own from binding 40.
layout(set = 4, binding = 40, std430) readonly buffer ShadowMatrices {
    vec4 header[4];  // shaders/shadow_data.glsl's cascade_far, cascade_texel, params, world_layout
    mat4 layer_vp[];
};
// Two uvec4 a caster draw: its first triangle over the table, first index, vertex offset and
// its record in Instances (the scene state's model matrix 2 * record); then its mesh's
// bounding sphere in the mesh's space (float bits: centre, radius). From uvec4
// pc.chunks_at, KERNEL 1's chunks: (row, first triangle, triangles, 0) each.
layout(set = 4, binding = 41, std430) readonly buffer Casters { uvec4 casters[]; };
layout(set = 4, binding = 42, std430) buffer Depths { uint depths[]; };
// [0] entries listed, [1..3] KERNEL 2's dispatch size, from 4 BIG_ENTRY-uint entries: a
// band and its triangle's Screen as KERNEL 1 set it up (`store_band`).
layout(set = 4, binding = 43, std430) buffer Big { uint big[]; };
// A scrolled layer's texels while they move (KERNELs 5, 6): the 2D layers' texels, as `depths`;
// for a CLIP_COPY layer, the still casters' kept map (every layer, as `depths`).
layout(set = 4, binding = 44, std430) buffer Scratch { uint scratch[]; };

layout(push_constant) uniform Raster {
    uint triangles;  // KERNEL 4: its draw's triangles
    uint unused1;  // (KERNEL 1 reads its rows from the chunk list)
    uint row;  // KERNEL 4: the masked draw's row
    uint matrix;  // the dispatch's first layer's matrix (its layer z is matrix + z)
    uint map_size;  // texels a side: the 2D layers, the cube faces
    uint cube_size;
    uint cube_base;  // where the cube layers start in `depths` (texels)
    uint max_layers;  // render/shadows.py MAX_LAYERS: the first cube matrix
    uint big_capacity;  // entries `big` holds
    uint has_colors;  // COLOR_0 per vertex (else colors[0..1] holds the one value)
    uint big_area;  // box texels above which work groups take a triangle, and their band's
    uint big_chunk;
    uint masked_area;  // KERNEL 4's: box texels above which the group covers it
    uint spot_layers;  // bit m: 2D layer m is a spot light's (else a directional light's)
    uint chunks_at;  // uvec4 index of the table's first chunk (KERNEL 1)
    uint chunks;  // the opaque rows' chunks
    vec4 bias_constant;  // DEPTH_BIAS by light kind: directional, spot, point
    vec4 bias_slope;
    uvec4 world;  // records a world, the first world's first record, texels a world, layers a world
    uvec4 world_at;  // x: the dispatch's first world; y: the clip rows' first mat4 (0: none)
} pc;

const uint BIG_LIST = 4u, BIG_ENTRY = 24u;  // render/shadow_raster.py BIG_ENTRY
const uint TEXEL_RUN = 16u;  // KERNELs 5, 6: runs of 256 texels a work group (shadow_raster.TEXEL_GROUP)
const uint MAX_GROUPS = 65535u;
const uint BIG_SUBGROUPS = 8u;  // KERNEL 2's bands a work group (256 lanes of subgroups of 32)

#if KERNEL != 3
const uint CLIP_FULL = 0u, CLIP_KEEP = 1u, CLIP_SCROLL = 2u, CLIP_COPY = 3u;  // render/shadows.py's

// Layer m's row after the matrices (render/shadows.py CLIP_AT; the pass's set of rows from
// mat4 pc.world_at.y): the texels drawn packed x | y << 16 (lo, hi: the box [lo, hi); for
// CLIP_SCROLL the strips that came into view, columns [lo.x, hi.x) and rows [lo.y, hi.y)),
// the move (dx & 0xffff) | dy << 16, the mode. Where there are none (pc.world_at.y 0: a batch
// of worlds' maps): drawn whole.
uvec4 clip_row(uint m) {
    if (pc.world_at.y == 0u) {
        uint s = m < pc.max_layers ? pc.map_size : pc.cube_size;
        return uvec4(0u, s | (s << 16), 0u, CLIP_FULL);
    }
    return floatBitsToUint(layer_vp[pc.world_at.y + m / 4u][m % 4u]);
}

uint layer_size(uint m) { return m < pc.max_layers ? pc.map_size : pc.cube_size; }

// Box [lo, hi) (texels, x and y) as a layer's row draws it: within its box; for a scrolled
// layer, the box around the box's parts in either strip (a superset of the texels that came
// into view: what it draws beyond them is what the moved texels hold already, to the last
// bits). Empty: lo >= hi.
void clip_box(uvec4 clip, inout ivec2 lo, inout ivec2 hi) {
    ivec2 a = ivec2(clip.x & 0xffffu, clip.x >> 16), b = ivec2(clip.y & 0xffffu, clip.y >> 16);
    if (clip.w != CLIP_SCROLL) {
        lo = max(lo, a);
        hi = min(hi, b);
        return;
    }
    bool columns = a.x < b.x && lo.x < b.x && hi.x > a.x;  // the box meets the columns strip
    bool rows = a.y < b.y && lo.y < b.y && hi.y > a.y;
    // (one strip: the box clipped to it; both: the box around the two parts)
    ivec2 l = rows ? ivec2(lo.x, columns ? lo.y : max(lo.y, a.y)) : ivec2(max(lo.x, a.x), lo.y);
    ivec2 h = rows ? ivec2(hi.x, columns ? hi.y : min(hi.y, b.y)) : ivec2(min(hi.x, b.x), hi.y);
    bool any_part = columns || rows;
    lo = any_part ? l : ivec2(1);
    hi = any_part ? h : ivec2(0);
}
uint layer_base(uint m, uint w) {
    uint s = layer_size(m);
    return w * pc.world.z
           + (m < pc.max_layers ? m * s * s : pc.cube_base + (m - pc.max_layers) * s * s);
}

vec3 position(uint i) { uint k = 3u * i; return vec3(positions[k], positions[k + 1u], positions[k + 2u]); }

// Caster row k in world w: its row, model matrix and bounding sphere in the world.
struct Caster { uvec4 r; mat4 model; vec4 sphere; };
Caster caster(uint k, uint w) {
    Caster a;
    a.r = casters[2u * k];
    a.model = instance_matrices[2u * (pc.world.y + w * pc.world.x + a.r.w)];
    a.sphere = world_sphere(a.model, uintBitsToFloat(casters[2u * k + 1u]));
    return a;
}

// Whether layer m's frustum meets the caster's sphere (one test instead of three vertices:
// most of a scene's draws miss a near cascade or a cube face), and where the layer draws
// only some of its texels this frame (its clip row: kept, none; scrolled, the strip that came
// into view), whether the sphere's box in texels meets them (a scrolled layer is a cascade:
// orthographic, so the box is the centre's texel +- the radius scaled by the matrix's rows;
// a texel of slack for rounding).
bool layer_sees(Caster a, uint m) {
    if (!sphere_visible(layer_vp[m], a.sphere)) return false;
    if (pc.world_at.y == 0u) return true;
    uvec4 clip = clip_row(m);
    if (clip.w != CLIP_SCROLL) return clip.w != CLIP_KEEP;
    mat4 vp = layer_vp[m];
    float half_size = 0.5 * float(pc.map_size);
    vec2 centre = ((vp * vec4(a.sphere.xyz, 1.0)).xy + 1.0) * half_size;
    vec2 reach = a.sphere.w * half_size * vec2(length(vp_row(vp, 0).xyz), length(vp_row(vp, 1).xyz))
                 + 1.0;
    ivec2 lo = ivec2(floor(centre - reach)), hi = ivec2(ceil(centre + reach));
    clip_box(clip, lo, hi);
    return all(lessThan(lo, hi));
}

// Triangle g of the caster: its vertex indices and world positions (model x position).
void corners(Caster a, uint g, out uvec3 vi, out vec4 wp[3]) {
    uint base = a.r.y + 3u * (g - a.r.x);
    for (int j = 0; j < 3; ++j) {
        vi[j] = indices[base + uint(j)] + a.r.z;
        wp[j] = a.model * vec4(position(vi[j]), 1.0);
    }
}

#if KERNEL == 4
// (See shadow_mask.frag: u() keeps lavapipe from compiling a variant per material.)
uint opaque_zero;
float u(float x) { return x + float(opaque_zero); }

vec4 color_at(uint i) {
    uint k = pc.has_colors != 0u ? i : 0u;
    return vec4(unpackUnorm2x16(colors[2u * k]), unpackUnorm2x16(colors[2u * k + 1u]));
}
#endif

// Triangle g in layer m: its clipped polygon in texels (x, y, depth), the polygon's `edge`
// area, its box of texel centres [lo, hi), the depth bias and, for the alpha test, what the
// unclipped triangle's texels interpolate (set up once a triangle, not once a texel).
struct Screen {
    vec3 s[5];
    int n;
    float area, bias;
    ivec2 lo, hi;
    uint m, w;  // the layer's matrix, the world (of the dispatch's)
#if KERNEL == 4
    mat3 inv_c;  // the inverse of the corners' (x, y, w) columns (`barycentrics`)
    vec2 tc[3];  // the vertices' texture coordinates of the base colour's set
    vec3 alpha;  // the vertices' COLOR_0 alpha
#endif
};

// Clip corner c in texels of a `size`-texel layer (x, y) and its depth; zmax: the largest
// |depth| so far (the constant bias's exponent).
vec3 texel(vec4 c, float size, inout float zmax) {
    vec3 ndc = c.xyz / c.w;
    zmax = max(zmax, abs(ndc.z));
    return vec3((ndc.xy * 0.5 + 0.5) * size, ndc.z);
}

// Triangle (vertices vi, world positions wp) in layer m of world w.
bool screen(uvec3 vi, vec4 wp[3], uint m, uint w, out Screen t) {
    vec4 c[3];
    for (int j = 0; j < 3; ++j) c[j] = layer_vp[m] * wp[j];  // as shadow.vert's
    t.m = m;
    t.w = w;
#if KERNEL == 4
    t.inv_c = inverse(mat3(c[0].xyw, c[1].xyw, c[2].xyw));
    bool second = u(material.base_color_uv_row0.w) > 0.5;
    for (int j = 0; j < 3; ++j) t.tc[j] = second ? texcoords1[vi[j]] : texcoords0[vi[j]];
    t.alpha = vec3(color_at(vi.x).a, color_at(vi.y).a, color_at(vi.z).a);
#endif
    float size = float(layer_size(m));
    float zmax = 0.0;
    if (unclipped(c)) {  // most triangles: no clipping, no arrays indexed at run time
        t.n = 3;
        t.s[0] = texel(c[0], size, zmax);
        t.s[1] = texel(c[1], size, zmax);
        t.s[2] = texel(c[2], size, zmax);
    } else {
        vec4 poly[5];
        t.n = clip(c, poly);
        if (t.n < 3) return false;
        for (int j = 0; j < t.n; ++j) t.s[j] = texel(poly[j], size, zmax);
    }
    t.area = 0.0;
    for (int j = 1; j + 1 < t.n; ++j) t.area += edge(t.s[0].xy, t.s[j].xy, t.s[j + 1].xy);
    if (!(abs(t.area) > 0.0)) return false;  // degenerate (a hidden draw's zero matrix), or NaN
    // The box of texel centres first: a small caster's triangles (a crowd's, 1-2 texels in a
    // cascade) mostly hold no texel centre, and need no slopes or bias then.
    vec2 lo2 = t.s[0].xy, hi2 = t.s[0].xy;
    for (int j = 1; j < t.n; ++j) { lo2 = min(lo2, t.s[j].xy); hi2 = max(hi2, t.s[j].xy); }
    int isize = int(size);
    t.lo = clamp(ivec2(ceil(lo2 - 0.5)), ivec2(0), ivec2(isize));
    t.hi = clamp(ivec2(floor(hi2 - 0.5)) + 1, ivec2(0), ivec2(isize));
    if (pc.world_at.y != 0u) clip_box(clip_row(m), t.lo, t.hi);  // the layer's texels drawn this frame
    if (!all(lessThan(t.lo, t.hi))) return false;
    // The plane's depth slopes in texels, from the polygon's largest fan triangle (all of
    // them lie in one plane): Vulkan's m = max(|dz/dx|, |dz/dy|).
    int best = 1;
    float best_area = 0.0;
    for (int j = 1; j + 1 < t.n; ++j) {
        float a = abs(edge(t.s[0].xy, t.s[j].xy, t.s[j + 1].xy));
        if (a > best_area) { best_area = a; best = j; }
    }
    vec3 p = t.s[0], q = t.s[best], r = t.s[best + 1];
    vec3 u = q - p, v = r - p;
    float det = u.x * v.y - v.x * u.y;
    float dzdx = (u.z * v.y - v.z * u.y) / det, dzdy = (v.z * u.x - u.z * v.x) / det;
    float slope = max(abs(dzdx), abs(dzdy));
    int e;
    frexp(zmax, e);  // zmax = f * 2^e, f in [0.5, 1): its float exponent is e - 1
    float r_unit = zmax > 0.0 ? ldexp(1.0, e - 1 - 23) : 0.0;
    uint kind = m >= pc.max_layers ? 2u : (pc.spot_layers >> m) & 1u;
    t.bias = slope * pc.bias_slope[kind] + r_unit * pc.bias_constant[kind];
    return true;
}

// Triangle g of caster row k in layer m of world w (KERNEL 4: one layer a dispatch z).
bool on_layer(uint g, uint k, uint m, uint w, out Screen t) {
    Caster a = caster(k, w);
    if (!layer_sees(a, m)) return false;
    uvec3 vi;
    vec4 wp[3];
    corners(a, g, vi, wp);
    return screen(vi, wp, m, w, t);
}

float box_area(Screen t) { return float(t.hi.x - t.lo.x) * float(t.hi.y - t.lo.y); }
int chunk_rows(Screen t) { return max(1, int(pc.big_chunk) / (t.hi.x - t.lo.x)); }
uint band_count(Screen t) { int r = chunk_rows(t); return uint((t.hi.y - t.lo.y + r - 1) / r); }

#if KERNEL == 4
// The alpha test at texel centre p (texels) of layer t.m: the base colour's alpha at the
// perspective-correct barycentrics of the unclipped triangle, gradients from the next texels.

// The clip-space point of the triangle under ndc p has (x, y, w) = C b (C: the corners'
// (x, y, w) columns, b its barycentrics) and (x, y, w) = w (ndc, 1): b is C^-1 (ndc, 1)
// normalised to sum 1 (C inverted once a triangle, in `screen`).
vec3 barycentrics(Screen t, vec2 p) {
    vec2 ndc = p / float(layer_size(t.m)) * 2.0 - 1.0;
    vec3 b = t.inv_c * vec3(ndc, 1.0);
    return b / (b.x + b.y + b.z);
}

bool alpha_passes(Screen t, vec2 p) {
    vec4 row0 = material.base_color_uv_row0, row1 = material.base_color_uv_row1;
    vec3 b = barycentrics(t, p), bx = barycentrics(t, p + vec2(1.0, 0.0)),
         by = barycentrics(t, p + vec2(0.0, 1.0));
    vec2 uv0 = b.x * t.tc[0] + b.y * t.tc[1] + b.z * t.tc[2];
    vec2 uvx = bx.x * t.tc[0] + bx.y * t.tc[1] + bx.z * t.tc[2];
    vec2 uvy = by.x * t.tc[0] + by.y * t.tc[1] + by.z * t.tc[2];
    mat2 rows = mat2(row0.x, row1.x, row0.y, row1.y);  // the UV transform's linear part
    vec2 uv = rows * uv0 + vec2(row0.z, row1.z);
    float vertex_alpha = dot(b, t.alpha);
    float alpha = textureGrad(base_color_map, uv, rows * (uvx - uv0), rows * (uvy - uv0)).a
                  * material.base_color_factor.a * vertex_alpha;
    return alpha >= u(material.alpha_cutoff);
}
#endif

// Cover fan triangle (s0, s1, s2) of t (positive `edge` area) in rows y0, y0 + ystep, ...
// below y1, in each row the candidates from the span's start + lane on, every `lanes`.
void cover(Screen t, vec3 s0, vec3 s1, vec3 s2, int y0, int y1, int ystep, int lane, int lanes) {
    uint size = layer_size(t.m), base = layer_base(t.m, t.w);
    float area = edge(s0.xy, s1.xy, s2.xy);
    for (int y = y0; y < y1; y += ystep) {
        float py = float(y) + 0.5, xl = float(t.lo.x), xr = float(t.hi.x - 1);
        edge_span(s1.xy, s2.xy, py, xl, xr);
        edge_span(s2.xy, s0.xy, py, xl, xr);
        edge_span(s0.xy, s1.xy, py, xl, xr);
        int xa = clamp(int(clamp(xl, float(t.lo.x), float(t.hi.x))), t.lo.x, t.hi.x) + lane;
        int xb = clamp(int(clamp(xr, float(t.lo.x - 1), float(t.hi.x - 1))), t.lo.x - 1, t.hi.x - 1);
        for (int x = xa; x <= xb; x += lanes) {
            vec2 p = vec2(x, y) + 0.5;
            float e0 = edge(s1.xy, s2.xy, p), e1 = edge(s2.xy, s0.xy, p), e2 = edge(s0.xy, s1.xy, p);
            if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) continue;
            float z = (e0 * s0.z + e1 * s1.z + e2 * s2.z) / area;
            uint bits = floatBitsToUint(clamp(z + t.bias, 0.0, 1.0));
            uint at = base + uint(y) * size + uint(x);
#if KERNEL == 4
            if (depths[at] >= bits) continue;  // nearer already stored: no alpha test
            if (!alpha_passes(t, p)) continue;
#endif
            // (No such read before the opaque kernels' atomic: an atomic whose result is unused
            // does not wait for memory, a read does: on the H200 it made shadow_big 1.55 ->
            // 1.95 ms for Sponza's cascades.)
            atomicMax(depths[at], bits);
        }
    }
}

// Bands [band0, band1) of t's box (chunk_rows rows each) as the share says, the polygon as
// a fan of triangles each turned to positive area.
void draw_layer(Screen t, uint band0, uint band1, int y_offset, int ystep, int lane, int lanes) {
    int rows = chunk_rows(t);
    uint bands = band_count(t);
    int y0 = t.lo.y + int(min(band0, bands)) * rows + y_offset;
    int y1 = band1 >= bands ? t.hi.y : t.lo.y + int(band1) * rows;
    for (int j = 1; j + 1 < t.n; ++j) {
        vec3 a = t.s[0], b = t.s[j], d = t.s[j + 1];
        if (t.area < 0.0) { vec3 x = b; b = d; d = x; }
        cover(t, a, b, d, y0, y1, ystep, lane, lanes);
    }
}

const uint ALL_BANDS = 0xffffffffu;

// A listed band: its triangle's Screen as set up (KERNEL 2 reads it back instead of setting
// the triangle up again: no chain of dependent loads from the table to the vertices a band):
// s[0..4] (15 floats), n, area, bias, lo, hi, m | w << 6, the band.
void store_band(uint e, Screen t, uint band) {
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 3; ++i) big[e + uint(3 * j + i)] = floatBitsToUint(t.s[j][i]);
    big[e + 15u] = uint(t.n);
    big[e + 16u] = floatBitsToUint(t.area);
    big[e + 17u] = floatBitsToUint(t.bias);
    big[e + 18u] = uint(t.lo.x);
    big[e + 19u] = uint(t.lo.y);
    big[e + 20u] = uint(t.hi.x);
    big[e + 21u] = uint(t.hi.y);
    big[e + 22u] = t.m | (t.w << 6u);
    big[e + 23u] = band;
}

Screen load_band(uint e, out uint band) {
    Screen t;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 3; ++i) t.s[j][i] = uintBitsToFloat(big[e + uint(3 * j + i)]);
    t.n = int(big[e + 15u]);
    t.area = uintBitsToFloat(big[e + 16u]);
    t.bias = uintBitsToFloat(big[e + 17u]);
    t.lo = ivec2(big[e + 18u], big[e + 19u]);
    t.hi = ivec2(big[e + 20u], big[e + 21u]);
    t.m = big[e + 22u] & 63u;
    t.w = big[e + 22u] >> 6u;
    band = big[e + 23u];
    return t;
}

#if KERNEL == 1
// A big triangle's bands listed for work groups; those past the list's end drawn here.
void list_bands(Screen t) {
    uint bands = band_count(t);
    uint slot = atomicAdd(big[0], bands);
    uint listed = slot < pc.big_capacity ? min(bands, pc.big_capacity - slot) : 0u;
    for (uint k = 0u; k < listed; ++k) store_band(BIG_LIST + BIG_ENTRY * (slot + k), t, k);
    if (listed < bands) draw_layer(t, listed, ALL_BANDS, 0, 1, 0, 1);
}
#endif

#if KERNEL == 4
shared uint group_big[64];  // this group's big triangles (triangle), covered by the group
shared uint group_big_count;
#endif
#endif  // KERNEL != 3

void main() {
#if KERNEL == 5 || KERNEL == 6
    // z is (world, layer) as the drawing kernels' (a frame's maps: world 0 of one); `scratch`
    // holds one world's layout (a batch of worlds: the kept map every world copies). A work
    // group takes TEXEL_RUN runs of 256 texels (a texel an invocation a run: coalesced), so
    // that a CPU device (lavapipe) runs a sixteenth of the invocations.
    uint z = gl_WorkGroupID.z, m = pc.matrix + z, w = 0u;
    if (pc.world.z != 0u) {  // (a frame's: z is the layer; a division per group otherwise)
        m = pc.matrix + z % pc.world.w;
        w = pc.world_at.x + z / pc.world.w;
    }
    uvec4 clip = clip_row(m);
    if (clip.w == CLIP_KEEP) return;
    uint size = layer_size(m), texels = size * size;
    uint first = (gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x) * 256u * TEXEL_RUN;
    uint base = layer_base(m, w), kept = layer_base(m, 0u);
    ivec2 move = ivec2(bitfieldExtract(int(clip.z), 0, 16), bitfieldExtract(int(clip.z), 16, 16));
    for (uint r = 0u; r < TEXEL_RUN; ++r) {
        uint i = first + r * 256u + gl_LocalInvocationIndex;
        if (i >= texels) return;
#if KERNEL == 5
        if (clip.w == CLIP_SCROLL) scratch[base + i] = depths[base + i];
#else
        uint value = clip.w == CLIP_COPY ? scratch[kept + i] : 0u;
        if (clip.w == CLIP_SCROLL) {  // the new texel (x, y) is the old (x - dx, y - dy)
            ivec2 from = ivec2(i % size, i / size) - move;
            if (all(greaterThanEqual(from, ivec2(0))) && all(lessThan(from, ivec2(size))))
                value = scratch[kept + uint(from.y) * size + uint(from.x)];
        }
        depths[base + i] = value;
#endif
    }
#elif KERNEL == 7
    big[0] = 0u;  // the list's count and dispatch size, before KERNEL 1 (a kernel rather than a
    big[1] = 0u;  // fill: raster.comp's KERNEL 7 says why)
    big[2] = 0u;
    big[3] = 0u;
#elif KERNEL == 3
    big[1] = max(min((big[0] + BIG_SUBGROUPS - 1u) / BIG_SUBGROUPS, MAX_GROUPS), 1u);
    big[2] = 1u;
    big[3] = 1u;
#elif KERNEL == 2
    // Subgroups in a grid stride over the list (any subgroup size: the dispatch is sized for
    // BIG_SUBGROUPS a group, and a group of more subgroups takes more bands a pass).
    uint listed = min(big[0], pc.big_capacity);
    uint stride = gl_NumWorkGroups.x * gl_NumSubgroups;
    for (uint k = gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID; k < listed; k += stride) {
        uint band;
        Screen t = load_band(BIG_LIST + BIG_ENTRY * k, band);
        // A band of a narrow box has many short rows: a lane a row, each walking its span
        // (the lanes along each row in turn pay every row's set-up in sequence, mostly for
        // one or two texels a lane). A wide box's band has few rows: the lanes along them.
        int lane = int(gl_SubgroupInvocationID), lanes = int(gl_SubgroupSize);
        if (chunk_rows(t) >= lanes) draw_layer(t, band, band + 1u, lane, lanes, 0, 1);
        else draw_layer(t, band, band + 1u, 0, 1, lane, lanes);
    }
#else
#if KERNEL == 1
    // Invocation z is the world; each invocation draws its triangle in every layer of the
    // dispatch (pc.world.w <= 32) whose frustum meets its row's sphere: the vertices are
    // fetched and placed once, not once a layer, and a chunk no layer sees stops at once.
    uint w = pc.world_at.x + gl_GlobalInvocationID.z;
    uint chunk = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    if (chunk >= pc.chunks) return;  // the whole group
    uvec4 c = casters[pc.chunks_at + chunk];  // (row, first triangle, triangles)
    Caster a = caster(c.x, w);
    uint seen = 0u;
    for (uint l = 0u; l < pc.world.w; ++l)
        if (layer_sees(a, pc.matrix + l)) seen |= 1u << l;
    if (seen == 0u || gl_LocalInvocationIndex >= c.z) return;
    uint i = c.y + gl_LocalInvocationIndex;
    uvec3 vi;
    vec4 wp[3];
    corners(a, i, vi, wp);
    for (uint l = 0u; l < pc.world.w; ++l) {
        if ((seen & (1u << l)) == 0u) continue;
        Screen t;
        if (!screen(vi, wp, pc.matrix + l, w, t)) continue;
        if (box_area(t) > float(pc.big_area)) list_bands(t);
        else draw_layer(t, 0u, ALL_BANDS, 0, 1, 0, 1);
    }
#else
    uint m = pc.matrix + gl_GlobalInvocationID.z % pc.world.w;
    uint w = pc.world_at.x + gl_GlobalInvocationID.z / pc.world.w;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    opaque_zero = uint(gl_NumWorkGroups.x == 0u);  // 0, unknown to the compiler (u())
    uint first = casters[2u * pc.row].x;
    if (gl_LocalInvocationIndex == 0u) group_big_count = 0u;
    barrier();
    if (i < pc.triangles) {
        Screen t;
        if (on_layer(first + i, pc.row, m, w, t)) {
            if (box_area(t) > float(pc.masked_area)) group_big[atomicAdd(group_big_count, 1u)] = first + i;
            else draw_layer(t, 0u, ALL_BANDS, 0, 1, 0, 1);
        }
    }
    barrier();
    for (uint k = 0u; k < group_big_count; ++k) {
        Screen t;
        if (on_layer(group_big[k], pc.row, m, w, t))
            draw_layer(t, 0u, ALL_BANDS, int(gl_SubgroupID), int(gl_NumSubgroups),
                       int(gl_SubgroupInvocationID), int(gl_SubgroupSize));
    }
#endif
#endif
}
