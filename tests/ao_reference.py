"""A NumPy Monte Carlo reference for ambient occlusion (render/ao.py's GTAO is tested against
it): the same triangles ray cast in float64, no renderer code.

For each pixel centre the camera ray (tests/pinhole.py) finds the first triangle it hits; from
that point, nudged off the surface, `rays` cosine-weighted directions about the triangle's
normal (turned towards the camera), stratified on a sqrt(rays)^2 grid (Malley's method), are
cast against every triangle within the radius. A direction hit at distance t occludes by
w(t) = clamp((R - t) / (falloff R), 0, 1): fully within the radius but its last `falloff`
share, where the weight falls to 0 as GTAO's samples do (XeGTAO's falloff); beyond R nothing
occludes. The visibility is 1 - mean(w): the cosine-weighted unoccluded share of the
hemisphere, GTAO's integral.
"""

from __future__ import annotations

import numpy as np
from pinhole import pixel_rays

from vkpbr.scene.types import Camera, Scene

__all__ = ["scene_triangles", "first_hits", "visibility"]


def scene_triangles(scene: Scene) -> np.ndarray:
    """(M, 3, 3) float64 world-space triangles of every node's mesh."""
    tris = []
    for node in scene.nodes:
        if node.mesh is None or node.mesh < 0:
            continue
        mesh = scene.meshes[node.mesh]
        m = np.asarray(node.matrix, np.float64)
        p = mesh.positions.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        tris.append(p[mesh.indices.reshape(-1, 3)])
    return np.concatenate(tris)


def _intersect(o: np.ndarray, d: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(N, M) hit distances of rays (o, d: (N, 3)) against triangles (M, 3, 3); inf: none.
    Moller-Trumbore, component by component (no (N, M, 3) temporaries)."""
    v0, e1, e2 = tri[:, 0].T, (tri[:, 1] - tri[:, 0]).T, (tri[:, 2] - tri[:, 0]).T
    dx, dy, dz = (c[:, None] for c in d.T)
    px, py, pz = dy * e2[2] - dz * e2[1], dz * e2[0] - dx * e2[2], dx * e2[1] - dy * e2[0]
    det = px * e1[0] + py * e1[1] + pz * e1[2]
    tx, ty, tz = (o[:, k, None] - v0[k] for k in range(3))
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        u = (tx * px + ty * py + tz * pz) * inv
        qx, qy, qz = ty * e1[2] - tz * e1[1], tz * e1[0] - tx * e1[2], tx * e1[1] - ty * e1[0]
        v = (dx * qx + dy * qy + dz * qz) * inv
        t = (e2[0] * qx + e2[1] * qy + e2[2] * qz) * inv
        ok = (np.abs(det) > 1e-14) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.where(ok, t, np.inf)


def first_hits(camera: Camera, width: int, height: int, tris: np.ndarray,
               pixels: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel: the first hit point (H, W, 3), the hit triangle's unit normal facing the
    camera (H, W, 3) and whether anything was hit (H, W); or, for `pixels` ((N, 2) rows,
    columns), (N, 3), (N, 3), (N,)."""
    eye = np.asarray(camera.eye, np.float64)
    d = pixel_rays(camera, width, height)
    d = d.reshape(-1, 3) if pixels is None else d[pixels[:, 0], pixels[:, 1]]
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-30)
    t_best = np.full(len(d), np.inf)
    j_best = np.zeros(len(d), int)
    for s in range(0, len(d), 256):
        for m in range(0, len(tris), 4096):
            t = _intersect(np.broadcast_to(eye, (len(d[s:s + 256]), 3)), d[s:s + 256],
                           tris[m:m + 4096])
            j = np.argmin(t, axis=1)
            tj = t[np.arange(len(j)), j]
            better = tj < t_best[s:s + 256]
            t_best[s:s + 256] = np.where(better, tj, t_best[s:s + 256])
            j_best[s:s + 256] = np.where(better, j + m, j_best[s:s + 256])
    hit = np.isfinite(t_best)
    p = eye + d * np.where(hit, t_best, 0.0)[:, None]
    n = normals[j_best]
    n = np.where((np.sum(n * d, -1) > 0)[:, None], -n, n)
    shape = (height, width) if pixels is None else (len(pixels),)
    return p.reshape(*shape, 3), n.reshape(*shape, 3), hit.reshape(shape)


def _cosine_directions(n: np.ndarray, rays: int, rng: np.random.Generator) -> np.ndarray:
    """(P, K, 3) cosine-weighted unit directions about unit normals n (P, 3), stratified."""
    s = int(round(np.sqrt(rays)))
    i, j = np.meshgrid(np.arange(s), np.arange(s), indexing="ij")
    u1 = (i.reshape(-1)[None] + rng.random((len(n), s * s))) / s
    u2 = (j.reshape(-1)[None] + rng.random((len(n), s * s))) / s
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], -1)
    a = np.where(np.abs(n[:, :1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t = np.cross(a, n)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    b = np.cross(n, t)
    return local[..., :1] * t[:, None] + local[..., 1:2] * b[:, None] + local[..., 2:] * n[:, None]


def visibility(points: np.ndarray, normals: np.ndarray, tris: np.ndarray, radius: float,
               falloff: float, rays: int = 144, seed: int = 0, chunk: int = 8) -> np.ndarray:
    """(P,) cosine-weighted visibility within `radius` of points (P, 3) with unit normals."""
    rng = np.random.default_rng(seed)
    lo, hi = tris.min(axis=1), tris.max(axis=1)
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p, n = points[s:s + chunk], normals[s:s + chunk]
        near = np.all((lo <= p.max(0) + radius) & (hi >= p.min(0) - radius), axis=1)
        d = _cosine_directions(n, rays, rng)
        if not near.any():
            out[s:s + chunk] = 1.0
            continue
        o = np.repeat(p + n * (1e-5 * radius), d.shape[1], axis=0)
        t = _intersect(o, d.reshape(-1, 3), tris[near]).min(axis=1)
        w = np.clip((radius - t) / (falloff * radius), 0.0, 1.0)
        out[s:s + chunk] = 1.0 - w.reshape(len(p), -1).mean(axis=1)
    return out
