"""Shadow-map projections, in NumPy: cascades for directional lights, spot and cube maps.

No Vulkan here (it is tested on any machine). Matrices are row-major (4, 4) float64 world ->
clip with column vectors, as render/camera.py's; `layouts.mat4_to_std140` transposes them.

Conventions: Vulkan clip space (x right, y down, depth 0..1) and REVERSED depth, as the
camera's: 1 nearest the light, falling towards 0 away from it; maps are cleared to 0 and
drawn GREATER_OR_EQUAL; the shader's compare is "lit when ref >= stored". Why reversed for
the shadow maps too: the spot and point maps are perspective with an infinite far plane,
where window depth = near / distance keeps float32's relative precision at every distance
(the same reason as the camera's, and no far plane to choose per light); the cascades are
orthographic, where the direction makes no difference, and one convention (one compare op,
one bias sign, one clear value) for every map is worth more than none.

Cascades: the view range is split by the practical scheme (Zhang et al. 2006: a blend of
logarithmic and uniform splits); each slice of the view frustum gets a bounding sphere
computed in VIEW space (so its radius depends only on the projection and the splits, never
on where the camera looks), the light's orthographic box is the sphere's square, its centre
snapped to a grid of snap_texels(resolution) whole shadow-map texels in light space (so a
moving camera moves the box by whole texels: no shimmering edges), and its depth range is
extended towards the light to the scene's bounds, so that casters outside the view still cast
into it, and away from the light to the scene's bounds too, so that the depth range (and with it
the matrix) does not follow the camera's depth along the light: that had been a fifth of a
walking camera's redraws (Sponza's walk on the H200: 0.42 -> 0.355 layers a frame); float32 depth keeps
~1e-7 of the scene's depth along the light in any case. The coarse grid (1/8 of the map; the
box is padded by half a step so the sphere stays inside) makes a cascade's matrix constant
while the camera moves within a step: the renderer redraws only the cascades whose matrix
changed (render/shadows.py ShadowMaps.stale), so a walking camera redraws its nearest cascade
every few dozen frames instead of all four every frame, for 1/8 of the map's resolution.
Why 1/8 (1/16 until session 17): redraws go as 1 / step, and on the H200 a frame that
redraws Sponza's nearest 2048^2 cascade costs ~1.2 ms more than one that redraws none (its
floor's triangles cover the whole map at 0.8 mm a texel); at 1/8 the walk (2 cm a frame)
redraws 0.16 layers a frame instead of 0.32, for texels 7% larger (2048 / 1790 against
2048 / 1918 of the sphere's diameter). For the same reason the split range is
rounded outwards to quarter octaves (`cascade_range`): an automatic far plane moves with the
camera, and the splits, radii and matrices would move with it. What a moving camera changes is
then the snapped centres alone: `cascade_shape` keeps the rest of the fit (per projection,
rounded range, light and resolution) and `cascade_columns` computes the centres in Python
floats every frame, the same bytes as the NumPy fit (`_fit_cascades`) at a fifth of its cost.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vkpbr.render.camera import look_at, projection_terms
from vkpbr.scene.types import Camera

__all__ = [
    "CASCADES",
    "SPLIT_BLEND",
    "MAX_SPOT_HALF_ANGLE",
    "CascadeFit",
    "cascade_range",
    "cascade_splits",
    "snap_texels",
    "slice_corners",
    "slice_sphere",
    "light_basis",
    "fit_cascade",
    "cascade_texel",
    "directional_cascades",
    "NO_FAR",
    "CascadeShape",
    "cascade_shape",
    "cascade_columns",
    "layer_scroll",
    "perspective_near",
    "spot_matrix",
    "spot_half_angle",
    "point_matrices",
    "project",
]

CASCADES = 4  # cascades per directional light
SPLIT_BLEND = 0.75  # practical split scheme: weight of the logarithmic splits
MAX_SPOT_HALF_ANGLE = math.radians(80.0)  # a wider cone cannot be one perspective map
_PCF_MARGIN = 1.0 / 64.0  # spot maps: widen the frustum a little so PCF taps stay inside


def _unit(v: Sequence[float]) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64)
    n = float(np.linalg.norm(a))
    if not (n > 0.0 and math.isfinite(n)):
        raise ValueError(f"direction {tuple(v)} is not a non-zero finite vector")
    return a / n


def _bounds_corners(lo: Sequence[float], hi: Sequence[float]) -> np.ndarray:
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                     for z in (lo[2], hi[2])])


def project(m: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N, 3) world points through the (4, 4) matrix `m` -> (N, 4) clip coordinates."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return np.c_[p, np.ones(len(p))] @ np.asarray(m, dtype=np.float64).T


# ShadowData's cascade_far for "no end" (a scene-wide cascade's infinite far, unused slots):
# a finite float32 beyond any view depth. One value for `ShadowMaps.write` and `cascade_shape`.
NO_FAR = 3.0e38


def snap_texels(resolution: int) -> int:
    """The grid a cascade's centre is snapped to, in texels of a `resolution`-texel map."""
    return max(resolution // 8, 1)


def cascade_range(znear: float, zfar: float) -> tuple[float, float]:
    """The view range the cascades split: [znear, zfar] rounded outwards to quarter octaves
    (2^(k/4)), so that a range that drifts with the camera gives the same cascades."""
    lo = 2.0 ** (math.floor(4.0 * math.log2(znear)) / 4.0)
    hi = 2.0 ** (math.ceil(4.0 * math.log2(zfar)) / 4.0)
    return min(lo, znear), max(hi, zfar, 2.0 * lo)


def cascade_splits(znear: float, zfar: float, count: int = CASCADES,
                   blend: float = SPLIT_BLEND) -> np.ndarray:
    """View depths bounding the cascades: (count + 1,) float64, [znear, ..., zfar].

    The practical split scheme: split_i = blend * log_i + (1 - blend) * uniform_i. The
    logarithmic part starts at max(znear, zfar / 1000): the automatic near plane can be tiny
    (1e-5 of the scene's radius, render/camera.py) and would give a useless first cascade.
    """
    if not (0 < znear < zfar) or count < 1:
        raise ValueError(f"cascade range {znear}..{zfar} ({count} cascades) is not increasing")
    i = np.arange(count + 1) / count
    log_near = max(znear, zfar * 1e-3)
    log = log_near * (zfar / log_near) ** i
    uniform = znear + (zfar - znear) * i
    splits = blend * log + (1.0 - blend) * uniform
    splits[0], splits[-1] = znear, zfar
    return splits


def _tangent_rect(camera: Camera, size: tuple[int, int]) -> np.ndarray:
    """The view frustum's four corners per unit of view depth: (4, 2) (x, y) in view space
    (OpenGL view axes: x right, y up, looking down -z)."""
    return _terms_rect(projection_terms(camera, size))


def _terms_rect(terms: tuple[float, float, float, float]) -> np.ndarray:
    sx, sy, ox, oy = terms
    return np.array([[(xn - ox) / sx, (oy - yn) / sy] for xn in (-1.0, 1.0) for yn in (-1.0, 1.0)])


def _view_rows(camera: Camera) -> np.ndarray:
    return look_at(camera.eye, camera.target, camera.up)


def slice_corners(camera: Camera, size: tuple[int, int], d0: float, d1: float) -> np.ndarray:
    """The 8 world-space corners (8, 3) of the view frustum between view depths d0 and d1."""
    t = _tangent_rect(camera, size)
    view = np.array([[x * d, y * d, -d] for d in (d0, d1) for x, y in t])
    inv = np.linalg.inv(_view_rows(camera))
    return (np.c_[view, np.ones(8)] @ inv.T)[:, :3]


def slice_sphere(camera: Camera, size: tuple[int, int], d0: float,
                 d1: float) -> tuple[np.ndarray, float]:
    """A sphere (world centre (3,), radius) holding the frustum slice [d0, d1].

    Computed in view space, so the radius depends on the projection and the depths only
    (a rotating camera keeps its cascades' texel size). The centre lies on the line through
    the slice's rectangle centres, where the symmetric frustum's minimal sphere lies
    (t = (d0 + d1) / 2 * (1 + k^2), k the half-diagonal per unit depth, at most d1); the
    radius is the largest distance to a corner, so containment is exact for any intrinsics.
    """
    centres, radii = _slice_spheres(camera, size, np.array([d0]), np.array([d1]))
    return centres[0], float(radii[0])


def _slice_spheres(camera: Camera, size: tuple[int, int], d0: np.ndarray,
                   d1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`slice_sphere` for n slices at once: centres (n, 3), radii (n,)."""
    centre_v, radii = _view_slice_spheres(projection_terms(camera, size), tuple(d0), tuple(d1))
    return _to_world(camera, centre_v), radii


def _to_world(camera: Camera, points_v: np.ndarray) -> np.ndarray:
    """View-space points (n, 3) in world space."""
    inv = np.linalg.inv(_view_rows(camera))
    return points_v @ inv[:3, :3].T + inv[:3, 3]


@functools.lru_cache(maxsize=64)
def _view_slice_spheres(terms: tuple[float, float, float, float], d0: tuple[float, ...],
                        d1: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The slice spheres in view space: centres (n, 3), radii (n,), read-only. They depend on
    the projection and the depths only, so a moving camera reuses them (a frame's cascade
    fit is then a few array operations: it runs per frame while the camera moves)."""
    t = _terms_rect(terms)
    d0, d1 = np.array(d0), np.array(d1)
    mid = t.mean(axis=0)
    k2 = float(np.max(np.sum((t - mid) ** 2, axis=1)))
    depth = np.minimum(0.5 * (d0 + d1) * (1.0 + k2), d1)
    centre_v = np.stack([mid[0] * depth, mid[1] * depth, -depth], axis=-1)  # (n, 3)
    d = np.stack([d0, d1], axis=-1)[:, :, None, None]  # (n, 2, 1, 1)
    rect = np.concatenate([t, -np.ones((4, 1))], axis=1)  # (4, 3) per unit depth
    corners_v = (d * rect).reshape(len(d0), 8, 3)
    radii = np.max(np.sqrt(np.sum((corners_v - centre_v[:, None]) ** 2, axis=-1)), axis=1)
    centre_v.setflags(write=False)
    radii.setflags(write=False)
    return centre_v, radii


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def light_basis(direction: Sequence[float]) -> np.ndarray:
    """(3, 3) rows: right, up, and the unit direction the light travels. Right-handed as the
    camera's (right, up, -forward) so that front faces keep their winding. Read-only (one
    per direction, kept)."""
    return _light_basis(tuple(float(x) for x in direction))


@functools.lru_cache(maxsize=256)
def _light_basis(direction: tuple[float, ...]) -> np.ndarray:
    f = _unit(direction)
    ref = np.array([0.0, 1.0, 0.0]) if abs(f[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    s = _cross(f, ref)
    s /= math.sqrt(float(s @ s))
    basis = np.array([s, _cross(s, f), f])
    basis.setflags(write=False)
    return basis


def fit_cascade(centre: Sequence[float], radius: float, direction: Sequence[float],
                scene_lo: Sequence[float], scene_hi: Sequence[float],
                resolution: int) -> np.ndarray:
    """The (4, 4) world -> clip matrix of one cascade: an orthographic square of side
    2 * radius (plus padding) around `centre` across the light, its centre snapped to a grid
    of `snap_texels` texels of a `resolution`-texel map (along the light too), deep enough to
    hold the sphere and, towards the light, the scene's bounds. Depth is reversed: 1 at the
    side facing the light, 0 at the far side."""
    return _fit_cascades(np.asarray(centre, np.float64)[None], np.array([float(radius)]),
                         light_basis(direction), scene_lo, scene_hi, resolution)[0]


def _fit_cascades(centres: np.ndarray, radii: np.ndarray, basis: np.ndarray,
                  scene_lo: Sequence[float], scene_hi: Sequence[float],
                  resolution: int) -> np.ndarray:
    """`fit_cascade` for n spheres (centres (n, 3), radii (n,)) of one light: (n, 4, 4)."""
    # The square is padded by half a grid step and a texel on each side: snapping moves its
    # centre by up to half a step, and the sphere must stay inside.
    texel = cascade_texel(radii, resolution)
    half = 0.5 * resolution * texel
    grid = (snap_texels(resolution) * texel)[:, None]
    c = np.round((centres @ basis.T) / grid) * grid  # (n, 3) in the light's basis
    nearest, farthest = _depths(basis, scene_lo, scene_hi)
    reach = radii + 0.5 * grid[:, 0]
    z_near = np.minimum(c[:, 2] - reach, nearest)
    z_far = np.maximum(np.maximum(c[:, 2] + reach, farthest), z_near + 1e-6 * np.maximum(radii, 1.0))
    span = z_far - z_near
    r, u, f = basis
    out = np.zeros((len(radii), 4, 4))
    out[:, 0, :3] = r[None] / half[:, None]
    out[:, 0, 3] = -c[:, 0] / half
    out[:, 1, :3] = -u[None] / half[:, None]
    out[:, 1, 3] = c[:, 1] / half
    out[:, 2, :3] = -f[None] / span[:, None]
    out[:, 2, 3] = z_far / span
    out[:, 3, 3] = 1.0
    # + 0.0 turns -0.0 into 0.0: a centre rounded to 0 from either side must give the same
    # bytes (ShadowMaps.stale compares the matrices' bytes to skip redraws).
    return out + 0.0


def cascade_texel(radius: float | np.ndarray, resolution: int) -> float | np.ndarray:
    """World size of one texel of a cascade of sphere `radius`: the map spans the sphere's
    diameter plus half a snapping step and one texel of padding on each side."""
    return 2.0 * radius / (resolution - snap_texels(resolution) - 2)


@dataclass(frozen=True)
class CascadeFit:
    """A directional light's cascades for one camera.

    matrices : (n, 4, 4) float64 world -> clip, one per cascade.
    far : (n,) float64 view depth where each cascade ends (the shader picks the first
        cascade whose `far` is beyond the fragment's view depth).
    texel : (n,) float64 world size of one shadow-map texel in each cascade (normal offset).
    """

    matrices: np.ndarray
    far: np.ndarray
    texel: np.ndarray


def directional_cascades(camera: Camera, size: tuple[int, int], direction: Sequence[float],
                         scene_lo: Sequence[float], scene_hi: Sequence[float], resolution: int,
                         znear: float, zfar: float, count: int = CASCADES) -> CascadeFit:
    """Fit `count` cascades of a directional light travelling along `direction` to the view
    range [znear, zfar] (`cascade_range` of it) of `camera` rendering `size` (W, H) pixels."""
    shape = cascade_shape(camera, size, direction, scene_lo, scene_hi, resolution, znear, zfar,
                          count)
    cols = cascade_columns(camera, shape)
    mats = np.array(cols).reshape(-1, 4, 4).transpose(0, 2, 1)  # column-major -> row-major
    return CascadeFit(np.ascontiguousarray(mats), shape.far.copy(), shape.texel.copy())


@dataclass(frozen=True)
class CascadeShape:
    """What a directional light's cascades keep while the camera only moves: everything of
    their fit but the snapped centres (a moving camera's frames differ in those alone).

    slices : per cascade, Python floats: the slice sphere's centre in view space (x, y, z),
        the square's half side, the snapping grid, the depth reach around the centre, the
        least depth span, then the matrix's first two rows without their translations
        (right / half, -up / half: 6 floats) and the light's travel direction (3).
    basis : the light's (right, up, travel) rows, 9 Python floats.
    nearest, farthest : the scene bounds' least and greatest depth along the light's travel.
    far, texel : (n,) float64 read-only, CascadeFit's.
    header : ShadowData's cascade_far (inf written as NO_FAR) and cascade_texel, 8 floats, for
        the first four cascades (the rest zero, far NO_FAR), as ShadowMaps.write writes them.
    """

    slices: tuple[tuple[float, ...], ...]
    basis: tuple[float, ...]
    nearest: float
    farthest: float
    far: np.ndarray
    texel: np.ndarray
    header: tuple[float, ...]


def cascade_shape(camera: Camera, size: tuple[int, int], direction: Sequence[float],
                  scene_lo: Sequence[float], scene_hi: Sequence[float], resolution: int,
                  znear: float, zfar: float, count: int = CASCADES) -> CascadeShape:
    """The `CascadeShape` of `directional_cascades`' fit (kept: a walking camera's frames
    share it while the projection, the rounded view range and the light stay)."""
    return _cascade_shape(projection_terms(camera, size), cascade_range(znear, zfar), count,
                          tuple(float(x) for x in direction),
                          tuple(float(x) for x in scene_lo), tuple(float(x) for x in scene_hi),
                          int(resolution))


@functools.lru_cache(maxsize=64)
def _cascade_shape(terms: tuple[float, float, float, float], view_range: tuple[float, float],
                   count: int, direction: tuple[float, ...], scene_lo: tuple[float, ...],
                   scene_hi: tuple[float, ...], resolution: int) -> CascadeShape:
    # The same array operations as `_fit_cascades` (so the same floats), done once.
    splits = _splits(view_range, count)
    centre_v, radii = _view_slice_spheres(terms, tuple(splits[:-1]), tuple(splits[1:]))
    basis = light_basis(direction)
    texel = cascade_texel(radii, resolution)
    half = 0.5 * resolution * texel
    grid = snap_texels(resolution) * texel
    reach = radii + 0.5 * grid
    least = 1e-6 * np.maximum(radii, 1.0)
    r, u, f = basis
    slices = tuple((*(float(v) for v in centre_v[i]), float(half[i]), float(grid[i]),
                    float(reach[i]), float(least[i]),
                    *(float(v) for v in r / half[i]), *(float(v) for v in -u / half[i]),
                    *(float(v) for v in f)) for i in range(count))
    far = splits[1:].copy()
    far.setflags(write=False)
    texel.setflags(write=False)
    n = min(count, 4)
    header = (*(float(v) if math.isfinite(v) else NO_FAR for v in far[:n]), *(NO_FAR,) * (4 - n),
              *(float(v) for v in texel[:n]), *(0.0,) * (4 - n))
    return CascadeShape(slices, tuple(float(v) for v in basis.ravel()),
                        *_depths(basis, scene_lo, scene_hi), far, texel, header)


def _depths(basis: np.ndarray, scene_lo: Sequence[float], scene_hi: Sequence[float]
            ) -> tuple[float, float]:
    """The scene bounds' least and greatest depth along the light's travel (basis[2])."""
    depths = _bounds_corners(scene_lo, scene_hi) @ basis[2]
    return float(depths.min()), float(depths.max())


def cascade_columns(camera: Camera, shape: CascadeShape) -> list[float]:
    """The cascades' (4, 4) world -> clip matrices for `camera`, each column-major (as
    ShadowData holds them, 16 floats a cascade, one list): `_fit_cascades`' maths in Python
    floats. It runs every frame a camera moves, where NumPy's overhead on 3-vectors was most
    of a walking frame's Python (~0.3 ms of ~0.7 on lavapipe's host); only the centres are
    computed here, the rest is `shape`'s. The slice centre goes to world space by the view's
    axes (look_at's rows, transposed: a rotation's inverse) instead of a 4x4 inverse, and to
    the light's basis by three dot products: both differ from the NumPy path's in the last
    bits at most, which the snapping rounds away (a centre exactly on a grid line aside)."""
    eye, target, up = camera.eye, camera.target, camera.up
    ex, ey, ez = float(eye[0]), float(eye[1]), float(eye[2])
    fx, fy, fz = float(target[0]) - ex, float(target[1]) - ey, float(target[2]) - ez
    n = math.sqrt(fx * fx + fy * fy + fz * fz)
    fx, fy, fz = fx / n, fy / n, fz / n
    ux, uy, uz = float(up[0]), float(up[1]), float(up[2])
    sx, sy, sz = fy * uz - fz * uy, fz * ux - fx * uz, fx * uy - fy * ux
    n = math.sqrt(sx * sx + sy * sy + sz * sz)
    sx, sy, sz = sx / n, sy / n, sz / n
    ux, uy, uz = sy * fz - sz * fy, sz * fx - sx * fz, sx * fy - sy * fx
    r0, r1, r2, v0, v1, v2, t0, t1, t2 = shape.basis
    nearest, farthest = shape.nearest, shape.farthest
    out: list[float] = []
    for (cx, cy, cz, half, grid, reach, least, a0, a1, a2, b0, b1, b2,
         d0, d1, d2) in shape.slices:
        # view (x right, y up, -z forward) -> world
        wx = ex + sx * cx + ux * cy - fx * cz
        wy = ey + sy * cx + uy * cy - fy * cz
        wz = ez + sz * cx + uz * cy - fz * cz
        # -> the light's basis, snapped to the grid (round: half to even, as np.round)
        lx = round((wx * r0 + wy * r1 + wz * r2) / grid) * grid
        ly = round((wx * v0 + wy * v1 + wz * v2) / grid) * grid
        lz = round((wx * t0 + wy * t1 + wz * t2) / grid) * grid
        z_near = min(lz - reach, nearest)
        z_far = max(lz + reach, farthest, z_near + least)
        span = z_far - z_near
        # + 0.0: -0.0 as 0.0 (ShadowMaps.stale compares the matrices' bytes; `_fit_cascades`)
        out += (a0 + 0.0, b0 + 0.0, -d0 / span + 0.0, 0.0,
                a1 + 0.0, b1 + 0.0, -d1 / span + 0.0, 0.0,
                a2 + 0.0, b2 + 0.0, -d2 / span + 0.0, 0.0,
                -lx / half + 0.0, ly / half + 0.0, z_far / span + 0.0, 1.0)
    return out


def layer_scroll(before: np.ndarray, after: np.ndarray, resolution: int
                 ) -> tuple[int, int] | None:
    """The whole texels (dx, dy) a cascade's map moves by from matrix `before` to `after`
    (16 float32 each, column-major, as ShadowData holds them): a map texel at (x, y) for
    `before` is at (x + dx, y + dy) for `after`. None where they differ in more than the
    translation across the light, by other than whole texels, or by the whole map along an
    axis (no texel kept). A walking camera's cascade crosses its snapping grid by a step of
    snap_texels along one axis or both: the kernels then move the map's texels and draw only
    the strips that came into view (render/shadows.py ShadowMaps.stale).
    Texel x = (clip x * 0.5 + 0.5) * resolution, so a clip translation t moves it by
    t * resolution / 2."""
    b = np.asarray(before, np.float32).reshape(16)
    a = np.asarray(after, np.float32).reshape(16)
    same = b.view(np.uint32) == a.view(np.uint32)
    if not (same[:12].all() and same[14:].all()) or same[12:14].all():
        return None
    shift = (a[12:14].astype(np.float64) - b[12:14].astype(np.float64)) * (0.5 * resolution)
    whole = np.round(shift)
    if not np.all(np.abs(shift - whole) < 1e-3) or np.abs(whole).max() >= resolution:
        return None
    return int(whole[0]), int(whole[1])


@functools.lru_cache(maxsize=64)
def _splits(view_range: tuple[float, float], count: int) -> np.ndarray:
    """cascade_splits of a rounded view range (cascade_range: it repeats while the camera
    moves), read-only."""
    splits = cascade_splits(*view_range, count)
    splits.setflags(write=False)
    return splits


def scene_cascade(direction: Sequence[float], scene_lo: Sequence[float],
                  scene_hi: Sequence[float], resolution: int) -> CascadeFit:
    """One cascade of a directional light covering the scene's whole bounds, the same for
    every camera (a batch's views share it: render/batch.py); it reaches every view depth."""
    lo, hi = np.asarray(scene_lo, dtype=np.float64), np.asarray(scene_hi, dtype=np.float64)
    centre, radius = (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 1e-6)
    return CascadeFit(np.array([fit_cascade(centre, radius, direction, lo, hi, resolution)]),
                      np.array([np.inf]), np.array([cascade_texel(radius, resolution)]))


def perspective_near(position: Sequence[float], light_range: float, scene_lo: Sequence[float],
                     scene_hi: Sequence[float]) -> float:
    """The near plane of a spot or point light's maps: 1/1000 of its reach (the range, else
    the distance to the farthest corner of the scene's bounds). Casters nearer than that to
    the light are clipped; with reversed float depth a small near plane costs no precision."""
    reach = float(light_range) if light_range > 0 else float(np.max(np.linalg.norm(
        _bounds_corners(scene_lo, scene_hi) - np.asarray(position, np.float64), axis=1)))
    return max(reach, 1e-3) * 1e-3


@functools.lru_cache(maxsize=256)
def perspective_maps(kind: str, position: tuple[float, ...], direction: tuple[float, ...],
                     light_range: float, outer_cone: float, scene_lo: tuple[float, ...],
                     scene_hi: tuple[float, ...]) -> tuple[np.ndarray, float]:
    """A spot (`kind` "spot") or point light's map matrices, (1 or 6, 4, 4) read-only, and
    their near plane. They do not depend on the camera: cached, so that a moving camera's
    frames do not remake them (~0.2 ms of Python a frame per point light)."""
    near = perspective_near(position, light_range, scene_lo, scene_hi)
    if kind == "spot":
        mats = spot_matrix(position, direction, outer_cone, near)[None]
    else:
        mats = point_matrices(position, near)
    mats.setflags(write=False)
    return mats, near


def spot_half_angle(outer_cone: float) -> float:
    """Half the field of view of a spot light's map: the outer cone, widened a little for
    PCF, at most MAX_SPOT_HALF_ANGLE (a wider cone is shadowed out to that angle only)."""
    return min(float(outer_cone) * (1.0 + _PCF_MARGIN) + 1e-3, MAX_SPOT_HALF_ANGLE)


def spot_matrix(position: Sequence[float], direction: Sequence[float], outer_cone: float,
                near: float) -> np.ndarray:
    """(4, 4) world -> clip of a spot light's perspective map: square, reversed-Z with an
    infinite far plane (depth = near / distance along the light's axis)."""
    r, u, f = light_basis(direction)
    g = 1.0 / math.tan(spot_half_angle(outer_cone))
    p = np.asarray(position, dtype=np.float64)
    return np.array([
        [*(g * r), -g * float(r @ p)],
        [*(-g * u), g * float(u @ p)],
        [0.0, 0.0, 0.0, near],
        [*f, -float(f @ p)],
    ])


# Vulkan's cube-map face selection (spec, "Cube Map Face Selection"): per face, the major
# axis and the rows giving sc and tc from the direction (rx, ry, rz); s = (sc/|ma| + 1)/2,
# t = (tc/|ma| + 1)/2 with t down the image, i.e. exactly NDC x and y (down) of a face render.
_CUBE_FACES = (
    ((1, 0, 0), (0, 0, -1), (0, -1, 0)),  # +X: sc = -rz, tc = -ry
    ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),  # -X: sc = +rz, tc = -ry
    ((0, 1, 0), (1, 0, 0), (0, 0, 1)),  # +Y: sc = +rx, tc = +rz
    ((0, -1, 0), (1, 0, 0), (0, 0, -1)),  # -Y: sc = +rx, tc = -rz
    ((0, 0, 1), (1, 0, 0), (0, -1, 0)),  # +Z: sc = +rx, tc = -ry
    ((0, 0, -1), (-1, 0, 0), (0, -1, 0)),  # -Z: sc = -rx, tc = -ry
)


def point_matrices(position: Sequence[float], near: float) -> np.ndarray:
    """(6, 4, 4) world -> clip of a point light's cube faces, in Vulkan's face order (+X, -X,
    +Y, -Y, +Z, -Z) and orientation, so that sampling the cube with the direction from the
    light finds the texel each face rendered. Reversed-Z, infinite far: depth = near / |ma|,
    |ma| the largest absolute component of (p - position), which the shader recomputes."""
    p = np.asarray(position, dtype=np.float64)
    out = []
    for major, sc, tc in _CUBE_FACES:
        major, sc, tc = (np.asarray(v, np.float64) for v in (major, sc, tc))
        out.append(np.array([
            [*sc, -float(sc @ p)],
            [*tc, -float(tc @ p)],
            [0.0, 0.0, 0.0, near],
            [*major, -float(major @ p)],
        ]))
    return np.array(out)
