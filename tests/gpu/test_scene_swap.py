"""`Renderer.set_scene` (render/scene_swap.py; issue 32, must-have 7): a Renderer keeps its
device and pipeline cache and draws another scene, exactly as a fresh Renderer of that scene
draws it (bit-equal colour, depth and instance ids on lavapipe), and swapping back and forth
leaves no Vulkan object behind but the immutable ones the device keeps (gpu/kept.py: layouts,
pipelines, samplers), which a second round of swaps makes none of."""

from __future__ import annotations

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.gpu.device import live_objects

SIZE = (64, 48)
OUTPUTS = ("color", "depth", "instance")


def _frame(renderer) -> dict[str, np.ndarray]:  # noqa: ANN001
    return renderer.render(size=SIZE, outputs=OUTPUTS)


def _equal(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> None:
    for name in OUTPUTS:
        assert a[name].shape == b[name].shape, name
        assert np.array_equal(a[name], b[name], equal_nan=True), name


def test_set_scene_renders_what_a_fresh_renderer_renders(make_renderer, sample_scene) -> None:  # noqa: ANN001
    textured = sample_scene("TextureCoordinateTest")
    fresh = make_renderer(textured)
    want = _frame(fresh)
    fresh_batch = fresh.render_batch([fresh.default_camera()] * 2, size=SIZE)
    fresh.close()

    renderer = make_renderer()  # the built-in chart first
    chart = _frame(renderer)
    device, cache = renderer.device, renderer.device.pipeline_cache
    children, kept = device.live_children, len(device.kept)
    renderer.world_slots(["sphere-m0-r0"])  # a node of the chart, gone with it
    renderer.set_scene(textured)
    with pytest.raises(UsageError, match="world_slots"):
        renderer.render_batch([renderer.default_camera()], size=SIZE, worlds=np.eye(4)[None, None])
    assert renderer.device is device and renderer.device.pipeline_cache is cache
    assert renderer.scene is textured
    _equal(_frame(renderer), want)
    batch = renderer.render_batch([renderer.default_camera()] * 2, size=SIZE)
    assert np.array_equal(batch, fresh_batch)
    assert renderer.timings["textures"] >= 0 and renderer.timings["pipelines_built"] > 0

    renderer.set_scene(None)  # back to the chart: the same frame as before the swaps
    _equal(_frame(renderer), chart)
    # Each swap destroyed what the scene before made (the device's children made for a scene;
    # what the device keeps for its life, kept handles and parts such as a GPU's compute-batch
    # atlases, is not a scene's: on the H200 the atlas's 14 objects counted here as a leak
    # when every Vulkan object was counted). The second round below counts every object.
    assert device.live_children == children
    assert len(device.kept) > kept  # (the textured scene's own pipelines, kept)

    # A second round makes nothing the first did not: no Vulkan object, no pipeline build.
    made = (live_objects(), device.live_children, len(device.kept))
    built = renderer.timings["pipelines_built"]
    renderer.set_scene(textured)
    _equal(_frame(renderer), want)
    renderer.set_scene(None)
    _equal(_frame(renderer), chart)
    assert renderer.timings["pipelines_built"] == built
    assert (live_objects(), device.live_children, len(device.kept)) == made

    # A compute batch's atlas passes to the next scene's batches (render/targets.py atlas;
    # its frames are checked by tests/gpu/test_compute_batch.py, atlases reused across calls).
    atlas = renderer.batch_path._atlas((8, 8), False)
    renderer.set_scene(textured)
    assert renderer.batch_path._atlas((8, 8), False) is atlas and atlas.color.handle is not None
