// shadow_sampling.glsl: shadow_factor, the fraction of a light that reaches a surface point past the
// shadow casters (1 = lit, 0 = shadowed), from the maps render/shadows.py draws each frame.
// Needs struct LightRecord (lights.glsl) before it. LightRecord.shadow (ShadowMaps.write):
//   x: first 2D layer (directional, spot) or cube index (point); -1: no shadow
//   y: layers (directional: its cascades)   z: near plane (spot, point)
//   w: world size of a texel at unit distance along the light's axis (spot, point)
// Depth is reversed (render/shadow_math.py): 1 nearest the light; a comparison sample is 1
// where the receiver's depth >= the stored one (GREATER_OR_EQUAL), filtered 2x2 (bilinear
// weights in 1/256ths, computed here from gathered compares on devices that filter D32
// linearly, so that the images and the compute rasteriser's buffer, read by hand, give the
// same shadow; nearest elsewhere, as the sampler), and PCF_TAPS x PCF_TAPS such samples a
// texel apart are averaged.
// Bias, three parts: the passes' slope-scaled depth bias (render/shadows.py), the normal
// offset here (the receiver moves along its geometric normal by params.z texels, more at
// grazing light), and reversed-Z float depth's relative precision.
#ifndef SHADOW_SAMPLING_GLSL
#define SHADOW_SAMPLING_GLSL
#include "shadow_data.glsl"

layout(set = 3, binding = 1) uniform sampler2DArrayShadow shadow_maps;
layout(set = 3, binding = 2) uniform samplerCubeArrayShadow shadow_cubes;
// The cubes' faces as 2D layers (6 a cube, Vulkan's face order), clamped to each face's edge.
layout(set = 3, binding = 5) uniform sampler2DArrayShadow shadow_cube_faces;

const int SHADOW_PCF_HALF = 1;  // (2 * 1 + 1)^2 = 9 taps

// Depths read by hand (no sampler): shadow_raster.comp's buffers of every layer's texels,
// a layer `size` x `size` texels row by row from its first texel, a cube's six faces in
// Vulkan's order (+X -X +Y -Y +Z -Z) one after the other, as that kernel writes them. Two:
// - ShadowDepths: the frame's own maps where the compute rasteriser draws them
//   (RenderOptions.shadow_raster; shadow_data.world_layout.z bit 0): the 2D layers from texel
//   0, the cubes from world_layout.w (render/shadow_raster.py). The raster units' maps
//   (bit 0 clear) are the images above, compared by the sampler.
// - ShadowWorldDepths: a batch of worlds whose poses move shadow casters
//   (render/world_shadows.py): each world's maps (world_layout.x texels a world: its 2D
//   layers, then its cubes' faces from .y), where the view's record names them
//   (views[].shadow_base = 1 + world; 0: the frame's maps).
// The compare and the filter are the images' sampler's (GREATER_OR_EQUAL, linear or nearest,
// depth 0 past the border; a cube face's edge texels clamped, as lavapipe filters cube maps).
layout(set = 3, binding = 3, std430) readonly buffer ShadowWorldDepths { uint world_depths[]; };
layout(set = 3, binding = 4, std430) readonly buffer ShadowDepths { uint frame_depths[]; };
#if BATCH
uint shadow_world() { return views[view_index].shadow_base; }
#else
uint shadow_world() { return 0u; }
#endif

// Specialisation constant 3 (render/compute_path.py ShadeVariant.hand_reads): whether the
// pipeline reads any map by hand (the frame's compute-drawn maps from ShadowDepths, or a
// batch's worlds' maps). False in the compute path's kernels of frames that compare only in
// hardware: every by-hand branch below is then a constant false that the driver folds away,
// and with it hand_compare / hand_pcf_linear (their mere presence cost the H200's shading
// kernels 0.015 ms a Sponza 1080p frame: registers and code size). True (the default) in
// every other pipeline: the fragment path's and the buffer-reading frames', which branch on
// the header's bit 0 at run time (a batch of worlds' kernels read the worlds' maps by hand
// while the frame's, shadow_base 0, may be the images: the bit stays).
layout(constant_id = 3) const bool SHADOW_HAND_READS = true;

// ShadowData's header flags (ShadowMaps.write, _choose_reads): the frame's maps are read from
// ShadowDepths (bit 0), and the images' sampler filters linearly (bit 1).
bool frame_maps_in_buffer() { return SHADOW_HAND_READS && (shadow_data.world_layout.z & 1u) != 0u; }
bool linear_filter() { return (shadow_data.world_layout.z & 2u) != 0u; }

// A linear filter's first texel `i` and weights `f` at `uv` of a `size`-texel layer, the
// weights in 1/256ths as samplers take them (subTexelPrecisionBits 8 on NVIDIA): a shadow's
// edge then filters as the images' does.
void filter_at(vec2 uv, int size, out ivec2 i, out vec2 f) {
    vec2 t = uv * float(size) - 0.5;
    f = floor(fract(t) * 256.0) / 256.0;
    i = ivec2(floor(t));
}

// The depth bits of texel `i` of the frame's maps (`frame`) or the worlds'.
uint depth_bits(bool frame, uint i) { return frame ? frame_depths[i] : world_depths[i]; }

float hand_texel(bool frame, uint base, int size, ivec2 p, float ref, bool clamp_edge) {
    if (clamp_edge) p = clamp(p, ivec2(0), ivec2(size - 1));
    else if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, ivec2(size)))) return ref >= 0.0 ? 1.0 : 0.0;
    return ref >= uintBitsToFloat(depth_bits(frame, base + uint(p.y * size + p.x))) ? 1.0 : 0.0;
}

// texture(sampler, (uv, layer), ref) of a layer starting at texel `base`, `size` a side, with
// the images' filter: world_layout.z bit 1 where it is linear (ShadowMaps.sampler: where the
// device filters D32 linearly, NVIDIA), else nearest (lavapipe), so that both sides agree.
float hand_compare(bool frame, uint base, int size, vec2 uv, float ref, bool clamp_edge) {
    if (!linear_filter())
        return hand_texel(frame, base, size, ivec2(floor(uv * float(size))), ref, clamp_edge);
    ivec2 i;
    vec2 f;
    filter_at(uv, size, i, f);
    float a = hand_texel(frame, base, size, i, ref, clamp_edge);
    float b = hand_texel(frame, base, size, i + ivec2(1, 0), ref, clamp_edge);
    float c = hand_texel(frame, base, size, i + ivec2(0, 1), ref, clamp_edge);
    float d = hand_texel(frame, base, size, i + ivec2(1, 1), ref, clamp_edge);
    return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

// Whether 2D layer `layer` is read by hand (the frame's compute-drawn maps or the view's
// world's), and then where: `frame` (which buffer), its first texel and its size.
bool hand_layer(float layer, out bool frame, out uint base, out int size) {
    uint world = shadow_world();
    frame = world == 0u;
    size = int(shadow_data.params.x);
    base = (frame ? 0u : (world - 1u) * shadow_data.world_layout.x) + uint(layer + 0.5) * uint(size * size);
    return SHADOW_HAND_READS && (!frame || frame_maps_in_buffer());
}

// The 2D layers' and cubes' comparisons: the images', the frame's compute-drawn maps, or the
// view's world's maps.
float compare_2d(vec2 uv, float layer, float ref) {
    bool frame;
    uint base;
    int size;
    if (!hand_layer(layer, frame, base, size)) return texture(shadow_maps, vec4(uv, layer, ref));
    return hand_compare(frame, base, size, uv, ref, false);
}

// shadow_pcf_2d's 3 x 3 taps a texel apart (PCF_RADIUS 1), each a linear 2 x 2 compare: the
// 4 x 4 texels they cover compared once (16, not 9 x 4), each weighted by the taps' filter
// weights on it, per axis (1 - f, 1, 1, f) (every tap has the same fraction f). The texels'
// compares come by hand (the kernels' buffers) or from the images (4 gathers), and both go
// through this one sum, so a frame reads the same shadow either way, bit for bit (the
// sampler's own linear filter, which the images used before, was up to 9/255 off the
// by-hand one on the H200).
float pcf_4x4(vec2 f, vec4 rows[4]) {
    vec4 wx = vec4(1.0 - f.x, 1.0, 1.0, f.x), wy = vec4(1.0 - f.y, 1.0, 1.0, f.y);
    float sum = 0.0;
    for (int y = 0; y < 4; ++y) sum += wy[y] * dot(wx, rows[y]);
    return sum / 9.0;
}

float hand_pcf_linear(bool frame, uint base, int size, vec2 uv, float ref) {
    ivec2 i;
    vec2 f;
    filter_at(uv, size, i, f);
    i -= 1;
    vec4 rows[4];
    for (int y = 0; y < 4; ++y) {
        rows[y] = vec4(hand_texel(frame, base, size, i + ivec2(0, y), ref, false),
                       hand_texel(frame, base, size, i + ivec2(1, y), ref, false),
                       hand_texel(frame, base, size, i + ivec2(2, y), ref, false),
                       hand_texel(frame, base, size, i + ivec2(3, y), ref, false));
    }
    return pcf_4x4(f, rows);
}

// The same 4 x 4 compares from the images: a gather of 2 x 2 compares at the corner its texels
// share ((k + 1) / size for texels k, k + 1), its components (0, 1), (1, 1), (1, 0), (0, 0).
float image_pcf_linear(float layer, int size, vec2 uv, float ref) {
    ivec2 i;
    vec2 f;
    filter_at(uv, size, i, f);
    vec2 at = vec2(i) / float(size);  // the corner of texels i - 1 and i
    float step_uv = 2.0 / float(size);
    vec4 a = textureGather(shadow_maps, vec3(at, layer), ref);
    vec4 b = textureGather(shadow_maps, vec3(at + vec2(step_uv, 0.0), layer), ref);
    vec4 c = textureGather(shadow_maps, vec3(at + vec2(0.0, step_uv), layer), ref);
    vec4 d = textureGather(shadow_maps, vec3(at + vec2(step_uv), layer), ref);
    vec4 rows[4] = vec4[](vec4(a.w, a.z, b.w, b.z), vec4(a.x, a.y, b.x, b.y),
                          vec4(c.w, c.z, d.w, d.z), vec4(c.x, c.y, d.x, d.y));
    return pcf_4x4(f, rows);
}

// hand_compare's linear filter (clamp_edge) from a face of the images: one gather of the
// 2 x 2 texels at the corner they share, weighed as hand_compare weighs them, so that a frame
// compares alike whether its cube was just redrawn (read by hand) or cached.
float face_compare(float layer, int size, vec2 uv, float ref) {
    ivec2 i;
    vec2 f;
    filter_at(uv, size, i, f);
    vec4 g = textureGather(shadow_cube_faces, vec3(vec2(i + 1) / float(size), layer), ref);
    return mix(mix(g.w, g.z, f.x), mix(g.x, g.y, f.x), f.y);
}

float compare_cube(vec3 q, float cube, float ref) {
    uint world = shadow_world();
    bool frame = world == 0u;
    // (SHADOW_HAND_READS 0: the images, whatever the view's world says: no by-hand code)
    bool images = !SHADOW_HAND_READS || (frame && !frame_maps_in_buffer());
    if (images && !linear_filter()) return texture(shadow_cubes, vec4(q, cube), ref);
    // Vulkan's face selection and face coordinates (+X -X +Y -Y +Z -Z).
    vec3 a = abs(q);
    uint face;
    float ma, sc, tc;
    if (a.x >= a.y && a.x >= a.z) { face = q.x > 0.0 ? 0u : 1u; ma = a.x; sc = q.x > 0.0 ? -q.z : q.z; tc = -q.y; }
    else if (a.y >= a.z) { face = q.y > 0.0 ? 2u : 3u; ma = a.y; sc = q.x; tc = q.y > 0.0 ? q.z : -q.z; }
    else { face = q.z > 0.0 ? 4u : 5u; ma = a.z; sc = q.z > 0.0 ? q.x : -q.x; tc = -q.y; }
    int size = int(shadow_data.params.y);
    vec2 uv = 0.5 * vec2(sc, tc) / ma + 0.5;
    if (images) return face_compare(float(6u * uint(cube + 0.5) + face), size, uv, ref);
    uint cubes = frame ? shadow_data.world_layout.w
                       : (world - 1u) * shadow_data.world_layout.x + shadow_data.world_layout.y;
    uint base = cubes + (6u * uint(cube + 0.5) + face) * uint(size * size);
    return hand_compare(frame, base, size, uv, ref, true);
}

// The receiver moved towards the light's side along its geometric normal, by `texel` world
// units times params.z, scaled by the sine of the angle to the light (no move when facing it,
// whose depth slope is zero; the full amount at grazing angles, where acne comes from).
vec3 shadow_offset_position(vec3 p, vec3 ng, vec3 l, float texel) {
    float cos_t = clamp(dot(ng, l), 0.0, 1.0);
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    return p + ng * (texel * shadow_data.params.z * (0.5 + sin_t));
}

float shadow_pcf_2d(float layer, vec3 ndc) {
    vec2 uv = ndc.xy * 0.5 + 0.5;
    bool frame;
    uint base;
    int size;
    if (SHADOW_PCF_HALF == 1 && shadow_data.params.w == 1.0 && linear_filter()) {
        return hand_layer(layer, frame, base, size) ? hand_pcf_linear(frame, base, size, uv, ndc.z)
                                                    : image_pcf_linear(layer, size, uv, ndc.z);
    }
    float step_uv = shadow_data.params.w / shadow_data.params.x;
    float sum = 0.0;
    for (int j = -SHADOW_PCF_HALF; j <= SHADOW_PCF_HALF; ++j)
        for (int i = -SHADOW_PCF_HALF; i <= SHADOW_PCF_HALF; ++i)
            sum += compare_2d(uv + vec2(i, j) * step_uv, layer, ndc.z);
    float n = float(2 * SHADOW_PCF_HALF + 1);
    return sum / (n * n);
}

float shadow_factor(LightRecord light, vec3 world_pos, vec3 ng, vec3 l, float view_depth) {
    float first = light.shadow.x;
    if (first < 0.0) return 1.0;
    int kind = int(light.direction_kind.w + 0.5);
    if (kind == 2) {  // directional: the first cascade reaching past the fragment
        int count = int(light.shadow.y + 0.5);
        int c = 0;
        while (c < count && view_depth > shadow_data.cascade_far[c]) ++c;
        if (c >= count) return 1.0;  // beyond the last cascade: unshadowed
        vec3 p = shadow_offset_position(world_pos, ng, l, shadow_data.cascade_texel[c]);
        vec4 s = shadow_data.layer_vp[int(first) + c] * vec4(p, 1.0);  // orthographic: w = 1
        return shadow_pcf_2d(first + float(c), s.xyz);
    }
    if (kind == 1) {  // spot: one perspective map
        mat4 m = shadow_data.layer_vp[int(first)];
        float axial = (m * vec4(world_pos, 1.0)).w;
        if (axial <= 0.0) return 1.0;  // behind the light: outside its cone anyway
        vec3 p = shadow_offset_position(world_pos, ng, l, light.shadow.w * axial);
        vec4 s = m * vec4(p, 1.0);
        return shadow_pcf_2d(first, s.xyz / s.w);
    }
    // point: the cube, sampled with the direction from the light; depth = near / |major axis|
    vec3 q0 = world_pos - light.position_range.xyz;
    float ma0 = max(max(abs(q0.x), abs(q0.y)), abs(q0.z));
    vec3 q = shadow_offset_position(world_pos, ng, l, light.shadow.w * ma0) - light.position_range.xyz;
    float ma = max(max(abs(q.x), abs(q.y)), abs(q.z));
    // PCF across the direction: a texel of the face is 2 |ma| / size wide.
    vec3 a = abs(q.x) < 0.9 * length(q) ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    vec3 t1 = normalize(cross(q, a));
    vec3 t2 = normalize(cross(q, t1));
    float step_w = shadow_data.params.w * 2.0 * ma / shadow_data.params.y;
    // The hardware's 2x2 filter reads texels of the neighbouring face near a cube edge, whose
    // depth is near / (another axis): up to about a texel's angle (2 / size) off the tap's
    // own. Comparing a texel's worth nearer keeps a lit receiver lit there (NVIDIA: 2.8% dark
    // specks along the seams without it; lavapipe filtered within the face and never showed it).
    float seam = 1.0 + 2.0 / shadow_data.params.y;
    float sum = 0.0;
    for (int j = -SHADOW_PCF_HALF; j <= SHADOW_PCF_HALF; ++j)
        for (int i = -SHADOW_PCF_HALF; i <= SHADOW_PCF_HALF; ++i)
        {
            // Each tap compares at its own major axis: a tap across a cube edge reads a face
            // whose depth is near / (another component), where the centre's ref would be off.
            vec3 qt = q + (float(i) * t1 + float(j) * t2) * step_w;
            float mt = max(max(abs(qt.x), abs(qt.y)), abs(qt.z));
            sum += compare_cube(qt, first, light.shadow.z * seam / mt);
        }
    float n = float(2 * SHADOW_PCF_HALF + 1);
    return sum / (n * n);
}

#endif
