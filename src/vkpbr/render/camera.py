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

__all__ = ["look_at", "perspective", "view_projection", "parse_camera", "format_camera"]


def look_at(eye: Sequence[float], target: Sequence[float], up: Sequence[float]) -> np.ndarray:
    """World-to-view matrix (4, 4) float64; the camera looks down its -Z axis."""
    eye_v = np.asarray(eye, dtype=np.float64)
    f = np.asarray(target, dtype=np.float64) - eye_v
    f /= np.linalg.norm(f)
    s = np.cross(f, np.asarray(up, dtype=np.float64))
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye_v
    return m


def perspective(yfov_deg: float, aspect: float, znear: float, zfar: float) -> np.ndarray:
    """View-to-clip matrix (4, 4) float64 for Vulkan: z in [0, 1], Y down in clip space."""
    f = 1.0 / math.tan(math.radians(yfov_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = -f  # Vulkan's clip-space Y points down
    m[2, 2] = zfar / (znear - zfar)
    m[2, 3] = znear * zfar / (znear - zfar)
    m[3, 2] = -1.0
    return m


def view_projection(camera: Camera, aspect: float) -> np.ndarray:
    return perspective(camera.yfov_deg, aspect, camera.znear, camera.zfar) @ look_at(
        camera.eye, camera.target, camera.up
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
