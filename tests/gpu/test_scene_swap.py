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


def test_ambient_occlusion_images_pass_to_the_next_scene(make_renderer, sample_scene) -> None:  # noqa: ANN001
    """The AO images and kernels are the device's (render/parts.py DeviceParts.ao): the next
    scene takes them as they are, grown by an earlier larger frame, and its `ao` output and
    colour equal a fresh renderer's; its kernels' sets are made anew (they named the last
    scene's depth views and buffers)."""
    helmet = sample_scene("DamagedHelmet")
    chart_first = make_renderer()
    ao_outputs = ("color", "ao")
    fresh = make_renderer(helmet)
    want = fresh.render(size=SIZE, outputs=ao_outputs)
    fresh.close()

    renderer = chart_first
    renderer.render(size=(2 * SIZE[0], 2 * SIZE[1]), outputs=ao_outputs)  # (the images grow)
    ao, images = renderer.parts.ao, list(renderer.parts.ao.images)
    sets = dict(ao._sets)
    renderer.set_scene(helmet)
    assert renderer.parts.ao is ao and ao.images == images and not ao._sets
    got = renderer.render(size=SIZE, outputs=ao_outputs)
    assert float(np.mean(got["ao"])) < 1.0  # (occlusion was computed: the helmet's folds)
    for name in ao_outputs:
        assert np.array_equal(got[name], want[name]), name
    assert sets and ao._sets  # (dropped with the last scene, made for this one's depths)
