"""The viewer's fly camera: both control schemes of renderer-spec section 7, no window code.

Report scheme: left drag = yaw and pitch, right drag = pan in the view plane, scroll = move
forward / back (the middle button, which hides the cursor, lives in the viewer). Course
scheme: W/S forward/back, A/D strafe, E/Q up/down, Shift x5, Ctrl x0.05, base speed 1.7
units/s, mouse look 0.01 rad per pixel. The course's 1.7 units/s is for Sponza; other scenes
scale it by their bounding radius, so that crossing any scene takes about as long.

The pose is eye + yaw/pitch about the start camera's up axis; `camera()` rebuilds a
`Camera` whose target sits `focus` units ahead, so `format_camera` prints a pose that
`vkpbr render --camera` reproduces.
"""

from __future__ import annotations

import math

from vkpbr.scene.types import Camera

__all__ = ["FlyCamera", "BASE_SPEED", "FOV_RANGE", "FOV_STEP", "LOOK_RAD_PER_PIXEL", "SPONZA_RADIUS"]

BASE_SPEED = 1.7  # units per second, the course skeleton's value (for Sponza)
LOOK_RAD_PER_PIXEL = 0.01
FAST, SLOW = 5.0, 0.05  # Shift and Ctrl multipliers
SPONZA_RADIUS = 18.5  # bounding-sphere radius of Khronos Sponza, where BASE_SPEED applies
_MAX_PITCH = math.radians(89.0)
FOV_RANGE = (10.0, 120.0)  # degrees: the [ and ] keys zoom within it
FOV_STEP = 5.0

Vec = tuple[float, float, float]


def _norm(v: Vec) -> Vec:
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) or 1.0
    return (v[0] / n, v[1] / n, v[2] / n)


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _axpy(a: float, x: Vec, y: Vec) -> Vec:
    return (y[0] + a * x[0], y[1] + a * x[1], y[2] + a * x[2])


class FlyCamera:
    """A first-person camera. Angles in radians, distances in scene units, time in seconds.

    Parameters
    ----------
    start : the initial pose (its fov, near and far are kept).
    scene_radius : bounding-sphere radius of the scene; sets the movement speed.
    """

    def __init__(self, start: Camera, scene_radius: float = SPONZA_RADIUS) -> None:
        self.start = start
        self.speed = BASE_SPEED * max(scene_radius, 1e-3) / SPONZA_RADIUS
        self.up = _norm(start.up)
        # A fixed horizontal basis (e1, e2) perpendicular to up: yaw is measured in it.
        helper = (1.0, 0.0, 0.0) if abs(self.up[0]) < 0.9 else (0.0, 0.0, 1.0)
        self._e1 = _norm(_cross(helper, self.up))
        self._e2 = _cross(self.up, self._e1)
        self.reset()

    def reset(self) -> None:
        """Back to the start pose."""
        c = self.start
        self.yfov_deg = float(c.yfov_deg)
        d = (c.target[0] - c.eye[0], c.target[1] - c.eye[1], c.target[2] - c.eye[2])
        self.focus = math.sqrt(_dot(d, d)) or 1.0
        f = _norm(d)
        self.eye: Vec = tuple(float(x) for x in c.eye)  # type: ignore[assignment]
        self.pitch = math.asin(max(-1.0, min(1.0, _dot(f, self.up))))
        self.pitch = max(-_MAX_PITCH, min(_MAX_PITCH, self.pitch))
        self.yaw = math.atan2(_dot(f, self._e2), _dot(f, self._e1))

    # --- basis ------------------------------------------------------------------------------
    def forward(self) -> Vec:
        a = math.cos(self.pitch) * math.cos(self.yaw)
        b = math.cos(self.pitch) * math.sin(self.yaw)
        c = math.sin(self.pitch)
        e1, e2, u = self._e1, self._e2, self.up
        return (a * e1[0] + b * e2[0] + c * u[0], a * e1[1] + b * e2[1] + c * u[1],
                a * e1[2] + b * e2[2] + c * u[2])

    def right(self) -> Vec:
        return _norm(_cross(self.forward(), self.up))

    # --- input ------------------------------------------------------------------------------
    def look(self, dx: float, dy: float) -> None:
        """Mouse look by a cursor motion of (dx, dy) pixels (y down): drag right turns right."""
        self.yaw -= dx * LOOK_RAD_PER_PIXEL
        self.pitch = max(-_MAX_PITCH, min(_MAX_PITCH, self.pitch - dy * LOOK_RAD_PER_PIXEL))

    def move(self, dt: float, forward: float, right: float, up: float, multiplier: float = 1.0) -> None:
        """Fly for `dt` seconds; each axis in [-1, 1] (W/S, D/A, E/Q)."""
        step = self.speed * multiplier * dt
        f, r = self.forward(), self.right()
        e = self.eye
        e = _axpy(step * forward, f, e)
        e = _axpy(step * right, r, e)
        self.eye = _axpy(step * up, self.up, e)

    def zoom(self, step_deg: float) -> None:
        """Change the vertical field of view by `step_deg`, kept within [10, 120] degrees."""
        self.yfov_deg = max(FOV_RANGE[0], min(FOV_RANGE[1], self.yfov_deg + step_deg))

    def pan(self, dx: float, dy: float, window_height: int) -> None:
        """Right drag: translate in the view plane so the point at the focus distance follows
        the cursor."""
        per_pixel = 2.0 * self.focus * math.tan(math.radians(self.yfov_deg) / 2.0)
        per_pixel /= max(window_height, 1)
        r = self.right()
        u = _cross(r, self.forward())
        self.eye = _axpy(dy * per_pixel, u, _axpy(-dx * per_pixel, r, self.eye))

    def dolly(self, notches: float, multiplier: float = 1.0) -> None:
        """Scroll: each notch moves a quarter of a second's flight forward (positive) or back."""
        self.eye = _axpy(0.25 * self.speed * multiplier * notches, self.forward(), self.eye)

    # --- output -----------------------------------------------------------------------------
    def camera(self) -> Camera:
        target = _axpy(self.focus, self.forward(), self.eye)
        c = self.start  # positional construction: dataclasses.replace costs ~10x more per frame
        return Camera(self.eye, target, self.up, self.yfov_deg, c.znear, c.zfar, "viewer")
