"""The binding's wrapper (gpu/vk.py): a failing call raises vkpbr's error naming the call and
its VkResult (and no binding exception), a succeeding one returns what the binding returns."""

from __future__ import annotations

import pytest

from vkpbr.errors import VulkanError
from vkpbr.gpu.vk import load


def test_failing_call_raises_vkpbr_error_with_its_result() -> None:
    vk = load()
    with pytest.raises(VulkanError, match="vkEnumerateInstanceExtensionProperties.*"
                                          "VK_ERROR_LAYER_NOT_PRESENT") as got:
        vk.vkEnumerateInstanceExtensionProperties("VK_LAYER_vkpbr_no_such_layer")
    assert type(got.value) is VulkanError and got.value.__cause__ is None


def test_succeeding_call_returns_the_bindings_value() -> None:
    vk = load()
    names = {p.extensionName for p in vk.vkEnumerateInstanceExtensionProperties(None)}
    raw = {p.extensionName for p in vk.raw.vkEnumerateInstanceExtensionProperties(None)}
    assert names == raw and names


@pytest.mark.parametrize("call", ["render", "render_many", "render_batch", "set_scene",
                                  "add_instances", "build_pipelines", "offscreen_target",
                                  "batch_step"])
def test_a_closed_renderer_says_so(call: str) -> None:
    """Every way of drawing with (or making GPU objects for) a closed Renderer raises one
    UsageError saying it is closed: each had aborted the process in the driver (a NULL
    device handle), from frames recorded on it (Device.lock refuses them) or from any
    binding call on it (the wrapper refuses a NULL dispatchable handle)."""
    import numpy as np

    from vkpbr.errors import UsageError
    from vkpbr.render.renderer import Renderer

    r = Renderer(validation=True)
    camera, mesh = r.default_camera(), r.scene.nodes[0].mesh
    r.close()
    calls = {
        "render": lambda: r.render(size=(32, 32)),
        "render_many": lambda: list(r.render_many([camera, camera], size=(32, 32))),
        "render_batch": lambda: r.render_batch([camera] * 2, (32, 32)),
        "set_scene": lambda: r.set_scene(None),
        "add_instances": lambda: r.add_instances(mesh, np.eye(4)[None]),
        "build_pipelines": lambda: r.build_pipelines(r.targets.new((32, 32), False)),
        "offscreen_target": lambda: r.offscreen_target((40, 30)),
        "batch_step": lambda: r.batch_step([camera], (32, 32))(),
    }
    with pytest.raises(UsageError, match="closed") as got:
        calls[call]()
    assert "\n" not in str(got.value)
    r.close()  # (again: idempotent)
