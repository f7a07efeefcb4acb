#version 450
// post_noise_copy.comp: the noisy depth and range (post_noise_depth.comp's transient) back
// into the dataset outputs' image, which the frame copies out.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;  // the transient
layout(set = 0, binding = 1, rg32f) uniform writeonly image2D dst;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    imageStore(dst, p, imageLoad(src, p));
}
