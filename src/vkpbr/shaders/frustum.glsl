// frustum.glsl: whether a world bounding sphere touches a view's frustum (batch_cull.comp's
// per-view draw culling, raster.comp's per-draw early out). The planes of clip space from
// VP's rows (Gribb & Hartmann): left, right, top, bottom and the near plane (reversed-Z:
// depth <= w); the far plane is left out (conservative).
#ifndef FRUSTUM_GLSL
#define FRUSTUM_GLSL

vec4 vp_row(mat4 m, int j) {
    return vec4(m[0][j], m[1][j], m[2][j], m[3][j]);
}

bool sphere_visible(mat4 vp, vec4 sphere) {
    vec4 r0 = vp_row(vp, 0), r1 = vp_row(vp, 1), r2 = vp_row(vp, 2), r3 = vp_row(vp, 3);
    vec4 planes[5] = vec4[](r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2);
    vec4 c = vec4(sphere.xyz, 1.0);
    for (int i = 0; i < 5; ++i) {
        // Conservative: a little slack for float rounding of the plane and the sphere.
        float reach = sphere.w * length(planes[i].xyz) * 1.0001 + 1e-6 * abs(planes[i].w);
        if (dot(planes[i], c) < -reach) return false;
    }
    return true;
}

// A mesh's bounding sphere (xyz centre, w radius) placed by `model`: the radius scaled by the
// longest axis, so that any scale or shear keeps it conservative. A hidden draw's zero matrix
// (render/scene_state.py) gives a point, whose triangles have no area.
vec4 world_sphere(mat4 model, vec4 local) {
    float s = max(length(model[0].xyz), max(length(model[1].xyz), length(model[2].xyz)));
    return vec4((model * vec4(local.xyz, 1.0)).xyz, local.w * s);
}

#endif
