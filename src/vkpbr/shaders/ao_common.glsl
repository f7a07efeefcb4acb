// ao_common.glsl: what the ambient occlusion kernels share (render/ao.py): their bindings,
// push constants, the view a pixel belongs to (one frame, or a batch's atlas of tiles), view
// space from the depth buffer, and the packed working term (visibility and edges).
#ifndef AO_COMMON_GLSL
#define AO_COMMON_GLSL
#define STRUCTS_ONLY 1
#include "generated.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;  // render/ao.py AO_GROUP

// Set 0: the frame's (or a batch's) views; set 1: this step's images (render/ao.py AoKernels).
layout(set = 0, binding = 0, std140) readonly buffer Views {
    ViewRecord views[];
};
// AO_LAYERED = 1: the layered batch's build (render/batch.py): its views are the layers of
// array images, a view a layer, the dispatch's z the layer; else one 2D image (a frame, or a
// compute batch's atlas of tiles). AO_AT(p) addresses pixel p in the invocation's layer.
#ifndef AO_LAYERED
#define AO_LAYERED 0
#endif
// One set of bindings, its types by build (an array image a layered batch's, else 2D).
#if AO_LAYERED
#define AO_SAMPLER sampler2DArray
#define AO_UIMAGE uimage2DArray
#define AO_IMAGE image2DArray
#define AO_AT(p) ivec3((p), int(gl_GlobalInvocationID.z))
#else
#define AO_SAMPLER sampler2D
#define AO_UIMAGE uimage2D
#define AO_IMAGE image2D
#define AO_AT(p) (p)
#endif
layout(set = 1, binding = 0) uniform AO_SAMPLER depth_map;  // the target's depth (reversed-Z)
layout(set = 1, binding = 1, r32ui) uniform AO_UIMAGE ao_raw;  // GTAO's term, packed
layout(set = 1, binding = 2, r32ui) uniform AO_UIMAGE ao_mid;  // after the first denoise pass
layout(set = 1, binding = 3, r32f) uniform AO_IMAGE ao_out;  // the visibility shading reads
// The view-space depth and its MIPs (ao_prefilter.comp writes them through the level views,
// ao_gtao.comp reads them: render/ao.py DEPTH_MIPS levels).
layout(set = 1, binding = 4) uniform AO_SAMPLER depth_mips;
layout(set = 1, binding = 5, r32f) uniform writeonly AO_IMAGE depth_mip0;
layout(set = 1, binding = 6, r32f) uniform writeonly AO_IMAGE depth_mip1;
layout(set = 1, binding = 7, r32f) uniform writeonly AO_IMAGE depth_mip2;
layout(set = 1, binding = 8, r32f) uniform writeonly AO_IMAGE depth_mip3;
layout(set = 1, binding = 9, r32f) uniform writeonly AO_IMAGE depth_mip4;
// The compute rasteriser's depths, a float a pixel of the frame (or the batch's atlas),
// row-major: ao_prefilter.comp's AO_DEPTH_BUFFER build reads them where the frame was drawn
// by the compute rasteriser (no copy into the depth image for GTAO alone); a stand-in else.
layout(set = 1, binding = 10) readonly buffer AoRasterDepths {
    float raster_depth[];
};

layout(push_constant) uniform Ao {
    uint tile_w;  // a view's pixels: the frame's size, or a batch's tile (column-major tiles)
    uint tile_h;
    uint rows;  // tiles a column (1 for a frame)
    uint views;  // views drawn (tiles past them are left alone)
    float radius;  // the effect radius, world units
    float falloff;  // share of the radius over which a sample's weight falls to 0 (XeGTAO)
    uint slices;  // GTAO's slice directions a pixel (ao_gtao.comp: its build's AO_SLICES)
    uint steps;  // samples a side of a slice (its build's AO_STEPS)
    uint final_pass;  // ao_denoise.comp: the last pass (full blur; at full resolution -> out)
    uint read_mid;  // ao_denoise.comp, ao_upsample.comp: read ao_mid (else ao_raw)
    uint scale;  // 1: GTAO at full resolution; 2: at half (a pixel of the working images per
                 // 2 x 2 of the frame's; ao_upsample.comp makes the full-resolution "ao")
    uint first_view;  // the view of the first tile (AO_LAYERED: of layer 0)
    uint fused;  // ao_upsample.comp: run the last denoise pass on the pixels it blends
    float mip_offset;  // ao_gtao.comp: XeGTAO's DepthMIPSamplingOffset (render/ao.py MIP_OFFSET)
    uint depth_row;  // AO_DEPTH_BUFFER: the frame's width, raster_depth's row
} pc;

// The view a tile (and, layered, the invocation's layer) stands for.
uint ao_view_of(uint tile) {
#if AO_LAYERED
    return pc.first_view + tile + gl_GlobalInvocationID.z;
#else
    return pc.first_view + tile;
#endif
}

// The view pixel p is drawn through, and its tile's first pixel; false past the last view.
bool ao_view(ivec2 p, out uint view, out ivec2 lo) {
    uvec2 t = uvec2(p) / uvec2(pc.tile_w, pc.tile_h);
    uint tile = t.x * pc.rows + t.y;
    view = ao_view_of(tile);
    lo = ivec2(t * uvec2(pc.tile_w, pc.tile_h));
    return t.y < pc.rows && tile < pc.views;
}

ivec2 ao_clamp(ivec2 p, ivec2 lo) {
    return clamp(p, lo, lo + ivec2(pc.tile_w, pc.tile_h) - 1);
}

// The working images (ao_raw, ao_mid) hold a view's tile at 1 / scale of its size (rounded
// up), in the same grid of tiles: working pixel w stands for the frame's pixel
// lo + (w - wlo) * scale, the top-left one of its scale x scale block.
ivec2 ao_work_tile() {
    return (ivec2(pc.tile_w, pc.tile_h) + int(pc.scale) - 1) / int(pc.scale);
}

// The view working pixel w belongs to, its tile's first working pixel and first frame pixel.
bool ao_work_view(ivec2 w, out uint view, out ivec2 wlo, out ivec2 lo) {
    uvec2 t = uvec2(w) / uvec2(ao_work_tile());
    uint tile = t.x * pc.rows + t.y;
    view = ao_view_of(tile);
    wlo = ivec2(t) * ao_work_tile();
    lo = ivec2(t * uvec2(pc.tile_w, pc.tile_h));
    return t.y < pc.rows && tile < pc.views;
}

ivec2 ao_work_clamp(ivec2 w, ivec2 wlo) {
    return clamp(w, wlo, wlo + ao_work_tile() - 1);
}

// The frame pixel a working pixel stands for (in the tile: the last block of an odd size
// is one pixel wide).
ivec2 ao_frame_pixel(ivec2 w, ivec2 wlo, ivec2 lo) {
    return ao_clamp(lo + (w - wlo) * int(pc.scale), lo);
}

// The depth MIPs' levels (render/ao.py DEPTH_MIPS) and their largest value: the view-space
// depth where nothing was drawn (XeGTAO_ClampDepth: finite, so that the MIP filter's sums
// stay numbers).
const int AO_MIPS = 5;
const float AO_FAR = 3.0e38;

// The depth MIPs hold each view's tile in a block of its own, the tile's size rounded up to a
// multiple of 16 (the MIPs' texels group the tile's own pixels, as a frame's alone do: a batch
// view's GTAO equals the view's rendered alone), in the tiles' grid: the block of the tile
// whose first pixel is lo starts at ao_mip_base(lo) (a multiple of 16: its texel of level k
// for tile pixel q is (base + q) >> k).
ivec2 ao_mip_tile() {
    return (ivec2(pc.tile_w, pc.tile_h) + 15) & ~15;
}
ivec2 ao_mip_base(ivec2 lo) {
    return lo / ivec2(pc.tile_w, pc.tile_h) * ao_mip_tile();
}

// Distance along the view axis at frame pixel p of the tile whose first pixel is lo: the depth
// MIPs' level 0 (ao_prefilter.comp: znear / depth, reversed-Z, infinite far plane, the
// depth buffer read once); +inf where nothing was drawn.
float ao_view_z(ivec2 p, ivec2 lo) {
    float z = texelFetch(depth_mips, AO_AT(ao_mip_base(lo) + p - lo), 0).r;
    return z < AO_FAR ? z : 1.0 / 0.0;
}

// View space as XeGTAO's (x right, y up, z forward, into the screen) of the point at pixel
// position `pix` of the tile (pixel centres at + 0.5, y down) with view-axis distance z. The
// view record's intrinsics: NDC x = sx x / z + ox, NDC y (down) = -sy y / z + oy.
vec3 ao_view_pos(vec2 pix, float z, vec4 intr) {
    vec2 ndc = pix / vec2(pc.tile_w, pc.tile_h) * 2.0 - 1.0;
    return vec3((ndc.x - intr.z) / intr.x, (intr.w - ndc.y) / intr.y, 1.0) * z;
}

// The working term: visibility in 16 bits, the four edges (2 bits each, XeGTAO's) above.
uint ao_pack(float visibility, uint edges) {
    return uint(clamp(visibility, 0.0, 1.0) * 65535.0 + 0.5) | (edges << 16);
}
float ao_visibility(uint packed) { return float(packed & 0xFFFFu) / 65535.0; }
vec4 ao_edges(uint packed) {  // left, right, top, bottom: 1 continuous, 0 an edge
    uint e = packed >> 16;
    return vec4((e >> 6) & 3u, (e >> 4) & 3u, (e >> 2) & 3u, e & 3u) / 3.0;
}
#endif
