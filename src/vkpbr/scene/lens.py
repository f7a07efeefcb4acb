"""Camera models beyond the pinhole: OpenCV's lens distortion and fisheye lenses, in NumPy.

Models (`Camera(model=..., distortion=...)`, docs/cameras.md), with the coefficients in
OpenCV's order:

- "pinhole": no distortion.
- "opencv": OpenCV's radial-tangential model with the rational radial term, `distortion` =
  (k1, k2, p1, p2[, k3[, k4, k5, k6]]) as `cv2.projectPoints`' distCoeffs (4, 5 or 8 numbers;
  COLMAP's OPENCV is the first four, FULL_OPENCV all eight). With x = X/Z, y = Y/Z,
  r2 = x^2 + y^2:
      R  = (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3)
      x' = x R + 2 p1 x y + p2 (r2 + 2 x^2),   y' = y R + p1 (r2 + 2 y^2) + 2 p2 x y
- "opencv_fisheye": OpenCV's fisheye (Kannala-Brandt) model, `distortion` = (k1, k2, k3, k4)
  as `cv2.fisheye.projectPoints`' D (COLMAP's OPENCV_FISHEYE). theta is the angle between
  the ray and the optical axis (atan2(sqrt(X^2 + Y^2), Z), so rays behind the camera have
  theta > 90 degrees):
      theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
      (x', y') = theta_d (X, Y) / sqrt(X^2 + Y^2)
- "equidistant": the ideal fisheye, theta_d = theta (no coefficients).

Pixels are u = fx x' + cx, v = fy y' + cy in OpenCV's convention (the centre of the top-left
pixel is (0, 0)), K from `Camera.intrinsics(size)`.

`pixel_rays` is the inverse (pixel -> ray), by Newton's method as the GPU's resample does it
(shaders/post_lens.comp mirrors `undistort`): iterative, not a precomputed map texture,
because the model is a few multiply-adds a pixel on a step bound by memory, so it costs
nothing measurable, while a map would be a full-size float texture to compute, upload and keep
per camera (a batch of different intrinsics would need one each) and its bilinear lookup
would itself be approximate. A ray whose Newton iteration does not converge (beyond the fold
of a strong distortion) or that lies outside the model's domain is invalid (NaN): the
resample writes the background there.

`source_view` plans how a model's image is rendered: a wider pinhole camera with the same
pose whose image covers every ray of the model's pixels, sampled at least as densely as the
model's densest pixel, then resampled on the GPU (render/post.py Lens). A fisheye whose
rays reach more than MAX_PINHOLE_ANGLE_DEG off its axis (up to 180: a 360-degree field) is
rendered as cube faces instead (`cube_view`: the faces its pixels see, FACES' axes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vkpbr.errors import UsageError

__all__ = ["MODELS", "COEFFICIENTS", "MAX_PINHOLE_ANGLE_DEG", "check_model", "distortion_vector",
           "project", "distort", "undistort", "pixel_rays", "source_view", "SourceView",
           "FACES", "CUBE_MARGIN", "face_of", "cube_view", "CubeView", "widest_angle", "widest_ray"]

# Model -> the names of its coefficients, in OpenCV's order (the longest form).
COEFFICIENTS: dict[str, tuple[str, ...]] = {
    "pinhole": (),
    "opencv": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
    "opencv_fisheye": ("k1", "k2", "k3", "k4"),
    "equidistant": (),
}
MODELS = tuple(COEFFICIENTS)
MODEL_IDS = {name: i for i, name in enumerate(MODELS)}  # (shaders/post_lens.comp's MODEL_*)
_COUNTS = {"pinhole": (0,), "opencv": (4, 5, 8), "opencv_fisheye": (4,), "equidistant": (0,)}
# The widest angle off the axis a pinhole source renders (150 degrees across): beyond it a
# pinhole's image grows without bound (tan 75 degrees = 3.7 focal lengths each side).
MAX_PINHOLE_ANGLE_DEG = 75.0
NEWTON_STEPS = 20
# A Newton solution counts when it reproduces its distorted point to this (normalised units:
# 1e-4 pixels at a focal length of 1000 pixels).
CONVERGED = 1e-7


def check_model(model: object, distortion: object) -> str | None:
    """What is wrong with a camera's `model` and `distortion`, or None."""
    if not isinstance(model, str) or model not in COEFFICIENTS:  # (a dict from JSON: unhashable)
        shown = repr(model) if len(repr(model)) <= 40 else repr(model)[:37] + "..."
        return f"model {shown}: choose from {', '.join(MODELS)}"
    try:
        values = [float(v) for v in distortion]  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        return f"distortion {distortion!r}: expected a sequence of numbers"
    if len(values) not in _COUNTS[model]:  # type: ignore[index]
        names = ", ".join(COEFFICIENTS[model]) or "none"  # type: ignore[index]
        counts = " or ".join(map(str, _COUNTS[model]))  # type: ignore[index]
        return f"model {model!r} takes {counts} distortion coefficients ({names}), got {len(values)}"
    if not all(map(math.isfinite, values)):
        return "distortion coefficients must be finite"
    return None


def distortion_vector(model: str, distortion: tuple[float, ...] | list[float]) -> np.ndarray:
    """The coefficients padded with zeros to the model's longest form, float64."""
    out = np.zeros(len(COEFFICIENTS[model]))
    out[: len(distortion)] = distortion
    return out


# -- forward: rays to distorted normalised coordinates ---------------------------------------
def _radial_tangential(c: np.ndarray, x: np.ndarray, y: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    k1, k2, p1, p2, k3, k4, k5, k6 = c
    r2 = x * x + y * y
    radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
    return (x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)


def _theta_d(c: np.ndarray, theta: np.ndarray) -> np.ndarray:
    t2 = theta * theta
    return theta * (1 + t2 * (c[0] + t2 * (c[1] + t2 * (c[2] + t2 * c[3]))))


def distort(model: str, distortion: tuple[float, ...], rays: np.ndarray) -> np.ndarray:
    """Distorted normalised coordinates (..., 2) of rays (..., 3) in OpenCV camera axes (x
    right, y down, z forward). Pinhole and "opencv" rays need z > 0 (NaN otherwise)."""
    d = np.asarray(rays, np.float64)
    X, Y, Z = d[..., 0], d[..., 1], d[..., 2]
    c = distortion_vector(model, distortion)
    if model in ("pinhole", "opencv"):
        with np.errstate(divide="ignore", invalid="ignore"):
            x, y = np.where(Z > 0, X / Z, np.nan), np.where(Z > 0, Y / Z, np.nan)
        if model == "opencv":
            x, y = _radial_tangential(c, x, y)
        return np.stack([x, y], -1)
    r = np.hypot(X, Y)
    theta = np.arctan2(r, Z)
    td = _theta_d(c, theta) if model == "opencv_fisheye" else theta
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(r > 0, td / np.where(r > 0, r, 1.0), 0.0)
    return np.stack([X * scale, Y * scale], -1)


def project(model: str, distortion: tuple[float, ...], K: np.ndarray,
            points: np.ndarray) -> np.ndarray:
    """Pixels (..., 2) of camera-space points (..., 3) (OpenCV axes) through `K` (3, 3)."""
    xy = distort(model, distortion, points)
    K = np.asarray(K, np.float64)
    return np.stack([K[0, 0] * xy[..., 0] + K[0, 2], K[1, 1] * xy[..., 1] + K[1, 2]], -1)


# -- inverse: distorted normalised coordinates to rays (Newton, as post_lens.comp) -----------
def undistort(model: str, distortion: tuple[float, ...], xd: np.ndarray) -> np.ndarray:
    """Unit rays (..., 3) (OpenCV axes) whose distorted normalised coordinates are `xd`
    (..., 2); NaN where the model has no ray (no convergence, outside its domain)."""
    xd = np.asarray(xd, np.float64)
    c = distortion_vector(model, distortion)
    if model in ("pinhole", "opencv"):
        x, y = (_newton_opencv(c, xd[..., 0], xd[..., 1]) if model == "opencv"
                else (xd[..., 0], xd[..., 1]))
        d = np.stack([x, y, np.ones_like(x)], -1)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)
    td = np.hypot(xd[..., 0], xd[..., 1])
    theta = _newton_fisheye(c, td) if model == "opencv_fisheye" else td
    theta = np.where(theta <= math.pi, theta, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(td > 0, np.sin(theta) / np.where(td > 0, td, 1.0), 0.0)
    return np.stack([xd[..., 0] * s, xd[..., 1] * s, np.cos(theta)], -1)


def _newton_opencv(c: np.ndarray, xd: np.ndarray, yd: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Solve _radial_tangential(x, y) = (xd, yd): Newton with the analytic (symmetric)
    Jacobian, started at the distorted point."""
    k1, k2, p1, p2, k3, k4, k5, k6 = c
    x, y = xd.copy(), yd.copy()
    for _ in range(NEWTON_STEPS):
        r2 = x * x + y * y
        a = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        b = 1 + r2 * (k4 + r2 * (k5 + r2 * k6))
        da = k1 + r2 * (2 * k2 + 3 * k3 * r2)
        db = k4 + r2 * (2 * k5 + 3 * k6 * r2)
        radial, dradial = a / b, (da * b - a * db) / (b * b)
        fx = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) - xd
        fy = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y - yd
        jxx = radial + 2 * x * x * dradial + 2 * p1 * y + 6 * p2 * x
        jyy = radial + 2 * y * y * dradial + 6 * p1 * y + 2 * p2 * x
        jxy = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y
        det = jxx * jyy - jxy * jxy
        with np.errstate(divide="ignore", invalid="ignore"):
            x, y = x - (jyy * fx - jxy * fy) / det, y - (jxx * fy - jxy * fx) / det
    rx, ry = _radial_tangential(c, x, y)
    bad = ~(np.hypot(rx - xd, ry - yd) <= CONVERGED * np.maximum(1.0, np.hypot(xd, yd)))
    return np.where(bad, np.nan, x), np.where(bad, np.nan, y)


def _newton_fisheye(c: np.ndarray, td: np.ndarray) -> np.ndarray:
    """Solve theta (1 + k1 theta^2 + ... + k4 theta^8) = td for theta by Newton."""
    theta = td.copy()
    for _ in range(NEWTON_STEPS):
        t2 = theta * theta
        g = _theta_d(c, theta) - td
        dg = 1 + t2 * (3 * c[0] + t2 * (5 * c[1] + t2 * (7 * c[2] + t2 * 9 * c[3])))
        with np.errstate(divide="ignore", invalid="ignore"):
            theta = theta - g / dg
    ok = (np.abs(_theta_d(c, theta) - td) <= CONVERGED * np.maximum(1.0, td)) & (theta >= 0)
    return np.where(ok, theta, np.nan)


def pixel_rays(model: str, distortion: tuple[float, ...], K: np.ndarray,
               pixels: np.ndarray) -> np.ndarray:
    """Unit rays (..., 3) (OpenCV axes) of pixel positions (..., 2) (OpenCV convention)."""
    K = np.asarray(K, np.float64)
    p = np.asarray(pixels, np.float64)
    xd = np.stack([(p[..., 0] - K[0, 2]) / K[0, 0], (p[..., 1] - K[1, 2]) / K[1, 1]], -1)
    return undistort(model, distortion, xd)


# -- the pinhole a model's image is resampled from -------------------------------------------
@dataclass(frozen=True)
class SourceView:
    """The pinhole image a model's image is resampled from: focal length `focal` (pixels,
    square), principal point (cx, cy) (OpenCV convention) and size (W, H)."""

    focal: float
    cx: float
    cy: float
    size: tuple[int, int]

    def K(self) -> np.ndarray:  # noqa: N802 (the matrix's usual name)
        return np.array([[self.focal, 0.0, self.cx], [0.0, self.focal, self.cy], [0.0, 0.0, 1.0]])


def source_view(model: str, distortion: tuple[float, ...], K: np.ndarray,
                size: tuple[int, int], max_pixels: int, max_side: int,
                granule: int = 1) -> SourceView:
    """The pinhole view (same pose) whose image covers every valid ray of the model's image of
    `size` through `K`, at least as densely as the model's densest pixel (its smallest
    singular value of d(tangent plane)/d(pixel)), with a texel of margin for the bilinear
    taps; the focal length is lowered to keep within `max_pixels` and `max_side` pixels. The
    size is rounded up to whole `granule`s (the margin split evenly), so that cameras of
    nearly the same intrinsics share one source size (the renderer keeps an image per size).
    UsageError when a ray is more than MAX_PINHOLE_ANGLE_DEG off the axis."""
    rays, valid = _sampled_rays(model, distortion, K, size)
    d = rays[0]
    widest = widest_angle(d, valid)
    if widest > MAX_PINHOLE_ANGLE_DEG + 1e-9:
        wider = ("; a wider field needs opencv_fisheye or equidistant (cube faces)"
                 if model in ("pinhole", "opencv") else "")
        raise UsageError(f"camera: model {model!r} sees rays {widest:.1f} degrees off its axis; "
                         f"at most {MAX_PINHOLE_ANGLE_DEG:g} are rendered through one pinhole (a "
                         f"{2 * MAX_PINHOLE_ANGLE_DEG:g}-degree field){wider}")
    t = [r[..., :2] / r[..., 2:3] for r in rays]
    jac = np.stack([t[1] - t[0], t[2] - t[0]], -1)  # (..., 2, 2): columns d/du, d/dv
    both = valid & np.isfinite(jac).all((-1, -2))
    sigma = np.linalg.svd(jac[both], compute_uv=False)[:, -1]
    focal = 1.0 / float(sigma.min())
    lo, hi = t[0][valid].min(0), t[0][valid].max(0)
    span = hi - lo
    focal = min(focal, (max_side - 4) / float(span.max()),
                math.sqrt(max_pixels / max(float(span[0] * span[1]), 1e-12)))
    cx, cy = 1.5 - focal * lo[0], 1.5 - focal * lo[1]  # a texel and a half of margin
    sw, sh = math.ceil(focal * hi[0] + cx) + 2, math.ceil(focal * hi[1] + cy) + 2
    rw, rh = (min(-(-n // granule) * granule, max(max_side, n)) for n in (sw, sh))
    cx, cy = cx + (rw - sw) // 2, cy + (rh - sh) // 2
    return SourceView(focal, float(cx), float(cy), (int(rw), int(rh)))


def _sampled_rays(model: str, distortion: tuple[float, ...], K: np.ndarray,
                  size: tuple[int, int]) -> tuple[list[np.ndarray], np.ndarray]:
    """Rays of a grid of the image's pixels (every `min(w, h) // 48`th, its borders and outer
    edges) and of their right and lower neighbours, and where the first are valid.
    UsageError where no ray is."""
    w, h = size
    step = max(1, min(w, h) // 48)
    xs = np.unique(np.r_[np.arange(0, w, step), w - 1, -0.5, w - 0.5])
    ys = np.unique(np.r_[np.arange(0, h, step), h - 1, -0.5, h - 0.5])
    gx, gy = np.meshgrid(xs, ys)
    grid = np.stack([gx, gy], -1)
    rays = [pixel_rays(model, distortion, K, grid + off) for off in ((0, 0), (1, 0), (0, 1))]
    valid = np.isfinite(rays[0]).all(-1)
    if not valid.any():
        raise UsageError(f"camera: model {model!r} has no valid ray in its image")
    return rays, valid


def widest_ray(model: str, distortion: tuple[float, ...], K: np.ndarray,
               size: tuple[int, int]) -> float:
    """The largest angle (degrees) off the axis of a ray of the model's image."""
    rays, valid = _sampled_rays(model, distortion, K, size)
    return widest_angle(rays[0], valid)


def widest_angle(rays: np.ndarray, valid: np.ndarray) -> float:
    """The largest angle (degrees) between a valid ray and the optical axis."""
    return math.degrees(math.acos(float(np.clip(rays[valid][:, 2].min(), -1.0, 1.0))))


# -- cube faces: fisheyes wider than a pinhole can render ------------------------------------
# Each face's camera axes (rows: right, down, forward) in the lens camera's OpenCV axes:
# front (+z), right (+x), left (-x), down (+y), up (-y), back (-z); right x down = forward.
FACES = np.array([
    [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
    [[0, 0, -1], [0, 1, 0], [1, 0, 0]],
    [[0, 0, 1], [0, 1, 0], [-1, 0, 0]],
    [[1, 0, 0], [0, 0, -1], [0, 1, 0]],
    [[1, 0, 0], [0, 0, 1], [0, -1, 0]],
    [[-1, 0, 0], [0, 1, 0], [0, 0, -1]],
], np.float64)
# Texels each face image has beyond its 90-degree square on every side, so that a ray's
# bilinear taps always lie in the one face its major axis picks (no sampling across seams).
CUBE_MARGIN = 2


def face_of(rays: np.ndarray) -> np.ndarray:
    """The face (index into FACES) each ray (..., 3) lies in: its major axis, ties to z
    before x before y (as lens_cube.glsl `cube_face`)."""
    a = np.abs(rays)
    z_major = (a[..., 2] >= a[..., 0]) & (a[..., 2] >= a[..., 1])
    x_major = ~z_major & (a[..., 0] >= a[..., 1])
    return np.where(z_major, np.where(rays[..., 2] >= 0, 0, 5),
                    np.where(x_major, np.where(rays[..., 0] >= 0, 1, 2),
                             np.where(rays[..., 1] >= 0, 3, 4)))


@dataclass(frozen=True)
class CubeView:
    """The cube faces a model's image is resampled from: `faces` (indices into FACES, in the
    order they are drawn), each a square pinhole image of `size` pixels a side whose focal
    length `focal` maps the face's 90 degrees to all but CUBE_MARGIN texels each side."""

    faces: tuple[int, ...]
    focal: float
    size: int

    def K(self) -> np.ndarray:  # noqa: N802 (the matrix's usual name)
        c = (self.size - 1) / 2.0
        return np.array([[self.focal, 0.0, c], [0.0, self.focal, c], [0.0, 0.0, 1.0]])


def cube_view(model: str, distortion: tuple[float, ...], K: np.ndarray, size: tuple[int, int],
              max_pixels: int, max_side: int, granule: int = 1) -> CubeView:
    """The cube faces that cover every valid ray of the model's image of `size` through `K`
    (a face is drawn where a sampled ray lies in it or within a grid step's angle of it: no
    output pixel between samples falls in a face left out), each sampled at least as densely
    as the model's densest pixel (the smallest singular value of d(unit ray)/d(pixel); a
    pinhole face is densest at its edges, sparsest at its centre, where its focal length is
    its density), lowered to keep all faces within `max_pixels` and `max_side`; the side a
    multiple of `granule`. UsageError for models that cannot see beyond 90 degrees."""
    if model in ("pinhole", "opencv"):
        raise UsageError(f"camera: model {model!r} cannot see beyond 90 degrees off its axis; "
                         "use opencv_fisheye or equidistant")
    rays, valid = _sampled_rays(model, distortion, K, size)
    jac = np.stack([rays[1] - rays[0], rays[2] - rays[0]], -1)  # (..., 3, 2)
    both = valid & np.isfinite(jac).all((-1, -2))
    sigma = np.linalg.svd(jac[both], compute_uv=False)[:, -1]
    density = 1.0 / float(sigma.min())  # texels a radian
    # The grid's step as an angle: rays within it of a face's boundary count for that face.
    gap = float(np.linalg.norm(jac[both], axis=-2).max()) * max(1, min(size) // 48) * 1.5
    d = rays[0][valid]
    faces = set(face_of(d).tolist())
    for tilt in ((gap, 0), (-gap, 0), (0, gap), (0, -gap)):
        faces |= set(face_of(d + _perpendicular(d, tilt)).tolist())
    order = tuple(sorted(faces, key=lambda f: (f == 0, f)))  # the front face last
    n = len(order)
    side = 2.0 * density + 2 * CUBE_MARGIN + 1
    side = min(side, max_side, math.sqrt(max_pixels / n))
    side = max(granule, int(-(-int(math.ceil(side)) // granule) * granule))
    side = min(side, max_side)
    focal = (side - 1) / 2.0 - CUBE_MARGIN
    return CubeView(order, focal, side)


def _perpendicular(d: np.ndarray, tilt: tuple[float, float]) -> np.ndarray:
    """Offsets of unit rays `d` by `tilt` radians along two directions across them."""
    up = np.where(np.abs(d[:, 1:2]) < 0.9, np.array([[0.0, 1.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    a = np.cross(d, up)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(d, a)
    return tilt[0] * a + tilt[1] * b
