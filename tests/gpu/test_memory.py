"""Device memory kept for reuse (gpu/memory.py): a freed buffer's or image's allocation serves
the next one of its memory type and size class instead of a new vkAllocateMemory (NVIDIA's
cost ~0.25 ms each, and a scene change made ~60); what comes back works as new memory does,
at most KEPT_BYTES wait, exportable memory is never kept, and closing the device frees all;
one-time submissions reuse their fence (Device.take_fence)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from vkpbr.gpu.buffer import Buffer, upload_buffer
from vkpbr.gpu.device import Device, live_objects, live_objects_by_kind
from vkpbr.gpu.memory import (
    KEPT_BYTES,
    LARGER,
    MAX_RECYCLED,
    MOST_KEPT,
    PAGE,
    fitting_classes,
    kept_limit,
    size_class,
)


@contextlib.contextmanager
def validated() -> Iterator[Device]:
    """A device with the Khronos validation layer (and synchronization validation); any
    error it reported fails the test before the device closes."""
    with Device(validation=True, sync_validation=True) as dev:
        yield dev
        dev.check_validation()


@given(st.integers(1, 1 << 40))
def test_size_classes_hold_the_size_within_a_quarter_octave(size: int) -> None:
    c = size_class(size)
    assert c >= size and c % PAGE == 0
    assert c <= max(2 ** 0.25 * size * (1 + 1e-12), size) + PAGE
    assert size_class(c) == c  # (a class's own size is its class: a kept one fits it again)


def test_a_freed_allocation_serves_the_next_buffer_of_its_class() -> None:
    start = live_objects_by_kind().get("Memory", 0)
    with validated() as dev:
        mem = dev.memory
        a = Buffer(dev, 10_000, "storage", host_visible=True)
        first = a.memory
        a.write(np.arange(100, dtype=np.uint32))
        a.destroy()
        assert mem.kept_bytes == size_class(10_000)
        # another size of the same class, mapped the same way: the same memory, which works
        b = Buffer(dev, 9_000, "storage|transfer_src", host_visible=True)
        assert b.memory == first and mem.reused == 1 and mem.kept_bytes == 0
        assert b.array(np.uint8).size == 9_000  # (its own size, not the class's)
        b.write(np.full(9_000 // 4, 7, np.uint32))
        assert np.all(b.array(np.uint32) == 7)
        # device-local memory is another type: not served by a host-visible allocation
        b.destroy()
        c = upload_buffer(dev, np.arange(2_000, dtype=np.float32), "storage")
        assert c.memory != first
        c.destroy()
        assert live_objects_by_kind().get("Memory", 0) - start >= 2  # (kept, not freed)
    assert live_objects_by_kind().get("Memory", 0) == start  # close freed the kept ones


def test_exportable_and_huge_allocations_are_not_kept() -> None:
    with validated() as dev:
        big = Buffer(dev, MAX_RECYCLED + 1, "storage")
        big.destroy()
        assert dev.memory.kept_bytes == 0
        if dev.external_memory_fd:
            ex = Buffer(dev, 4096, "storage", exportable=True)
            ex.destroy()
            assert dev.memory.kept_bytes == 0


def test_at_most_the_limit_waits() -> None:
    start = live_objects()
    with validated() as dev:
        assert dev.memory.limit == kept_limit(dev._device_local_bytes()) >= KEPT_BYTES
        dev.memory.limit = 1 << 20
        sizes = [100_000 * (i + 1) for i in range(12)]  # (several classes, 6.6 MB in all)
        for b in [Buffer(dev, n, "storage") for n in sizes]:
            b.destroy()
        assert 0 < dev.memory.kept_bytes <= 1 << 20
        assert dev.memory.made == len(sizes) and dev.memory.reused == 0
    assert live_objects() == start


def test_beyond_the_limit_mapped_memory_is_kept_longest() -> None:
    """A scene change frees more device-local memory (textures) than the limit: the kept
    mapped allocations (an upload's staging buffers, the costliest to make) stay, the
    device-local ones are freed oldest first, and the mapped go only when nothing else is left."""
    with validated() as dev:
        dev.memory.limit = 1 << 20
        staging = Buffer(dev, 300_000, "transfer_src", host_visible=True)
        staging.destroy()  # (the oldest kept)
        for b in [Buffer(dev, 100_000 * (i + 1), "storage") for i in range(8)]:
            b.destroy()
        mapped = [alloc for key, alloc in dev.memory._kept.values() if key[2]]
        assert len(mapped) == 1 and dev.memory.kept_bytes <= 1 << 20
        again = Buffer(dev, 300_000, "transfer_src", host_visible=True)
        assert dev.memory.reused == 1, "the staging buffer's memory was not kept"
        again.destroy()
        for b in [Buffer(dev, 400_000, "transfer_src", host_visible=True) for _ in range(4)]:
            b.destroy()  # (mapped alone beyond the limit: the oldest of them go)
        assert dev.memory.kept_bytes <= 1 << 20


def test_one_time_submissions_reuse_their_fence_unsignalled() -> None:
    """Device.take_fence / give_fence: an upload's fence is reset and kept for the next (no
    vkCreateFence a submission: ~0.5 ms each on NVIDIA), and one taken is never signalled
    already (a wait on it would return before its submission ran)."""
    with validated() as dev:
        vk = dev.vk
        upload_buffer(dev, np.arange(64, dtype=np.float32), "storage").destroy()
        fences = live_objects_by_kind().get("Fence", 0)
        for n in range(3):
            data = np.arange(64, dtype=np.float32) + n
            buf = upload_buffer(dev, data, "storage|transfer_src")
            host = Buffer(dev, data.nbytes, "transfer_dst", host_visible=True)
            with dev.one_time_commands() as cmd:
                vk.vkCmdCopyBuffer(cmd, buf.handle, host.handle, 1,
                                   [vk.VkBufferCopy(srcOffset=0, dstOffset=0, size=data.nbytes)])
            np.testing.assert_array_equal(host.array(np.float32, 64), data)  # (it waited)
            buf.destroy()
            host.destroy()
        assert live_objects_by_kind().get("Fence", 0) == fences
        fence = dev.take_fence()
        assert vk.lib.vkGetFenceStatus(dev.handle, fence) == vk.VK_NOT_READY
        dev.give_fence(fence)


def test_a_kept_allocation_serves_smaller_requests_down_to_half_its_size() -> None:
    """A job's next scene asks for other sizes than the last freed: a kept allocation serves
    a request of up to LARGER classes below its own (at most half its size), the smallest
    kept one that holds it first, never a request it cannot hold."""
    with validated() as dev:
        mem = dev.memory
        big = Buffer(dev, 1 << 20, "storage")
        small = Buffer(dev, 300_000, "storage")
        big_memory, small_memory = big.memory, small.memory
        big.destroy()
        small.destroy()
        assert fitting_classes(1 << 20)[0] == 1 << 20 and len(fitting_classes(1 << 20)) == LARGER + 1
        got = Buffer(dev, 290_000, "storage")  # (both hold it: the smaller is taken)
        assert got.memory == small_memory and mem.reused == 1
        half = Buffer(dev, 500_000, "storage")  # (2^18.75 < n <= 2^19: four classes below)
        assert half.memory == big_memory and mem.reused == 2
        half.destroy()
        under = Buffer(dev, 440_000, "storage")  # (2^18.5 < n <= 2^18.75: five below: its own)
        assert under.memory != big_memory and mem.reused == 2
        over = Buffer(dev, (1 << 20) + 1, "storage")  # (larger than any kept)
        assert over.memory != big_memory and mem.reused == 2
        for b in (got, under, over):
            b.destroy()
        dev.check_validation()


def test_the_kept_limit_follows_the_device_memory_within_bounds() -> None:
    assert kept_limit(0) == kept_limit(4 << 30) == KEPT_BYTES  # (lavapipe, small GPUs)
    assert kept_limit(32 << 30) == 1 << 30
    assert kept_limit(141 << 30) == MOST_KEPT  # (the H200)


def test_an_image_larger_than_its_heap_is_refused_and_the_device_stays_valid() -> None:
    """An image whose memory exceeds the whole heap (render(size=(16384, 16384)) on lavapipe's
    2 GiB heap; found by hand): one OutOfDeviceMemoryError before vkAllocateMemory (which Vulkan
    forbids to ask for more than a heap: the validation layer's error had failed every later
    check of the device), the half-made image destroyed at once (its close had raised an
    AttributeError), and the device goes on (validated() checks it)."""
    import pytest

    from vkpbr.errors import OutOfDeviceMemoryError
    from vkpbr.gpu.image import Image

    with validated() as dev:
        vk = dev.vk
        mp = dev.memory_properties
        heap = max(int(mp.memoryHeaps[i].size) for i in range(mp.memoryHeapCount))
        layer = 16384 * 16384 * 16  # bytes of one RGBA32F layer
        before = live_objects_by_kind().get("Image", 0)
        with pytest.raises(OutOfDeviceMemoryError, match="VK_ERROR_OUT_OF_DEVICE_MEMORY"):
            Image(dev, 16384, 16384, vk.VK_FORMAT_R32G32B32A32_SFLOAT,
                  vk.VK_IMAGE_USAGE_SAMPLED_BIT, layers=heap // layer + 1)
        assert live_objects_by_kind().get("Image", 0) == before
        Buffer(dev, 1 << 20, "storage").destroy()  # (the device still makes things)
