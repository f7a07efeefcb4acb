"""Buffers: device-local with staging upload, or host-visible and persistently mapped.

Host-visible buffers stay mapped for their whole life: per-frame uniform updates and readbacks
are then a NumPy copy into or out of `Buffer.array(...)`, with no Vulkan call at all.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.device import Device
from vkpbr.gpu.memory import Allocation, check_heap

__all__ = ["Buffer", "upload_buffer"]


_USAGES = {
    "vertex": "VK_BUFFER_USAGE_VERTEX_BUFFER_BIT", "index": "VK_BUFFER_USAGE_INDEX_BUFFER_BIT",
    "uniform": "VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT", "storage": "VK_BUFFER_USAGE_STORAGE_BUFFER_BIT",
    "indirect": "VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT",
    "transfer_src": "VK_BUFFER_USAGE_TRANSFER_SRC_BIT", "transfer_dst": "VK_BUFFER_USAGE_TRANSFER_DST_BIT",
}


def _OPAQUE_FD(vk: Any) -> int:  # noqa: N802 - a Vulkan constant's name
    return vk.VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT


def buffer_usage(vk: Any, usage: int | str) -> int:
    """VkBufferUsageFlags from flags or from names ("vertex", "index", "uniform", "storage",
    "indirect", "transfer_src", "transfer_dst"; several joined by "|"), so that layers above
    gpu/ say what a buffer is for without Vulkan's vocabulary."""
    if isinstance(usage, int):
        return usage
    flags = 0
    for name in usage.split("|"):
        flags |= getattr(vk, _USAGES[name.strip()])
    return flags


class Buffer:
    """One VkBuffer with a VkDeviceMemory of its own (from the device's kept ones:
    gpu/memory.py; an exportable buffer's its own alone).
    `usage`: VkBufferUsageFlags or names (see `buffer_usage`)."""

    def __init__(
        self,
        device: Device,
        size: int,
        usage: int | str,
        host_visible: bool = False,
        name: str = "",
        exportable: bool = False,
        device_local: bool = False,
    ) -> None:
        """`exportable`: its memory can be handed to another API as a POSIX file descriptor
        (`export_fd`; VK_KHR_external_memory_fd: CUDA imports it, gpu/cuda.py).
        `device_local` (with `host_visible`): prefer memory that is both (the GPU reads it
        often, the host writes it), else plain host-visible memory."""
        vk = device.vk
        usage = buffer_usage(vk, usage)
        self.device = device
        self.size = max(int(size), 4)
        self.name = name
        self.host_visible = host_visible
        self._mapped: Any = None
        self.memory = None
        self.handle = vk.vkCreateBuffer(
            device.handle,
            vk.VkBufferCreateInfo(
                pNext=vk.VkExternalMemoryBufferCreateInfo(handleTypes=_OPAQUE_FD(vk))
                if exportable else None,
                size=self.size, usage=usage, sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE
            ),
            None,
        )
        device.track(self)
        req = vk.vkGetBufferMemoryRequirements(device.handle, self.handle)
        if host_visible:
            required = (
                vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | vk.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
            )
            # Cached memory makes CPU reads of readback buffers fast on discrete GPUs.
            preferred = required | (vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT if device_local
                                    else vk.VK_MEMORY_PROPERTY_HOST_CACHED_BIT)
        else:
            required = preferred = vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
        mtype = device.memory_type(req.memoryTypeBits, required, preferred)
        self.allocation_size = int(req.size)
        self._alloc: Allocation | None = None  # memory from (and back to) device.memory
        if exportable:  # (its own: the allocation carries the export)
            check_heap(device, int(req.size), mtype)
            self.memory = vk.vkAllocateMemory(device.handle, vk.VkMemoryAllocateInfo(
                pNext=vk.VkExportMemoryAllocateInfo(handleTypes=_OPAQUE_FD(vk)),
                allocationSize=req.size, memoryTypeIndex=mtype), None)
            if host_visible:
                self._mapped = vk.vkMapMemory(device.handle, self.memory, 0, self.size, 0)
        else:
            self._alloc = device.memory.allocate(int(req.size), mtype, host_visible)
            self.memory = self._alloc.memory
            if host_visible:  # (the allocation is mapped whole, for its life)
                self._mapped = memoryview(self._alloc.mapped)[:self.size]
        vk.vkBindBufferMemory(device.handle, self.handle, self.memory, 0)

    def export_fd(self) -> int:
        """A new file descriptor of the buffer's memory (an `exportable` buffer); the caller
        owns it (CUDA's import takes ownership)."""
        vk = self.device.vk
        get_fd = vk.vkGetDeviceProcAddr(self.device.handle, "vkGetMemoryFdKHR")
        return int(get_fd(self.device.handle, vk.VkMemoryGetFdInfoKHR(
            memory=self.memory, handleType=_OPAQUE_FD(vk))))

    def array(self, dtype: Any = np.uint8, count: int = -1, offset: int = 0) -> np.ndarray:
        """A zero-copy NumPy view of the mapped memory (host-visible buffers only).

        The view dangles once the buffer is destroyed: do not keep it beyond that.
        """
        if self._mapped is None:
            raise RuntimeError(f"buffer {self.name!r} is not host-visible")
        return np.frombuffer(self._mapped, dtype=dtype, count=count, offset=offset)

    def write(self, data: np.ndarray | bytes, offset: int = 0) -> None:
        """Copy bytes into a mapped buffer."""
        src = np.frombuffer(memoryview(data).cast("B"), dtype=np.uint8)
        self.array(np.uint8, len(src), offset)[:] = src

    def destroy(self) -> None:
        if self.handle is None:
            return
        vk = self.device.vk
        dev = self.device.handle
        handle, self.handle = self.handle, None
        alloc, self._alloc = self._alloc, None
        if self._mapped is not None:
            if alloc is None:  # (else the allocation stays mapped for its next buffer)
                vk.vkUnmapMemory(dev, self.memory)
            self._mapped = None
        vk.vkDestroyBuffer(dev, handle, None)
        if alloc is not None:
            self.device.memory.release(alloc)
        elif self.memory is not None:
            vk.vkFreeMemory(dev, self.memory, None)
        self.memory = None
        self.device.untrack(self)


def upload_buffer(device: Device, data: np.ndarray, usage: int | str, name: str = "") -> Buffer:
    """A device-local buffer filled with `data` through a temporary staging buffer."""
    vk = device.vk
    usage = buffer_usage(vk, usage)
    data = np.ascontiguousarray(data)
    dst = Buffer(device, data.nbytes, usage | vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, name=name)
    if data.nbytes == 0:
        return dst
    staging = Buffer(
        device, data.nbytes, vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, host_visible=True
    )
    try:
        staging.write(data)
        with device.one_time_commands() as cmd:
            vk.vkCmdCopyBuffer(
                cmd, staging.handle, dst.handle, 1, [vk.VkBufferCopy(size=data.nbytes)]
            )
    finally:
        staging.destroy()
    return dst


def download_buffer(device: Device, buffer: Buffer, dtype: Any = np.uint8) -> np.ndarray:
    """A copy of a device-local buffer's contents (`buffer` made with "transfer_src"), read
    after the work submitted so far: for tests and diagnostics, not for frames."""
    vk = device.vk
    staging = Buffer(device, buffer.size, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, host_visible=True,
                     name=f"{buffer.name} download")
    try:
        with device.one_time_commands() as cmd:
            # The writes of earlier submissions (compute or transfer) before this copy's read
            # (a raw barrier: gpu/commands.py imports this module).
            vk.vkCmdPipelineBarrier(
                cmd, vk.VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, vk.VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                1, [vk.VkMemoryBarrier(srcAccessMask=vk.VK_ACCESS_MEMORY_WRITE_BIT,
                                       dstAccessMask=vk.VK_ACCESS_TRANSFER_READ_BIT)],
                0, None, 0, None)
            vk.vkCmdCopyBuffer(cmd, buffer.handle, staging.handle, 1,
                               [vk.VkBufferCopy(size=buffer.size)])
        return staging.array(dtype).copy()
    finally:
        staging.destroy()
