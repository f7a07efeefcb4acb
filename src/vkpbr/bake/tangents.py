# Per-vertex tangent generation: the course's "tgen" method, vectorised with NumPy.
#
# References: renderer-spec.md section 4 (tgen, the accumulated-bitangent sign trap);
# E. Lengyel, "Computing Tangent Space Basis Vectors for an Arbitrary Mesh" (2001);
# T. Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017 (the
# branch-free perpendicular used for degenerate frames); glTF 2.0 spec, meshes (TANGENT:
# bitangent = w * cross(normal, tangent), normal textures are +Y up).
"""Tangent generation (tgen) and NaN-safe vector helpers shared by the bake stage.

Sign convention. glTF texture coordinates have their origin at the image's top-left with
v growing downwards, while glTF normal maps store +Y "up" in the image. The bitangent
``B = w * cross(N, T)`` must therefore point toward *decreasing* glTF v (toward increasing
``1 - v``, the OpenGL convention that MikkTSpace exporters use). `generate_tangents` thus
computes tgen's per-corner frame with ``v' = -v``; the test against the TANGENT attributes
of Khronos' NormalTangentMirrorTest (mirrored half included) pins this down.
"""

from __future__ import annotations

import numpy as np

from ..scene.types import Material

__all__ = [
    "EPS_DET",
    "EPS_LEN",
    "any_perpendicular",
    "generate_tangents",
    "normalize_safe",
    "orthonormal_tangent",
    "tangent_uv_set",
]

EPS_DET = 1e-10  # tgen: UV determinants at or below this give a zero corner frame
EPS_LEN = 1e-8  # vectors shorter than this are treated as having no direction


def normalize_safe(v: np.ndarray, fallback: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Normalise rows without ever producing NaN.

    Parameters
    ----------
    v : (N, K) float array
    fallback : (N, K) or (K,) float array, optional
        Rows shorter than `EPS_LEN` (or non-finite) take this value; zeros by default.

    Returns
    -------
    unit : (N, K) array, same dtype as `v`
    ok : (N,) bool, True where the row had a usable direction
    """
    length = np.sqrt(np.einsum("ij,ij->i", v, v))
    ok = np.isfinite(length) & (length > EPS_LEN)
    # Divide by 1 where the row is unusable so that no inf/NaN is ever formed.
    unit = v / np.where(ok, length, 1.0)[:, None]
    fb = np.zeros_like(v) if fallback is None else np.broadcast_to(fallback, v.shape)
    return np.where(ok[:, None], unit, fb).astype(v.dtype, copy=False), ok


def any_perpendicular(n: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to each unit normal (Duff et al. 2017, branch-free).

    Parameters
    ----------
    n : (N, 3) float array of unit vectors

    Returns
    -------
    (N, 3) array of unit vectors t with dot(n, t) == 0 (up to rounding)
    """
    # copysign keeps -0.0 on the negative branch so that sign + z never reaches 0.
    sign = np.copysign(1.0, n[:, 2])
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    t = np.stack([1.0 + sign * n[:, 0] * n[:, 0] * a, sign * b, -sign * n[:, 0]], axis=1)
    return t.astype(n.dtype, copy=False)


@np.errstate(under="ignore")
def orthonormal_tangent(n: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Gram-Schmidt `t` against unit normals `n`; degenerate results get any perpendicular.

    Parameters
    ----------
    n : (N, 3) float array, unit normals
    t : (N, 3) float array, approximate tangents (any length, possibly zero or parallel to n)

    Returns
    -------
    (N, 3) array of unit tangents perpendicular to `n`, never NaN
    """
    t = np.where(np.isfinite(t), t, 0.0)
    t = t - n * np.einsum("ij,ij->i", n, t)[:, None]
    unit, ok = normalize_safe(t)
    if not ok.all():
        unit[~ok] = any_perpendicular(n[~ok])
    return unit


def _accumulate(index: np.ndarray, values: np.ndarray, count: int) -> np.ndarray:
    """Sum (M, 3) `values` into (count, 3) rows by `index`; bincount per component is several
    times faster than np.add.at and sums in a fixed order (deterministic output)."""
    return np.stack(
        [np.bincount(index, weights=values[:, k], minlength=count) for k in range(values.shape[1])],
        axis=1,
    )


@np.errstate(under="ignore")  # tiny edges underflow harmlessly to 0
def generate_tangents(
    positions: np.ndarray,
    normals: np.ndarray,
    texcoords: np.ndarray | None,
    indices: np.ndarray,
) -> np.ndarray:
    """Per-vertex tangents with handedness, by tgen's corner accumulation.

    For each triangle (p0, p1, p2) with UVs (t0, t1, t2) in glTF convention: ``e1 = p1 - p0``,
    ``e2 = p2 - p0``, ``d1 = t1 - t0``, ``d2 = t2 - t0`` with v negated (see the module
    docstring), ``r = 1 / det`` (0 when ``|det| <= 1e-10``), ``T = (e1 d2.v - e2 d1.v) r``,
    ``B = (e2 d1.u - e1 d2.u) r``. T and B are summed over the corners of each vertex,
    T is orthogonalised against the normal and normalised, and
    ``w = sign(dot(cross(n, t), B_sum))`` (+1 when 0) uses the accumulated bitangent, so that
    mirrored UV islands get w = -1.

    Parameters
    ----------
    positions : (N, 3) float32
    normals : (N, 3) float32; need not be unit length (zero rows are tolerated)
    texcoords : (N, 2) float32 or None (no UVs: every tangent is an arbitrary perpendicular)
    indices : (M,) uint32, M % 3 == 0, every index < N

    Returns
    -------
    (N, 4) float32: unit xyz perpendicular to the normal, w = +1 or -1. Never NaN.
    """
    n_vert = int(positions.shape[0])
    p = np.asarray(positions, dtype=np.float64)
    n, _ = normalize_safe(np.asarray(normals, dtype=np.float64), np.array([0.0, 0.0, 1.0]))
    tri = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    if texcoords is None or tri.shape[0] == 0:
        uv = np.zeros((n_vert, 2))
    else:
        uv = np.asarray(texcoords, dtype=np.float64) * np.array([1.0, -1.0])
    p = np.where(np.isfinite(p), p, 0.0)
    uv = np.where(np.isfinite(uv), uv, 0.0)

    i0, i1, i2 = tri[:, 0], tri[:, 1], tri[:, 2]
    e1, e2 = p[i1] - p[i0], p[i2] - p[i0]
    d1, d2 = uv[i1] - uv[i0], uv[i2] - uv[i0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    big = np.abs(det) > EPS_DET
    r = np.where(big, 1.0 / np.where(big, det, 1.0), 0.0)[:, None]
    t_face = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * r
    b_face = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * r

    # Every corner of a triangle carries the same (T, B): tgen computes them per corner from
    # that corner's edges, which is the same vector up to rounding.
    corners = tri.reshape(-1)
    t_sum = _accumulate(corners, np.repeat(t_face, 3, axis=0), n_vert)
    b_sum = _accumulate(corners, np.repeat(b_face, 3, axis=0), n_vert)

    t = orthonormal_tangent(n, t_sum)
    # The sign must come from the accumulated bitangent: with B recomputed as cross(n, t) it
    # would always be +1 and mirrored UVs would shade inside out (renderer-spec.md 4).
    w = np.where(np.einsum("ij,ij->i", np.cross(n, t), b_sum) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1).astype(np.float32)


def tangent_uv_set(material: Material | None) -> int:
    """The UV set (0 or 1) to generate a mesh's tangents from: the one its normal texture reads.

    glTF 2.0 (3.7.2.1): without TANGENT, tangents are computed from "the texture coordinates
    associated with the normal texture"; a normal map on TEXCOORD_1 whose tangents came from
    TEXCOORD_0 would bend its normals the wrong way wherever the two layouts differ.
    """
    ref = material.normal_texture if material is not None else None
    return 1 if ref is not None and ref.texcoord == 1 else 0
