"""The one place that imports the `vulkan` binding, and translates its failures.

Everything in vkpbr reaches Vulkan through `vkpbr.gpu`; this module loads the binding lazily so
that `import vkpbr` stays fast and works on machines without a Vulkan loader, and turns the
binding's exceptions into vkpbr's own (VulkanError and subclasses) at this boundary.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

from vkpbr.errors import (
    DeviceLostError,
    NoVulkanError,
    OutOfDeviceMemoryError,
    VulkanError,
)

__all__ = ["load", "translate_errors", "INSTALL_HINT"]

INSTALL_HINT = (
    "install a Vulkan loader and driver: on Debian/Ubuntu `apt-get install libvulkan1 "
    "mesa-vulkan-drivers` (or run scripts/setup.sh); on a GPU machine, the vendor driver"
)

_vk: Any = None


def load() -> Any:
    """Import the `vulkan` module once; raise NoVulkanError when no loader is installed."""
    global _vk
    if _vk is None:
        try:
            import vulkan
        except OSError as exc:  # cffi raises OSError when libvulkan.so.1 cannot be opened
            raise NoVulkanError("dlopen(libvulkan.so.1)", "not found", INSTALL_HINT) from exc
        _vk = vulkan
    return _vk


def _result_name(exc: BaseException) -> str:
    name = type(exc).__name__  # VkErrorOutOfDeviceMemory -> VK_ERROR_OUT_OF_DEVICE_MEMORY
    out = []
    for i, ch in enumerate(name):
        if ch.isupper() and i and not name[i - 1].isupper():
            out.append("_")
        out.append(ch.upper())
    return "".join(out)


@contextlib.contextmanager
def translate_errors(function: str) -> Iterator[None]:
    """Run a block of binding calls; re-raise the binding's exceptions as vkpbr errors."""
    vk = load()
    try:
        yield
    except vk.VkErrorOutOfDeviceMemory as exc:
        raise OutOfDeviceMemoryError(function, _result_name(exc)) from None
    except vk.VkErrorOutOfHostMemory as exc:
        raise OutOfDeviceMemoryError(function, _result_name(exc)) from None
    except vk.VkErrorDeviceLost as exc:
        raise DeviceLostError(function, _result_name(exc)) from None
    except (vk.VkErrorIncompatibleDriver, vk.VkErrorInitializationFailed) as exc:
        raise NoVulkanError(function, _result_name(exc), INSTALL_HINT) from None
    except (vk.VkError, vk.VkException) as exc:
        raise VulkanError(function, _result_name(exc)) from None


def check_result(result: int, function: str) -> None:
    """Raise the vkpbr error for a VkResult returned by a raw `vulkan.lib` call (hot paths
    call the C entry points directly: the binding's wrappers cost 10-100 us per call)."""
    if result == 0:
        return
    vk = load()
    exc_type = vk.exception_codes.get(result)
    if exc_type is None:
        raise VulkanError(function, f"VkResult {result}")
    with translate_errors(function):
        raise exc_type()
