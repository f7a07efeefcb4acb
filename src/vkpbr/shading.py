# The shading model's choices and constants, shared by the renderer (render/layouts.py writes
# them into uniforms and generated.glsl) and its NumPy mirror (reference/brdf.py). They live
# below both so that the reference, like scene/ and bake/, imports nothing of render/ or gpu/.
"""Shading constants (`MIN_ROUGHNESS`, `AMBIENT`) and choices (`Brdf`, `Tonemap`), as named
IntEnums: the value goes to the shader, the name to the command line, the HUD and messages."""

from __future__ import annotations

import enum

__all__ = ["AMBIENT", "MIN_ROUGHNESS", "SUN_DIRECTION", "Brdf", "Named", "Tonemap"]

MIN_ROUGHNESS = 0.03  # roughness is clamped here so that D stays finite as r -> 0
AMBIENT = 0.02  # the course's ambient constant: L_ambient = 0.02 * c
# The built-in sky's sun and the automatic key light: the unit vector its light TRAVELS (glTF's
# -Z of a light node), from 50 degrees of elevation, behind and right of a camera looking
# along -Z (to the sun: (cos 50 sin 30, sin 50, cos 50 cos 30)).
SUN_DIRECTION = (-0.32139380484326974, -0.766044443118978, -0.5566703992264194)


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


class Brdf(Named):
    GGX = 0
    BLINN_PHONG = 1


class Tonemap(Named):
    NONE = 0
    REINHARD = 1
    ACES = 2
