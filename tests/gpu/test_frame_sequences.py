"""A long-lived Renderer's frames under random sequences of what users change between
frames (hypothesis): the options (debug views, tone maps, exposure, frame path, rasteriser,
alpha mask, normal and occlusion maps, shadows and their size, the environment, its
intensity and rotation, GTAO and its radius, bloom, the BRDF, the lighting mode), the size,
linear or 8-bit frames, the camera, the lights, and the scene's state (a node moved, a
material's colour, a node hidden). Each frame must equal, bit for bit, the frame of a
Renderer made for it (the same state changes applied): whatever the long-lived one keeps
(recordings, shadow maps, the environment's maps, GTAO's images, the frame slots' copies)
must never show. 150 sequences passed here with up to 8 changes each; CI runs a few."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from vkpbr.scene.default import default_scene
from vkpbr.scene.types import Light

OPTION_VALUES: dict[str, list[Any]] = {
    "view": ["final", "d", "shadow", "base-color", "mapped-normal", "occlusion", "emissive",
             "alpha", "ibl-specular"],
    "tonemap": ["none", "aces", "reinhard", "pbr-neutral"],
    "exposure": [0.0, 1.5],
    "pipeline": ["forward", "compute"],
    "raster": ["hardware", "compute"],
    "alpha_mask": [True, False],
    "normal_mapping": [True, False],
    "occlusion": [True, False],
    "shadows": [True, False],
    "shadow_resolution": [128, 256],
    "env": ["sky", "none"],
    "env_intensity": [1.0, 0.5],
    "env_rotation": [0.0, 90.0],
    "ao": ["off", "gtao", "gtao-low"],
    "ao_radius": [0.0, 0.5],
    "bloom": [0.0, 0.3],
    "brdf": ["gltf", "ggx"],
    "lighting": ["pbr", "course"],
}
LIGHTS: dict[str, list[Light] | None] = {
    "scene": None,
    "point": [Light(kind="point", position=(0.5, 2.0, 1.0), intensity=20.0)],
    "spot+sun": [Light(kind="spot", position=(0.0, 3.0, 0.5), direction=(0.0, -1.0, 0.0),
                       intensity=30.0, outer_cone=0.6),
                 Light(kind="directional", direction=(0.3, -1.0, 0.2))],
}
CHANGES = st.one_of(
    st.tuples(st.just("option"), st.sampled_from(sorted(OPTION_VALUES)), st.integers(0, 8)),
    st.tuples(st.just("size"), st.sampled_from([(64, 48), (48, 64), (80, 40)])),
    st.tuples(st.just("linear"), st.booleans()),
    st.tuples(st.just("camera"), st.integers(-3, 3)),
    st.tuples(st.just("lights"), st.sampled_from(sorted(LIGHTS))),
    st.tuples(st.just("pose"), st.integers(0, 3), st.integers(-3, 3)),
    st.tuples(st.just("paint"), st.integers(0, 3), st.floats(0.0, 1.0)),
    st.tuples(st.just("hide"), st.integers(0, 3), st.booleans()),
)
STATE_CHANGES = ("pose", "paint", "hide")
# The shadow maps by the raster units: compute-drawn cascades scroll with the camera, within
# a bound rather than bit for bit (tests/gpu/test_shadow_cache_sequences.py checks those).
BASE = {"shadow_raster": "hardware", "pipeline": "forward"}


@pytest.fixture(scope="module")
def long_lived() -> Iterator[Any]:
    from vkpbr import Renderer

    with Renderer(default_scene(), validation=True) as r:
        yield r
        r.check_validation()


@dataclasses.dataclass
class Frames:
    """A sequence's frame arguments, and its state changes (replayed on a new Renderer)."""

    opts: dict = dataclasses.field(default_factory=lambda: dict(BASE))
    size: tuple[int, int] = (64, 48)
    linear: bool = False
    angle: int = 0
    lights: str = "scene"
    state: list = dataclasses.field(default_factory=list)

    def change(self, change: tuple) -> None:
        kind, *a = change
        if kind == "option":
            values = OPTION_VALUES[a[0]]
            self.opts[a[0]] = values[a[1] % len(values)]
        elif kind == "camera":
            self.angle += a[0]
        elif kind in ("size", "linear", "lights"):
            setattr(self, kind, a[0])
        else:  # (STATE_CHANGES)
            self.state.append(change)

    def frame(self, r: Any, changes: list) -> np.ndarray:  # noqa: ANN001
        for kind, node, value in changes:
            if kind == "pose":
                m = r.state.tree.local[node].copy()
                m[0, 3] += 0.1 * value
                r.set_pose(node, m)
            elif kind == "paint":
                r.set_material(node, base_color=(value, 0.5, 0.5, 1.0))
            else:
                r.set_visible(node, value)
        c = r.default_camera()
        a = 0.15 * self.angle
        turn = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        eye = np.asarray(c.target) + turn @ (np.asarray(c.eye) - np.asarray(c.target))
        return r.render(dataclasses.replace(c, eye=tuple(eye)), LIGHTS[self.lights],
                        size=self.size, linear=self.linear, **self.opts)


@settings(max_examples=5, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(changes=st.lists(CHANGES, min_size=2, max_size=6))
@example(changes=[("paint", 0, 0.9), ("option", "exposure", 1), ("pose", 1, 2), ("hide", 2, False),
                  ("option", "pipeline", 1), ("lights", "point"), ("option", "ao", 1)])
def test_every_frame_equals_a_new_renderers(long_lived, changes) -> None:  # noqa: ANN001
    from vkpbr import Renderer

    long_lived.state.reset()
    frames = Frames()
    for step, change in enumerate(changes):
        frames.change(change)
        got = frames.frame(long_lived, [change] if change[0] in STATE_CHANGES else [])
        with Renderer(default_scene(), validation=True) as new:
            want = frames.frame(new, frames.state)
            new.check_validation()
        assert np.array_equal(got, want), (step, change, frames)
