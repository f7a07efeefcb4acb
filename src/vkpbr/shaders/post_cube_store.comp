#version 450
// post_cube_store.comp: a cube face's HDR radiance (the face frame's "color") into the face's
// own image, which the frame that resamples the faces reads (render/lens_cube.py).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    imageStore(dst, p, imageLoad(src, p));
}
