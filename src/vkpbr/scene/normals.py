# Flat (face) normals of triangle lists, arrays in and arrays out. NumPy only, and no scene
# type: geometry.py's ensure_normals (every loader) and the trimesh reading under types.py
# (trimesh_parts.py, which Scene.from_trimesh imports) share it without an import cycle.
#
# Reference: glTF 2.0 spec, "Meshes": flat normals when NORMAL is absent.

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["flat_normals", "safe_normalize", "unweld_flat"]


def safe_normalize(v: np.ndarray, fallback: tuple[float, float, float]) -> np.ndarray:
    """Normalise rows of `v` (N, 3); rows shorter than 1e-20 become `fallback` (no NaN)."""
    length = np.linalg.norm(v, axis=1, keepdims=True)
    good = length[:, 0] > 1e-20
    out = np.empty_like(v)
    out[good] = v[good] / length[good]
    out[~good] = fallback
    return out


def flat_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Face normals of a triangle list, one per corner.

    Parameters
    ----------
    positions : (N, 3) float32
    indices : (M,) uint32, M % 3 == 0

    Returns
    -------
    (M, 3) float32 unit normals, counter-clockwise winding (glTF front faces); degenerate
    triangles get +Z rather than NaN so that shading stays finite.
    """
    tri = positions[indices.reshape(-1, 3)].astype(np.float64)  # (T, 3 corners, 3)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n = safe_normalize(n, (0.0, 0.0, 1.0)).astype(np.float32)
    return np.repeat(n, 3, axis=0)


def unweld_flat(attributes: Mapping[str, np.ndarray], indices: np.ndarray,
                ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Flat shading's vertices: every triangle corner its own vertex.

    Parameters
    ----------
    attributes : per-vertex arrays by name, (N, k) each; "positions" (N, 3) among them.
    indices : (M,) uint32 triangle list, M % 3 == 0.

    Returns
    -------
    Each array gathered by `indices` ((M, k), C-contiguous) plus "normals" (M, 3) float32,
    one face normal per corner; and the new indices, 0..M-1 (uint32).
    """
    idx = np.asarray(indices).astype(np.intp)
    gathered = {name: np.ascontiguousarray(a[idx]) for name, a in attributes.items()}
    gathered["normals"] = flat_normals(attributes["positions"], indices)
    return gathered, np.arange(len(idx), dtype=np.uint32)
