"""Device memory kept for reuse: freed allocations wait, by memory type and size class, for
the next buffer or image that fits (issue 32, a job's scene changes).

A scene change frees a scene's buffers and images and makes the next one's (render/
scene_swap.py), and each one was its own VkDeviceMemory. NVIDIA's driver takes ~0.25 ms for
a vkAllocateMemory and as long for a vkFreeMemory (H200, run f of 2026-12-04: 61 of each a
swap, 30 of a small model's 77 ms), where lavapipe's are nearly free. Here a freed
allocation of up to MAX_RECYCLED bytes is not freed but kept (mapped, where it was, for
host-visible buffers), and an allocation asks first for a kept one of its memory type and
size class, else of one of the LARGER classes above (the smallest that holds it): sizes
rounded up to quarter octaves (at most 19% more memory than asked; up to twice as much for a
larger class's), so that a next scene's buffers and images of other sizes still fit (a job's
items change models: in a 100-scene job on the H200 an item made 8.5-13 allocations, at
0.5-1.3 ms each with one to six processes on the GPU, run s20c). At most `kept_limit`
bytes wait at once (1/32 of the device's memory, 512 MiB to 2 GiB; beyond that the oldest
are freed, memory the host cannot see before mapped memory: `_drop_oldest`);
`clear` frees them all (the device's close, and an allocation the driver refuses, which is
then asked again).

Memory is bound at offset 0 of an allocation at least as large as asked and aligned as any
allocation is, so a reused allocation is valid for the next buffer or image as a new one
would be. Its contents are what its last user left (Vulkan leaves a new allocation's
contents undefined too: nothing may read memory it did not write). Exportable memory (CUDA
imports it) is never kept: its allocation carries the export.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from typing import Any

__all__ = ["MemoryRecycler", "MAX_RECYCLED", "KEPT_BYTES", "MOST_KEPT", "LARGER", "size_class",
           "fitting_classes", "kept_limit", "check_heap"]

MAX_RECYCLED = 64 << 20  # larger allocations are freed (few, and their memory is wanted back)
KEPT_BYTES = 512 << 20  # at least this much may be kept at once (kept_limit)
MOST_KEPT = 2 << 30  # and at most this much
PAGE = 4096
LARGER = 4  # a kept allocation serves requests down to this many classes below its own


def _class_size(k: int) -> int:
    """Class k's size: 2^(k/4) rounded up to whole pages."""
    return -(-max(math.ceil(2.0 ** (k / 4.0)), 1) // PAGE) * PAGE


def _class_index(size: int) -> int:
    """The index k of the smallest class that holds `size` (several k of one page size: the
    smallest)."""
    size = max(int(size), 1)
    k = math.ceil(4.0 * math.log2(size))
    while _class_size(k) < size:  # (the float's rounding)
        k += 1
    while k > 0 and _class_size(k - 1) >= size:  # (pages round several classes to one size)
        k -= 1
    return k


def size_class(size: int) -> int:
    """`size` rounded up to the smallest of the classes, 2^(k/4) rounded up to whole pages,
    that holds it (a class's own size is its class: a kept allocation fits it again)."""
    return _class_size(_class_index(size))


def fitting_classes(size: int) -> list[int]:
    """The classes a kept allocation may have to serve `size`: its own, then up to LARGER
    classes above it (at most twice the size: a job's next scene has other sizes than the
    last, and an allocation is bound at offset 0, valid for anything smaller)."""
    k = _class_index(size)
    return list(dict.fromkeys(_class_size(k + i) for i in range(LARGER + 1)))


def kept_limit(device_local: int) -> int:
    """How much freed memory a device keeps at once: 1/32 of its device-local heap, at least
    KEPT_BYTES and at most MOST_KEPT (2 GiB of the H200's 141 GB: a job's scenes of tens to
    hundreds of MiB of textures each, such as Sponza's 31 allocations of 5.3 MiB, had pushed
    each other out of 512 MiB)."""
    return max(KEPT_BYTES, min(MOST_KEPT, int(device_local) // 32))


class Allocation:
    """One VkDeviceMemory: its type, size and, for host-visible memory, its mapping (the whole
    allocation, mapped once for its life)."""

    __slots__ = ("memory", "type_index", "size", "mapped")

    def __init__(self, memory: Any, type_index: int, size: int, mapped: Any = None) -> None:
        self.memory, self.type_index, self.size, self.mapped = memory, type_index, size, mapped


class MemoryRecycler:
    """A device's kept allocations (Device.memory)."""

    def __init__(self, device: Any) -> None:
        self.device = device
        self._kept: OrderedDict[int, tuple[tuple[int, int, bool], Allocation]] = OrderedDict()
        self._by_key: dict[tuple[int, int, bool], list[Allocation]] = {}
        self.kept_bytes = 0
        self.limit = KEPT_BYTES  # at most this many bytes kept
        self.reused = 0  # allocations served from the kept ones (tests and benchmarks read it)
        self.made = 0
        # (a device's objects may be made on another thread: Device.keeping)
        self._lock = threading.Lock()

    def allocate(self, size: int, type_index: int, mapped: bool) -> Allocation:
        """An allocation of at least `size` bytes of memory type `type_index` (mapped whole
        where `mapped`): a kept one of its size class, else a new one."""
        if size <= MAX_RECYCLED:
            classes = fitting_classes(size)
            size = classes[0]
            with self._lock:
                for fits in classes:  # (the smallest kept one that holds it)
                    got = self._by_key.get((type_index, fits, mapped))
                    if got:
                        alloc = got.pop()
                        del self._kept[id(alloc)]
                        self.kept_bytes -= alloc.size
                        self.reused += 1
                        return alloc
        vk, dev = self.device.vk, self.device.handle
        check_heap(self.device, size, type_index)
        info = vk.VkMemoryAllocateInfo(allocationSize=size, memoryTypeIndex=type_index)
        try:
            memory = vk.vkAllocateMemory(dev, info, None)
        except Exception:
            if not self._kept:
                raise
            self.clear()  # (the kept memory may be what is missing: freed, then asked again)
            memory = vk.vkAllocateMemory(dev, info, None)
        self.made += 1
        view = vk.vkMapMemory(dev, memory, 0, size, 0) if mapped else None
        return Allocation(memory, type_index, size, view)

    def release(self, alloc: Allocation) -> None:
        """`alloc` is no longer bound to anything (its buffer or image destroyed): kept for
        the next allocation of its class, or freed."""
        if alloc.size > MAX_RECYCLED or alloc.size > self.limit:
            self._free(alloc)
            return
        key = (alloc.type_index, alloc.size, alloc.mapped is not None)
        with self._lock:
            self._by_key.setdefault(key, []).append(alloc)
            self._kept[id(alloc)] = (key, alloc)
            self.kept_bytes += alloc.size
            while self.kept_bytes > self.limit:
                self._drop_oldest()

    def clear(self) -> None:
        """Free every kept allocation."""
        with self._lock:
            while self._kept:
                self._drop_oldest()

    def _drop_oldest(self) -> None:
        """Free the oldest kept allocation that is not mapped, else the oldest: mapped
        (host-visible) memory is what drivers take longest to make (NVIDIA pins its pages:
        ~10 ms for an upload's 64 MiB staging buffer on the H200, run g), and a scene change
        frees far more device-local memory (its textures) than the limit, which had pushed
        the staging buffers out before the next scene's upload."""
        oldest = next((k for k, (key, _) in self._kept.items() if not key[2]),
                      next(iter(self._kept)))
        key, alloc = self._kept.pop(oldest)
        self._by_key[key].remove(alloc)
        self.kept_bytes -= alloc.size
        self._free(alloc)

    def _free(self, alloc: Allocation) -> None:
        vk, dev = self.device.vk, self.device.handle
        if alloc.mapped is not None:
            vk.vkUnmapMemory(dev, alloc.memory)
            alloc.mapped = None
        vk.vkFreeMemory(dev, alloc.memory, None)
        alloc.memory = None


def check_heap(device: Any, size: int, type_index: int) -> None:
    """Raise OutOfDeviceMemoryError where `size` bytes exceed the whole heap of memory type
    `type_index`: Vulkan forbids asking that of vkAllocateMemory (VUID-vkAllocateMemory-
    pAllocateInfo-01713, which the validation layer reports and keeps: every later check of
    the device failed), so it is refused here, as the driver would refuse a smaller excess."""
    from vkpbr.errors import OutOfDeviceMemoryError

    mp = device.memory_properties
    heap = int(mp.memoryHeaps[mp.memoryTypes[type_index].heapIndex].size)
    if size > heap:
        raise OutOfDeviceMemoryError("vkAllocateMemory", "VK_ERROR_OUT_OF_DEVICE_MEMORY",
                                     f"{size / 2**30:.1f} GiB asked of a heap of "
                                     f"{heap / 2**30:.1f} GiB (ask for smaller images or "
                                     "fewer views at once)")
