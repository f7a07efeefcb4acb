// lens.glsl: the camera models' inverse (pixel -> ray), mirrored by scene/lens.py
// `pixel_rays` (its docstring says why Newton's method rather than a precomputed map), and
// the source pinhole's texel position of a ray. Pixels and K follow OpenCV: the centre of
// the top-left pixel is (0, 0); rays are in OpenCV camera axes (x right, y down, z forward).
#ifndef LENS_GLSL
#define LENS_GLSL

const int MODEL_PINHOLE = 0, MODEL_OPENCV = 1, MODEL_FISHEYE = 2, MODEL_EQUIDISTANT = 3;
const int NEWTON_STEPS = 20;

#ifdef LENS_BATCH
// A compute batch's views (post_lens_batch.comp): each view's constants in a buffer (set 1,
// render/post.py lens_batch_steps), copied into `lens` by the kernel for its pixel's view.
struct LensParams {
    vec4 k_out;
    vec4 k_src;
    vec4 c0;
    vec4 c1;
    int model;
};
layout(set = 1, binding = 0, std430) readonly buffer LensViews { LensParams view_lens[]; };
LensParams lens;
#elif defined(LENS_CUBE)
// A cube-face lens (render/lens_cube.py): LensPush with k_src the faces' pinhole (focal,
// focal, centre, centre) and which cube face is drawn into which slot.
layout(push_constant) uniform LensPush {
    vec4 k_out;
    vec4 k_src;
    vec4 c0;
    vec4 c1;
    int model;
    int store;  // post_cube_store*.comp: unused (the slot is the bound image)
    int size;  // a face image's side, texels
    int pad;
    ivec4 slot_a;  // the slot (bound image) of faces 0..3 (lens_cube.glsl FACE_*), -1: none
    ivec4 slot_b;  // of faces 4, 5
} lens;
#else
layout(push_constant) uniform LensPush {
    vec4 k_out;  // the model's fx, fy, cx, cy (pixels, at the output's size)
    vec4 k_src;  // the source pinhole's fx, fy, cx, cy
    vec4 c0;  // opencv: k1 k2 p1 p2; opencv_fisheye: k1 k2 k3 k4
    vec4 c1;  // opencv: k3 k4 k5 k6
    int model;  // MODEL_*
} lens;
#endif

// (x', y') of OpenCV's radial-tangential model at undistorted (x, y); `d` its Jacobian's
// entries (dxx, dyy, dxy: symmetric).
vec2 radial_tangential(vec2 p, out vec3 d) {
    float k1 = lens.c0.x, k2 = lens.c0.y, p1 = lens.c0.z, p2 = lens.c0.w;
    float k3 = lens.c1.x, k4 = lens.c1.y, k5 = lens.c1.z, k6 = lens.c1.w;
    float x = p.x, y = p.y, r2 = x * x + y * y;
    float a = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    float b = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
    float da = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    float db = k4 + r2 * (2.0 * k5 + 3.0 * k6 * r2);
    float radial = a / b, dr = (da * b - a * db) / (b * b);
    d = vec3(radial + 2.0 * x * x * dr + 2.0 * p1 * y + 6.0 * p2 * x,
             radial + 2.0 * y * y * dr + 6.0 * p1 * y + 2.0 * p2 * x,
             2.0 * x * y * dr + 2.0 * p1 * x + 2.0 * p2 * y);
    return vec2(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
}

float theta_d(float t) {
    float t2 = t * t;
    return t * (1.0 + t2 * (lens.c0.x + t2 * (lens.c0.y + t2 * (lens.c0.z + t2 * lens.c0.w))));
}

// The unit ray of output pixel `pixel` (its centre, OpenCV convention); w = 0 where the model
// has none (Newton did not converge, or beyond 180 degrees).
vec4 lens_ray(vec2 pixel) {
    vec2 xd = (pixel - lens.k_out.zw) / lens.k_out.xy;
    if (lens.model == MODEL_PINHOLE) return vec4(normalize(vec3(xd, 1.0)), 1.0);
    if (lens.model == MODEL_OPENCV) {
        vec2 p = xd;
        vec3 d;
        for (int i = 0; i < NEWTON_STEPS; ++i) {
            vec2 f = radial_tangential(p, d) - xd;
            float det = d.x * d.y - d.z * d.z;
            p -= vec2(d.y * f.x - d.z * f.y, d.x * f.y - d.z * f.x) / det;
        }
        // float32: converged to a few ulps of the distorted point (1e-4 of a pixel).
        bool ok = length(radial_tangential(p, d) - xd) <= 2e-5 * max(1.0, length(xd))
                  && !any(isnan(p));
        return vec4(normalize(vec3(p, 1.0)), ok ? 1.0 : 0.0);
    }
    float td = length(xd), t = td;
    if (lens.model == MODEL_FISHEYE) {
        for (int i = 0; i < NEWTON_STEPS; ++i) {
            float t2 = t * t;
            float dg = 1.0 + t2 * (3.0 * lens.c0.x + t2 * (5.0 * lens.c0.y
                                   + t2 * (7.0 * lens.c0.z + t2 * 9.0 * lens.c0.w)));
            t -= (theta_d(t) - td) / dg;
        }
        if (!(abs(theta_d(t) - td) <= 2e-5 * max(1.0, td)) || t < 0.0) return vec4(0.0);
    }
    if (t > 3.14159265) return vec4(0.0);
    vec2 s = td > 0.0 ? xd * (sin(t) / td) : vec2(0.0);
    return vec4(s, cos(t), 1.0);
}

// The output pixel (OpenCV convention) of a ray `d` in front of the camera (d.z > 0): the
// model's forward projection (scene/lens.py `project`), as cv2.projectPoints and
// cv2.fisheye.projectPoints compute it.
vec2 lens_project(vec3 d) {
    vec2 x = d.xy / d.z;
    if (lens.model == MODEL_OPENCV) {
        vec3 unused;
        x = radial_tangential(x, unused);
    } else if (lens.model != MODEL_PINHOLE) {
        float r = length(d.xy);
        x = r > 0.0 ? d.xy * (theta_d(atan(r, d.z)) / r) : vec2(0.0);
    }
    return lens.k_out.xy * x + lens.k_out.zw;
}

// The source pinhole's texel position (OpenCV convention: texel centres at integers) of ray `d`.
vec2 source_texel(vec3 d) { return lens.k_src.xy * (d.xy / d.z) + lens.k_src.zw; }

#endif
