#version 450
// background.comp: the compute path's environment behind the scene, background.frag's in
// compute: for every pixel nothing covers (the visibility image's 0), env_specular's sharpest
// level in the direction of the pixel's ray, rotated and scaled as image-based lighting sees
// it, then the exposure and tone map. Left to classify.comp's clear colour when the frame
// has no background or the view is not final. BATCH = 1: a compute batch's atlas
// (render/batch_path.py), each tile through its view; BATCH = 0: one frame through the
// camera (no fragment pass: on the H200 that pass cost 0.10-0.15 ms at 1080p).
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
#include "brdf.glsl"
#include "env_common.glsl"
#include "frame_output.glsl"
#include "worlds.glsl"  // a batch of worlds' environment

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(push_constant) uniform Background {
    uint views;  // the atlas's tiles, as raster.comp's
    uint tile_w;
    uint tile_h;
    uint rows;
} pc;

void main() {
    opaque_zero = 0u;  // no uniform block is read here (COMPUTE_SET): a plain 0
    uvec2 pixel = gl_GlobalInvocationID.xy;
    ivec2 size = imageSize(out_image);
    if (pixel.x >= uint(size.x) || pixel.y >= uint(size.y)) return;
    if ((lighting.flags & LIGHTING_BACKGROUND) == 0u || settings.view != VIEW_FINAL) return;
    if (imageLoad(visibility, ivec2(pixel)).x != 0u) return;
    uvec2 tile = uvec2(pc.tile_w, pc.tile_h);
#if BATCH
    view_index = (pixel.x / tile.x) * pc.rows + pixel.y / tile.y;  // column-major tiles
    if (view_index >= pc.views) return;
#endif
    vec2 ndc = (vec2(pixel % tile) + 0.5) / vec2(tile) * 2.0 - 1.0;
    // The infinite far plane's point: a direction (surface_fetch.glsl ray_dir says why).
    vec3 ray = (views[view_index].inv_VP * vec4(ndc, 0.0, 1.0)).xyz;
    vec3 d = env_rotate(normalize(ray), ENV_ROTATION);
    vec3 radiance = textureLod(env_specular, d, 0.0).rgb * ENV_INTENSITY;
    vec3 value = radiance_output(radiance);
    bool srgb_target = (settings.flags & SETTINGS_SRGB_TARGET) != 0u;
    imageStore(out_image, ivec2(pixel), stored_color(vec4(value, 1.0), srgb_target));
}
