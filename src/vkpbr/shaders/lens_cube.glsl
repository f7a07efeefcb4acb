// lens_cube.glsl: a wide fisheye's cube faces (render/lens_cube.py, scene/lens.py FACES and
// face_of): which face a ray lies in, its axes, and the face image's texel of a ray. Needs
// lens.glsl with LENS_CUBE defined.
#ifndef LENS_CUBE_GLSL
#define LENS_CUBE_GLSL

// Each face's right, down and forward axes in the lens camera's OpenCV axes (FACES' rows):
// front (+z), right (+x), left (-x), down (+y), up (-y), back (-z).
const vec3 FACE_RIGHT[6] = vec3[](vec3(1, 0, 0), vec3(0, 0, -1), vec3(0, 0, 1), vec3(1, 0, 0),
                                  vec3(1, 0, 0), vec3(-1, 0, 0));
const vec3 FACE_DOWN[6] = vec3[](vec3(0, 1, 0), vec3(0, 1, 0), vec3(0, 1, 0), vec3(0, 0, -1),
                                 vec3(0, 0, 1), vec3(0, 1, 0));
const vec3 FACE_FORWARD[6] = vec3[](vec3(0, 0, 1), vec3(1, 0, 0), vec3(-1, 0, 0),
                                    vec3(0, 1, 0), vec3(0, -1, 0), vec3(0, 0, -1));

// The face of ray `d`: its major axis, ties to z before x before y (face_of).
int cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.z >= a.x && a.z >= a.y) return d.z >= 0.0 ? 0 : 5;
    if (a.x >= a.y) return d.x >= 0.0 ? 1 : 2;
    return d.y >= 0.0 ? 3 : 4;
}

int face_slot(int face) { return face < 4 ? lens.slot_a[face] : lens.slot_b[face - 4]; }

// Ray `d` (lens axes) in face `face`'s camera axes.
vec3 face_local(int face, vec3 d) {
    return vec3(dot(FACE_RIGHT[face], d), dot(FACE_DOWN[face], d), dot(FACE_FORWARD[face], d));
}

// A face camera's ray `l` back in the lens's axes.
vec3 face_to_lens(int face, vec3 l) {
    return FACE_RIGHT[face] * l.x + FACE_DOWN[face] * l.y + FACE_FORWARD[face] * l.z;
}

// The face image's texel position (OpenCV convention) of a ray in its axes (l.z > 0).
vec2 face_texel(vec3 l) { return lens.k_src.xy * (l.xy / l.z) + lens.k_src.zw; }

#endif
