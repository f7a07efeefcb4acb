"""Punctual lights as users write them, and the course's view of a light.

`parse_light_spec` reads one `--light` value:

    point:X,Y,Z[:OPTION...]                a point light at X,Y,Z
    spot:X,Y,Z:DX,DY,DZ[:OPTION...]        a spot light at X,Y,Z shining along DX,DY,DZ
    dir:DX,DY,DZ[:OPTION...]               a directional light travelling along DX,DY,DZ
    X,Y,Z                                  a point light at X,Y,Z (the course's form)
    none                                   no punctual light (not even the automatic sun)
    FILE.json                              the lights of a lights file (`load_lights_file`)

with OPTIONs `color=R,G,B`, `intensity=F` (candela; lux for `dir`), `range=F`,
`inner=DEG`, `outer=DEG` (spot cone half-angles), `falloff=none|inverse-square`,
`shadows=on|off`. Unnamed properties take glTF's defaults (white, intensity 1, infinite
range, cone 0..45 degrees, inverse-square falloff) and cast shadows.

A lights file is JSON: a list of objects (or {"lights": [...]}) with KHR_lights_punctual's
names: "type" ("point", "spot", "directional"), "color", "intensity", "range",
"spot": {"innerConeAngle", "outerConeAngle"} (radians), plus "position", "direction" and
"shadows" (the node transform glTF would give them).

`course_point_light` is how the course's lighting mode sees any light: one point light
(spot and directional lights approximated as they always were in that mode).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import read_json
from vkpbr.scene.types import Light

__all__ = ["parse_light_spec", "light_spec", "load_lights_file", "course_point_light", "normalized"]

_KINDS = {"point": "point", "spot": "spot", "dir": "directional", "directional": "directional"}


def normalized(v: Sequence[float], what: str) -> tuple[float, float, float]:
    """`v` scaled to unit length (UsageError for a zero or non-finite vector)."""
    x = np.asarray(v, dtype=np.float64)
    n = float(np.linalg.norm(x)) if np.all(np.isfinite(x)) else 0.0
    if not n > 1e-12 or not math.isfinite(n):
        raise UsageError(f"{what} {tuple(v)}: a direction must be a finite, non-zero vector")
    return tuple(float(c) for c in x / n)  # type: ignore[return-value]


def _floats(text: str, n: int, what: str) -> tuple[float, ...]:
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != n or not all(math.isfinite(v) for v in values):
        raise UsageError(f"{what} {text!r}: expected {n} finite comma-separated numbers")
    return values


def _option(light: dict[str, Any], item: str, spec: str) -> None:
    key, sep, value = item.partition("=")
    key = key.strip().lower()
    where = f"--light {spec!r}: {key}"
    if not sep:
        raise UsageError(f"--light {spec!r}: {item!r} is not KEY=VALUE (color=, intensity=, "
                         "range=, inner=, outer=, falloff=, shadows=)")
    if key in ("color", "colour"):
        light["color"] = _floats(value, 3, where)
    elif key in ("intensity", "range"):
        light[key] = _floats(value, 1, where)[0]
    elif key in ("inner", "outer"):
        degrees = _floats(value, 1, where)[0]
        if not 0.0 <= degrees <= 90.0:
            raise UsageError(f"{where}: {degrees:g} degrees; a cone half-angle is 0 to 90")
        light[f"{key}_cone"] = math.radians(degrees)
    elif key == "falloff":
        if value not in ("none", "inverse-square", "inverse_square"):
            raise UsageError(f"{where}: choose none or inverse-square, not {value!r}")
        light["falloff"] = value.replace("-", "_")
    elif key == "shadows":
        if value not in ("on", "off"):
            raise UsageError(f"{where}: choose on or off, not {value!r}")
        light["shadows"] = value == "on"
    else:
        raise UsageError(f"--light {spec!r}: unknown property {key!r} (color, intensity, range, "
                         "inner, outer, falloff, shadows)")


def parse_light_spec(spec: str) -> list[Light] | None:
    """The lights one `--light` value names (see the module docstring); None for the
    course's bare `X,Y,Z`, which the caller applies to its default light's position."""
    text = spec.strip()
    if text.lower() == "none":
        return []
    if text.lower().endswith(".json"):
        return load_lights_file(text)
    kind_name, sep, rest = text.partition(":")
    if not sep:
        _floats(text, 3, "--light")  # the course's form: a position only
        return None
    kind = _KINDS.get(kind_name.strip().lower())
    if kind is None:
        raise UsageError(f"--light {spec!r}: unknown light type {kind_name!r}; use point:X,Y,Z, "
                         "spot:X,Y,Z:DX,DY,DZ, dir:DX,DY,DZ, none or a lights .json file")
    parts = rest.split(":")
    light: dict[str, Any] = {"kind": kind, "falloff": "inverse_square"}
    if kind in ("point", "spot"):
        light["position"] = _floats(parts.pop(0), 3, f"--light {spec!r}: position")
    if kind in ("spot", "directional"):
        if not parts:
            raise UsageError(f"--light {spec!r}: a {kind} light needs a direction DX,DY,DZ")
        light["direction"] = normalized(_floats(parts.pop(0), 3, f"--light {spec!r}: direction"),
                                        f"--light {spec!r}: direction")
    for item in parts:
        _option(light, item, spec)
    return [_checked(Light(**light), f"--light {spec!r}")]


def light_spec(light: Light) -> str:
    """The `--light` value that `parse_light_spec` reads back as `light` (the viewer prints
    these to reproduce a frame)."""
    def vec(v: Sequence[float]) -> str:
        return ",".join(f"{x:.6g}" for x in v)

    head = {"point": f"point:{vec(light.position)}",
            "spot": f"spot:{vec(light.position)}:{vec(light.direction)}",
            "directional": f"dir:{vec(light.direction)}"}[light.kind]
    parts = [head, f"color={vec(light.color)}", f"intensity={light.intensity:.6g}"]
    if light.range:
        parts.append(f"range={light.range:.6g}")
    if light.kind == "spot":
        parts += [f"inner={math.degrees(light.inner_cone):.6g}",
                  f"outer={math.degrees(light.outer_cone):.6g}"]
    if light.falloff == "none":
        parts.append("falloff=none")
    if not light.shadows:
        parts.append("shadows=off")
    return ":".join(parts)


def _checked(light: Light, where: str) -> Light:
    from vkpbr.scene.validate import validate_lights

    try:
        validate_lights([light], "light")
    except UsageError as exc:
        raise UsageError(f"{where}: {exc}") from None
    return light


def load_lights_file(path: str | os.PathLike[str]) -> list[Light]:
    """The lights of a lights JSON file (module docstring); UsageError naming the file."""
    p = Path(path)
    try:
        doc = read_json(p)
    except OSError as exc:
        raise UsageError(f"{p}: cannot read the lights file: {exc.strerror or exc}") from None
    except JsonError as exc:
        raise UsageError(f"{p}: not a JSON lights file: {exc.problem}") from None
    items = doc.get("lights") if isinstance(doc, dict) else doc
    if not isinstance(items, list):
        raise UsageError(f"{p}: expected a list of lights (or {{\"lights\": [...]}})")
    lights = [_light_from_json(item, f"{p}: lights[{i}]") for i, item in enumerate(items)]
    from vkpbr.scene.validate import validate_lights

    try:
        validate_lights(lights)
    except UsageError as exc:
        raise UsageError(f"{p}: {exc}") from None
    return lights


def _json_vector(item: dict, key: str, default: tuple[float, ...], where: str) -> tuple[float, ...]:
    value = item.get(key, default)
    if (not isinstance(value, list | tuple) or len(value) != 3
            or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)):
        raise UsageError(f"{where}.{key}: expected 3 numbers, got {value!r}")
    return tuple(float(x) for x in value)


def _json_number(item: dict, key: str, default: float, where: str) -> float:
    value = item.get(key, default)
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise UsageError(f"{where}.{key}: expected a number, got {value!r}")
    return float(value)


def _light_from_json(item: Any, where: str) -> Light:
    if not isinstance(item, dict):
        raise UsageError(f"{where}: expected an object, got {item!r}")
    kind = item.get("type", "point")
    if kind not in ("point", "spot", "directional"):
        raise UsageError(f"{where}.type: expected point, spot or directional, got {kind!r}")
    spot = item.get("spot", {})
    if not isinstance(spot, dict):
        raise UsageError(f"{where}.spot: expected an object, got {spot!r}")
    shadows = item.get("shadows", True)
    if not isinstance(shadows, bool):
        raise UsageError(f"{where}.shadows: expected true or false, got {shadows!r}")
    direction = _json_vector(item, "direction", (0.0, 0.0, -1.0), where)
    return Light(
        kind=kind,
        position=_json_vector(item, "position", (0.0, 0.0, 0.0), where),
        direction=normalized(direction, f"{where}.direction") if kind != "point" else direction,
        color=_json_vector(item, "color", (1.0, 1.0, 1.0), where),
        intensity=_json_number(item, "intensity", 1.0, where),
        range=_json_number(item, "range", 0.0, where),
        inner_cone=_json_number(spot, "innerConeAngle", 0.0, f"{where}.spot"),
        outer_cone=_json_number(spot, "outerConeAngle", math.pi / 4, f"{where}.spot"),
        falloff="inverse_square",
        shadows=shadows,
    )


def course_point_light(light: Light, bounds: tuple[np.ndarray, np.ndarray]) -> Light:
    """The one point light the course's lighting mode draws for `light`: a point light as it
    is; a spot light as a point light at its position; a directional light as a far point
    light against its direction whose inverse-square intensity lux * d^2 gives the same
    illuminance at the centre of `bounds` (scene min, max) -- the seed's approximations."""
    if light.kind == "point":
        return light
    if light.kind == "spot":
        return Light(light.position, light.color, light.intensity, light.falloff, light.range)
    lo, hi = (np.asarray(b, dtype=np.float64) for b in bounds)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        lo = hi = np.zeros(3)
    centre = (lo + hi) / 2
    d = 10.0 * max(float(np.linalg.norm(hi - lo)), 1.0)
    position = centre - np.asarray(light.direction, dtype=np.float64) * d
    intensity = light.intensity * d * d if light.falloff == "inverse_square" else light.intensity
    return Light(tuple(map(float, position)), light.color, intensity, light.falloff, 0.0)

