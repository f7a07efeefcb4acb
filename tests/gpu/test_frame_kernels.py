"""A frame's pipelines are made ahead, at once (gpu/graph.py `Step.kernels`, issue 32's cold
start): each step names the pipelines its commands bind, and `record_steps` has them made on
the kernel threads before it records. What is asserted: on every frame path, raster and
shadow choice, with and without alpha-masked and blended materials, no pipeline is compiled
on the recording's own thread during a first frame (one that is, is a pipeline some step
binds without naming it: its compile would wait in line again), and a frame
drawn with them has content; a second frame builds nothing."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from vkpbr.render.options import RenderOptions
from vkpbr.scene.types import Light

SIZE = (48, 40)
LIGHTS = [Light(kind="point", position=(0.5, 4.0, 2.0), intensity=30.0),
          Light(kind="directional", direction=(-0.3, -1.0, -0.4), intensity=2.0)]
CHOICES = [dict(pipeline="forward"), dict(pipeline="compute"),
           dict(pipeline="compute", raster="compute"),
           dict(pipeline="compute", raster="compute", shadow_raster="compute"),
           # (the post steps' kernels: the bloom's levels, sensor noise, the encode)
           dict(pipeline="compute", bloom=0.5), dict(pipeline="forward", bloom=0.4,
                                                       noise="realsense-d435")]


@pytest.fixture(autouse=True)
def _no_kernels_ahead(monkeypatch) -> None:  # noqa: ANN001
    """What is checked here is the frame graph's own making: a GPU's renderer would have made
    the compute path's kernels ahead (render/kernels_ahead.py, tests/gpu/test_kernels_ahead.py)."""
    monkeypatch.setenv("VKPBR_KERNELS_AHEAD", "0")


def _first_frame_builds(renderer, **options) -> list[tuple[str, str]]:  # noqa: ANN001
    """(shaders, thread) of each pipeline the first frame built, the sky's bake apart."""
    stats = renderer.device.pipeline_cache.stats
    renderer.environments.get(RenderOptions())  # (the sky's kernels: made at once too)
    start = len(stats.builds)
    renderer.render(size=SIZE, lights=LIGHTS, **options)
    return [(name, thread) for name, _, _, _, thread in stats.builds[start:]]


@pytest.mark.parametrize("options", CHOICES, ids=lambda o: "-".join(map(str, o.values())))
def test_a_first_frame_compiles_nothing_on_its_own_thread(make_renderer, options) -> None:  # noqa: ANN001
    r = make_renderer()
    built = _first_frame_builds(r, **options)
    here = threading.current_thread().name
    assert built, "the first frame built no pipeline: nothing was checked"
    alone = [name for name, thread in built if thread == here]
    assert alone == [], f"compiled while recording, not made ahead by its step: {alone}"
    assert all(thread.startswith("vkpbr-kernels") for _, thread in built)
    again = len(r.device.pipeline_cache.stats.builds)
    r.render(size=SIZE, lights=LIGHTS, **options)
    assert len(r.device.pipeline_cache.stats.builds) == again  # (every one was made once)


@pytest.mark.parametrize("options", CHOICES[:2], ids=lambda o: "-".join(map(str, o.values())))
def test_masked_and_blended_materials_kernels_are_made_ahead(make_renderer, sample_scene,  # noqa: ANN001
                                                             options) -> None:
    r = make_renderer(sample_scene("AlphaBlendModeTest"))
    built = _first_frame_builds(r, **options)
    here = threading.current_thread().name
    assert any("mask" in name for name, _ in built), built  # (the masked draws' own pipelines)
    assert [name for name, thread in built if thread == here] == []
    image = r.render(size=SIZE, lights=LIGHTS, **options)
    assert np.asarray(image).std() > 0  # (a frame was drawn with them)


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
@pytest.mark.parametrize("ao", ["off", "gtao"])
def test_a_first_batch_compiles_nothing_on_its_own_thread(make_renderer, pipeline: str,  # noqa: ANN001
                                                          ao: str) -> None:
    """The layered batch's chunks (their passes, the GTAO depth pre-pass) and the compute
    batch's kernels are named by their steps too."""
    r = make_renderer()
    stats = r.device.pipeline_cache.stats
    r.environments.get(RenderOptions())
    r.render(size=SIZE, lights=LIGHTS, pipeline=pipeline, ao=ao)  # (the frame's own first)
    start = len(stats.builds)
    cams = [r.default_camera()] * 3
    frames = r.render_batch(cams, size=(32, 24), lights=LIGHTS, pipeline=pipeline, ao=ao)
    built = [(name, thread) for name, _, _, _, thread in stats.builds[start:]]
    here = threading.current_thread().name
    assert built, "the batch built no pipeline of its own: nothing was checked"
    assert [name for name, thread in built if thread == here] == []
    assert np.asarray(frames).std() > 0
