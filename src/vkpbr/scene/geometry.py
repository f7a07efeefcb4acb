# Shared, vectorised geometry helpers for the scene loaders: flat normals (unwelding; the
# arithmetic is normals.py's), strip and fan triangulation, clean-up of non-finite vertices,
# dtype normalisation and an automatic camera that frames a scene. NumPy only; no Python loop
# runs per vertex or per index.
#
# References: glTF 2.0 spec section 3.7.2.1 (primitive modes, strip/fan vertex order) and
# "Meshes" (flat normals when NORMAL is absent).

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np

from vkpbr.scene.normals import flat_normals, unweld_flat
from vkpbr.scene.types import Camera, Mesh, Scene

__all__ = [
    "auto_camera",
    "drop_nonfinite",
    "ensure_normals",
    "fan_triangles",
    "flat_normals",
    "normalize_mesh_arrays",
    "polygon_fan",
    "strip_triangles",
]

# Per-vertex attributes of a Mesh that are gathered together when vertices are unwelded.
_VERTEX_ATTRS = ("positions", "normals", "texcoords", "texcoords1", "tangents", "colors")


def ensure_normals(mesh: Mesh) -> Mesh:
    """Return `mesh` unchanged if it has normals, else an unwelded copy with flat normals.

    Flat shading needs one normal per triangle, so every corner becomes its own vertex: all
    per-vertex attributes are gathered by `indices` and the new indices are 0..M-1.
    """
    if mesh.normals is not None:
        return mesh
    attributes = {name: getattr(mesh, name) for name in _VERTEX_ATTRS + ("joints", "weights")
                  if getattr(mesh, name) is not None}
    gathered, indices = unweld_flat(attributes, mesh.indices)
    # Morph displacements are per vertex too: (T, N, 3) gathered along N. Normal ones are
    # dropped, as the normals they displace are made here (docs/animation.md).
    idx = np.asarray(mesh.indices).astype(np.intp)
    targets = {key: np.ascontiguousarray(d[:, idx]) for key, d in mesh.morph_targets.items()
               if key != "NORMAL"}
    return replace(mesh, indices=indices, morph_targets=targets, **gathered)


def drop_nonfinite(mesh: Mesh, source: object = "") -> Mesh:
    """Remove triangles that touch a non-finite (NaN/inf) position and zero those positions.

    Policy (shared by all loaders): a NaN vertex is dropped with a warning instead of failing
    the whole file, because exporters occasionally emit a few stray NaNs; zeroing the position
    as well keeps `Scene.bounds` finite. Non-finite values in the other attributes become 0.
    """
    bad = ~np.isfinite(mesh.positions).all(axis=1)
    other = {
        name: np.nan_to_num(getattr(mesh, name), nan=0.0, posinf=0.0, neginf=0.0)
        for name in _VERTEX_ATTRS[1:]
        if getattr(mesh, name) is not None and not np.isfinite(getattr(mesh, name)).all()
    }
    if not bad.any() and not other:
        return mesh
    indices = mesh.indices
    positions = mesh.positions
    if bad.any():
        tri = indices.reshape(-1, 3)
        keep = ~bad[tri].any(axis=1)
        indices = np.ascontiguousarray(tri[keep].reshape(-1))
        positions = positions.copy()
        positions[bad] = 0.0
        warnings.warn(
            f"{source}: mesh {mesh.name!r}: {int(bad.sum())} non-finite positions; "
            f"dropped {int((~keep).sum())} triangles",
            stacklevel=3,
        )
    return replace(mesh, positions=positions, indices=indices, **other)


def normalize_mesh_arrays(mesh: Mesh) -> Mesh:
    """Make every array C-contiguous float32 (attributes) / uint32 (indices), as types.py says."""
    arrays = {
        name: np.ascontiguousarray(getattr(mesh, name), dtype=np.float32)
        for name in _VERTEX_ATTRS
        if getattr(mesh, name) is not None
    }
    return replace(mesh, indices=np.ascontiguousarray(mesh.indices, dtype=np.uint32), **arrays)


def strip_triangles(indices: np.ndarray) -> np.ndarray:
    """TRIANGLE_STRIP -> triangle list; odd triangles swap two corners to keep the winding.

    glTF: triangle i = (v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]). Degenerate triangles (two
    equal corners, how strips are stitched) are dropped.

    Parameters
    ----------
    indices : (K,) integer, K >= 3 for any output

    Returns
    -------
    (3T,) same dtype
    """
    n = len(indices) - 2
    if n <= 0:
        return indices[:0]
    i = np.arange(n)
    odd = i % 2
    tri = np.stack([indices[i], indices[i + 1 + odd], indices[i + 2 - odd]], axis=1)
    return _drop_degenerate(tri)


def fan_triangles(indices: np.ndarray) -> np.ndarray:
    """TRIANGLE_FAN -> triangle list: triangle i = (v[i + 1], v[i + 2], v[0]) (glTF order)."""
    n = len(indices) - 2
    if n <= 0:
        return indices[:0]
    i = np.arange(n)
    tri = np.stack([indices[i + 1], indices[i + 2], np.broadcast_to(indices[0], n)], axis=1)
    return _drop_degenerate(tri)


def _drop_degenerate(tri: np.ndarray) -> np.ndarray:
    keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    return np.ascontiguousarray(tri[keep].reshape(-1))


def polygon_fan(counts: np.ndarray) -> np.ndarray:
    """Fan-triangulate polygons stored back to back (OBJ faces with any number of corners).

    Parameters
    ----------
    counts : (F,) integer, corners per polygon (each >= 3)

    Returns
    -------
    (T, 3) int64 indices into the concatenated corner list, T = sum(counts - 2); polygon f
    yields (s, s + k + 1, s + k + 2) for k = 0..counts[f]-3, s its first corner.
    """
    counts = np.asarray(counts, dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ntri = counts - 2
    total = int(ntri.sum())
    s = np.repeat(starts, ntri)
    # k restarts at 0 for every polygon: position minus the index of the polygon's first tri.
    first = np.repeat(np.cumsum(ntri) - ntri, ntri)
    k = np.arange(total) - first
    return np.stack([s, s + k + 1, s + k + 2], axis=1)


# The share of the field of view the automatic camera gives the scene's bounds: the box's
# farthest corner reaches 95% of the way to the image's edge (top and bottom, or left and
# right of a square image; a wider image has room to spare at the sides).
AUTO_FILL = 0.95


def auto_camera(scene: Scene, yfov_deg: float = 60.0) -> Camera:
    """A camera that frames the whole scene.

    The eye looks at the centre of the world bounds from a +Z-leaning diagonal (slightly from
    above and the right, so that flat test models are not seen edge-on), as close as it can
    while every corner of the bounds projects inside `AUTO_FILL` of the vertical field of
    view, and of the horizontal one of a square image (`framing_distance_to_box`): the
    model fills the view, as the glTF Sample Viewer frames it, instead of its bounding
    sphere (about a seventh of the image for a flat model). Near and far are left to each
    render (reversed-Z: see render/camera.py depth_range).
    """
    lo, hi = scene.bounds()
    centre = (lo + hi) / 2.0
    direction = np.array([0.35, 0.3, 1.0]) / np.linalg.norm([0.35, 0.3, 1.0])
    distance = framing_distance_to_box(lo, hi, direction, (0.0, 1.0, 0.0), yfov_deg)
    eye = centre + direction * distance
    return Camera(
        eye=tuple(float(x) for x in eye),
        target=tuple(float(x) for x in centre),
        up=(0.0, 1.0, 0.0),
        yfov_deg=yfov_deg,
        name="auto",
    )


def framing_distance_to_box(lo: np.ndarray, hi: np.ndarray, direction: np.ndarray,
                            up: tuple[float, float, float], yfov_deg: float,
                            fill: float = AUTO_FILL) -> float:
    """The distance from the box's centre, along unit `direction` (towards the eye), at
    which a camera looking at the centre sees every corner of the box [lo, hi] within
    `fill` of its half field of view, vertically and horizontally at aspect 1: for each
    corner at (x, y) across and z along the view from the centre (z > 0: beyond it), at
    depth d + z, |x| <= t (d + z) and |y| <= t (d + z), t = fill tan(yfov / 2). The eye
    stays outside the box. An empty or degenerate box: a unit one."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.linalg.norm(hi - lo) <= 1e-9:
        c = (lo + hi) / 2.0 if np.all(np.isfinite(lo + hi)) else np.zeros(3)
        lo, hi = c - 0.5, c + 0.5
    forward = -np.asarray(direction, np.float64)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    half = (hi - lo) / 2.0
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    x, y, z = corners @ right, corners @ true_up, corners @ forward
    t = fill * math.tan(math.radians(yfov_deg) / 2.0)
    need = np.maximum(np.abs(x), np.abs(y)) / t - z
    outside = float((-z).max() + 0.05 * np.linalg.norm(hi - lo))  # the nearest corner ahead
    return float(max(need.max(), outside))
