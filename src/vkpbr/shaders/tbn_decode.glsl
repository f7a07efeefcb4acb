// Tangent frame decode: QTangent quaternion -> mat3(T, B, N), and the packed 32-bit frame.
// Mirrors src/vkpbr/bake/frames.py exactly (qtangent_to_tbn, unpack_qtangent); read the
// layout in that module's docstring. References: Frey & Schulz, "Spherical Skinning with
// Dual-Quaternions and QTangents" (Crytek, SIGGRAPH 2011); glTF 2.0 (B = w * cross(N, T)).
#ifndef TBN_DECODE_GLSL
#define TBN_DECODE_GLSL

const float QTANGENT_BIAS = 1.0 / 32767.0;
const uint PACK_LEVELS = 812u;
const float PACK_RANGE = 0.70710678118654752;  // 1 / sqrt(2)

// Rotation matrix of q with handedness: columns (T, B, N), B = sign * cross(N, T) where
// sign = q.w < 0 ? -1 : 1. q need not be unit length; q and -q give the same T and N.
mat3 tbn_from_qtangent(vec4 q)
{
    float sign_w = q.w < 0.0 ? -1.0 : 1.0;
    q = normalize(q);
    float x = q.x, y = q.y, z = q.z, w = q.w;
    vec3 t = vec3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y));
    vec3 n = vec3(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y));
    vec3 b = sign_w * cross(n, t);
    return mat3(t, b, n);
}

// Packed frame (R32_UINT) -> QTangent quaternion (x, y, z, w): w >= bias, negated if mirrored.
// bit 31 mirrored, bits 29-30 index of the dropped largest component, bits 0-28 three
// base-812 digits (a, b, d) of the other components in x, y, z, w order.
vec4 qtangent_unpack(uint p)
{
    uint code = p & 0x1FFFFFFFu;
    uint d = code % PACK_LEVELS;
    uint b = (code / PACK_LEVELS) % PACK_LEVELS;
    uint a = min(code / (PACK_LEVELS * PACK_LEVELS), PACK_LEVELS - 1u);
    uint k = (p >> 29) & 3u;
    vec3 c = vec3(a, b, d) * (2.0 * PACK_RANGE / float(PACK_LEVELS - 1u)) - PACK_RANGE;
    float largest = sqrt(max(0.0, 1.0 - dot(c, c)));
    vec4 q;
    if (k == 0u)      q = vec4(largest, c.x, c.y, c.z);
    else if (k == 1u) q = vec4(c.x, largest, c.y, c.z);
    else if (k == 2u) q = vec4(c.x, c.y, largest, c.z);
    else              q = vec4(c.x, c.y, c.z, largest);
    q = normalize(q);
    // QTangent canonical form, as frames._bias_and_sign: w >= 0, then w >= bias.
    if (q.w < 0.0) q = -q;
    if (q.w < QTANGENT_BIAS) {
        q.xyz *= sqrt(1.0 - QTANGENT_BIAS * QTANGENT_BIAS) / max(length(q.xyz), QTANGENT_BIAS);
        q.w = QTANGENT_BIAS;
    }
    return ((p >> 31) != 0u) ? -q : q;
}

#endif  // TBN_DECODE_GLSL
