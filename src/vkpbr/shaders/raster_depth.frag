#version 450
// raster_depth.frag: the compute rasteriser's depths (raster.comp) into the target's depth
// buffer, for what tests it afterwards: the visibility pass's masked draws, the background,
// the blended draws and depth readback. Depth compare ALWAYS, no colour written.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define RASTER_INT64 1  // generated.glsl declares the 64-bit buffer
#include "generated.glsl"

layout(push_constant) uniform RasterDepth {
    uint width;
} pc;

void main() {
    uvec2 p = uvec2(gl_FragCoord.xy);
    gl_FragDepth = uintBitsToFloat(uint(raster[p.y * pc.width + p.x] >> 32));  // 0: nothing
}
