"""The one place that imports the `vulkan` binding, and translates its failures.

Everything in vkpbr reaches Vulkan through `vkpbr.gpu`; this module loads the binding lazily so
that `import vkpbr` stays fast and works on machines without a Vulkan loader, and turns the
binding's exceptions into vkpbr's own (VulkanError and subclasses) at this boundary.

`load()` returns the binding wrapped once, in the manner of wgpu-py's SafeLibCalls: every
`vk*` function (and every extension function fetched through vkGet*ProcAddr) raises vkpbr's
error carrying the call's name, so no binding exception (VkErrorDeviceLost, VkNotReady, ...)
reaches a caller. Constants, struct factories, `ffi` and `lib` pass through untouched; the
hot paths call `lib` entry points directly and check their VkResult with `check_result`.

The same wrapper counts the Vulkan objects alive in the process (`live_objects()`): every
handle a wrapped vkCreate* / vkAllocate* returns is recorded by kind, and the matching
vkDestroy* / vkFree* removes it; destroying (or resetting) a command or descriptor pool
removes the buffers or sets allocated from it. A leak test compares the count before a
Renderer with the count after its `close()`. Handles created outside the wrapper (a GLFW
surface, `lib` calls) are not counted, and destroying them is ignored.
"""

from __future__ import annotations

import contextlib
import threading
from collections import Counter
from collections.abc import Iterator
from typing import Any

from vkpbr.errors import (
    DeviceLostError,
    NoVulkanError,
    OutOfDeviceMemoryError,
    UsageError,
    VulkanError,
)

__all__ = ["load", "translate_errors", "check_result", "SafeVulkan", "INSTALL_HINT",
           "live_objects", "live_objects_by_kind"]

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
            value = _counted(_safe_call(value, name), name)
            if name in ("vkGetInstanceProcAddr", "vkGetDeviceProcAddr"):
                value = _safe_proc_addr(value)
        setattr(self, name, value)  # later lookups skip __getattr__
        return value


# Calls whose first argument may be NULL; every other call's first is a dispatchable handle
# (instance, device, queue, command buffer), which NULL makes the driver abort the process.
_NULL_FIRST = frozenset({"vkCreateInstance", "vkEnumerateInstanceExtensionProperties",
                         "vkEnumerateInstanceLayerProperties", "vkEnumerateInstanceVersion",
                         "vkGetInstanceProcAddr"})


def _safe_call(fn: Any, name: str) -> Any:
    raw = _raw_binding()
    caught = (raw.VkError, raw.VkException)
    null_first = name in _NULL_FIRST

    # try/except rather than `with translate_errors(name)`: the same errors, without a
    # context manager's ~3 us on each of the ~700 calls a scene change makes (issue 32).
    def call(*args: Any, **kwargs: Any) -> Any:
        if args and args[0] is None and not null_first:  # (a closed device's handle)
            raise UsageError(f"{name}: the device is closed, or was made before this process "
                             "was forked: make a new Renderer")
        try:
            return fn(*args, **kwargs)
        except caught as exc:
            raise _translated(exc, name) from None

    call.__name__ = call.__qualname__ = name
    call.__doc__ = getattr(fn, "__doc__", None)
    return call


def _safe_proc_addr(get: Any) -> Any:
    def get_proc(handle: Any, name: str) -> Any:
        return _counted(_safe_call(get(handle, name), name), name)

    return get_proc


# --- live object count -----------------------------------------------------------------------
# kind -> {handle address: parent pool address or 0}
_live: dict[str, dict[int, int]] = {}
_live_lock = threading.Lock()
# vkAllocate* / vkFree* names that are not "vkAllocate" + kind + "s".
_ALLOC_KIND = {"vkAllocateMemory": "Memory", "vkFreeMemory": "Memory",
               "vkCreateGraphicsPipelines": "Pipeline", "vkCreateComputePipelines": "Pipeline"}
_POOL_CHILD = {"CommandPool": "CommandBuffer", "DescriptorPool": "DescriptorSet"}


def live_objects() -> int:
    """Vulkan objects created through the wrapped binding and not yet destroyed, in the whole
    process (instances, devices, buffers, memory, command buffers, descriptor sets, ...)."""
    with _live_lock:
        return sum(len(handles) for handles in _live.values())


def live_objects_by_kind() -> dict[str, int]:
    """`live_objects()` split by object kind ("Buffer", "Memory", "Pipeline", ...); kinds
    with none alive are left out."""
    with _live_lock:
        return dict(Counter({k: len(v) for k, v in _live.items() if v}))


def _address(handle: Any) -> int:
    if handle is None:
        return 0
    if isinstance(handle, int):
        return handle
    return int(_raw_binding().ffi.cast("uintptr_t", handle))


def _kind(name: str) -> tuple[str, str] | None:
    """("create" | "destroy" | "reset", kind) for a function that makes or ends objects."""
    if name in _ALLOC_KIND:
        return ("destroy" if name.startswith("vkFree") else "create"), _ALLOC_KIND[name]
    for prefix, op in (("vkCreate", "create"), ("vkDestroy", "destroy"),
                       ("vkAllocate", "create"), ("vkFree", "destroy")):
        if name.startswith(prefix):
            kind = name[len(prefix):]
            if prefix in ("vkAllocate", "vkFree"):
                kind = kind.removesuffix("s")  # vkAllocateCommandBuffers -> CommandBuffer
            return op, kind
    if name in ("vkResetDescriptorPool",):
        return "reset", "DescriptorPool"
    return None


def _counted(fn: Any, name: str) -> Any:
    """`fn` recording the objects it creates or destroys in the live count (see above)."""
    what = _kind(name)
    if what is None:
        return fn
    op, kind = what

    if op == "create":
        def create(*args: Any, **kwargs: Any) -> Any:
            result = fn(*args, **kwargs)
            handles = result if kind in ("CommandBuffer", "DescriptorSet", "Pipeline") else [result]
            parent = 0
            if kind in ("CommandBuffer", "DescriptorSet"):  # parent pool from the allocate info
                info = args[1] if len(args) > 1 else next(iter(kwargs.values()))
                parent = _address(getattr(info, "commandPool", None)
                                  or getattr(info, "descriptorPool", None))
            with _live_lock:
                table = _live.setdefault(kind, {})
                for h in handles:
                    table[_address(h)] = parent
            return result

        create.__name__ = create.__qualname__ = name
        return create

    def destroy(*args: Any, **kwargs: Any) -> Any:
        result = fn(*args, **kwargs)
        if kind in ("Instance", "Device"):
            ended = [args[0]]
        elif kind in ("CommandBuffer", "DescriptorSet"):  # (device, pool, count, handles)
            ended = list(args[3])[: int(args[2])]
        elif op == "reset":
            ended = []
        else:
            ended = [args[1]]
        with _live_lock:
            table = _live.get(kind, {})
            for h in ended:
                table.pop(_address(h), None)
            child = _POOL_CHILD.get(kind)
            if child is not None:
                pool = _address(args[1])
                children = _live.get(child, {})
                for h in [h for h, p in children.items() if p == pool]:
                    del children[h]
        return result

    destroy.__name__ = destroy.__qualname__ = name
    return destroy


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
    except (vk.VkError, vk.VkException) as exc:
        raise _translated(exc, function) from None


def _translated(exc: BaseException, function: str) -> VulkanError:
    """vkpbr's error for the binding's exception `exc`, raised by `function`."""
    vk = _raw_binding()
    if isinstance(exc, (vk.VkErrorOutOfDeviceMemory, vk.VkErrorOutOfHostMemory)):
        return OutOfDeviceMemoryError(function, _result_name(exc))
    if isinstance(exc, vk.VkErrorDeviceLost):
        return DeviceLostError(function, _result_name(exc))
    if isinstance(exc, (vk.VkErrorIncompatibleDriver, vk.VkErrorInitializationFailed)):
        return NoVulkanError(function, _result_name(exc), INSTALL_HINT)
    return VulkanError(function, _result_name(exc))


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
