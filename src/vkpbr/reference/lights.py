"""NumPy mirror of shaders/lights.glsl: the radiance a punctual light sends to points.

Evaluated from the `Light` dataclass itself (not from the GPU's light records), so a test
comparing the two also checks how render/frames.py packs a light.
"""

from __future__ import annotations

import math

import numpy as np

from vkpbr.reference.brdf import light_attenuation
from vkpbr.scene.types import Light

__all__ = ["spot_falloff", "light_incident"]


def spot_falloff(light: Light, l: np.ndarray) -> np.ndarray:  # noqa: E741
    """KHR_lights_punctual: t = clamp((cos - cos_outer) / (cos_inner - cos_outer), 0, 1), t^2,
    with cos the cosine between the spot axis and -l (..., 3)."""
    cos_outer, cos_inner = math.cos(light.outer_cone), math.cos(light.inner_cone)
    scale = 1.0 / max(1e-3, cos_inner - cos_outer)
    cd = -np.sum(np.asarray(light.direction, dtype=np.float64) * l, axis=-1)
    t = np.clip(cd * scale - cos_outer * scale, 0.0, 1.0)
    return t * t


def light_incident(light: Light, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(radiance (..., 3), unit direction to the light l (..., 3)) at world points p (..., 3)."""
    p = np.asarray(p, dtype=np.float64)
    color = np.asarray(light.color, dtype=np.float64) * light.intensity
    if light.kind == "directional":
        l = np.broadcast_to(-np.asarray(light.direction, dtype=np.float64), p.shape)  # noqa: E741
        return np.broadcast_to(color, p.shape).copy(), l.copy()
    to_light = np.asarray(light.position, dtype=np.float64) - p
    dist2 = np.sum(to_light * to_light, axis=-1)
    l = to_light / np.sqrt(np.maximum(dist2, 1e-300))[..., None]  # noqa: E741
    att = light_attenuation(dist2, 0 if light.falloff == "none" else 1, light.range)
    if light.kind == "spot":
        att = att * spot_falloff(light, l)
    return color * att[..., None], l
