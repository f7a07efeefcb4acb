"""Camera matrices for Vulkan: right-handed view, reversed-Z depth with an infinite far plane,
Y flipped (the course's "reversed-Y" projection), so that +Y world-up appears at the top of
the image. The near plane is chosen per render from the scene's bounds (`depth_range`).

Matrices here are row-major NumPy (column vectors: clip = P @ V @ p); `layouts.mat4_to_std140`
transposes them for GLSL. What frames and batches draw with is render/views.py's: one
function for 1..N views, whose column-major terms these NumPy matrices equal (the tests'
reference); `camera_frame_columns`, `depth_range` and `batch_frame_terms` return its values.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

# The views record's maths (projection_terms re-exported for the shadow cascades).
from vkpbr.render.views import batch_view_terms, camera_view_terms, projection_terms

# Moved to the scene layer (NumPy only); re-exported so that existing imports keep working.
from vkpbr.scene.camera import as_camera, format_camera, parse_camera, validate_camera  # noqa: F401
from vkpbr.scene.camera_batch import CameraBatch
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


# Plain float arithmetic: the shadow maps' cascades (render/shadow_math.py) call these when
# the camera moves, and NumPy's per-call overhead on 3-vectors would cost ~20x the maths.
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
    """`view_projection` as GLSL's column-major mat4: 16 plain floats, column by column (the
    view record's VP; `f` is not needed any more and ignored)."""
    return camera_frame_columns(camera, size, znear)[0]


def camera_frame_columns(camera: Camera, size: tuple[int, int], znear: float,
                         f: tuple[float, float, float] | None = None
                         ) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """(VP, VP's inverse, the camera's rotation) with the near plane `znear`, column-major
    plain floats: render/views.py's terms of the view (kept for its callers; `f` ignored).
    The rotation is world-from-camera in OpenGL axes, the columns right, up, backward."""
    # The near plane is given, so the scene's bounds only feed zfar, which is not returned:
    # the eye stands in for them.
    t = camera_view_terms(dataclasses.replace(camera, znear=znear), size, (camera.eye,), 1.0)
    return t.vp, t.inv_vp, t.rotation


def depth_range(camera: Camera, corners: Sequence[Sequence[float]], scale: float,
                f: tuple[float, float, float] | None = None) -> tuple[float, float]:
    """(znear, zfar) for a render, from the 8 corners of the scene's bounds and its radius
    `scale` (render/views.py's planes of the view; `f` ignored)."""
    t = camera_view_terms(camera, (1, 1), corners, scale)
    return t.znear, t.zfar


def batch_frame_terms(eye: np.ndarray, target: np.ndarray, up: np.ndarray, yfov_deg: np.ndarray,
                      intrinsics: np.ndarray | None, znear: np.ndarray | None,
                      zfar: np.ndarray | None, size: tuple[int, int],
                      corners: Sequence[Sequence[float]], scale: float) -> dict[str, np.ndarray]:
    """render/views.py's terms of B cameras (arrays as CameraBatch holds them) as arrays:
    {"vp": (B, 16) column-major VP, "inv_vp": its inverse, "forward": (B, 3), "znear",
    "zfar": (B,)} (kept for its callers: views.batch_view_terms is the batch's path)."""
    n = len(eye)
    t = batch_view_terms(CameraBatch(eye, target, up, yfov_deg, intrinsics, znear, zfar), size,
                         corners, scale)

    def stacked(values: Sequence[np.ndarray | float]) -> np.ndarray:
        return np.stack([np.broadcast_to(v, n) for v in values], 1)

    return {"vp": stacked(t.vp), "inv_vp": stacked(t.inv_vp), "forward": stacked(t.forward),
            "znear": t.znear, "zfar": t.zfar}


def linear_depth(d: np.ndarray, znear: float | np.ndarray) -> np.ndarray:
    """Reversed-Z window depth -> view-space distance along the axis (inf = background);
    `znear` broadcasts against `d` (a batch: one per view)."""
    with np.errstate(divide="ignore"):
        z = znear / d.astype(np.float64)
    z[d <= 0.0] = np.inf
    return z.astype(np.float32)
