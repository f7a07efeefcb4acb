"""A GPU that never finishes is a clear error after $VKPBR_GPU_TIMEOUT_S, not a hang (this
session's H200 run hung forever in one unbounded shader loop; every wait is bounded now)."""

from __future__ import annotations

import pytest

from vkpbr.errors import GpuTimeoutError, VkpbrError
from vkpbr.gpu.device import GPU_TIMEOUT_DEFAULT_S, Device, gpu_timeout_ns


@pytest.mark.timeout(60)  # the hang guard: a wait that never returned would fail here
def test_a_fence_that_never_signals_times_out(monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setenv("VKPBR_GPU_TIMEOUT_S", "0.2")
    with Device(None, validation=True) as d:
        vk = d.vk
        fence = vk.vkCreateFence(d.handle, vk.VkFenceCreateInfo(), None)  # never submitted
        try:
            with pytest.raises(GpuTimeoutError, match="did not finish a frame in 0.2 s") as info:
                d.wait_fences(vk.ffi.new("VkFence[1]", [fence]), "a frame")
            assert isinstance(info.value, VkpbrError) and "\n" not in str(info.value)
            assert "VKPBR_GPU_TIMEOUT_S" in str(info.value)  # says what to do
        finally:
            vk.vkDestroyFence(d.handle, fence, None)


@pytest.mark.parametrize("text, seconds", [("", GPU_TIMEOUT_DEFAULT_S), ("30", 30.0),
                                           ("junk", GPU_TIMEOUT_DEFAULT_S), ("-1", GPU_TIMEOUT_DEFAULT_S),
                                           ("inf", GPU_TIMEOUT_DEFAULT_S)])
def test_timeout_setting(monkeypatch, text: str, seconds: float) -> None:  # noqa: ANN001
    monkeypatch.setenv("VKPBR_GPU_TIMEOUT_S", text)
    assert gpu_timeout_ns() == int(seconds * 1e9)
