"""The options `render` and `view` share, defined once: flag, kind, choices, default, help.

`SHARED_OPTIONS` is the table. `add_options(parser, table)` turns it into argparse arguments
(enum options get `choices=` from the enum, so `--help` lists them and a typo is argparse's
one-line error, exit 2; defaults are RenderOptions' defaults), `render_options_from_args`
turns parsed arguments into a RenderOptions, and `option_flags` turns a RenderOptions back
into the flags that reproduce it (the viewer's `C` key prints them).

Nothing here imports the render layer at import time: the enums and RenderOptions are looked
up when the table is applied, which `vkpbr --help` never does.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from vkpbr.app.parsing import light_arg, vec3_arg

if TYPE_CHECKING:
    from vkpbr.render.options import RenderOptions

__all__ = ["OptionSpec", "SHARED_OPTIONS", "shared_options", "SCENE_LOADING_FLAGS", "add_options",
           "add_scene_loading_options", "render_options_from_args", "option_flags"]

Kind = Literal["enum", "float", "int", "vec3", "off", "on", "onoff", "text", "dir?", "choice",
               "append"]


@dataclass(frozen=True)
class OptionSpec:
    """One command-line option.

    Parameters
    ----------
    flag : the option string, e.g. "--light-color"; `dest` is derived from it as argparse does.
    kind : "enum" (a RenderOptions enum field: choices are its labels), "float", "int",
        "vec3" ("x,y,z"), "off" (`--no-x` sets field False), "on" (a plain switch), "onoff"
        (`--x on|off` sets a bool field), "text",
        "dir?" (an optional folder: `--cache` alone means the default folder), "choice"
        (fixed `choices`), "append" (repeatable text: a list of every value given).
    help : help text; "%(default)s" and "%(choices)s" are expanded by argparse.
    field : the RenderOptions field the option sets, if any.
    group : the --help section it is listed under.
    """

    flag: str
    kind: Kind
    help: str
    field: str | None = None
    group: str = "shading"
    metavar: str | None = None
    choices: tuple[str, ...] = ()

    @property
    def dest(self) -> str:
        return self.flag.lstrip("-").replace("-", "_")


SHARED_OPTIONS: tuple[OptionSpec, ...] = (
    OptionSpec("--fov", "float", "vertical field of view in degrees (default: the camera's)",
               group="camera and light", metavar="DEG"),
    OptionSpec("--lighting", "enum", "lighting mode (default %(default)s): pbr = the scene's "
               "lights (else an automatic sun) with shadows and image-based lighting; course = "
               "the seed's one point light and 0.02 ambient", field="lighting",
               group="camera and light"),
    OptionSpec("--light", "append", "a punctual light, repeatable: point:X,Y,Z | "
               "spot:X,Y,Z:DX,DY,DZ | dir:DX,DY,DZ (the direction it travels), each optionally "
               "followed by :color=R,G,B :intensity=F :range=F :inner=DEG :outer=DEG "
               ":falloff=none|inverse-square :shadows=on|off; or LIGHTS.json; or none (no "
               "punctual light); a bare X,Y,Z moves the default light. Default: the scene's "
               "lights, else the automatic sun (pbr) or a light at 0,2,0 (course)",
               group="camera and light", metavar="SPEC"),
    OptionSpec("--light-color", "vec3", "colour of every light, linear (default: each light's)",
               group="camera and light", metavar="R,G,B"),
    OptionSpec("--light-intensity", "float", "intensity of every light (default: each light's)",
               group="camera and light", metavar="F"),
    OptionSpec("--falloff", "choice", "distance falloff of every light (default: each light's)",
               group="camera and light", choices=("none", "inverse-square")),
    OptionSpec("--env", "text", "environment of the pbr lighting: sky (the built-in sky, "
               "matched to the automatic sun), none, or an equirectangular FILE.hdr / FILE.exr "
               "(or an LDR FILE.jpg / FILE.png: sRGB, its light clipped) (default %(default)s)", field="env", group="environment", metavar="ENV"),
    OptionSpec("--env-intensity", "float", "scale of the environment's radiance (default "
               "%(default)g)", field="env_intensity", group="environment", metavar="F"),
    OptionSpec("--env-rotation", "float", "turn the environment (and the automatic sun) by "
               "DEG about +Y (default %(default)g)", field="env_rotation", group="environment",
               metavar="DEG"),
    OptionSpec("--env-background", "choice", "draw the environment behind the scene (default: "
               "on with pbr lighting and an environment; course: black)",
               field="env_background", group="environment", choices=("on", "off")),
    OptionSpec("--ao", "enum", "screen-space ambient occlusion of the image-based light "
               "(default %(default)s: GTAO at half resolution where frames have an "
               "environment; gtao-full: full resolution; gtao-low: fewer samples; off)", field="ao",
               group="environment"),
    OptionSpec("--ao-radius", "float", "GTAO's radius in world units (default 0: 15%% of the "
               "scene's bounding radius)", field="ao_radius", group="environment",
               metavar="R"),
    OptionSpec("--view", "enum", "debug view, one of: %(choices)s (default %(default)s; "
               "`vkpbr render --list-views` says what each shows)", field="view", metavar="NAME"),
    OptionSpec("--brdf", "enum", "BRDF: gltf (the glTF spec's), or the course's Cook-Torrance "
               "with D = ggx or blinn-phong (default: pbr lighting gltf, course ggx)", field="brdf"),
    OptionSpec("--tbn", "enum", "tangent-frame vertex stream (default %(default)s)", field="tbn"),
    OptionSpec("--tonemap", "enum", "tone map: none, reinhard, aces (Narkowicz), aces-hill, "
               "pbr-neutral (Khronos) (default: pbr lighting pbr-neutral, course none)",
               field="tonemap"),
    OptionSpec("--exposure", "float", "exposure in EV stops, -64..64 (default %(default)g)",
               field="exposure", metavar="EV"),
    OptionSpec("--pipeline", "enum", "frame path (default %(default)s): forward shades in "
               "fragment shaders; compute shades a visibility buffer in compute shaders (all "
               "SMs of a datacenter GPU); auto: compute on GPUs (offscreen, no MSAA), forward "
               "on CPUs", field="pipeline"),
    OptionSpec("--raster", "enum", "what makes the visibility buffer of the compute path and "
               "the dataset outputs (default %(default)s): hardware (the raster units), "
               "compute (a compute rasteriser on all SMs) or auto (compute on GPUs that have "
               "64-bit atomics, hardware on CPUs)", field="raster"),
    OptionSpec("--no-alpha-mask", "off", "draw masked materials as opaque", field="alpha_mask"),
    OptionSpec("--no-normal-maps", "off", "ignore normal maps", field="normal_mapping"),
    OptionSpec("--no-occlusion", "off", "ignore occlusion maps", field="occlusion"),
    OptionSpec("--shadows", "onoff", "shadow maps for the lights that cast shadows "
               "(default %(default)s)", field="shadows"),
    OptionSpec("--shadow-resolution", "int", "texels per side of a shadow map, 16..16384 "
               "(cube faces get half; default %(default)s)", field="shadow_resolution",
               metavar="N"),
    OptionSpec("--world-shadow-resolution", "int", "texels per side of each world's own shadow "
               "map in a batch of worlds that move shadow casters, 16..16384 (cube faces get "
               "half; default %(default)s)", field="world_shadow_resolution", metavar="N"),
    OptionSpec("--shadow-raster", "enum", "what draws the shadow maps (default %(default)s): "
               "hardware (the raster units), compute (compute shaders on all SMs) or auto "
               "(compute on GPUs, hardware on CPUs)", field="shadow_raster"),
    OptionSpec("--variant", "text", "the glTF material variant to load (KHR_materials_variants; "
               "default: the file's default materials)", group="device and scene loading",
               metavar="NAME"),
    OptionSpec("--device", "text", "device name substring or index (see `vkpbr info`)",
               group="device and scene loading", metavar="NAME|INDEX"),
    OptionSpec("--validation", "on", "enable the Vulkan validation layer",
               group="device and scene loading"),
    OptionSpec("--cache", "dir?", "load SCENE through a baked copy in DIR (default "
               "$VKPBR_CACHE_DIR, else ~/.cache/vkpbr), baked on first use and again when the "
               "source changes", group="device and scene loading", metavar="DIR"),
    OptionSpec("--strict", "on", "a missing texture (or another defect the loader would "
               "work around) is an error, exit status 1", group="device and scene loading"),
    OptionSpec("--allow-outside-paths", "on", "read files the scene names outside its folder "
               "(../x.bin, absolute paths, symlinks out); by default such a buffer or mesh "
               "is an error and such a texture is replaced like a missing one "
               "(docs/security.md)", group="device and scene loading"),
)


# The options every command that loads a user's scene file takes (render, view, bake, bench):
# one definition each, in SHARED_OPTIONS; `add_scene_loading_options` adds them elsewhere.
SCENE_LOADING_FLAGS: tuple[str, ...] = ("--strict", "--allow-outside-paths", "--variant")


def _enum_types() -> dict[str, type]:
    from vkpbr.render.options import ENUM_FIELDS

    return ENUM_FIELDS


def _label(text: str) -> str:
    """How enum names are typed: "MAPPED_NORMAL" and "mapped_normal" mean "mapped-normal"."""
    return text.strip().lower().replace("_", "-")


def shared_options() -> tuple[OptionSpec, ...]:
    """SHARED_OPTIONS with the post steps' options (render/options.py POST_OPTIONS: each
    declared once there, beside its field; imports the render layer's options)."""
    from vkpbr.render.options import POST_OPTIONS

    return SHARED_OPTIONS + tuple(OptionSpec(row.flag, "float" if row.parse is None else "text",
                                             row.help, field=row.field, group="post",
                                             metavar="STRENGTH" if row.parse is None else "SPEC")
                                  for row in POST_OPTIONS)


def _with_post(table: tuple[OptionSpec, ...]) -> tuple[OptionSpec, ...]:
    return shared_options() if table is SHARED_OPTIONS else table


def add_options(parser: argparse.ArgumentParser, table: tuple[OptionSpec, ...] = SHARED_OPTIONS) -> None:
    """Add every option of `table` to `parser`, in argument groups named by `spec.group`."""
    table = _with_post(table)
    defaults: Any = None
    enums: dict[str, type] = {}
    if any(spec.field for spec in table):  # only then the render layer (NumPy) is needed
        from vkpbr.render.options import RenderOptions

        defaults, enums = RenderOptions(), _enum_types()
    groups: dict[str, Any] = {}
    for spec in table:
        group = groups.get(spec.group)
        if group is None:
            group = groups[spec.group] = parser.add_argument_group(f"{spec.group} options")
        kw: dict[str, Any] = {"help": spec.help, "dest": spec.dest}
        if spec.metavar:
            kw["metavar"] = spec.metavar
        if spec.kind == "enum":
            assert spec.field is not None
            default = getattr(defaults, spec.field)  # None: the lighting mode's choice
            kw.update(type=_label, choices=enums[spec.field].labels(),
                      default=None if default is None else str(default))
        elif spec.kind == "choice":
            kw.update(type=_label, choices=spec.choices)
        elif spec.kind == "text" and spec.field:
            kw["default"] = getattr(defaults, spec.field)
        elif spec.kind in ("float", "int"):
            kw["type"] = float if spec.kind == "float" else int
            if spec.field:
                kw["default"] = getattr(defaults, spec.field)
        elif spec.kind == "onoff":
            assert spec.field is not None
            kw.update(type=_label, choices=("on", "off"),
                      default="on" if getattr(defaults, spec.field) else "off")
        elif spec.kind == "vec3":
            kw["type"] = vec3_arg(spec.flag)
        elif spec.kind in ("on", "off"):
            kw["action"] = "store_true"
        elif spec.kind == "dir?":
            kw.update(nargs="?", const="")
        elif spec.kind == "append":
            kw.update(action="append", type=light_arg(spec.flag))
        group.add_argument(spec.flag, **kw)


def add_scene_loading_options(parser: argparse.ArgumentParser,
                              flags: tuple[str, ...] = SCENE_LOADING_FLAGS) -> None:
    """Add the scene-loading options (`--strict`, `--allow-outside-paths`, `--variant`) of SHARED_OPTIONS
    to a command that loads a scene but takes no render options (`bake`, `bench`); imports
    nothing of the render layer."""
    table = tuple(spec for spec in SHARED_OPTIONS if spec.flag in flags)
    assert len(table) == len(flags), flags
    add_options(parser, table)


def render_options_from_args(args: argparse.Namespace,
                             table: tuple[OptionSpec, ...] = SHARED_OPTIONS) -> RenderOptions:
    """The RenderOptions that the parsed `args` ask for (invalid values raise UsageError)."""
    from vkpbr.render.options import RenderOptions

    table = _with_post(table)
    values = {}
    for spec in table:
        if spec.field is None:
            continue
        value = getattr(args, spec.dest)
        if spec.kind == "off":
            value = not value
        elif spec.kind == "onoff":
            value = value == "on"
        values[spec.field] = value
    return RenderOptions(**values)


def option_flags(options: RenderOptions, table: tuple[OptionSpec, ...] = SHARED_OPTIONS) -> list[str]:
    """Command-line flags that reproduce `options` (every enum and the exposure, and the
    `--no-*` switches that are on), e.g. ["--view", "d", "--brdf", "ggx", ...]."""
    table = _with_post(table)
    out: list[str] = []
    for spec in table:
        if spec.field is None:
            continue
        value = getattr(options, spec.field)
        if spec.kind == "enum" and value is not None:
            out += [spec.flag, str(value)]
        elif spec.kind == "float" and not (spec.group == "post" and value == 0):
            out += [spec.flag, f"{value:g}"]
        elif spec.kind == "int":
            out += [spec.flag, str(value)]
        elif spec.kind == "onoff":
            out += [spec.flag, "on" if value else "off"]
        elif spec.kind == "off" and not value:
            out.append(spec.flag)
        elif spec.kind == "text" and value is not None:
            out += [spec.flag, str(value)]
        elif spec.kind == "choice" and isinstance(value, bool):
            out += [spec.flag, "on" if value else "off"]
    return out
