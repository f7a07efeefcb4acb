#version 450
// shade.comp: the compute path's shading (render/compute_path.py). Dispatched once per
// material with that material's set 1 bound (classify.comp binned the pixels); one invocation
// per pixel of the bin reads the visibility buffer (draw index + 1, primitive index) that the
// raster pass wrote, fetches the triangle's three vertices from the scene's storage buffers, intersects the pixel-centre
// ray with it for perspective-correct barycentrics (and the rays of its 2x2 quad's pixels for
// the texture derivatives the fragment path's quads take), and shades the point with
// shade.glsl -- the fragment path's own function -- on all SMs of the GPU, not only those that
// run fragment shaders. Pixels nothing covers were cleared by classify.comp.
// TBN_MODE: the tangent-frame stream, as in pbr.vert.
#extension GL_GOOGLE_include_directive : require
#include "generated.glsl"
#if TBN_MODE != 0
#include "tbn_decode.glsl"
#endif

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;  // compute_path.SHADE_GROUP

layout(push_constant) uniform Shade {
    uint material;  // the bin this dispatch shades (its set 1 is bound)
    uint views;  // BATCH: the atlas's tiles (raster.comp's): views, tile size, tiles a column
    uint tile_w;
    uint tile_h;
    uint rows;
} pc;

#define MATERIAL_INDEX pc.material
#include "surface_fetch.glsl"

#if OUTPUTS
// The motion output: where this surface point was in the previous frame's image, in pixels
// from where it is now (x right, y down; 0 on a renderer's first frame). The point keeps its
// triangle and barycentrics; its previous world position comes from the draw's previous model
// matrix (the frame slot's Motion table, render/scene_state.py) and, for skinned and morphed
// draws, the previous frame's posed vertices (PrevPositions, render/deform.py).
vec2 surface_motion(uint draw, uvec3 vi, vec3 bary, vec2 size) {
    uvec4 head = floatBitsToUint(motion[4]);
    if (head.x == 0u) return vec2(0.0);
    mat4 prev_vp = mat4(motion[0], motion[1], motion[2], motion[3]);
    uint row = 5u + 5u * draw;
    mat4 prev_model = mat4(motion[row], motion[row + 1u], motion[row + 2u], motion[row + 3u]);
    bool deformed = floatBitsToUint(motion[row + 4u]).x != 0u;
    vec3 p[3];
    for (int k = 0; k < 3; ++k) {
        uint at = 3u * (vi[k] - head.y);
        p[k] = deformed ? vec3(prev_positions[at], prev_positions[at + 1u], prev_positions[at + 2u])
                        : vec3_at(vi[k], false);
    }
    vec4 was = prev_vp * (prev_model * vec4(mat3(p[0], p[1], p[2]) * bary, 1.0));
    vec4 now = views[view_index].VP * vec4(s_world_pos, 1.0);
    return (was.xy / was.w - now.xy / now.w) * 0.5 * size;
}
#endif

void main() {
    uvec4 bin = bins[pc.material];
    if (gl_GlobalInvocationID.x >= bin.x) return;
    ivec2 size = imageSize(out_image);
    uint index = pixel_list[bin.y + gl_GlobalInvocationID.x];
    uvec2 pixel = uvec2(index % uint(size.x), index / uint(size.x));
    // The leak guard's zero (frame_output.glsl) may be a plain 0 here: this shader reads no
    // uniform block for lavapipe to inline (COMPUTE_SET).
    opaque_zero = 0u;
    uvec2 vis = imageLoad(visibility, ivec2(pixel)).xy;
    // OPAQUE_COPY: the transmission's copy of the opaque scene (render/transmission.py):
    // linear radiance, the final view (shade.glsl), whatever the frame's target encodes.
    bool srgb_target = OPAQUE_COPY == 0 && (u(settings.flags) & SETTINGS_SRGB_TARGET) != 0u;
    uvec3 vi;
    vec3 w0, w1, w2, bary;
#if BATCH  // a compute batch (render/batch_path.py): the pixel's view is its tile's
    uvec2 tile = uvec2(pc.tile_w, pc.tile_h);
    view_index = (pixel.x / tile.x) * pc.rows + pixel.y / tile.y;  // column-major tiles
    DrawRecord dr = surface_at(vis.x - 1u, vis.y, pixel % tile, vec2(tile), vi, w0, w1, w2, bary);
#else
    DrawRecord dr = surface_at(vis.x - 1u, vis.y, pixel, vec2(size), vi, w0, w1, w2, bary);
#endif
    surface_frame_at(vis.x - 1u, vi, w0, w1, w2, bary);
    s_pixel = ivec2(pixel);
    vec3 eye = views[view_index].eye_near.xyz;

#if OUTPUTS
    // Dataset outputs (Renderer.render(outputs=...)): ids, normals, distances of this point.
    vec3 frame_ng, frame_t, frame_b, frame_n;
    surface_frame(u(settings.flags), u(MAT.flags), frame_ng, frame_t, frame_b, frame_n);
    ivec2 at = ivec2(pixel);
    imageStore(out_ids, at, uvec4(dr.ids.xy, 0u, 0u));
    imageStore(out_normal, at, vec4(frame_n, 0.0));
    imageStore(out_normal_geometric, at, vec4(frame_ng, 0.0));
    vec3 to_point = s_world_pos - eye;
#if BATCH
    vec2 moved = vec2(0.0);  // a batch's views have no previous frame
#else
    vec2 moved = surface_motion(vis.x - 1u, vi, bary, vec2(size));
#endif
    imageStore(out_depth_range, at, vec4(dot(to_point, views[view_index].forward_far.xyz),
                                         length(to_point), moved));
#else
    vec4 value = shade_surface();
    // The storage view is UNORM: encode sRGB here, as the attachment would (shade_surface
    // pre-linearised data views for an sRGB target, exactly as for the fragment path).
    imageStore(out_image, ivec2(pixel), stored_color(value, srgb_target));
#endif
}
