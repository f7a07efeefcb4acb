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
           "Tonemap", "MIN_SHEEN_ROUGHNESS", "SHEEN_ALBEDO_FIT", "SHEEN_FIT_MIN_N_DOT_V"]

MIN_ROUGHNESS = 0.03  # roughness is clamped here so that D stays finite as r -> 0
AMBIENT = 0.02  # the course's ambient constant: L_ambient = 0.02 * c
MAX_LIGHTS = 256  # punctual lights per frame (a storage buffer of this many records)
# KHR_materials_sheen: the Charlie distribution's sheen roughness (alpha_g) is clamped here,
# where its D stays finite in float32 (three.js clamps at the same value).
MIN_SHEEN_ROUGHNESS = 0.07


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


# KHR_materials_sheen's albedo scaling needs the Charlie lobe's directional albedo E(n.v, a)
# (a = sheen roughness). It is this polynomial in x = (n.v)^(1/3) and y = sqrt(a),
# E = sum_ij SHEEN_ALBEDO_FIT[i][j] x^i y^j, least-squares fitted to the integral of the
# extension's distribution and visibility over n.v in [0.02, 1], a in [0.07, 1] (max error
# 0.004; tests/unit/test_layer_mirror.py integrates it again). A polynomial, not a table:
# lavapipe compiles a dynamically indexed constant array into a tree of branches per lookup,
# minutes per pipeline. Generated into shaders/generated.glsl (sheen_albedo_fit) and evaluated
# by reference/brdf.py, from these numbers alone.
SHEEN_ALBEDO_FIT: tuple[tuple[float, ...], ...] = (
    (1.09927, -0.4456763, -2.387564, 6.252952, -3.489524),
    (12.52236, -70.76933, 154.0586, -146.4862, 50.86578),
    (-54.14374, 288.7846, -608.6334, 560.6368, -189.5136),
    (66.47369, -367.9202, 784.6235, -728.6155, 247.9961),
    (-25.8705, 149.7473, -326.3621, 307.6033, -105.8631),
)
SHEEN_FIT_MIN_N_DOT_V = 0.02  # the fit's range of n.v starts here (n.v is clamped to it)
