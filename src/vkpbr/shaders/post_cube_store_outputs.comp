#version 450
// post_cube_store_outputs.comp: a cube face's dataset outputs (ids, depth|range|motion,
// normals) into the face's own images (render/lens_cube.py), as post_cube_store.comp its
// radiance.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rg32ui) uniform readonly uimage2D src_ids;
layout(set = 0, binding = 1, rg32ui) uniform writeonly uimage2D dst_ids;
layout(set = 0, binding = 2, rgba32f) uniform readonly image2D src_depth;
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2D dst_depth;
layout(set = 0, binding = 4, rgba32f) uniform readonly image2D src_normal;
layout(set = 0, binding = 5, rgba32f) uniform writeonly image2D dst_normal;
layout(set = 0, binding = 6, rgba32f) uniform readonly image2D src_geometric;
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2D dst_geometric;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst_ids)))) return;
    imageStore(dst_ids, p, imageLoad(src_ids, p));
    imageStore(dst_depth, p, imageLoad(src_depth, p));
    imageStore(dst_normal, p, imageLoad(src_normal, p));
    imageStore(dst_geometric, p, imageLoad(src_geometric, p));
}
