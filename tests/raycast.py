"""First hits of rays on triangles (Moller-Trumbore in float64), for the tests' NumPy
references: independent of the renderer (no matrix, no shader of vkpbr's)."""

from __future__ import annotations

import numpy as np

# How far past a chunk's rays (in tangent units of its projection plane) a triangle's
# projected box may end and still be tested: a margin for rounding in the projection, so the
# cull never drops a triangle a ray grazes (hits are tested exactly, without one).
CULL_MARGIN = 1e-6


def first_hits(tri: np.ndarray, eye: np.ndarray, dirs: np.ndarray, chunk: int = 256
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For (R, 3) unit `dirs` from `eye` against (T, 3, 3) triangles: the index of the
    first triangle hit (-1: none), the distance t (inf: none) and the barycentrics
    (R, 3) of the hit (w0, w1, w2; 0 without a hit).

    Each chunk of rays is tested only against the triangles `_candidates` cannot rule out;
    the others would give it no hit, so the result is the same as testing every pair (ties
    still go to the lowest triangle index: the candidates keep their order)."""
    eye = np.asarray(eye, np.float64)
    rel = tri - eye
    best_t, best = np.full(len(dirs), np.inf), np.full(len(dirs), -1)
    bary = np.zeros((len(dirs), 3))
    for s in range(0, len(dirs), chunk):
        keep = _candidates(rel, dirs[s:s + chunk])
        if len(keep):
            b, best_t[s:s + chunk], bary[s:s + chunk] = _hits(tri[keep], eye, dirs[s:s + chunk])
            best[s:s + chunk] = np.where(b >= 0, keep[np.maximum(b, 0)], -1)
    return best, best_t, bary


def _candidates(rel: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Indices (ascending) of the triangles (corners relative to the eye) that rays `dirs`
    may hit. Central projection onto the plane facing the rays' mean direction c maps a
    triangle wholly in front of the eye to a triangle and a ray to a point (lines stay
    lines), so a ray can hit it only if its point is in the triangle's projected box; a
    triangle reaching to or behind the eye's plane is always kept."""
    c = dirs.mean(axis=0)
    c /= max(np.linalg.norm(c), 1e-300)
    a = np.cross(c, [1.0, 0.0, 0.0] if abs(c[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(c, a)
    dz = dirs @ c
    if dz.min() <= 1e-6:  # a ray near or past the plane: no bounded projection
        return np.arange(len(rel))
    du, dv = (dirs @ a) / dz, (dirs @ b) / dz
    z = rel @ c
    front = np.all(z > 1e-12, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        u, v = (rel @ a) / z, (rel @ b) / z
    inside = ((u.min(1) <= du.max() + CULL_MARGIN) & (u.max(1) >= du.min() - CULL_MARGIN)
              & (v.min(1) <= dv.max() + CULL_MARGIN) & (v.max(1) >= dv.min() - CULL_MARGIN))
    return np.flatnonzero(~front | inside)


def _hits(tri: np.ndarray, eye: np.ndarray, dirs: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """first_hits of every ray against every triangle (the Moller-Trumbore test itself)."""
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    dd = dirs[:, None, :]
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
    uu, vv = u[rows, j], v[rows, j]
    bary = np.where(hit[:, None], np.stack([1 - uu - vv, uu, vv], -1), 0.0)
    return np.where(hit, j, -1), t[rows, j], bary
