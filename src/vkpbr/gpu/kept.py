"""Handles a device keeps for its whole life, shared by every wrapper of the same definition.

A renderer that changes scene on one device (render/scene_swap.py) destroys what a scene
made and makes the next scene's objects; most of the immutable ones are the same again:
descriptor set layouts of the same bindings, pipeline layouts of the same set layouts and
push constants, pipelines of the same shaders and state, samplers of the same spec. On a
device with `Device.kept` set (a `KeptHandles`), their wrappers (DescriptorSetLayout,
PipelineLayout, Pipeline, ComputePipeline, Sampler) look their definition up here first and
share the handle made the first time: the wrapper is still a tracked child of the device,
but its `destroy` only lets go of the handle (DeviceObject.destroy); the handles themselves
are destroyed once, newest first, when the device closes. A new scene's pipelines are then
neither compiled nor looked up in the driver's pipeline cache, and swapping scenes back and
forth creates no Vulkan object the first round did not.

Keys name handles by address: safe because a kept handle is never destroyed before the
device, so no later object can reuse its address while a key names it.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from pathlib import Path
from typing import Any

__all__ = ["KeptHandles", "address", "file_key"]


def address(handle: Any, ffi: Any) -> int:
    """A handle's address as an int (cdata handles compare by identity in some bindings)."""
    return int(ffi.cast("uintptr_t", handle))


def file_key(path: Path) -> tuple[str, int, int]:
    """A SPIR-V file as a key: its path, size and modification time (a shader compiled again
    into the same path is another module)."""
    st = path.stat()
    return (str(path), st.st_size, st.st_mtime_ns)


class KeptHandles:
    """Handles by definition key (see the module's docstring); thread-safe: pipelines are
    built on several threads at once (FrameRecorder.build_pipelines)."""

    def __init__(self) -> None:
        self._by_key: dict[Hashable, Any] = {}
        self._made: list[tuple[str, Any]] = []  # (vkDestroy* name, handle), in making order
        self._lock = threading.Lock()
        self._making: dict[Hashable, threading.Event] = {}  # keys being made, set when done
        self.hits = 0  # look-ups that found a handle (benchmarks: what a swap did not make)

    def __len__(self) -> int:
        return len(self._made)

    def get(self, key: Hashable, destroy_fn: str, make: Callable[[], Any]) -> Any:
        """The handle of `key`, made by `make()` the first time, outside the lock: a second
        caller of a key being made waits for it (the frame graph makes a recording's
        pipelines on several threads; two steps may share one), and makes it itself when
        the first maker failed."""
        while True:
            with self._lock:
                handle = self._by_key.get(key)
                if handle is not None:
                    self.hits += 1
                    return handle
                making = self._making.get(key)
                if making is None:
                    making = self._making[key] = threading.Event()
                    break
            making.wait()
        try:
            handle = make()
        except BaseException:
            with self._lock:
                self._making.pop(key).set()
            raise
        with self._lock:
            self._made.append((destroy_fn, handle))
            self._by_key[key] = handle
            self._making.pop(key).set()
        return handle

    def destroy(self, vk: Any, device_handle: Any) -> None:
        """Destroy every handle, newest first (pipelines before their layouts)."""
        with self._lock:
            made, self._made, self._by_key = self._made, [], {}
        for destroy_fn, handle in reversed(made):
            getattr(vk, destroy_fn)(device_handle, handle, None)
