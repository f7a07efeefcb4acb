"""The views record: every camera a frame or a batch draws through, as layouts.VIEW_RECORD
(view-projection, its inverse, eye and near plane, forward and far plane, intrinsics,
viewport, layer), built by one function for 1..N views and read by every shader as
`views[view_index]` (set 0's Views storage buffer: record 0 for a single frame, the
instance's or tile's view in a batch).

`view_terms` is the camera maths, written once over columns: each input is either a Python
float (one view: a single frame) or a (N,) NumPy array (N views: a batch), and each view's
values come from the same float operations in the same order, element by element. Python
floats and NumPy float64 round +, -, *, / and sqrt alike (IEEE 754), so view i of a batch
equals view i drawn alone, bit for bit, by construction. A single frame is the batch of one
in Python floats: on (1,) arrays NumPy's per-call overhead makes the terms ~70 us and the
record ~140 us more, where the floats take ~5 us and one struct pack ~1 (2-core test
machine; a frame's whole uniform write for a moving camera is ~7 us).

Matrices are GLSL's column-major mat4 as 16 values, column by column (layouts.mat4_to_std140
is the NumPy matrices' transpose).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from vkpbr.render import layouts as L
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.types import Camera

__all__ = ["ViewTerms", "view_terms", "camera_view_terms", "batch_view_terms",
           "projection_terms", "pack_view", "fill_views"]

Value = Any  # a Python float (one view) or a (N,) float64 array (N views)
Vec3 = tuple[Value, Value, Value]


class ViewTerms(NamedTuple):
    """One view's (or N views') camera terms; each value a float or a (N,) array."""

    vp: tuple[Value, ...]  # 16: clip from world, column-major (reversed-Z, infinite far)
    inv_vp: tuple[Value, ...]  # 16: world from clip (pixel rays), column-major
    eye: Vec3
    forward: Vec3  # unit viewing direction
    znear: Value  # the near plane: the camera's own, else just in front of the scene's bounds
    zfar: Value  # the camera's own, else the bounds' far side (scales the depth view only)
    intrinsics: tuple[Value, Value, Value, Value]  # sx, sy, ox, oy (projection_terms)
    rotation: tuple[Value, ...]  # 9: world from camera (OpenGL axes), columns right, up, back


class _Floats:
    """The column operations on one view's Python floats."""

    sqrt = staticmethod(math.sqrt)
    least = staticmethod(min)  # over the corners' list
    most = staticmethod(max)
    maximum = staticmethod(max)

    @staticmethod
    def where(has: bool, a: float, b: float) -> float:
        return a if has else b

    @staticmethod
    def given(plane: float | None, derived: float) -> float:
        return derived if plane is None else plane

    @staticmethod
    def present(fx: float) -> bool:  # one view's intrinsics, when given, are given
        return True

    @staticmethod
    def tan_terms(yfov_deg: float) -> float:
        return 1.0 / math.tan(math.radians(yfov_deg) / 2.0)


class _Arrays:
    """The same operations on N views' (N,) arrays (NaN planes and intrinsics: derived)."""

    sqrt = staticmethod(np.sqrt)
    least = staticmethod(np.minimum.reduce)
    most = staticmethod(np.maximum.reduce)
    maximum = staticmethod(np.maximum)
    where = staticmethod(np.where)

    @staticmethod
    def given(plane: np.ndarray | None, derived: np.ndarray) -> np.ndarray:
        return derived if plane is None else np.where(np.isnan(plane), derived, plane)

    @staticmethod
    def present(fx: np.ndarray) -> np.ndarray:
        return ~np.isnan(fx)

    @staticmethod
    def tan_terms(yfov_deg: np.ndarray) -> np.ndarray:
        """With math.tan, as one view takes it (NumPy's tan may differ in the last bit),
        once per distinct field of view."""
        values, inverse = np.unique(yfov_deg, return_inverse=True)
        g = np.array([1.0 / math.tan(math.radians(float(v)) / 2.0) for v in values])
        return g[inverse.reshape(-1)]


def _sub(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: Vec3, b: Vec3) -> Value:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _unit(xp: Any, a: Vec3) -> Vec3:
    n = xp.sqrt(_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def _projection(xp: Any, yfov_deg: Value, intrinsics: Sequence[Value] | None,
                size: tuple[int, int]) -> tuple[Value, Value, Value, Value]:
    """(sx, sy, ox, oy): NDC x = sx x / -z + ox, y (down) = -sy y / -z + oy for a view-space
    point (x, y, z) (OpenGL axes). Square pixels centred from the field of view, or from
    OpenCV's K (fx, fy, cx, cy at an image of w0 x h0: pixel centres at integers) scaled to
    `size` (as scene.camera.intrinsics scales it), so a calibrated K lands each point on
    the pixel OpenCV projects it to."""
    w, h = size
    g = xp.tan_terms(yfov_deg)
    square = (g * h / w, g, 0.0, 0.0)
    if intrinsics is None:
        return square
    fx, fy, cx, cy, w0, h0 = intrinsics
    kx, ky = w / w0, h / h0
    fx, fy = fx * kx, fy * ky
    cx, cy = (cx + 0.5) * kx - 0.5, (cy + 0.5) * ky - 0.5
    pinhole = (2.0 * fx / w, 2.0 * fy / h, 2.0 * (cx + 0.5) / w - 1.0, 2.0 * (cy + 0.5) / h - 1.0)
    has = xp.present(intrinsics[0])
    return tuple(xp.where(has, a, b) for a, b in zip(pinhole, square, strict=True))  # type: ignore[return-value]


def _planes(xp: Any, f: Vec3, eye: Vec3, znear: Value | None, zfar: Value | None,
            corners: Sequence[Sequence[float]], scale: float) -> tuple[Value, Value]:
    """(znear, zfar) from the 8 corners of the scene's bounds. znear: the camera's own, else
    half the nearest corner's depth along the view axis, and never less than 1e-5 * `scale`
    (the scene's radius) when the camera is inside or beside the bounds: with reversed-Z
    float depth the near plane costs no precision, so erring small is free. zfar never clips
    (the far plane is at infinity): it scales the depth debug view only; the camera's own,
    else the farthest corner."""
    depths = [f[0] * (c[0] - eye[0]) + f[1] * (c[1] - eye[1]) + f[2] * (c[2] - eye[2])
              for c in corners]
    near = xp.given(znear, xp.maximum(0.5 * xp.least(depths), 1e-5 * scale))
    far = xp.given(zfar, xp.maximum(xp.most(depths), 2.0 * near))
    return near, far


def view_terms(eye: Vec3, target: Vec3, up: Vec3, yfov_deg: Value,
               intrinsics: Sequence[Value] | None, znear: Value | None, zfar: Value | None,
               size: tuple[int, int], corners: Sequence[Sequence[float]],
               scale: float) -> ViewTerms:
    """The camera terms of one view (every value a Python float; `intrinsics` the camera's
    (fx, fy, cx, cy, w0, h0) or None, the planes a float or None) or of N views (every value
    a (N,) float64 array: the columns of CameraBatch's arrays, NaN: derived), for frames of
    `size` (W, H) of a scene whose bounds have `corners` and radius `scale`."""
    xp = _Floats if isinstance(yfov_deg, float) else _Arrays
    f = _unit(xp, _sub(target, eye))
    s = _unit(xp, _cross(f, up))
    u = _cross(s, f)
    sx, sy, ox, oy = _projection(xp, yfov_deg, intrinsics, size)
    near, far = _planes(xp, f, eye, znear, zfar, corners, scale)
    se, ue, fe = _dot(s, eye), _dot(u, eye), _dot(f, eye)
    # V's rows: s (x), u (y), -f (z), with translations -s.e, -u.e, f.e. P is sparse, so the
    # rows of P @ V are sx*x - ox*z, -sy*y - oy*z, znear * e3 and -z, where -z = f.p - f.e.
    vp = (sx * s[0] + ox * f[0], -sy * u[0] + oy * f[0], 0.0, f[0],
          sx * s[1] + ox * f[1], -sy * u[1] + oy * f[1], 0.0, f[1],
          sx * s[2] + ox * f[2], -sy * u[2] + oy * f[2], 0.0, f[2],
          -sx * se - ox * fe, sy * ue - oy * fe, near, -fe)
    # VP's inverse, solved from its rows: with q = p - e h and h = Z / znear, s.q = (X - ox W)
    # / sx, u.q = (oy W - Y) / sy, f.q = W.
    w = tuple(f[i] - s[i] * ox / sx + u[i] * oy / sy for i in range(3))
    inv = (s[0] / sx, s[1] / sx, s[2] / sx, 0.0,
           -u[0] / sy, -u[1] / sy, -u[2] / sy, 0.0,
           eye[0] / near, eye[1] / near, eye[2] / near, 1.0 / near,
           w[0], w[1], w[2], 0.0)
    rotation = (*s, *u, -f[0], -f[1], -f[2])
    return ViewTerms(vp, inv, eye, f, near, far, (sx, sy, ox, oy), rotation)


def projection_terms(camera: Camera, size: Sequence[int]) -> tuple[float, float, float, float]:
    """One camera's (sx, sy, ox, oy) at `size` (W, H), as its view record has them."""
    k = camera.pixel_intrinsics
    return _projection(_Floats, float(camera.yfov_deg),
                       None if k is None else tuple(float(v) for v in k),
                       (int(size[0]), int(size[1])))


def camera_view_terms(camera: Camera, size: Sequence[int], corners: Sequence[Sequence[float]],
                      scale: float) -> ViewTerms:
    """`view_terms` of one Camera, in Python floats (the per-frame path)."""
    e, t, u = camera.eye, camera.target, camera.up
    k = camera.pixel_intrinsics
    return view_terms(
        (float(e[0]), float(e[1]), float(e[2])), (float(t[0]), float(t[1]), float(t[2])),
        (float(u[0]), float(u[1]), float(u[2])), float(camera.yfov_deg),
        None if k is None else tuple(float(v) for v in k),
        None if camera.znear is None else float(camera.znear),
        None if camera.zfar is None else float(camera.zfar),
        (int(size[0]), int(size[1])), corners, scale)


def batch_view_terms(batch: CameraBatch, size: Sequence[int], corners: Sequence[Sequence[float]],
                     scale: float) -> ViewTerms:
    """`view_terms` of a CameraBatch's views, in (N,) arrays."""
    def columns(a: np.ndarray) -> tuple[np.ndarray, ...]:
        return tuple(a.T)

    k = batch.intrinsics
    return view_terms(columns(batch.eye), columns(batch.target), columns(batch.up),  # type: ignore[arg-type]
                      batch.yfov_deg, None if k is None else columns(k), batch.znear,
                      batch.zfar, (int(size[0]), int(size[1])), corners, scale)


def pack_view(buffer: Any, terms: ViewTerms, viewport: tuple[int, int, int, int],
              layer: int = 0) -> None:
    """Write one view's record (Python floats) into `buffer` (a writable buffer of
    VIEW_RECORD.size bytes): one struct pack, the per-frame write."""
    t = terms
    L.VIEW_RECORD.pack_into(buffer, VP=t.vp, inv_VP=t.inv_vp, eye_near=(*t.eye, t.znear),
                            forward_far=(*t.forward, t.zfar), intrinsics=t.intrinsics,
                            viewport=viewport, layer=layer, instance_base=0, factor_base=0,
                            shadow_base=0)


def fill_views(records: np.ndarray, terms: ViewTerms, viewport: np.ndarray,
               layer: np.ndarray | int) -> None:
    """Write N views' records ((N,) arrays) into `records` ((N,) VIEW_RECORD.dtype), field
    for field what `pack_view` writes; `viewport` (N, 4) and `layer` (N,) unsigned (or one
    for all)."""
    n = len(records)

    def stacked(values: Sequence[Value]) -> np.ndarray:  # (N, len(values)); floats broadcast
        return np.stack([np.broadcast_to(v, n) for v in values], 1)

    t = terms
    records["VP"] = stacked(t.vp).reshape(n, 4, 4)
    records["inv_VP"] = stacked(t.inv_vp).reshape(n, 4, 4)
    records["eye_near"] = stacked((*t.eye, t.znear))
    records["forward_far"] = stacked((*t.forward, t.zfar))
    records["intrinsics"] = stacked(t.intrinsics)
    records["viewport"] = viewport
    records["layer"] = layer
    records["instance_base"] = 0
    records["factor_base"] = 0
    records["shadow_base"] = 0
