"""What lights a frame besides its geometry: the punctual lights and the lighting mode's terms.

`Lighting` resolves the lights a run of frames is drawn with (the scene's; with none, the
physically based mode's automatic sun or the course's point light), the Lighting block's
inputs for the options' mode (render/frames.py FrameLighting: its flags, the environment's
intensity, rotation and mip count), what the compute path's shading kernels are specialised
for, and whether frames draw the copy of the opaque scene that transmissive surfaces see
(render/transmission.py). It is given the scene, the opaque copies and the environments
(render/environments.py); it draws nothing.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Iterable
from typing import Any

from vkpbr.errors import UsageError
from vkpbr.render import layouts as L
from vkpbr.render.compute_path import ShadeVariant
from vkpbr.render.environments import Environments
from vkpbr.render.frames import FrameLighting
from vkpbr.render.options import RenderOptions
from vkpbr.render.transmission import OpaqueCopies
from vkpbr.scene.lights import course_point_light
from vkpbr.scene.sky import sun_radiometry
from vkpbr.scene.types import Light, Scene
from vkpbr.scene.validate import validate_lights
from vkpbr.shading import AMBIENT, SUN_DIRECTION

__all__ = ["Lighting", "LightsArg", "automatic_sun", "lighting_flags", "screen_transmission"]

# What a caller may give as the lights of a frame: None (the scene's, or the lighting mode's
# default), one Light, or a sequence of them (empty: no punctual light at all).
LightsArg = Light | Iterable[Light] | None


class Lighting:
    """The lights and lighting terms of frames of `scene` (see the module's docstring)."""

    def __init__(self, scene: Scene, opaque_copies: OpaqueCopies,
                 environments: Environments, state: Any = None, shadows: Any = None) -> None:
        # state: the living scene (vkpbr.scene.state): its lights follow animation pointers;
        # shadows: the ShadowMaps, whose frame's choice of reads the shading kernels follow
        self.scene, self.opaque_copies, self.environments = scene, opaque_copies, environments
        self.state, self.shadows = state, shadows
        self._last: tuple[RenderOptions, bool, FrameLighting] | None = None

    def default_light(self) -> Light:
        """The course's light: the scene's first, else a white point light at (0, 2, 0)."""
        return self.scene.lights[0] if self.scene.lights else Light()

    def frame_lights(self, options: RenderOptions, lights: LightsArg = None) -> tuple[Light, ...]:
        """The lights frames are drawn with, resolved once per call (not per frame).

        None: the scene's lights; with none in the scene, the physically based mode's
        automatic sun, the course's default point light. Course lighting draws one point
        light: the first light, as `scene.lights.course_point_light` sees it.
        """
        if lights is None:
            if self.scene.lights:
                chosen: tuple[Light, ...] = tuple(
                    self.state.lights() if self.state is not None else self.scene.lights)
            elif options.lighting == L.Lighting.COURSE:
                chosen = (Light(),)
            else:
                chosen = (automatic_sun(float(options.env_rotation)),)
        else:
            if isinstance(lights, (str, bytes)) or not isinstance(lights, Light | Iterable):
                raise UsageError(f"lights: expected a Light or a list of them, got "
                                 f"{type(lights).__name__}")
            chosen = (lights,) if isinstance(lights, Light) else tuple(lights)
            validate_lights(chosen)
        if options.lighting == L.Lighting.COURSE:
            return (course_point_light(chosen[0], self.scene.bounds()),) if chosen else ()
        return chosen

    def frame_lighting(self, options: RenderOptions, ao: bool = False) -> FrameLighting:
        """What lights a frame besides its punctual lights, for `options`' lighting mode;
        `ao`: the frame's GTAO occludes its image-based light (render/ao.py, LIGHTING_AO).
        The last answer kept: a run of frames has one options object."""
        last = self._last
        if last is not None and last[0] is options and last[1] == ao:
            return last[2]
        lighting = self._frame_lighting(options)
        if ao:
            lighting = dataclasses.replace(lighting, flags=lighting.flags | L.LIGHTING_AO)
        self._last = (options, ao, lighting)
        return lighting

    def shade_variant(self, options: RenderOptions, ao: bool = False,
                      hand_reads: bool | None = None) -> ShadeVariant:
        """What the compute path's shading kernels are specialised for with `options` (and
        `ao`, as frame_lighting's): the frame's lighting flags and BRDF, and whether it reads
        shadow maps by hand (`hand_reads`; None: as the shadow maps' last `stale` chose,
        ShadowMaps.hand_reads) (render/compute_path.py ShadeVariant)."""
        if hand_reads is None:
            hand_reads = self.shadows is None or self.shadows.hand_reads
        return ShadeVariant(self.frame_lighting(options, ao).flags, int(options.shading_brdf),
                            hand_reads)

    def screen_transmission(self, options: RenderOptions) -> bool:
        """Whether frames with `options` draw the copy of the opaque scene that transmissive
        surfaces see through (render/transmission.py): see `screen_transmission`."""
        return screen_transmission(options, self.opaque_copies.present)

    def _frame_lighting(self, options: RenderOptions) -> FrameLighting:
        if options.lighting == L.Lighting.COURSE:
            return FrameLighting(mode=int(L.Lighting.COURSE), ambient=AMBIENT)
        flags = lighting_flags(options, self.opaque_copies.present)
        if not options.has_environment:
            return FrameLighting(mode=int(L.Lighting.PBR), flags=flags)
        return FrameLighting(mode=int(L.Lighting.PBR), flags=flags,
                             env_intensity=options.env_intensity,
                             env_rotation=math.radians(options.env_rotation),
                             env_max_lod=float(self.environments.get(options).max_lod))


def screen_transmission(options: RenderOptions, transmissive: bool) -> bool:
    """Whether frames with `options` draw the copy of the opaque scene that transmissive
    surfaces see through: the scene has one (`transmissive`), and the frame shades with the
    physically based mode's glTF BRDF (the layers' only)."""
    return (transmissive and options.lighting == L.Lighting.PBR
            and options.shading_brdf == L.Brdf.GLTF)


def lighting_flags(options: RenderOptions, transmissive: bool, ao: bool = False) -> int:
    """The Lighting block's flags (L.LIGHTING_*) of the physically based mode's frames with
    `options` in a scene with (`transmissive`) or without a transmissive surface; `ao`: as
    Lighting.frame_lighting's. (The course's mode has none but LIGHTING_AO.)"""
    flags = L.LIGHTING_AO if ao else 0
    if options.lighting == L.Lighting.COURSE:
        return flags
    flags |= ((L.LIGHTING_SHADOWS if options.shadows else 0)
              | (L.LIGHTING_SCREEN_TRANSMISSION if screen_transmission(options, transmissive)
                 else 0))
    if options.has_environment:
        flags |= L.LIGHTING_IBL | (L.LIGHTING_BACKGROUND if options.draws_background else 0)
    return flags


@functools.lru_cache(maxsize=64)
def automatic_sun(env_rotation: float = 0.0) -> Light:
    """The physically based mode's key light when the scene has none: the built-in sky's sun
    (vkpbr.shading.SUN_DIRECTION, colour and illuminance from scene.sky's sun_radiometry) as
    a directional Light, turned with the environment by `env_rotation` degrees about +Y:
    R_y(+theta), as the environment's lookups turn by R_y(-theta) (shaders/env_common.glsl
    env_rotate)."""
    color, illuminance = sun_radiometry(SUN_DIRECTION)
    t = math.radians(env_rotation)
    x, y, z = SUN_DIRECTION
    direction = (math.cos(t) * x + math.sin(t) * z, y, -math.sin(t) * x + math.cos(t) * z)
    return Light(kind="directional", direction=direction, color=color, intensity=illuminance,
                 falloff="inverse_square")
