"""RenderOptions: what a frame shows, as typed values parsed once at the edge.

Enum fields accept their user-facing names ("blinn-phong", "mapped-normal") or the members
themselves; construction (and `dataclasses.replace`) turns names into members and rejects
unknown ones with a UsageError that lists the choices. After that the renderer reads ints
straight out of the members, with no parsing per frame.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable
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

__all__ = ["RenderOptions", "ENUM_FIELDS", "POST_OPTIONS", "PostOption", "SensorNoise",
           "NOISE_PRESETS", "parse_noise", "with_overrides"]


@dataclass(frozen=True)
class PostOption:
    """A post step's option (render/post.py): the RenderOptions field, its command-line flag,
    its range (0 is off) and help; `parse` where the value is not a number in that range:
    text (or its own value) -> a hashable value, None or 0 for off (the flag takes text)."""

    field: str
    flag: str
    low: float
    high: float
    help: str
    parse: Callable[[Any], Any] | None = None


@dataclass(frozen=True)
class SensorNoise:
    """A depth and colour sensor's noise (render/post.py Noise, shaders/post_noise*.comp),
    drawn on the GPU from counter-based hashes of (seed, view, pixel): the same seed and
    camera give the same noise, another camera (or seed) independent noise.

    Depth (a stereo camera; the dataset outputs' depth and range, and render(depth=True)):
    disparity d = f b / Z (f the frame's focal length fy in pixels, b `baseline` metres)
    gets Gaussian noise of `disparity_sigma` pixels, so sigma(Z) = Z^2 sigma_d / (f b) to
    first order, then is quantised to `disparity_step` pixels (0: none); the depth is
    sampled `lateral_sigma` pixels off (Gaussian, nearest texel); a pixel drops out with a
    probability rising linearly from 0 to 1 as the angle between its ray and the surface
    normal goes from `grazing_start` to `grazing_end` degrees, with probability `edge_rate`
    where a 4-neighbour's depth differs by more than `edge_jump` of its own, and beyond
    `max_range` metres. Invalid depth (dropped, nothing in range, background) is 0 in depth
    and range, as the sensors' own images write it.
    Colour (the frame's linear radiance, before the tone map and encoding): Poisson-Gaussian
    per channel, y = x + sqrt(x / full_well + (read_noise / full_well)^2) n, x in units where
    1 is the full well (`full_well` electrons; `read_noise` electrons), clamped at 0.
    0 turns a part off: disparity_sigma 0 and no dropouts (depth untouched), full_well 0.
    """

    seed: int = 0
    baseline: float = 0.05
    disparity_sigma: float = 0.08
    disparity_step: float = 0.0
    lateral_sigma: float = 0.0
    grazing_start: float = 75.0
    grazing_end: float = 88.0
    edge_jump: float = 0.05
    edge_rate: float = 1.0
    max_range: float = 10.0
    full_well: float = 0.0
    read_noise: float = 0.0

    @property
    def depth(self) -> bool:
        """Whether the depth outputs get noise or dropouts."""
        return self.disparity_sigma > 0 or self.lateral_sigma > 0 or self.edge_rate > 0 \
            or self.grazing_start < 90 or math.isfinite(self.max_range)

    @property
    def colour(self) -> bool:
        return self.full_well > 0


# Sensor presets (their data sheets' typical figures, as the frame's own focal length sees
# them): a RealSense D435 (50 mm baseline, ~0.08 px subpixel noise, 1/32 px disparity steps),
# a Kinect v1 (structured light, 75 mm, 1/8 px steps), a ZED 2 (120 mm, wide range).
NOISE_PRESETS: dict[str, SensorNoise] = {
    "realsense-d435": SensorNoise(baseline=0.05, disparity_sigma=0.08, disparity_step=1 / 32,
                                  lateral_sigma=0.3, max_range=10.0, full_well=6000.0,
                                  read_noise=2.5),
    "kinect-v1": SensorNoise(baseline=0.075, disparity_sigma=0.125, disparity_step=1 / 8,
                             lateral_sigma=0.5, grazing_start=70.0, grazing_end=85.0,
                             max_range=4.0, full_well=4000.0, read_noise=4.0),
    "zed2": SensorNoise(baseline=0.12, disparity_sigma=0.1, disparity_step=1 / 16,
                        lateral_sigma=0.3, max_range=20.0, full_well=10000.0, read_noise=2.0),
}


def parse_noise(value: Any) -> SensorNoise | None:
    """`noise=`: None, "none", a SensorNoise, a preset name (NOISE_PRESETS), or
    "PRESET,key=value,..." / "key=value,..." (SensorNoise's fields; the rest default)."""
    if value is None or isinstance(value, SensorNoise):
        return value
    if not isinstance(value, str):
        raise UsageError(f"noise {value!r}: expected none, a preset ({', '.join(NOISE_PRESETS)}) "
                         "or key=value pairs")
    parts = [p.strip() for p in value.split(",") if p.strip()]
    if not parts or parts == ["none"]:
        return None
    base = SensorNoise()
    if "=" not in parts[0]:
        if parts[0] not in NOISE_PRESETS:
            raise UsageError(f"noise preset {parts[0]!r}: choose from {', '.join(NOISE_PRESETS)}")
        base = NOISE_PRESETS[parts.pop(0)]
    known = {f.name for f in fields(SensorNoise)}
    changes: dict[str, Any] = {}
    for part in parts:
        key, _, text = part.partition("=")
        key = key.strip().replace("-", "_")
        if key not in known:
            raise UsageError(f"noise: unknown parameter {key!r} (choose from {', '.join(sorted(known))})")
        try:
            number = float(text)
        except ValueError:
            raise UsageError(f"noise: {key}={text!r}: expected a number") from None
        if key == "seed":
            if not number.is_integer() or not 0 <= number < 2**32:
                raise UsageError(f"noise: seed={text}: expected an integer from 0 to 2^32 - 1")
            number = int(number)
        elif not (number >= 0) or (math.isinf(number) and key != "max_range"):
            raise UsageError(f"noise: {key}={text}: expected a finite number >= 0")
        changes[key] = number
    noise = dataclasses.replace(base, **changes)
    if noise.baseline <= 0:
        raise UsageError("noise: baseline must be > 0")
    return noise


# The post steps, in the order a frame runs them (render/post.py: each a render/post_*.py).
POST_OPTIONS: tuple[PostOption, ...] = (
    PostOption("noise", "--noise", 0.0, 0.0, "sensor noise: none, a preset ("
               + ", ".join(NOISE_PRESETS) + ") or PRESET,key=value,... (seed, baseline, "
               "disparity_sigma, disparity_step, lateral_sigma, grazing_start, grazing_end, "
               "edge_jump, edge_rate, max_range, full_well, read_noise; docs/cameras.md); "
               "depth noise in the dataset outputs' depth, colour noise before the encoding",
               parse=parse_noise),
    PostOption("bloom", "--bloom", 0.0, 1.0, "bloom strength 0..1: bright light spreads over "
               "its surroundings, the frame's total light kept (default 0: off)"),
)

# RenderOptions field -> the enum its values come from (the CLI's choices, the viewer's cycles).
ENUM_FIELDS: dict[str, type] = {"view": View, "lighting": Lighting, "brdf": Brdf, "tbn": TbnMode,
                                "tonemap": Tonemap, "pipeline": PipelinePath, "raster": RasterPath,
                                "shadow_raster": RasterPath, "ao": Ao}
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
    world_shadow_resolution : int
        Texels per side of each world's own shadow maps in a batch of worlds whose poses move
        shadow casters (render/world_shadows.py; cube faces get half), 16..16384: W worlds
        take W x layers x this^2 x 4 bytes (256: a point light's cube 384 KiB a world).
    shadow_raster : RasterPath or str
        What draws the shadow maps: "auto" (compute shaders on GPUs, whose few raster units
        are the limit of a redrawn map; the raster units on CPUs, but compute shaders while
        the casters that move hold under a tenth of the casters' triangles: the still ones'
        kept maps are then copied in), "hardware" (the raster units) or "compute" (compute
        shaders: render/shadow_raster.py, the same maps).
    env : str
        The environment of the physically based mode: "sky" (the built-in Preetham sky
        matched to the automatic sun), "none" (no image-based light, black background) or
        the path of an equirectangular .hdr / .exr panorama, or an LDR .jpg / .png one
        (sRGB decoded to linear; its light is clipped at 1: scene/environment.py). The course mode has none.
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
        default: XeGTAO's ground-truth ambient occlusion at half resolution, upsampled by
        depth, in the physically based mode with an environment, on single-sample offscreen
        frames), "gtao-full" (full resolution), "gtao-low" (half, fewer samples) or "off".
    ao_radius : float
        GTAO's effect radius in world units (>= 0; 0: 15% of the scene's bounding radius as
        loaded, which moving nodes do not change).
    bloom : float
        Bloom strength, 0..1 (0: off): a post step (render/post_bloom.py) on the frame's HDR
        radiance before its tone map; the frame's total light is kept.
    noise : SensorNoise or str or None
        Sensor noise (a post step: render/post.py Noise): None / "none", a preset name
        ("realsense-d435", "kinect-v1", "zed2"), "PRESET,key=value,..." or a SensorNoise.
        It runs before the bloom (on the sensor's image).
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
    world_shadow_resolution: int = 256
    shadow_raster: RasterPath = RasterPath.AUTO
    env: str = "sky"
    env_intensity: float = 1.0
    env_rotation: float = 0.0
    env_background: bool | None = None
    ao: Ao = Ao.GTAO
    ao_radius: float = 0.0
    bloom: float = 0.0
    noise: SensorNoise | str | None = None

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
        for name in ("shadow_resolution", "world_shadow_resolution"):
            res = getattr(self, name)
            if isinstance(res, bool) or not isinstance(res, int) or not 16 <= res <= 16384:
                raise UsageError(f"{name.replace('_', ' ')} {res!r}: expected an integer from "
                                 "16 to 16384")
        self._check_environment()
        self._check_post()
        for f in fields(self):
            if f.type == "bool" and not isinstance(getattr(self, f.name), bool):
                raise UsageError(f"{f.name} {getattr(self, f.name)!r}: expected True or False")

    def _check_post(self) -> None:
        for row in POST_OPTIONS:
            value = getattr(self, row.field)
            if row.parse is not None:
                object.__setattr__(self, row.field, row.parse(value))
                continue
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
            raise UsageError(f"env {self.env!r}: expected sky, none or a .hdr / .exr / .jpg / .png file")
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


def with_overrides(options: Any, overrides: dict[str, Any]) -> RenderOptions:
    """`options` (None: the defaults) updated by render's keyword overrides (view="d", ...):
    a one-line UsageError for options that are not a RenderOptions or a name it has no field
    of (where dataclasses.replace raised a TypeError)."""
    if options is not None and not isinstance(options, RenderOptions):
        raise UsageError(f"options: expected a RenderOptions, got {type(options).__name__}")
    unknown = [name for name in overrides if name not in _OVERRIDABLE]
    if unknown:
        raise UsageError(f"unknown render option {unknown[0]!r} (RenderOptions' fields: "
                         f"{', '.join(sorted(_OVERRIDABLE)[:6])} ...; Renderer(msaa=...) "
                         "takes the renderer's own)")
    return dataclasses.replace(options or RenderOptions(), **overrides)


_OVERRIDABLE = frozenset(f.name for f in fields(RenderOptions) if f.init)
