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
