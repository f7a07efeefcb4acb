"""Frames in flight: each slot owns its uniform blocks (views into one mapped buffer), the
descriptor sets that point at them, and two timestamp queries, so several frames can be
queued on the GPU at once while Python prepares the next."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.descriptors import DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.render import layouts as L

__all__ = ["FrameSlot", "FrameStats", "create_slots"]

FRAME_BLOCKS = (L.CAMERA, L.SETTINGS, L.LIGHT)


@dataclass
class FrameStats:
    cpu_ms: float = 0.0  # Python-side: uniforms + submit (excludes the wait)
    wait_ms: float = 0.0  # waiting for the GPU
    gpu_ms: float = float("nan")  # timestamp queries around the frame's commands
    readback_ms: float = 0.0  # copying the mapped image into NumPy


@dataclass
class FrameSlot:
    index: int
    set0: Any  # camera + settings
    set2: Any  # light
    # Zero-copy byte views of the blocks in the mapped uniform buffer, written by the
    # blocks' struct packers (layouts.Std140Block.packer).
    m_camera: memoryview
    m_settings: memoryview
    m_light: memoryview
    query_base: int  # first of this slot's two timestamp queries
    uniform_key: tuple | None = None  # inputs of the uniforms last written here
    stats: FrameStats = field(default_factory=FrameStats)


def create_slots(
    device: Device, set0_layout: DescriptorSetLayout, set2_layout: DescriptorSetLayout, count: int
) -> tuple[Buffer, DescriptorPool, list[FrameSlot]]:
    """One host-visible uniform buffer holding `count` copies of the frame blocks, a pool,
    and the slots. The caller owns (and destroys) the buffer and the pool via the device."""
    vk = device.vk
    align = int(device.limits.minUniformBufferOffsetAlignment)
    offsets, offset = [], 0
    for block in FRAME_BLOCKS:
        offsets.append(offset)
        offset += (block.size + align - 1) // align * align
    stride = offset
    buffer = Buffer(device, stride * count, vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                    host_visible=True, name="frame uniforms")
    pool = DescriptorPool(device, [(set0_layout, count), (set2_layout, count)])
    writer = DescriptorWriter(device)
    slots = []
    for i in range(count):
        base = i * stride
        cam, settings, light = (base + o for o in offsets)
        set0, set2 = pool.allocate(set0_layout), pool.allocate(set2_layout)
        writer.uniform(set0, 0, buffer, L.CAMERA.size, cam)
        writer.uniform(set0, 1, buffer, L.SETTINGS.size, settings)
        writer.uniform(set2, 0, buffer, L.LIGHT.size, light)
        slots.append(FrameSlot(
            index=i, set0=set0, set2=set2,
            m_camera=memoryview(buffer.array(np.uint8, L.CAMERA.size, cam)),
            m_settings=memoryview(buffer.array(np.uint8, L.SETTINGS.size, settings)),
            m_light=memoryview(buffer.array(np.uint8, L.LIGHT.size, light)),
            query_base=2 * i,
        ))
    writer.update()
    return buffer, pool, slots
