// raster_clip.glsl: what the compute rasterisers share (raster.comp for views,
// shadow_raster.comp for shadow maps): clipping to the depth planes and the edge functions
// of their per-row spans.
#ifndef RASTER_CLIP_GLSL
#define RASTER_CLIP_GLSL

// Whether the triangle lies within both clip planes (z <= w and z >= 0), where clip() would
// return its three corners unchanged, in order. Checked first because clip()'s arrays,
// indexed by a running count, live in local memory (the H200's driver reported 240 bytes a
// thread for raster_small): the common triangle then never touches them. NaN corners fail
// the test and take clip() as before.
bool unclipped(vec4 c[3]) {
    vec3 z = vec3(c[0].z, c[1].z, c[2].z), w = vec3(c[0].w, c[1].w, c[2].w);
    return all(greaterThanEqual(w - z, vec3(0.0))) && all(greaterThanEqual(z, vec3(0.0)));
}

// The polygon left of the triangle inside z <= w (the near plane, reversed-Z) and z >= 0
// (the far plane): at most 5 corners.
int clip(vec4 c[3], out vec4 poly[5]) {
    vec4 a[5], b[5];
    int n = 3;
    for (int j = 0; j < 3; ++j) a[j] = c[j];
    for (int plane = 0; plane < 2; ++plane) {
        int m = 0;
        for (int j = 0; j < n; ++j) {
            vec4 p = a[j], q = a[(j + 1) % n];
            float dp = plane == 0 ? p.w - p.z : p.z, dq = plane == 0 ? q.w - q.z : q.z;
            if (dp >= 0.0 && m < 5) b[m++] = p;
            if ((dp >= 0.0) != (dq >= 0.0) && m < 5) b[m++] = mix(p, q, dp / (dp - dq));
        }
        n = m;
        for (int j = 0; j < n; ++j) a[j] = b[j];
    }
    for (int j = 0; j < n; ++j) poly[j] = a[j];
    return n;
}

float edge(vec2 a, vec2 b, vec2 p) { return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x); }

// Narrow [xl, xr] (pixel indices of a row whose centres are at y = py) to where the edge
// from a to b can be >= 0: edge(a, b, p) >= 0 where (b.y - a.y) * (p.x - a.x) <=
// (b.x - a.x) * (py - a.y). Widened by a pixel for rounding: the exact test follows.
void edge_span(vec2 a, vec2 b, float py, inout float xl, inout float xr) {
    float slope = b.y - a.y, rhs = (b.x - a.x) * (py - a.y);
    if (slope == 0.0) {  // parallel to the row: all of it or none
        if (rhs < 0.0) xr = xl - 1.0;
        return;
    }
    float x = a.x + rhs / slope - 0.5;  // where it crosses the row, in pixel indices
    if (slope > 0.0) xr = min(xr, floor(x) + 1.0); else xl = max(xl, ceil(x) - 1.0);
}

#endif
