"""Viewpoints and lights for scenes whose files carry none.

Known scenes (by file stem) get a hand-chosen camera and the course's light; any other scene
gets `auto_camera` framing its bounds and a light above and behind the camera's right
shoulder, so that a model opened cold is lit from the front as its screenshots are.
"""

from __future__ import annotations

import numpy as np

from vkpbr.scene.types import Camera, Light, Scene

__all__ = ["PRESETS", "apply_presets", "auto_light"]

# Sponza (glTF, metres): inside the atrium, at its east end, looking down its length (-X)
# towards the lion-head wall; the course's light: a point light at (0, 2, 0), white, no falloff.
PRESETS: dict[str, tuple[Camera, Light]] = {
    "sponza": (
        Camera(eye=(9.0, 1.8, -0.4), target=(-9.0, 3.5, -0.4), yfov_deg=60.0, znear=0.1, zfar=100.0,
               name="vkpbr: atrium"),
        Light(position=(0.0, 2.0, 0.0), color=(1.0, 1.0, 1.0), intensity=1.0, falloff="none"),
    ),
}


def auto_light(scene: Scene, camera: Camera) -> Light:
    """A course-style light (no falloff) above and to the right of the camera."""
    lo, hi = scene.bounds()
    radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-3)
    eye, target = np.asarray(camera.eye, float), np.asarray(camera.target, float)
    up = np.asarray(camera.up, float)
    forward = (target - eye) / max(np.linalg.norm(target - eye), 1e-12)
    right = np.cross(forward, up)
    right /= max(np.linalg.norm(right), 1e-12)
    position = eye + radius * (0.6 * up + 0.4 * right) + 0.2 * radius * forward
    return Light(position=tuple(float(x) for x in position), intensity=1.0, falloff="none")


def apply_presets(scene: Scene) -> Scene:
    """Give a scene without cameras or lights its preset (known scenes) or automatic ones."""
    from vkpbr.scene.geometry import auto_camera

    preset = PRESETS.get(scene.name.lower())
    if not scene.cameras:
        scene.cameras = [preset[0] if preset else auto_camera(scene)]
    if not scene.lights:
        scene.lights = [preset[1] if preset else auto_light(scene, scene.cameras[0])]
    return scene
