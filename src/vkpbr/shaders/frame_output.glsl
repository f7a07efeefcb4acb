// frame_output.glsl: what every colour pass of a frame shares at its end (pbr.frag and the
// background pass, background.frag), so that surfaces and the environment behind them go
// through one exposure and one tone map. Needs generated.glsl and brdf.glsl (tonemap).
#ifndef FRAME_OUTPUT_GLSL
#define FRAME_OUTPUT_GLSL

// Mesa 22.3's lavapipe (Debian 12) inlines the uniforms a branch depends on: whenever a draw
// binds other values (a material, a frame's settings) it compiles the shader again and never
// frees the old compile, about 1 MB a draw that no vkDestroy* returns (issue 11, class 7; Mesa
// 23.1 caches the variants). A uniform combined with a value the compiler cannot know is not
// inlined: `opaque_zero` is 0 for every fragment (pixel centres have x >= 0.5; main() sets it
// first), so each `u(x)` below equals x exactly and costs one OR or add.
uint opaque_zero;
uint u(uint x) { return x | opaque_zero; }
int u(int x) { return x + int(opaque_zero); }
float u(float x) { return x + float(opaque_zero); }  // x + 0.0: exact (the sign of a 0 aside)

// Scene-referred radiance -> the value written to the colour target: the frame's exposure,
// then its tone map (Settings.tonemap; an sRGB target encodes in hardware afterwards).
// OPAQUE_COPY builds (render/transmission.py) write the radiance itself: transmission
// samples it as light, as the Sample Viewer's LINEAR_OUTPUT pass does.
vec3 radiance_output(vec3 radiance) {
#if OPAQUE_COPY
    return radiance;
#else
    return tonemap(radiance * settings.exposure, u(settings.tonemap));
#endif
}

// The debug view this pass writes (Settings.view): the opaque copy is always the final image.
int frame_view() {
#if OPAQUE_COPY
    return VIEW_FINAL;
#else
    return u(settings.view);
#endif
}

#endif
