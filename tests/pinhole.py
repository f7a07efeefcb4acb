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


# Where the GPU's surface is, to within this fraction of a pixel: vertices snap to the
# rasteriser's sub-pixel grid (Vulkan's subPixelPrecisionBits: 8 on NVIDIA and lavapipe, 1/256
# pixel) and attributes interpolate in float32; a quarter of a grid step past that for the
# interpolation, 1/64 pixel in all. It matters where radiance changes fast across a pixel:
# grazing rows far off and the edges of the lights' range and cone windows.
RASTER_SLACK_PX = 1.0 / 64.0


def raster_slack(image: np.ndarray) -> np.ndarray:
    """Per pixel, how far `image` moves over RASTER_SLACK_PX: the largest step to a 4-neighbour
    (rows and columns, channels alike) times that fraction."""
    img = np.asarray(image, np.float64)
    step = np.zeros_like(img)
    for axis in (0, 1):
        d = np.abs(np.diff(img, axis=axis))
        lo = [slice(None)] * img.ndim
        hi = [slice(None)] * img.ndim
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        step[tuple(lo)] = np.maximum(step[tuple(lo)], d)
        step[tuple(hi)] = np.maximum(step[tuple(hi)], d)
    return step * RASTER_SLACK_PX


def assert_close_on_raster(got: np.ndarray, want: np.ndarray, rtol: float, atol: float,
                           what: str = "") -> None:
    """|got - want| <= rtol |want| + atol + raster_slack(want) everywhere, else the worst pixel."""
    got, want = np.asarray(got, np.float64), np.asarray(want, np.float64)
    bound = rtol * np.abs(want) + atol + raster_slack(want)
    excess = np.abs(got - want) - bound
    if np.any(excess > 0):
        i = np.unravel_index(int(np.argmax(excess)), excess.shape)
        raise AssertionError(f"{what}: {int((excess > 0).sum())} of {excess.size} values off; worst at "
                             f"{i}: {got[i]:.6g} vs {want[i]:.6g} (bound {bound[i]:.3g})")
