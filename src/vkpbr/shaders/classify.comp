#version 450
// classify.comp: the compute path's per-frame binning of pixels by material
// (render/compute_path.py), so that shade.comp runs once per material with that material's
// descriptor set bound -- no texture arrays, no non-uniform indexing (lavapipe has neither).
// KERNEL 1 (count): per pixel, count it in its material's bin; pixels nothing covers get the
//   clear colour here. KERNEL 2 (offsets): one work group turns counts into list offsets and
//   one indirect dispatch size per material (a parallel prefix sum, MATERIAL_SCAN at a time).
//   KERNEL 3 (scatter): per pixel, its index into its material's part of the pixel list.
// AGGREGATE = 1 (GPUs): a work group (a 16x16 tile) totals its pixels per material in shared
// memory first, then adds each total with one atomic (bin_tiles.glsl).
// AGGREGATE = 0: one global atomic a pixel (lavapipe, where the subgroup loop costs ~10x more).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "generated.glsl"
#include "brdf.glsl"

#define MATERIAL_SCAN 256u
#if KERNEL == 2
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;  // MATERIAL_SCAN
#else
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;  // compute_path.CLASSIFY_GROUP
#endif

layout(push_constant) uniform Classify {
    vec4 clear_color;    // linear
    uint material_count;
    uint shade_group;    // shade.comp's work-group size (pixels per group)
} pc;

#if KERNEL == 2
shared uint scan[MATERIAL_SCAN];
shared uint carried;  // the counts of the chunks before this one

void main() {
    uint t = gl_LocalInvocationID.x;
    if (t == 0u) carried = 0u;
    barrier();
    for (uint first = 0u; first < pc.material_count; first += MATERIAL_SCAN) {
        uint m = first + t;
        uint count = m < pc.material_count ? bins[m].x : 0u;
        scan[t] = count;
        barrier();
        for (uint d = 1u; d < MATERIAL_SCAN; d <<= 1u) {  // inclusive Hillis-Steele scan
            uint before = t >= d ? scan[t - d] : 0u;
            barrier();
            scan[t] += before;
            barrier();
        }
        if (m < pc.material_count) {
            bins[m] = uvec4(count, carried + scan[t] - count, 0u, 0u);
            bin_args[3u * m] = (count + pc.shade_group - 1u) / pc.shade_group;
            bin_args[3u * m + 1u] = 1u;
            bin_args[3u * m + 2u] = 1u;
        }
        barrier();
        if (t == MATERIAL_SCAN - 1u) carried += scan[t];
        barrier();
    }
}
#else

#if AGGREGATE
#define TILE_COUNTER x
#if KERNEL == 3
#undef TILE_COUNTER
#define TILE_COUNTER z
#endif
#include "bin_tiles.glsl"
#endif

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    ivec2 size = imageSize(out_image);
    bool inside = pixel.x < uint(size.x) && pixel.y < uint(size.y);
    uvec2 vis = inside ? imageLoad(visibility, ivec2(pixel)).xy : uvec2(0u);
#if KERNEL == 1
    if (inside && vis.x == 0u) {
        // OPAQUE_COPY: the transmission's copy (render/transmission.py) holds linear values.
        bool srgb_target = OPAQUE_COPY == 0 && (settings.flags & SETTINGS_SRGB_TARGET) != 0u;
        imageStore(out_image, ivec2(pixel), stored_color(pc.clear_color, srgb_target));
    }
#endif
    bool covered = inside && vis.x != 0u;
    uint material = covered ? draws[vis.x - 1u].info.z : 0xFFFFFFFFu;
    uint pixel_index = pixel.y * uint(size.x) + pixel.x;
#if !AGGREGATE
    if (!covered) return;
#if KERNEL == 1
    atomicAdd(bins[material].x, 1u);
#else
    uint at = atomicAdd(bins[material].z, 1u);
    pixel_list[bins[material].y + at] = pixel_index;
#endif
#else
    uint slot, offset;
    tile_bins_begin();
    tile_bins_add(covered, material, slot, offset);
    tile_bins_commit();
#if KERNEL == 3
    if (covered) {
        uint at = slot < TILE_SLOTS ? tile_base[slot] + offset : offset;
        pixel_list[bins[material].y + at] = pixel_index;
    }
#endif
#endif
}
#endif
