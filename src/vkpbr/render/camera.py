"""Camera matrices for Vulkan: right-handed view, depth in [0, 1], Y flipped (the course's
"reversed-Y" projection), so that +Y world-up appears at the top of the image.

Matrices are row-major NumPy (column vectors: clip = P @ V @ p); `layouts.mat4_to_std140`
transposes them for GLSL.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene.types import Camera

__all__ = ["look_at", "perspective", "forward", "view_projection", "view_projection_columns",
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


def perspective(yfov_deg: float, aspect: float, znear: float, zfar: float) -> np.ndarray:
    """View-to-clip matrix (4, 4) float64 for Vulkan: z in [0, 1], Y down in clip space."""
    f = 1.0 / math.tan(math.radians(yfov_deg) / 2.0)
    a, b = zfar / (znear - zfar), znear * zfar / (znear - zfar)
    # m[1, 1] is negative: Vulkan's clip-space Y points down.
    return np.array([[f / aspect, 0, 0, 0], [0, -f, 0, 0], [0, 0, a, b], [0, 0, -1.0, 0]])


def forward(camera: Camera) -> tuple[float, float, float]:
    """Unit viewing direction."""
    return _unit(_sub(camera.target, camera.eye))


def view_projection(camera: Camera, aspect: float) -> np.ndarray:
    return perspective(camera.yfov_deg, aspect, camera.znear, camera.zfar) @ look_at(
        camera.eye, camera.target, camera.up
    )


def view_projection_columns(camera: Camera, aspect: float) -> tuple[tuple[float, ...], ...]:
    """`view_projection` as GLSL's column-major mat4 (four columns), in plain floats.

    The per-frame path when the camera moves: P is sparse, so P @ V is four scaled rows of V,
    ~5x cheaper than NumPy's array creation and matmul (which is kept for everything else).
    """
    eye = camera.eye
    f = _unit(_sub(camera.target, eye))
    s = _unit(_cross(f, (float(camera.up[0]), float(camera.up[1]), float(camera.up[2]))))
    u = _cross(s, f)
    g = 1.0 / math.tan(math.radians(camera.yfov_deg) / 2.0)
    zn, zf = camera.znear, camera.zfar
    a, b = zf / (zn - zf), zn * zf / (zn - zf)
    gx = g / aspect
    se, ue, fe = _dot3(s, eye), _dot3(u, eye), _dot3(f, eye)
    # Rows of P @ V: gx*s_row, -g*u_row, a*w_row + b*e3, -w_row, with w_row = (-f, f.eye).
    return (
        (gx * s[0], -g * u[0], -a * f[0], f[0]),
        (gx * s[1], -g * u[1], -a * f[1], f[1]),
        (gx * s[2], -g * u[2], -a * f[2], f[2]),
        (-gx * se, g * ue, a * fe + b, -fe),
    )


def validate_camera(camera: Camera) -> None:
    eye, target, up = (np.asarray(x, dtype=np.float64) for x in (camera.eye, camera.target, camera.up))
    if not all(np.all(np.isfinite(x)) for x in (eye, target, up)):
        raise UsageError("camera: eye, target and up must be finite numbers")
    forward = target - eye
    if np.linalg.norm(forward) < 1e-9:
        raise UsageError("camera: eye and target coincide")
    if np.linalg.norm(np.cross(forward, up)) < 1e-9 * np.linalg.norm(forward) * max(np.linalg.norm(up), 1e-30):
        raise UsageError("camera: up is parallel to the viewing direction (or zero)")
    if not 0.0 < camera.yfov_deg < 180.0:
        raise UsageError(f"camera: field of view {camera.yfov_deg} must be in (0, 180) degrees")
    if not 0.0 < camera.znear < camera.zfar:
        raise UsageError(f"camera: need 0 < near ({camera.znear}) < far ({camera.zfar})")


def parse_camera(text: str, base: Camera | None = None) -> Camera:
    """Parse "ex,ey,ez,tx,ty,tz[,ux,uy,uz]" (the format `format_camera` prints)."""
    try:
        values = [float(x) for x in text.replace(" ", "").split(",")]
    except ValueError:
        raise UsageError(f"--camera {text!r}: expected 6 or 9 comma-separated numbers") from None
    if len(values) not in (6, 9):
        raise UsageError(f"--camera {text!r}: expected 6 or 9 numbers, got {len(values)}")
    base = base or Camera()
    cam = Camera(
        eye=tuple(values[0:3]),
        target=tuple(values[3:6]),
        up=tuple(values[6:9]) if len(values) == 9 else base.up,
        yfov_deg=base.yfov_deg,
        znear=base.znear,
        zfar=base.zfar,
    )
    validate_camera(cam)
    return cam


def format_camera(camera: Camera) -> str:
    vals = [*camera.eye, *camera.target, *camera.up]
    return ",".join(f"{v:.6g}" for v in vals)
