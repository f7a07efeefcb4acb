"""RenderOptions: what a frame shows, as typed values parsed once at the edge.

Enum fields accept their user-facing names ("blinn-phong", "mapped-normal") or the members
themselves; construction (and `dataclasses.replace`) turns names into members and rejects
unknown ones with a UsageError that lists the choices. After that the renderer reads ints
straight out of the members, with no parsing per frame.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields
from typing import Any

from vkpbr.errors import UsageError
from vkpbr.render.layouts import (
    Ao,
    Brdf,
    Lighting,
    PipelinePath,
    RasterPath,
    TbnMode,
    Tonemap,
    View,
    enum_by_name,
)
from vkpbr.scene.environment import ENV_SUFFIXES

__all__ = ["RenderOptions", "ENUM_FIELDS", "POST_OPTIONS", "PostOption"]


@dataclass(frozen=True)
class PostOption:
    """A post step's option (render/post.py): the RenderOptions field, its command-line flag,
    its range (0 is off) and help."""

    field: str
    flag: str
    low: float
    high: float
    help: str


# The post steps, in the order a frame runs them (render/post.py: each a render/post_*.py).
POST_OPTIONS: tuple[PostOption, ...] = (
    PostOption("bloom", "--bloom", 0.0, 1.0, "bloom strength 0..1: bright light spreads over "
               "its surroundings, the frame's total light kept (default 0: off)"),
)

# RenderOptions field -> the enum its values come from (the CLI's choices, the viewer's cycles).
ENUM_FIELDS: dict[str, type] = {"view": View, "lighting": Lighting, "brdf": Brdf, "tbn": TbnMode,
                                "tonemap": Tonemap, "pipeline": PipelinePath, "raster": RasterPath,
                                "ao": Ao}
# Fields whose None means "the lighting mode's choice" (MODE_DEFAULTS).
MODE_DEFAULT_FIELDS = ("brdf", "tonemap")
MODE_DEFAULTS: dict[Lighting, dict[str, Any]] = {
    Lighting.COURSE: {"brdf": Brdf.GGX, "tonemap": Tonemap.NONE},  # the seed's images
    Lighting.PBR: {"brdf": Brdf.GLTF, "tonemap": Tonemap.PBR_NEUTRAL},  # the Sample Viewer's
}


@dataclass(frozen=True)
class RenderOptions:
    """Everything that selects what a frame shows.

    Parameters
    ----------
    view : View or str
        Debug view (`vkpbr render --list-views`); "final" is the shaded image.
    lighting : Lighting or str
        "pbr" (every light of the scene or the automatic sun, shadows, image-based lighting)
        or "course" (the seed's one point light and 0.02 ambient; see vkpbr.shading.Lighting).
    brdf : Brdf or str or None
        "gltf" (the glTF 2.0 specification's BRDF), or the course's Cook-Torrance with the
        D "ggx" or "blinn-phong". None: the lighting mode's (pbr: gltf, course: ggx).
    tbn : TbnMode or str
        Tangent-frame vertex stream: "vectors", "quat" or "packed".
    tonemap : Tonemap or str or None
        "none", "reinhard", "aces" (Narkowicz), "aces-hill" or "pbr-neutral" (Khronos); see
        vkpbr.shading.Tonemap. None: the lighting mode's (pbr: pbr-neutral, course: none) for
        8-bit frames, none for linear float32 frames (scene-referred radiance).
    exposure : float
        EV stops in [-64, 64]: radiance is multiplied by 2 ** exposure.
    pipeline : PipelinePath or str
        "auto", "forward" (fragment shading) or "compute" (a visibility buffer shaded in
        compute shaders: the same pixels, on all of a datacenter GPU's SMs).
    raster : RasterPath or str
        What makes the compute path's visibility buffer (and its dataset outputs'): "auto"
        (compute on GPUs with 64-bit storage atomics, hardware on CPUs), "hardware" (the
        raster units) or "compute" (a compute rasteriser on all SMs, masked draws alpha-tested
        there as the shading samples them; needs 64-bit storage atomics). Frames on the forward path ignore it:
        their passes test the depths their own rasterisation makes.
    alpha_mask, normal_mapping, occlusion : bool
        Alpha masking (off: masked materials are drawn opaque), normal maps, occlusion maps.
    shadows : bool
        Shadow maps for the lights that cast shadows (Light.shadows); False: none at all.
    shadow_resolution : int
        Texels per side of a shadow map (cascade or spot map; cube faces get half), 16..16384.
    env : str
        The environment of the physically based mode: "sky" (the built-in Preetham sky
        matched to the automatic sun), "none" (no image-based light, black background) or
        the path of an equirectangular .hdr / .exr panorama. The course mode has none.
    env_intensity : float
        Scale of the environment's radiance (>= 0; image-based light and background alike).
    env_rotation : float
        Degrees about +Y (counter-clockwise seen from above) the environment is turned by;
        the automatic sun turns with it.
    env_background : bool or None
        Draw the environment where no surface is (None: yes in the physically based mode,
        with an environment; the course mode's background is black).
    ao : Ao or str
        Screen-space ambient occlusion of the image-based light (render/ao.py): "gtao" (the
        default: XeGTAO's ground-truth ambient occlusion, in the physically based mode with an
        environment, on single-sample offscreen frames) or "off".
    ao_radius : float
        GTAO's effect radius in world units (>= 0; 0: 15% of the scene's bounding radius).
    bloom : float
        Bloom strength, 0..1 (0: off): a post step (render/post_bloom.py) on the frame's HDR
        radiance before its tone map; the frame's total light is kept.
    """

    view: View = View.FINAL
    lighting: Lighting = Lighting.PBR
    brdf: Brdf | None = None
    tbn: TbnMode = TbnMode.VECTORS
    tonemap: Tonemap | None = None
    exposure: float = 0.0
    pipeline: PipelinePath = PipelinePath.AUTO
    raster: RasterPath = RasterPath.AUTO
    alpha_mask: bool = True
    normal_mapping: bool = True
    occlusion: bool = True
    shadows: bool = True
    shadow_resolution: int = 2048
    env: str = "sky"
    env_intensity: float = 1.0
    env_rotation: float = 0.0
    env_background: bool | None = None
    ao: Ao = Ao.GTAO
    ao_radius: float = 0.0
    bloom: float = 0.0

    def __post_init__(self) -> None:
        for name, enum_type in ENUM_FIELDS.items():
            value = getattr(self, name)
            if value is None and name in MODE_DEFAULT_FIELDS:
                continue
            object.__setattr__(self, name, enum_by_name(enum_type, value))
        try:
            exposure = float(self.exposure)
        except (TypeError, ValueError):
            raise UsageError(f"exposure {self.exposure!r}: expected a number of EV stops") from None
        if not math.isfinite(exposure) or abs(exposure) > 64:
            raise UsageError(f"exposure {self.exposure} must be a finite number of stops in [-64, 64]")
        object.__setattr__(self, "exposure", exposure)
        res = self.shadow_resolution
        if isinstance(res, bool) or not isinstance(res, int) or not 16 <= res <= 16384:
            raise UsageError(f"shadow resolution {res!r}: expected an integer from 16 to 16384")
        self._check_environment()
        self._check_post()
        for f in fields(self):
            if f.type == "bool" and not isinstance(getattr(self, f.name), bool):
                raise UsageError(f"{f.name} {getattr(self, f.name)!r}: expected True or False")

    def _check_post(self) -> None:
        for row in POST_OPTIONS:
            value = getattr(self, row.field)
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise UsageError(f"{row.field} {value!r}: expected a number") from None
            if isinstance(value, bool) or not row.low <= number <= row.high:  # (NaN fails too)
                raise UsageError(f"{row.field} {value!r}: expected a number from {row.low:g} "
                                 f"to {row.high:g}")
            object.__setattr__(self, row.field, number)

    def _check_environment(self) -> None:
        env = os.fspath(self.env) if isinstance(self.env, os.PathLike) else self.env
        if not isinstance(env, str) or not env.strip():
            raise UsageError(f"env {self.env!r}: expected sky, none or a .hdr / .exr file")
        if env.strip().lower() in ("sky", "none"):
            env = env.strip().lower()
        elif os.path.splitext(env)[1].lower() not in ENV_SUFFIXES:
            raise UsageError(f"env {env!r}: expected sky, none or a panorama file "
                             f"({', '.join(ENV_SUFFIXES)})")
        object.__setattr__(self, "env", env)
        for name, low in (("env_intensity", 0.0), ("env_rotation", -1e6), ("ao_radius", 0.0)):
            try:
                value = float(getattr(self, name))
            except (TypeError, ValueError):
                raise UsageError(f"{name.replace('_', '-')} {getattr(self, name)!r}: "
                                 "expected a number") from None
            if not math.isfinite(value) or value < low or value > 1e6:
                raise UsageError(f"{name.replace('_', '-')} {value}: expected a finite number"
                                 + (" >= 0" if low == 0.0 else ""))
            object.__setattr__(self, name, value)
        bg = self.env_background
        if isinstance(bg, str) and bg.strip().lower() in ("on", "off"):
            bg = bg.strip().lower() == "on"
        if bg is not None and not isinstance(bg, bool):
            raise UsageError(f"env-background {self.env_background!r}: expected on or off")
        object.__setattr__(self, "env_background", bg)

    @property
    def has_environment(self) -> bool:
        """Whether frames are lit by an environment (the physically based mode, env not
        "none")."""
        return self.lighting == Lighting.PBR and self.env != "none"

    @property
    def draws_background(self) -> bool:
        """Whether the environment is drawn where no surface is."""
        return self.has_environment and self.env_background is not False

    @property
    def shading_brdf(self) -> Brdf:
        """The BRDF frames are shaded with: `brdf`, or the lighting mode's."""
        return self.brdf if self.brdf is not None else MODE_DEFAULTS[self.lighting]["brdf"]

    @property
    def shading_tonemap(self) -> Tonemap:
        """The tone map of 8-bit frames: `tonemap`, or the lighting mode's."""
        return self.tonemap if self.tonemap is not None else MODE_DEFAULTS[self.lighting]["tonemap"]

    def tonemap_for(self, linear: bool) -> Tonemap:
        """The tone map of a frame: linear float32 frames are scene-referred radiance, so the
        mode's default tone map applies only to 8-bit frames (an explicit `tonemap` to both)."""
        if linear and self.tonemap is None:
            return Tonemap.NONE
        return self.shading_tonemap

    def with_names(self) -> dict[str, Any]:
        """The options as plain values (enum members as their names; None where the lighting
        mode chooses), e.g. for JSON."""
        return {f.name: (str(v) if f.name in ENUM_FIELDS and v is not None else v)
                for f in fields(self) for v in (getattr(self, f.name),)}
