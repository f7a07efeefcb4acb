"""The one place that imports the `vulkan` binding, and translates its failures.

Everything in vkpbr reaches Vulkan through `vkpbr.gpu`; this module loads the binding lazily so
that `import vkpbr` stays fast and works on machines without a Vulkan loader, and turns the
binding's exceptions into vkpbr's own (VulkanError and subclasses) at this boundary.

`load()` returns the binding wrapped once, in the manner of wgpu-py's SafeLibCalls: every
`vk*` function (and every extension function fetched through vkGet*ProcAddr) raises vkpbr's
error carrying the call's name, so no binding exception (VkErrorDeviceLost, VkNotReady, ...)
reaches a caller. Constants, struct factories, `ffi` and `lib` pass through untouched; the
hot paths call `lib` entry points directly and check their VkResult with `check_result`.
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

__all__ = ["load", "translate_errors", "check_result", "SafeVulkan", "INSTALL_HINT"]

INSTALL_HINT = (
    "install a Vulkan loader and driver: on Debian/Ubuntu `apt-get install libvulkan1 "
    "mesa-vulkan-drivers` (or run scripts/setup.sh); on a GPU machine, the vendor driver"
)

_vk: Any = None
_raw: Any = None


def _raw_binding() -> Any:
    global _raw
    if _raw is None:
        try:
            import vulkan
        except OSError as exc:  # cffi raises OSError when libvulkan.so.1 cannot be opened
            raise NoVulkanError("dlopen(libvulkan.so.1)", "not found", INSTALL_HINT) from exc
        _raw = vulkan
    return _raw


class SafeVulkan:
    """The `vulkan` module with its functions wrapped to raise vkpbr errors (see the module
    docstring). Attributes are looked up once and cached on the instance."""

    def __init__(self, module: Any) -> None:
        self.raw = module

    def __getattr__(self, name: str) -> Any:
        value = getattr(self.raw, name)
        if name.startswith("vk") and callable(value):
            value = _safe_call(value, name)
            if name in ("vkGetInstanceProcAddr", "vkGetDeviceProcAddr"):
                value = _safe_proc_addr(value)
        setattr(self, name, value)  # later lookups skip __getattr__
        return value


def _safe_call(fn: Any, name: str) -> Any:
    def call(*args: Any, **kwargs: Any) -> Any:
        with translate_errors(name):
            return fn(*args, **kwargs)

    call.__name__ = call.__qualname__ = name
    call.__doc__ = getattr(fn, "__doc__", None)
    return call


def _safe_proc_addr(get: Any) -> Any:
    def get_proc(handle: Any, name: str) -> Any:
        return _safe_call(get(handle, name), name)

    return get_proc


def load() -> Any:
    """The wrapped binding, imported once; NoVulkanError when no loader is installed."""
    global _vk
    if _vk is None:
        _vk = SafeVulkan(_raw_binding())
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
    vk = _raw_binding()
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
    exc_type = _raw_binding().exception_codes.get(result)
    if exc_type is None:
        raise VulkanError(function, f"VkResult {result}")
    with translate_errors(function):
        raise exc_type()
