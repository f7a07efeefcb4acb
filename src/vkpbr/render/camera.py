"""Camera matrices for Vulkan: right-handed view, reversed-Z depth with an infinite far plane,
Y flipped (the course's "reversed-Y" projection), so that +Y world-up appears at the top of
the image. The near plane is chosen per render from the scene's bounds (`depth_range`).

Matrices are row-major NumPy (column vectors: clip = P @ V @ p); `layouts.mat4_to_std140`
transposes them for GLSL.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

# Moved to the scene layer (NumPy only); re-exported so that existing imports keep working.
from vkpbr.scene.camera import as_camera, format_camera, parse_camera, validate_camera  # noqa: F401
from vkpbr.scene.types import Camera

__all__ = ["look_at", "perspective", "forward", "view_projection", "view_projection_columns",
           "batch_frame_terms", "linear_depth",
           "camera_frame_columns",
           "projection_terms", "depth_range",
           "parse_camera", "format_camera"]


def _sub(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, float]:
    return (float(a[0]) - float(b[0]), float(a[1]) - float(b[1]), float(a[2]) - float(b[2]))


def _cross(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, float]:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit(a: Sequence[float]) -> tuple[float, float, float]:
    n = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    return (a[0] / n, a[1] / n, a[2] / n)


def _dot3(a: Sequence[float], b: Sequence[float]) -> float:
    return float(a[0]) * b[0] + float(a[1]) * b[1] + float(a[2]) * b[2]


# Plain float arithmetic: these run once per frame when the camera moves, and NumPy's
# per-call overhead on 3-vectors would cost ~20x more than the maths.
def look_at(eye: Sequence[float], target: Sequence[float], up: Sequence[float]) -> np.ndarray:
    """World-to-view matrix (4, 4) float64; the camera looks down its -Z axis."""
    f = _unit(_sub(target, eye))
    s = _unit(_cross(f, (float(up[0]), float(up[1]), float(up[2]))))
    u = _cross(s, f)
    return np.array([
        [s[0], s[1], s[2], -_dot3(s, eye)],
        [u[0], u[1], u[2], -_dot3(u, eye)],
        [-f[0], -f[1], -f[2], _dot3(f, eye)],
        [0.0, 0.0, 0.0, 1.0],
    ])


def projection_terms(camera: Camera, size: tuple[int, int]) -> tuple[float, float, float, float]:
    """(sx, sy, ox, oy): normalised device x = sx * x / -z + ox and y = -sy * y / -z + oy for
    a view-space point (x, y, z) (OpenGL view axes: x right, y up, looking down -z), with
    Vulkan's NDC y pointing down. From the camera's pinhole intrinsics K at `size` (OpenCV's
    pixel convention: pixel centres at integers), so a K from a calibration lands each point
    on the pixel OpenCV would project it to."""
    w, h = size
    if camera.pixel_intrinsics is None:  # square pixels, centred: the per-frame fast path
        g = 1.0 / math.tan(math.radians(camera.yfov_deg) / 2.0)
        return g * h / w, g, 0.0, 0.0
    k = camera.intrinsics(size)
    fx, fy, cx, cy = float(k[0][0]), float(k[1][1]), float(k[0][2]), float(k[1][2])
    return 2.0 * fx / w, 2.0 * fy / h, 2.0 * (cx + 0.5) / w - 1.0, 2.0 * (cy + 0.5) / h - 1.0


def perspective(camera: Camera, size: tuple[int, int], znear: float) -> np.ndarray:
    """View-to-clip matrix (4, 4) float64: reversed-Z with an infinite far plane.

    Window depth is znear / distance along the view axis: 1 at the near plane, falling
    towards 0 at infinity, so nothing beyond the near plane is ever clipped, and a float32
    depth buffer keeps ~7 significant digits of relative precision at every distance.
    Depth tests use GREATER_OR_EQUAL and clear to 0.
    """
    sx, sy, ox, oy = projection_terms(camera, size)
    # clip w = -z; x_ndc = sx x/(-z) + ox; y_ndc (down) = -sy y/(-z) + oy; depth = znear/(-z).
    return np.array([[sx, 0, -ox, 0], [0, -sy, -oy, 0], [0, 0, 0, znear], [0, 0, -1.0, 0]])


def forward(camera: Camera) -> tuple[float, float, float]:
    """Unit viewing direction."""
    return _unit(_sub(camera.target, camera.eye))


def view_projection(camera: Camera, size: tuple[int, int], znear: float) -> np.ndarray:
    return perspective(camera, size, znear) @ look_at(camera.eye, camera.target, camera.up)


def view_projection_columns(camera: Camera, size: tuple[int, int], znear: float,
                            f: tuple[float, float, float] | None = None) -> tuple[float, ...]:
    """`view_projection` as GLSL's column-major mat4: 16 plain floats, column by column.

    The per-frame path when the camera moves: P is sparse, so P @ V is a few scaled rows of
    V, ~5x cheaper than NumPy's array creation and matmul (which is kept for everything else).
    `f`: forward(camera), when the caller has it already.
    """
    return camera_frame_columns(camera, size, znear, f)[0]


def camera_frame_columns(camera: Camera, size: tuple[int, int], znear: float,
                         f: tuple[float, float, float] | None = None
                         ) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """(VP, VP's inverse, the camera's rotation), column-major plain floats: what a frame
    writes when its camera moves, in plain float maths (no NumPy per frame).

    VP: as `view_projection_columns`. Its inverse (world from clip: the compute path's pixel
    rays), solved from VP's rows below: with q = p - e h and h = Z / znear, s.q = (X - ox W) /
    sx, u.q = (oy W - Y) / sy, f.q = W. The rotation: world-from-camera in OpenGL axes, the
    columns right s, up u, backward -f (3 x 3, the outputs' camera-space normals).
    """
    eye = camera.eye
    f = f or forward(camera)
    s = _unit(_cross(f, (float(camera.up[0]), float(camera.up[1]), float(camera.up[2]))))
    u = _cross(s, f)
    sx, sy, ox, oy = projection_terms(camera, size)
    se, ue, fe = _dot3(s, eye), _dot3(u, eye), _dot3(f, eye)
    # V's rows: s (x), u (y), -f (z), with translations -s.e, -u.e, f.e. Rows of P @ V:
    # sx*x - ox*z, -sy*y - oy*z, znear * e3, -z, where -z = f.p - f.e.
    vp = (sx * s[0] + ox * f[0], -sy * u[0] + oy * f[0], 0.0, f[0],
          sx * s[1] + ox * f[1], -sy * u[1] + oy * f[1], 0.0, f[1],
          sx * s[2] + ox * f[2], -sy * u[2] + oy * f[2], 0.0, f[2],
          -sx * se - ox * fe, sy * ue - oy * fe, znear, -fe)
    w = tuple(f[i] - s[i] * ox / sx + u[i] * oy / sy for i in range(3))
    inv = (s[0] / sx, s[1] / sx, s[2] / sx, 0.0,
           -u[0] / sy, -u[1] / sy, -u[2] / sy, 0.0,
           eye[0] / znear, eye[1] / znear, eye[2] / znear, 1.0 / znear,
           w[0], w[1], w[2], 0.0)
    rotation = (*s, *u, -f[0], -f[1], -f[2])
    return vp, inv, rotation


def depth_range(camera: Camera, corners: Sequence[Sequence[float]], scale: float,
                f: tuple[float, float, float] | None = None) -> tuple[float, float]:
    """(znear, zfar) for a render, from the 8 corners of the scene's bounds.

    znear: the camera's own, else just in front of the nearest corner along the view axis,
    and never less than 1e-5 * `scale` (the scene's radius) when the camera is inside or
    beside the bounds. With reversed-Z float depth the near plane costs no precision, so
    erring small is free. zfar never clips (the far plane is at infinity): it only scales
    the depth debug view: the camera's own, or the farthest corner along the view axis.
    """
    f, e = f or forward(camera), camera.eye
    ex, ey, ez = float(e[0]), float(e[1]), float(e[2])
    depths = [f[0] * (c[0] - ex) + f[1] * (c[1] - ey) + f[2] * (c[2] - ez) for c in corners]
    znear = float(camera.znear) if camera.znear is not None else max(0.5 * min(depths), 1e-5 * scale)
    zfar = float(camera.zfar) if camera.zfar is not None else max(max(depths), 2.0 * znear)
    return znear, zfar


def _unique_tan_terms(yfov_deg: np.ndarray) -> np.ndarray:
    """1 / tan(yfov / 2) per view, with math.tan (as `projection_terms`): NumPy's tan may
    differ from it in the last bit, and a batch's views must be bit-equal to single frames.
    Evaluated once per distinct field of view."""
    values, inverse = np.unique(yfov_deg, return_inverse=True)
    g = np.array([1.0 / math.tan(math.radians(float(v)) / 2.0) for v in values])
    return g[inverse.reshape(-1)]


def batch_frame_terms(eye: np.ndarray, target: np.ndarray, up: np.ndarray, yfov_deg: np.ndarray,
                      intrinsics: np.ndarray | None, znear: np.ndarray | None,
                      zfar: np.ndarray | None, size: tuple[int, int],
                      corners: Sequence[Sequence[float]], scale: float) -> dict[str, np.ndarray]:
    """`camera_frame_columns` and `depth_range` for B cameras at once, in the same float
    operations in the same order (so each view's values equal a single frame's, bit for
    bit): {"vp": (B, 16) column-major VP, "inv_vp": its inverse (as camera_frame_columns
    solves it), "forward": (B, 3), "znear", "zfar": (B,)}.
    Arrays as vkpbr.scene.camera_batch.CameraBatch holds them (NaN planes: derived)."""
    w, h = size
    d = target - eye
    f = d / np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])[:, None]
    c = np.stack([f[:, 1] * up[:, 2] - f[:, 2] * up[:, 1], f[:, 2] * up[:, 0] - f[:, 0] * up[:, 2],
                  f[:, 0] * up[:, 1] - f[:, 1] * up[:, 0]], 1)
    s = c / np.sqrt(c[:, 0] * c[:, 0] + c[:, 1] * c[:, 1] + c[:, 2] * c[:, 2])[:, None]
    u = np.stack([s[:, 1] * f[:, 2] - s[:, 2] * f[:, 1], s[:, 2] * f[:, 0] - s[:, 0] * f[:, 2],
                  s[:, 0] * f[:, 1] - s[:, 1] * f[:, 0]], 1)
    g = _unique_tan_terms(yfov_deg)
    sx, sy = g * h / w, g
    ox = oy = np.zeros(len(eye))
    if intrinsics is not None:  # OpenCV K where given (as scene.camera.intrinsics scales it)
        has = ~np.isnan(intrinsics[:, 0])
        fx, fy, cx, cy, w0, h0 = (intrinsics[:, i] for i in range(6))
        kx, ky = w / w0, h / h0
        fx, fy = fx * kx, fy * ky
        cx, cy = (cx + 0.5) * kx - 0.5, (cy + 0.5) * ky - 0.5
        sx = np.where(has, 2.0 * fx / w, sx)
        sy = np.where(has, 2.0 * fy / h, sy)
        ox = np.where(has, 2.0 * (cx + 0.5) / w - 1.0, 0.0)
        oy = np.where(has, 2.0 * (cy + 0.5) / h - 1.0, 0.0)

    def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]

    depths = np.stack([f[:, 0] * (cc[0] - eye[:, 0]) + f[:, 1] * (cc[1] - eye[:, 1])
                       + f[:, 2] * (cc[2] - eye[:, 2]) for cc in corners], 1)
    near = np.maximum(0.5 * depths.min(axis=1), 1e-5 * scale)
    if znear is not None:
        near = np.where(np.isnan(znear), near, znear)
    far = np.maximum(depths.max(axis=1), 2.0 * near)
    if zfar is not None:
        far = np.where(np.isnan(zfar), far, zfar)
    se, ue, fe = dot(s, eye), dot(u, eye), dot(f, eye)
    zero = np.zeros(len(eye))
    vp = np.stack([sx * s[:, 0] + ox * f[:, 0], -sy * u[:, 0] + oy * f[:, 0], zero, f[:, 0],
                   sx * s[:, 1] + ox * f[:, 1], -sy * u[:, 1] + oy * f[:, 1], zero, f[:, 1],
                   sx * s[:, 2] + ox * f[:, 2], -sy * u[:, 2] + oy * f[:, 2], zero, f[:, 2],
                   -sx * se - ox * fe, sy * ue - oy * fe, near, -fe], 1)
    # VP's inverse as camera_frame_columns solves it (the compute batch's pixel rays).
    wv = f - s * (ox / sx)[:, None] + u * (oy / sy)[:, None]
    inv = np.stack([s[:, 0] / sx, s[:, 1] / sx, s[:, 2] / sx, zero,
                    -u[:, 0] / sy, -u[:, 1] / sy, -u[:, 2] / sy, zero,
                    eye[:, 0] / near, eye[:, 1] / near, eye[:, 2] / near, 1.0 / near,
                    wv[:, 0], wv[:, 1], wv[:, 2], zero], 1)
    return {"vp": vp, "inv_vp": inv, "forward": f, "znear": near, "zfar": far}


def linear_depth(d: np.ndarray, znear: float | np.ndarray) -> np.ndarray:
    """Reversed-Z window depth -> view-space distance along the axis (inf = background);
    `znear` broadcasts against `d` (a batch: one per view)."""
    with np.errstate(divide="ignore"):
        z = znear / d.astype(np.float64)
    z[d <= 0.0] = np.inf
    return z.astype(np.float32)
