"""The frame path's own promises: the depth pre-pass changes no pixel, per-pass GPU timings
are reported, and every failing Vulkan call raises vkpbr's error with the call's name."""

from __future__ import annotations

import numpy as np
import pytest

from vkpbr.errors import VulkanError


def test_depth_prepass_changes_no_pixel(make_renderer) -> None:
    from vkpbr.scene.synthetic import sphere_field

    scene = sphere_field(draws=40, rings=8, segments=16, materials=4)
    # The pre-pass is the fragment path's (auto takes the compute path on GPUs); GTAO off,
    # which takes the visibility pass as the fragment passes' pre-pass (render/paths.py).
    plain = make_renderer(scene, depth_prepass=False).render(size=(96, 64), depth=True,
                                                              pipeline="forward", ao="off")
    pre = make_renderer(scene, depth_prepass=True)
    image = pre.render(size=(96, 64), depth=True, pipeline="forward", ao="off")
    assert np.array_equal(plain[0], image[0]) and np.array_equal(plain[1], image[1])
    passes = pre.last_stats.pass_ms
    assert {"shadows", "prepass_opaque", "opaque", "mask", "blend", "copy"} <= set(passes)
    if pre.device.timestamps:
        assert passes["prepass_opaque"] >= 0 and pre.last_stats.gpu_ms > 0


def test_failing_calls_raise_vkpbr_errors_named(make_renderer) -> None:
    """A query read before anything wrote it: VK_NOT_READY, through the wrapped binding."""
    r = make_renderer()
    vk, dev = r.device.vk, r.device.handle
    pool = vk.vkCreateQueryPool(dev, vk.VkQueryPoolCreateInfo(
        queryType=vk.VK_QUERY_TYPE_OCCLUSION, queryCount=1), None)
    try:
        with r.device.one_time_commands() as cmd:
            vk.vkCmdResetQueryPool(cmd, pool, 0, 1)
        data = vk.ffi.new("uint64_t[1]")
        with pytest.raises(VulkanError, match="vkGetQueryPoolResults failed with VK_NOT_READY"):
            vk.vkGetQueryPoolResults(dev, pool, 0, 1, 8, data, 8, vk.VK_QUERY_RESULT_64_BIT)
    finally:
        vk.vkDestroyQueryPool(dev, pool, None)
    assert vk.vkCreateFence.__name__ == "vkCreateFence"


@pytest.mark.parametrize("options", [{"pipeline": "forward"},
                                     {"pipeline": "compute", "raster": "hardware"},
                                     {"pipeline": "compute", "raster": "compute"}])
def test_instanced_sphere_field_draws_the_separate_one(make_renderer, options: dict) -> None:
    """The scale benchmark's two forms (vkpbr bench spheres-5k-20m[-instanced]): one node a
    sphere, or one node a mesh holding its spheres as instances, render the same pixels."""
    from vkpbr.scene.synthetic import sphere_field

    size = (96, 64)
    nodes = make_renderer(sphere_field(draws=40, rings=8, segments=16, materials=4))
    if options.get("raster") == "compute" and not nodes.device.compute_raster:
        pytest.skip("no 64-bit storage atomics on this device")
    inst = make_renderer(sphere_field(draws=40, rings=8, segments=16, materials=4, instanced=True))
    a, b = nodes.render(size=size, **options), inst.render(size=size, **options)
    assert a[..., :3].std() > 10  # spheres over the sky, not a flat image
    assert np.array_equal(a, b)


def test_recordings_stay_bounded_when_a_loop_changes_a_keyed_value(make_renderer, monkeypatch) -> None:  # noqa: ANN001
    """A dataset that draws every image with its own bloom strength (a value of the
    recording's key): each new value records anew, and past RECORDINGS_KEPT a frame slot's
    least recently used recordings are freed (they had piled up, one a frame, until the
    renderer closed); a freed one's options drawn again are recorded again, the same
    pixels."""
    from vkpbr.render import recorder

    monkeypatch.setattr(recorder, "RECORDINGS_KEPT", 3)
    r = make_renderer()
    strengths = np.linspace(0.05, 0.6, 14)
    first = r.render(size=(48, 36), bloom=float(strengths[0]))
    counts = []
    for s in strengths[1:]:
        r.render(size=(48, 36), bloom=float(s))
        counts.append(len(r.recorder._recorded))
    slots = len(r.parts.slots)
    assert max(counts) <= 3 * slots and counts[-1] == 3 * slots, counts
    assert np.array_equal(r.render(size=(48, 36), bloom=float(strengths[0])), first)
