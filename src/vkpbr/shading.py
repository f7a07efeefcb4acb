# The shading model's choices and constants, shared by the renderer (render/layouts.py writes
# them into uniforms and generated.glsl) and its NumPy mirror (reference/brdf.py). They live
# below both so that the reference, like scene/ and bake/, imports nothing of render/ or gpu/.
"""Shading constants (`MIN_ROUGHNESS`, `AMBIENT`, `SUN_DIRECTION`, `MAX_LIGHTS`) and choices
(`Lighting`, `Brdf`, `Tonemap`), as named IntEnums: the value goes to the shader, the name to
the command line, the HUD and messages."""

from __future__ import annotations

import enum
import math

__all__ = ["AMBIENT", "MIN_ROUGHNESS", "MAX_LIGHTS", "SUN_DIRECTION", "Brdf", "Lighting", "Named",
           "Tonemap"]

MIN_ROUGHNESS = 0.03  # roughness is clamped here so that D stays finite as r -> 0
AMBIENT = 0.02  # the course's ambient constant: L_ambient = 0.02 * c
MAX_LIGHTS = 256  # punctual lights per frame (a storage buffer of this many records)


def _sun_direction(elevation_deg: float, azimuth_deg: float) -> tuple[float, float, float]:
    """The unit direction sunlight travels for a sun at this elevation above the horizon
    (y up) and azimuth (degrees from +Z towards +X)."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    to_sun = (math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a))
    return (-to_sun[0], -to_sun[1], -to_sun[2])


# The built-in sky's sun and the automatic key light of the physically based mode travel along
# this direction (one fact for both): a sun 50 degrees up, from in front and to the right of a
# camera on +Z looking at the origin (glTF's convention), so that faces towards the viewer
# are lit and shadows fall behind and to the left of objects.
SUN_DIRECTION = _sun_direction(50.0, 35.0)


class Named(enum.IntEnum):
    """An IntEnum whose str() and plain format are the user-facing name ("blinn-phong"): the
    value goes to the shader, the name to the command line, the HUD and messages."""

    @property
    def label(self) -> str:
        return self.name.lower().replace("_", "-")

    def __str__(self) -> str:
        return self.label

    def __format__(self, spec: str) -> str:
        return self.label if not spec else int.__format__(int(self), spec)

    @classmethod
    def labels(cls) -> tuple[str, ...]:
        return tuple(m.label for m in cls)


class Lighting(Named):
    """How a frame is lit.

    COURSE: the seed's model: one point light (the scene's first, spot and directional lights
    as point lights), ambient 0.02 c, no shadows, no environment, black background.
    PBR: every punctual light of the scene (or the automatic sun), shadows, image-based
    lighting from an environment (the built-in sky unless one is given).
    """

    PBR = 0
    COURSE = 1


class Brdf(Named):
    """GGX and BLINN_PHONG: the course's Cook-Torrance (that D, Cook-Torrance G, Schlick F on
    F0 = mix(0.04, c, M), diffuse (c/pi)(1-F)(1-M)). GLTF: the glTF 2.0 specification's
    Appendix B (GGX D, height-correlated Smith V, Schlick F, the dielectric/metal mix), as the
    Khronos Sample Viewer and Filament shade."""

    GGX = 0
    BLINN_PHONG = 1
    GLTF = 2


class Tonemap(Named):
    """Tone curves (applied to exposed linear radiance, before the sRGB encoding):
    NONE: clamp only. REINHARD: x / (1 + x) per channel. ACES: Narkowicz 2015's fit of the
    ACES RRT+ODT, per channel, no pre-scale (bright: 1.0 in -> 0.80 out). ACES_HILL: Stephen
    Hill's fit (the sRGB->ACES input matrix, RRT+ODT rational fit, output matrix; the Sample
    Viewer's "ACES Hill", without its optional 1/0.6 exposure boost). PBR_NEUTRAL: Khronos PBR Neutral
    (2024), which keeps base colours under normal light unchanged and desaturates highlights:
    the Sample Viewer's default and the physically based mode's."""

    NONE = 0
    REINHARD = 1
    ACES = 2
    ACES_HILL = 3
    PBR_NEUTRAL = 4
