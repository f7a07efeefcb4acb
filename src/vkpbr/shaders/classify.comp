#version 450
// classify.comp: the compute path's per-frame binning of pixels by material
// (render/compute_path.py), so that shade.comp runs once per material with that material's
// descriptor set bound -- no texture arrays, no non-uniform indexing (lavapipe has neither).
// KERNEL 1 (count): per pixel, count it in its material's bin; pixels nothing covers get the
//   clear colour here. KERNEL 2 (offsets): one invocation turns counts into list offsets and
//   one indirect dispatch size per material. KERNEL 3 (scatter): per pixel, its index into its
//   material's part of the pixel list.
// AGGREGATE = 1: atomics are aggregated per subgroup (one per material present in the
// subgroup), which keeps a frame's ~2 M pixels from queueing on a few dozen counters on a GPU;
// AGGREGATE = 0: one atomic per pixel (lavapipe, where the subgroup loop costs ~10x more).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "generated.glsl"
#include "brdf.glsl"

#if KERNEL == 2
layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;
#else
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
#endif

layout(push_constant) uniform Classify {
    vec4 clear_color;    // linear
    uint material_count;
    uint shade_group;    // shade.comp's work-group size (pixels per group)
} pc;

#if KERNEL == 2
void main() {
    uint offset = 0u;
    for (uint m = 0u; m < pc.material_count; ++m) {
        uint count = bins[m].x;
        bins[m] = uvec4(count, offset, 0u, 0u);
        bin_args[3u * m] = (count + pc.shade_group - 1u) / pc.shade_group;
        bin_args[3u * m + 1u] = 1u;
        bin_args[3u * m + 2u] = 1u;
        offset += count;
    }
}
#else
void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    ivec2 size = imageSize(out_image);
    bool inside = pixel.x < uint(size.x) && pixel.y < uint(size.y);
    uvec2 vis = inside ? imageLoad(visibility, ivec2(pixel)).xy : uvec2(0u);
#if KERNEL == 1
    if (inside && vis.x == 0u) {
        vec4 bg = pc.clear_color;
        // OPAQUE_COPY: the transmission's copy (render/transmission.py) holds linear values.
        bool srgb_target = OPAQUE_COPY == 0 && (settings.flags & SETTINGS_SRGB_TARGET) != 0u;
        imageStore(out_image, ivec2(pixel), srgb_target ? vec4(linear_to_srgb(bg.rgb), bg.a) : bg);
    }
#endif
    bool covered = inside && vis.x != 0u;
    uint material = covered ? draws[vis.x - 1u].info.z : 0xFFFFFFFFu;
#if !AGGREGATE
    if (!covered) return;
#if KERNEL == 1
    atomicAdd(bins[material].x, 1u);
#else
    uint slot = atomicAdd(bins[material].z, 1u);
    pixel_list[bins[material].y + slot] = pixel.y * uint(size.x) + pixel.x;
#endif
#else
    // Waterfall over the materials present in this subgroup: one atomic each.
    bool pending = covered;
    // At most one round per lane: each round retires the first pending lane's material, and
    // the bound keeps a mistake here from ever hanging a GPU.
    for (uint round = 0u; round < gl_SubgroupSize && subgroupAny(pending); ++round) {
        // The material of the first lane still pending (not of the first active lane: that
        // one may be done, and then no lane would match).
        uint m = subgroupShuffle(material, subgroupBallotFindLSB(subgroupBallot(pending)));
        bool mine = pending && material == m;
        uvec4 ballot = subgroupBallot(mine);
        if (mine) {
            uint n = subgroupBallotBitCount(ballot);
            uint rank = subgroupBallotExclusiveBitCount(ballot);
            uint leader = subgroupBallotFindLSB(ballot);
            uint base = 0u;
#if KERNEL == 1
            if (gl_SubgroupInvocationID == leader) atomicAdd(bins[m].x, n);
#else
            if (gl_SubgroupInvocationID == leader) base = atomicAdd(bins[m].z, n);
            base = subgroupShuffle(base, leader);
            pixel_list[bins[m].y + base + rank] = pixel.y * uint(size.x) + pixel.x;
#endif
            pending = false;
        }
    }
#endif
}
#endif
