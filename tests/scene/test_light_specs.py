"""Lights as users write them: `--light` specs, lights files, and the course's view of a light
(vkpbr.scene.lights). No GPU."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.errors import UsageError
from vkpbr.scene.lights import course_point_light, light_spec, load_lights_file, parse_light_spec
from vkpbr.scene.types import Light

coord = st.floats(-1e4, 1e4, allow_nan=False).map(lambda x: float(f"{x:.6g}"))
unit = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
    lambda v: math.hypot(*v) > 0.1).map(lambda v: tuple(x / math.hypot(*v) for x in v))


@st.composite
def lights(draw: st.DrawFn) -> Light:
    kind = draw(st.sampled_from(["point", "spot", "directional"]))
    outer = draw(st.floats(0.05, math.pi / 2))
    return Light(
        kind=kind, position=draw(st.tuples(coord, coord, coord)),
        direction=draw(unit) if kind != "point" else (0.0, -1.0, 0.0),
        color=draw(st.tuples(*[st.floats(0, 10).map(lambda x: float(f"{x:.6g}"))] * 3)),
        intensity=float(f"{draw(st.floats(0, 1e5)):.6g}"),
        range=float(f"{draw(st.floats(0, 100)):.6g}") if kind != "directional" else 0.0,
        inner_cone=float(f"{math.degrees(outer * draw(st.floats(0, 0.9))):.6g}") * math.pi / 180
        if kind == "spot" else 0.0,
        outer_cone=float(f"{math.degrees(outer):.6g}") * math.pi / 180 if kind == "spot" else math.pi / 4,
        falloff=draw(st.sampled_from(["none", "inverse_square"])),
        shadows=draw(st.booleans()))


@given(lights())
@settings(max_examples=200, deadline=None)
def test_a_printed_light_reads_back(light: Light) -> None:
    """The viewer prints `--light light_spec(li)` to reproduce a frame: it reads back as the
    same light (to the printed precision)."""
    (back,) = parse_light_spec(light_spec(light))
    assert back.kind == light.kind and back.falloff == light.falloff
    assert back.shadows == light.shadows
    for name in ("color", "intensity", "range", "inner_cone", "outer_cone"):
        np.testing.assert_allclose(getattr(back, name), getattr(light, name), rtol=1e-5,
                                   atol=1e-9, err_msg=name)
    if light.kind != "directional":
        np.testing.assert_allclose(back.position, light.position, rtol=1e-5, atol=1e-9)
    if light.kind != "point":
        np.testing.assert_allclose(back.direction, light.direction, atol=1e-5)


def test_spec_forms() -> None:
    assert parse_light_spec("none") == []
    assert parse_light_spec("1,2,3") is None  # the course's form: the caller moves its light
    (dir_,) = parse_light_spec("dir:0,-2,0:intensity=3")
    assert dir_.kind == "directional" and dir_.direction == (0.0, -1.0, 0.0) and dir_.intensity == 3
    (spot,) = parse_light_spec("spot:0,4,0:0,-1,0:inner=10:outer=20:color=1,0.5,0:shadows=off")
    assert spot.position == (0.0, 4.0, 0.0) and spot.color == (1.0, 0.5, 0.0)
    assert math.isclose(spot.inner_cone, math.radians(10)) and not spot.shadows
    assert spot.falloff == "inverse_square"  # glTF's, unless said


@pytest.mark.parametrize("spec, message", [
    ("lamp:1,2,3", "unknown light type"),
    ("point:1,2", "expected 3"),
    ("spot:0,1,0", "needs a direction"),
    ("dir:0,0,0", "non-zero"),
    ("point:0,1,0:intensity=-1", "intensity"),
    ("spot:0,1,0:0,-1,0:inner=30:outer=20", "outer_cone"),
    ("point:0,1,0:brightness=2", "unknown property"),
    ("point:0,1,0:shadows=maybe", "on or off"),
    ("point:0,1,0:nan", "KEY=VALUE"),
    ("spot:0,1,0:0,-1,0:outer=200", "200 degrees; a cone half-angle is 0 to 90"),
])
def test_bad_specs_are_one_line(spec: str, message: str) -> None:
    with pytest.raises(UsageError, match=message) as info:
        parse_light_spec(spec)
    assert "\n" not in str(info.value)


def test_lights_file(tmp_path: Path) -> None:
    path = tmp_path / "lights.json"
    path.write_text(json.dumps({"lights": [
        {"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "intensity": 5,
         "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.3}},
        {"type": "directional", "direction": [1, -1, 0], "color": [1, 0.9, 0.8]}]}))
    spot, sun = parse_light_spec(str(path))
    assert (spot.kind, spot.inner_cone, spot.outer_cone, spot.intensity) == ("spot", 0.1, 0.3, 5.0)
    np.testing.assert_allclose(sun.direction, np.array([1, -1, 0]) / math.sqrt(2))
    for bad, message in (("[{\"type\": \"area\"}]", "type"), ("{\"lights\": 3}", "list of lights"),
                         ("[{\"position\": [1, 2]}]", "3 numbers"), ("not json", "not a JSON"),
                         ("[{\"type\": \"spot\", \"direction\": [0, -1, 0], \"spot\": "
                          "{\"outerConeAngle\": 0}}]", "outer_cone")):
        path.write_text(bad)
        with pytest.raises(UsageError, match=message) as info:
            load_lights_file(path)
        assert str(path) in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(UsageError, match="cannot read"):
        load_lights_file(tmp_path / "missing.json")


def test_the_course_sees_one_point_light() -> None:
    """The course's mode draws the seed's approximations: a spot as a point light where it
    is, a sun as a far point light whose inverse-square intensity keeps the centre's lux."""
    bounds = (np.array([-1.0, 0, -1]), np.array([1.0, 2, 1]))
    spot = Light(kind="spot", position=(0.0, 3.0, 0.0), direction=(0.0, -1.0, 0.0), intensity=7.0,
                 falloff="inverse_square", outer_cone=0.5)
    assert course_point_light(spot, bounds) == Light((0.0, 3.0, 0.0), (1.0, 1.0, 1.0), 7.0,
                                                     "inverse_square", 0.0)
    sun = Light(kind="directional", direction=(0.0, -1.0, 0.0), intensity=2.0,
                falloff="inverse_square")
    far = course_point_light(sun, bounds)
    centre = np.array([0.0, 1.0, 0.0])
    d = np.linalg.norm(np.subtract(far.position, centre))
    assert far.kind == "point" and far.position[1] > 10
    assert math.isclose(far.intensity / d**2, 2.0, rel_tol=1e-9)  # the same illuminance
