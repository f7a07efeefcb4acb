"""render_batch's cache and replays (render/batch_cache.py, render/batch_replay.py) under
random sequences of calls and state changes (hypothesis): calls that differ in their
cameras, world poses, pipeline, expansion, per-world materials and visibility, shadows and
lights, repeated until the ring's slots replay them, interleaved with the state's own
changes (a node outside the world slots moved, a material's factors, a node hidden) and
`batch_step` calls. Every result must equal, bit for bit, the same call made fresh on a
second renderer given the same changes (its cache and replays cleared first). The replays'
key losing the state's version fails it. test_batch_cache.py pins each case by script;
these find what their interleavings break."""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_outputs import CAMERA, analytic_scene
from test_worlds import MOVED, cameras, world_poses

from vkpbr.render.batch_cache import batch_cache
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.types import Light

SIZE = (24, 18)
POINT = Light(kind="point", position=(-0.5, 3.0, 1.5), intensity=25.0, falloff="inverse_square")
SUN = Light(kind="directional", direction=(0.0, -0.6, 1.0), intensity=8.0)

BATCHES = (CameraBatch.from_cameras(cameras(3), CAMERA),
           CameraBatch.from_cameras([CAMERA, *cameras(2)], CAMERA))
CALLS = st.fixed_dictionaries({
    "cameras": st.sampled_from((0, 1, 2)),  # (2: a list of Camera objects)
    "poses": st.sampled_from((None, 1, 2)),
    "pipeline": st.sampled_from(("forward", "compute")),
    "expand": st.sampled_from(("auto", "gpu")),
    "materials": st.booleans(),
    "visible": st.booleans(),
    "shadows": st.booleans(),
    "lights": st.sampled_from(("point", "sun", "scene")),
})
ACTIONS = st.one_of(
    st.tuples(st.just("call"), CALLS),
    st.tuples(st.just("repeat"), st.integers(1, 4)),  # the last call again: replays
    st.tuples(st.just("step"), st.integers(1, 3)),  # the last call as a batch_step
    st.tuples(st.just("ground"), st.floats(-0.2, 0.2)),  # a node outside the slots moved
    st.tuples(st.just("paint"), st.floats(0.0, 1.0)),  # a material's factor
    st.tuples(st.just("hide"), st.booleans()),  # the big sphere hidden or shown
)


@pytest.fixture(scope="module")
def pair() -> Iterator[list]:
    """The renderer whose calls cache and replay, and the one whose calls are all made fresh
    (a call made fresh on the first would clear what its next calls replay)."""
    from vkpbr.render.renderer import Renderer

    made = [Renderer(analytic_scene(), validation=True,
                     sync_validation=os.environ.get("VKPBR_SYNC_VALIDATION", "1") != "0")
            for _ in range(2)]
    for r in made:
        r.world_slots(MOVED, materials=["m2"])
    yield made
    for r in made:
        instance = r.device.instance
        r.close()
        assert instance.errors == [], instance.errors[:3]


def arguments(r: Any, call: dict) -> tuple[Any, dict]:  # noqa: ANN001
    """render_batch's cameras and keywords for `call` (3 views, 3 worlds where posed)."""
    # A CameraBatch is what a loop's calls share (the cache keeps no list: render/batch_cache.py)
    cams = BATCHES[call["cameras"]] if call["cameras"] < 2 else cameras(3)
    pipeline = call["pipeline"] if call["pipeline"] == "forward" or not r.compute_batch_unavailable() \
        else "forward"
    kw: dict[str, Any] = {"pipeline": pipeline, "ao": "off", "shadows": call["shadows"],
                          "world_shadow_resolution": 64, "shadow_resolution": 64,
                          "lights": {"point": [POINT], "sun": [SUN], "scene": None}[call["lights"]]}
    if call["poses"] is not None:
        kw.update(worlds=world_poses(3, seed=call["poses"]), quaternion="wxyz",
                  world_expand=call["expand"])
        if call["visible"]:
            kw["world_visible"] = np.array([[True, False], [True, True], [False, True]])
    if call["materials"]:
        kw["world_materials"] = {"base_color": np.array([[[0.9, 0.1, 0.1]], [[0.1, 0.9, 0.1]],
                                                         [[0.1, 0.1, 0.9]]])}
    return cams, kw


def fresh(r: Any, cams: list, kw: dict) -> np.ndarray:  # noqa: ANN001
    batch_cache(r).clear()
    r.batch_path.replays.clear()
    return r.render_batch(cams, SIZE, **kw)


@settings(max_examples=16, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(actions=st.lists(ACTIONS, min_size=3, max_size=10))
def test_every_call_of_a_random_sequence_equals_a_fresh_call(pair, actions) -> None:  # noqa: ANN001
    r, reference = pair
    rest = r.state.local[3].copy()
    last: tuple[Any, dict] | None = None
    try:
        for i, (kind, value) in enumerate(actions):
            for each in pair:
                change(each, kind, value, rest)
            if kind == "call":
                last = arguments(r, value)
            if last is None:
                continue
            cams, kw = last
            if kind == "step":
                per_call = ("worlds", "world_visible")  # (a step's own arguments)
                step = r.batch_step(cams, SIZE, **{k: v for k, v in kw.items() if k not in per_call})
                got = [step(**{k: kw[k] for k in per_call if k in kw}) for _ in range(value)][-1]
            else:
                for _ in range(value if kind == "repeat" else 1):
                    got = r.render_batch(cams, SIZE, **kw)
            want = fresh(reference, cams, kw)
            assert np.array_equal(got, want), (i, kind, float(np.abs(got.astype(int) - want).max()))
    finally:
        for each in pair:
            change(each, "ground", 0.0, rest)
            change(each, "hide", True, rest)
            each.set_material("m0", base_color=(0.2, 0.5, 0.5, 1.0))


def change(r: Any, kind: str, value: Any, rest: np.ndarray) -> None:
    """The state's own changes (the same on both renderers)."""
    if kind == "ground":
        pose = rest.copy()
        pose[1, 3] += value
        r.set_pose(3, pose)
    elif kind == "paint":
        r.set_material("m0", base_color=(value, 0.5, 0.5, 1.0))
    elif kind == "hide":
        r.set_visible(0, value)
