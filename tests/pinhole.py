"""An independent pinhole camera for tests: rays and projections from eye/target/up and the
vertical field of view alone (no renderer matrices), in the image convention the renderer
promises: +Y world-up at the top, pixel (row, column) centres at (i + 0.5, j + 0.5) in units
of pixels from the top-left corner."""

from __future__ import annotations

import math

import numpy as np


def basis(camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # noqa: ANN001
    """Unit (right, up, forward) of a Camera."""
    f = np.subtract(camera.target, camera.eye).astype(np.float64)
    f /= np.linalg.norm(f)
    r = np.cross(f, camera.up)
    r /= np.linalg.norm(r)
    return r, np.cross(r, f), f


def pixel_rays(camera, width: int, height: int) -> np.ndarray:  # noqa: ANN001
    """(H, W, 3) unit ray directions through the pixel centres."""
    r, u, f = basis(camera)
    t = math.tan(math.radians(camera.yfov_deg) / 2)
    x = ((np.arange(width) + 0.5) / width * 2 - 1) * t * width / height
    y = (1 - (np.arange(height) + 0.5) / height * 2) * t
    d = f + x[None, :, None] * r + y[:, None, None] * u
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def project(camera, point, width: int, height: int) -> tuple[float, float, float]:  # noqa: ANN001
    """(row, column, depth along the view axis) of a world point, in pixels (continuous)."""
    r, u, f = basis(camera)
    p = np.subtract(point, camera.eye)
    z = float(p @ f)
    t = math.tan(math.radians(camera.yfov_deg) / 2)
    x, y = float(p @ r) / (z * t * width / height), float(p @ u) / (z * t)
    return (1 - y) / 2 * height, (x + 1) / 2 * width, z
