"""Many cameras as arrays (Renderer.render_batch): no Python object per view.

A `CameraBatch` holds B cameras as NumPy arrays with the fields of `Camera`: eye, target and
up (B, 3) float64, the vertical field of view (B,), optional OpenCV pinhole intrinsics
(B, 6: fx, fy, cx, cy and the W, H they belong to) and near/far planes (NaN: derived per
render, as Camera's None). Build one from arrays of eyes and targets, from (B, 4, 4)
world-from-camera poses (OpenGL or OpenCV axes), from OpenCV K and poses, or from a list of
Cameras; `camera(i)` gives view i back as a Camera, which renders the same pixels alone.
Checked as `validate_camera` checks one camera, vectorised: the first bad view is named.
NumPy only (no Vulkan).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene.camera import MAX_COORDINATE, MIN_YFOV_DEG, as_camera, validate_camera
from vkpbr.scene.types import Camera

__all__ = ["CameraBatch", "as_camera_batch", "framing_distance"]

# OpenGL camera axes (x right, y up, z backward) from OpenCV's (x right, y down, z forward).
_FLIP = np.diag([1.0, -1.0, -1.0, 1.0])


def _vectors(value: Any, count: int | None, name: str) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise UsageError(f"cameras: {name} must be numbers") from None
    if a.ndim == 1 and a.shape == (3,) and count is not None:
        a = np.broadcast_to(a, (count, 3))
    if a.ndim != 2 or a.shape[1] != 3:
        raise UsageError(f"cameras: {name} must have shape (B, 3), got {a.shape}")
    return np.ascontiguousarray(a)


def _per_view(value: Any, count: int, name: str) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise UsageError(f"cameras: {name} must be numbers") from None
    if a.ndim == 0:
        a = np.full(count, float(a))
    if a.shape != (count,):
        raise UsageError(f"cameras: {name} must be one number or {count} numbers, got shape {a.shape}")
    return a


@dataclass(frozen=True)
class CameraBatch:
    """B cameras as arrays (see the module docstring). Make one with the class methods."""

    eye: np.ndarray  # (B, 3) float64
    target: np.ndarray  # (B, 3) float64
    up: np.ndarray  # (B, 3) float64
    yfov_deg: np.ndarray  # (B,) float64
    intrinsics: np.ndarray | None = None  # (B, 6) float64: fx, fy, cx, cy, W, H
    znear: np.ndarray | None = None  # (B,) float64, NaN: derived per render
    zfar: np.ndarray | None = None  # (B,) float64, NaN: from the scene's bounds
    # Each view's (model, distortion) where any view has a lens (scene/lens.py): such
    # batches render view by view (render/batch_route.py), each resampled to its model.
    lenses: tuple[tuple[str, tuple[float, ...]], ...] | None = None

    def __post_init__(self) -> None:
        # Read-only copies of the arrays (where they are the caller's, writable): a batch
        # never changes after it is made, so a renderer given the same batch again reuses
        # what it made of it (its validation, its view records) without comparing arrays.
        for name in ("eye", "target", "up", "yfov_deg", "intrinsics", "znear", "zfar"):
            a = getattr(self, name)
            if isinstance(a, np.ndarray) and a.flags.writeable:
                a = a.copy()
                a.flags.writeable = False
                object.__setattr__(self, name, a)
        object.__setattr__(self, "_valid", False)

    def __len__(self) -> int:
        return len(self.eye)

    @classmethod
    def from_look_at(cls, eye: Any, target: Any, up: Any = (0.0, 1.0, 0.0),
                     yfov_deg: Any = 45.0, znear: Any = None, zfar: Any = None) -> CameraBatch:
        """Cameras at `eye` (B, 3) looking at `target` (B, 3 or 3), `up` (B, 3 or 3)."""
        e = _vectors(eye, None, "eye")
        b = len(e)
        batch = cls(e, _vectors(target, b, "target"), _vectors(up, b, "up"),
                    _per_view(yfov_deg, b, "yfov_deg"),
                    znear=None if znear is None else _per_view(znear, b, "znear"),
                    zfar=None if zfar is None else _per_view(zfar, b, "zfar"))
        batch.validate()
        return batch

    @classmethod
    def from_poses(cls, poses: Any, yfov_deg: Any = 45.0, convention: str = "opengl") -> CameraBatch:
        """Cameras from (B, 4, 4) world-from-camera poses: OpenGL axes (x right, y up, z
        backward: NeRF, Blender) or "opencv" (x right, y down, z forward). The same cameras
        as `Camera.from_pose` makes one at a time (eye, eye + forward, up)."""
        if convention not in ("opengl", "opencv"):
            raise UsageError(f"cameras: convention {convention!r}: expected 'opengl' or 'opencv'")
        m = np.asarray(poses, dtype=np.float64)
        if m.ndim != 3 or m.shape[1:] != (4, 4):
            raise UsageError(f"cameras: poses must have shape (B, 4, 4), got {m.shape}")
        if convention == "opengl":
            m = m @ _FLIP
        eye = np.ascontiguousarray(m[:, :3, 3])
        batch = cls(eye, eye + m[:, :3, 2], np.ascontiguousarray(-m[:, :3, 1]),
                    _per_view(yfov_deg, len(m), "yfov_deg"))
        batch.validate()
        return batch

    @classmethod
    def from_opencv(cls, K: Any, poses: Any, size: tuple[int, int]) -> CameraBatch:
        """Cameras from OpenCV intrinsics K ((3, 3) or (B, 3, 3), pixels of an image of
        `size` (W, H)) and (B, 4, 4) world-from-camera poses in OpenCV axes."""
        batch = cls.from_poses(poses, 45.0, "opencv")
        k = np.asarray(K, dtype=np.float64)
        k = np.broadcast_to(k, (len(batch), 3, 3)) if k.shape == (3, 3) else k
        if k.shape != (len(batch), 3, 3):
            raise UsageError(f"cameras: K must have shape (3, 3) or ({len(batch)}, 3, 3), got {k.shape}")
        fx, fy = k[:, 0, 0], k[:, 1, 1]
        if not (np.all(fx > 0) and np.all(fy > 0)):
            raise UsageError("cameras: K's fx and fy must be > 0")
        w, h = (float(v) for v in size)
        intr = np.stack([fx, fy, k[:, 0, 2], k[:, 1, 2], np.full(len(k), w), np.full(len(k), h)], 1)
        yfov = np.degrees(2.0 * np.arctan(h / (2.0 * fy)))
        return cls(batch.eye, batch.target, batch.up, yfov, intrinsics=intr)

    @classmethod
    def from_cameras(cls, cameras: Iterable[Any], base: Camera) -> CameraBatch:
        """A list of Cameras (or anything `as_camera` takes: 4x4 poses, strings, pose dicts)."""
        cams = [base if c is None else as_camera(c, base) for c in cameras]
        for c in cams:
            validate_camera(c)
        if not cams:
            raise UsageError("cameras: the batch is empty")
        has_k = any(c.pixel_intrinsics is not None for c in cams)

        def planes(name: str) -> np.ndarray | None:
            values = [getattr(c, name) for c in cams]
            if all(v is None for v in values):
                return None
            return np.array([math.nan if v is None else float(v) for v in values])

        intr = None
        if has_k:
            intr = np.array([c.pixel_intrinsics if c.pixel_intrinsics is not None
                             else (math.nan,) * 6 for c in cams], dtype=np.float64)
        lenses = (tuple((c.model, tuple(c.distortion)) for c in cams)
                  if any(c.model != "pinhole" for c in cams) else None)
        return cls(np.array([c.eye for c in cams], dtype=np.float64),
                   np.array([c.target for c in cams], dtype=np.float64),
                   np.array([c.up for c in cams], dtype=np.float64),
                   np.array([c.yfov_deg for c in cams], dtype=np.float64),
                   intr, planes("znear"), planes("zfar"), lenses)

    # -- generators: orbits, spheres and random views around a scene's bounds -----------------

    @classmethod
    def orbit(cls, n: int, center: Any = None, radius: float | None = None, *,
              bounds: Any = None, elevation_deg: float = 20.0, start_deg: float = 0.0,
              turns: float = 1.0, yfov_deg: float = 45.0,
              up: Any = (0.0, 1.0, 0.0)) -> CameraBatch:
        """`n` views on a circle about `up` through `center` (a turntable), each looking at
        `center` from `radius` away, `elevation_deg` above the circle's plane; azimuths from
        `start_deg` over `turns` turns (the last view one step short of the first), counter-
        clockwise seen from above, starting on the +Z side for up = +Y.

        `bounds` (lo, hi), as `Scene.bounds()` returns them, gives the centre and a radius
        that frames the bounds (`framing_distance`) where `center` / `radius` are not given.
        """
        c, r, u = _orbit_frame(center, radius, bounds, yfov_deg, up)
        a = np.radians(start_deg) + 2.0 * np.pi * turns * np.arange(_count(n)) / _count(n)
        e = np.radians(elevation_deg)
        side, front = _basis(u)
        d = (np.cos(e) * (np.sin(a)[:, None] * side + np.cos(a)[:, None] * front)
             + np.sin(e) * u)
        return cls.from_look_at(c + r * d, c, u, yfov_deg)

    @classmethod
    def sphere(cls, n: int, center: Any = None, radius: float | None = None, *,
               bounds: Any = None, upper: bool = False, yfov_deg: float = 45.0,
               up: Any = (0.0, 1.0, 0.0)) -> CameraBatch:
        """`n` views spread evenly over a sphere about `center` (a Fibonacci lattice: equal
        areas, no clumping at the poles), each looking at `center` from `radius` away;
        `upper`: the hemisphere on `up`'s side only (views from above the ground). `bounds`
        as for `orbit`. No view looks along `up` exactly (the lattice avoids the poles)."""
        c, r, u = _orbit_frame(center, radius, bounds, yfov_deg, up)
        k = _count(n)
        i = np.arange(k) + 0.5
        h = 1.0 - i / k if upper else 1.0 - 2.0 * i / k  # height along up, in (-1, 1)
        ring = np.sqrt(np.maximum(0.0, 1.0 - h * h))
        a = np.pi * (3.0 - math.sqrt(5.0)) * np.arange(k)  # the golden angle
        side, front = _basis(u)
        d = ring[:, None] * (np.cos(a)[:, None] * front + np.sin(a)[:, None] * side) + h[:, None] * u
        return cls.from_look_at(c + r * d, c, u, yfov_deg)

    @classmethod
    def look_at_random(cls, n: int, bounds: Any, *, distance: tuple[float, float] = (1.0, 2.0),
                       seed: int | None = None, yfov_deg: float = 45.0,
                       up: Any = (0.0, 1.0, 0.0)) -> CameraBatch:
        """`n` random views of the box `bounds` (lo, hi): each looks at a point drawn
        uniformly inside the box from a direction drawn uniformly over the sphere, at
        `distance` (a range, drawn uniformly) times the distance that frames the whole box
        (`framing_distance`). `seed` makes the batch repeatable (NumPy's default_rng). A
        direction within 1 degree of `up` is drawn again."""
        lo, hi = _bounds(bounds)
        rng = np.random.default_rng(seed)
        k = _count(n)
        u = _unit(up, "up")
        dirs = np.empty((0, 3))
        while len(dirs) < k:  # rejection: keep views off the up axis (look_at needs a side)
            d = rng.normal(size=(2 * k, 3))
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            dirs = np.concatenate([dirs, d[np.abs(d @ u) < math.cos(math.radians(1.0))]])
        target = lo + rng.random((k, 3)) * (hi - lo)
        lo_d, hi_d = (float(x) for x in distance)
        if not 0.0 < lo_d <= hi_d:
            raise UsageError(f"cameras: distance {distance}: expected 0 < low <= high")
        far = framing_distance((lo, hi), yfov_deg) * rng.uniform(lo_d, hi_d, k)
        return cls.from_look_at(target + far[:, None] * dirs[:k], target, u, yfov_deg)

    def camera(self, i: int) -> Camera:
        """View `i` as a Camera (rendered alone, it gives view i's pixels)."""
        def opt(a: np.ndarray | None) -> float | None:
            return None if a is None or math.isnan(a[i]) else float(a[i])

        k = None
        if self.intrinsics is not None and not math.isnan(self.intrinsics[i, 0]):
            fx, fy, cx, cy, w, h = (float(v) for v in self.intrinsics[i])
            k = (fx, fy, cx, cy, int(w), int(h))
        model, distortion = self.lenses[i] if self.lenses is not None else ("pinhole", ())
        return Camera(eye=tuple(map(float, self.eye[i])), target=tuple(map(float, self.target[i])),
                      up=tuple(map(float, self.up[i])), yfov_deg=float(self.yfov_deg[i]),
                      znear=opt(self.znear), zfar=opt(self.zfar), pixel_intrinsics=k,
                      model=model, distortion=distortion)

    def validate(self) -> None:
        """Raise a one-line UsageError naming the first view `validate_camera` would refuse
        (once: the batch cannot change afterwards)."""
        if self._valid:  # type: ignore[attr-defined]
            return
        if not len(self):  # (a (0, 4, 4) array of poses, a look-at of no eyes)
            raise UsageError("cameras: the batch is empty")
        with np.errstate(all="ignore"):  # NaN and inf are what is being looked for
            bad = self._bad_views()
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            try:
                validate_camera(self.camera(i))
            except UsageError as e:
                raise UsageError(f"cameras[{i}]: {str(e).removeprefix('camera: ')}") from None
            raise UsageError(f"cameras[{i}]: not a valid camera")
        object.__setattr__(self, "_valid", True)

    def _bad_views(self) -> np.ndarray:
        """(B,) bool: the views `validate_camera` refuses (its checks, vectorised)."""
        f = self.target - self.eye
        coords = np.concatenate([self.eye, self.target, self.up], 1)
        bad = ~np.all(np.isfinite(coords), axis=1)
        bad |= np.abs(np.nan_to_num(coords)).max(axis=1) > MAX_COORDINATE
        f_len = np.sqrt(np.einsum("ij,ij->i", f, f))
        cross = np.cross(f, self.up)
        u_len = np.sqrt(np.einsum("ij,ij->i", self.up, self.up))
        bad |= f_len < 1e-9
        bad |= np.sqrt(np.einsum("ij,ij->i", cross, cross)) < 1e-9 * f_len * np.maximum(u_len, 1e-30)
        bad |= ~((self.yfov_deg >= MIN_YFOV_DEG) & (self.yfov_deg < 180.0))
        for planes in (self.znear, self.zfar):
            if planes is not None:
                bad |= ~(np.isnan(planes) | ((planes > 0) & (planes < math.inf)))
        if self.znear is not None and self.zfar is not None:
            bad |= ~(np.isnan(self.zfar) | (self.zfar > np.nan_to_num(self.znear)))
        return bad


def framing_distance(bounds: Any, yfov_deg: float = 45.0) -> float:
    """How far from the centre of the box `bounds` (lo, hi) a camera with vertical field of
    view `yfov_deg` sees all of it from any direction (and horizontally too in an image at
    least as wide as it is high): the bounding sphere's radius over sin(fov / 2)."""
    lo, hi = _bounds(bounds)
    r = float(np.linalg.norm(hi - lo)) / 2.0
    r = r if math.isfinite(r) and r > 1e-9 else 1.0
    if not MIN_YFOV_DEG <= yfov_deg < 180.0:
        raise UsageError(f"cameras: yfov_deg {yfov_deg}: expected a field of view in (0, 180)")
    return r / math.sin(math.radians(yfov_deg) / 2.0)


def _count(n: Any) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise UsageError(f"cameras: n {n!r}: expected a number of views >= 1")
    return int(n)


def _unit(v: Any, name: str) -> np.ndarray:
    a = _vectors([v], None, name)[0]
    n = float(np.linalg.norm(a))
    if not math.isfinite(n) or n < 1e-12:
        raise UsageError(f"cameras: {name} {tuple(a)}: expected a non-zero vector")
    return a / n


def _bounds(bounds: Any) -> tuple[np.ndarray, np.ndarray]:
    try:
        lo, hi = (np.asarray(b, dtype=np.float64).reshape(3) for b in bounds)
    except (TypeError, ValueError):
        raise UsageError("cameras: bounds must be (lo, hi), two 3-vectors (Scene.bounds())") from None
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi >= lo)):
        raise UsageError(f"cameras: bounds {lo.tolist()}, {hi.tolist()}: expected finite lo <= hi")
    return lo, hi


def _basis(up: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing `up` to a right-handed frame: (side, front), front = +Z
    and side = +X for up = +Y."""
    ref = np.array([0.0, 0.0, 1.0]) if abs(up[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    front = ref - (ref @ up) * up
    front /= np.linalg.norm(front)
    return np.cross(up, front), front


def _orbit_frame(center: Any, radius: float | None, bounds: Any, yfov_deg: float,
                 up: Any) -> tuple[np.ndarray, float, np.ndarray]:
    """The centre, radius and unit up of an orbit or sphere of views."""
    if center is None and bounds is None:
        raise UsageError("cameras: give center (and radius), or bounds (Scene.bounds())")
    if center is None:
        lo, hi = _bounds(bounds)
        center = (lo + hi) / 2.0
    c = _vectors([center], None, "center")[0]
    if radius is None:
        if bounds is None:
            raise UsageError("cameras: give radius, or bounds to frame")
        radius = framing_distance(bounds, yfov_deg)
    r = float(radius)
    if not (math.isfinite(r) and r > 0.0):
        raise UsageError(f"cameras: radius {radius!r}: expected a number > 0")
    return c, r, _unit(up, "up")


def as_camera_batch(cameras: Any, base: Camera) -> CameraBatch:
    """What a user passed as a batch's cameras, as a CameraBatch: a CameraBatch, a (B, 4, 4)
    array of OpenGL world-from-camera poses (the field of view from `base`), or an iterable
    of Cameras / anything `as_camera` takes."""
    if isinstance(cameras, CameraBatch):
        cameras.validate()
        return cameras
    if isinstance(cameras, np.ndarray) and cameras.ndim == 3:
        return CameraBatch.from_poses(cameras, base.yfov_deg)
    if isinstance(cameras, (str, bytes, Camera)) or not isinstance(cameras, Iterable):
        raise UsageError(f"cameras: expected a list of cameras, (B, 4, 4) poses or a "
                         f"CameraBatch, got {type(cameras).__name__}")
    return CameraBatch.from_cameras(cameras, base)
