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


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="os.fork: POSIX only")
def test_a_forked_child_is_told_to_make_its_own_renderer() -> None:
    """A Renderer made before a fork (torch's DataLoader workers fork by default on Linux):
    in the child, drawing with it raises one line saying so (it hung: the driver's threads
    stayed in the parent), a Renderer made in the child renders, and the parent's still
    works afterwards."""
    import os
    import select

    import numpy as np

    from vkpbr.render.renderer import Renderer

    with Renderer(validation=True) as r:
        want = r.render(size=(32, 32))
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: report, then leave without running the parent's clean-up
            lines = []
            for attempt in (lambda: r.render(size=(32, 32)),
                            lambda: r.add_instances(r.scene.nodes[0].mesh, np.eye(4)[None])):
                try:
                    attempt()
                    lines.append("drew")
                except Exception as exc:  # noqa: BLE001 (reported to the parent)
                    lines.append(f"{type(exc).__name__}: {exc}")
            with Renderer(validation=True) as own:
                lines.append(f"own {own.render(size=(32, 32)).shape} {len(own.device.instance.errors)}")
            os.write(write, "\n".join(lines).encode())
            os._exit(0)
        os.close(write)
        ready, _, _ = select.select([read], [], [], 60.0)
        if not ready:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            pytest.fail("the forked child hung")
        got = os.read(read, 65536).decode().splitlines()
        os.close(read)
        os.waitpid(pid, 0)
        assert got[0].startswith("UsageError: this renderer was made before this process was forked")
        assert got[1].startswith("UsageError: ") and "forked" in got[1]
        assert got[2] == "own (32, 32, 4) 0"  # (validation on in the child too: no error)
        assert np.array_equal(r.render(size=(32, 32)), want)
