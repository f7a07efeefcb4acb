"""First hits of rays on triangles (Moller-Trumbore in float64), for the tests' NumPy
references: independent of the renderer (no matrix, no shader of vkpbr's)."""

from __future__ import annotations

import numpy as np


def first_hits(tri: np.ndarray, eye: np.ndarray, dirs: np.ndarray, chunk: int = 256
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For (R, 3) unit `dirs` from `eye` against (T, 3, 3) triangles: the index of the
    first triangle hit (-1: none), the distance t (inf: none) and the barycentrics
    (R, 3) of the hit (w0, w1, w2; 0 without a hit)."""
    eye = np.asarray(eye, np.float64)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    best_t, best = np.full(len(dirs), np.inf), np.full(len(dirs), -1)
    bary = np.zeros((len(dirs), 3))
    for s in range(0, len(dirs), chunk):
        dd = dirs[s:s + chunk, None, :]
        pv = np.cross(dd, e2[None])
        det = np.sum(e1[None] * pv, -1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = eye - tri[None, :, 0]
            u = np.sum(tv * pv, -1) * inv
            qv = np.cross(tv, e1[None])
            v = np.sum(dd * qv, -1) * inv
            t = np.sum(e2[None] * qv, -1) * inv
            ok = (np.abs(det) > 1e-14) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6)
        t = np.where(ok, t, np.inf)
        j = np.argmin(t, axis=1)
        rows = np.arange(len(j))
        hit = np.isfinite(t[rows, j])
        best_t[s:s + chunk] = t[rows, j]
        best[s:s + chunk] = np.where(hit, j, -1)
        uu, vv = u[rows, j], v[rows, j]
        bary[s:s + chunk] = np.where(hit[:, None], np.stack([1 - uu - vv, uu, vv], -1), 0.0)
    return best, best_t, bary
