"""Command recording in the renderer's words: the only way `render/` writes a command buffer.

A `Commands` wraps one primary command buffer. Passes call `bind_pipeline`, `bind_sets`,
`draw_indexed`, ... and never see a Vulkan enum; this keeps every Vulkan call in `gpu/`
(style.md: "Vulkan vocabulary stays in gpu/"). Recording happens once per mode set (command
buffers are reused frame after frame), so these go through the binding's checked wrappers;
the per-frame hot path (submit, fences) lives in gpu/frames.py on raw entry points.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.device import Device

__all__ = ["Commands"]


class Commands:
    """One primary command buffer being recorded (or recorded, ready to submit)."""

    def __init__(self, device: Device) -> None:
        self.device = device
        self.vk = device.vk
        self.handle = device.allocate_command_buffer()
        self._layout: Any = None  # the pipeline layout of the last bound pipeline

    # --- lifetime ---------------------------------------------------------------------------
    def begin(self) -> Commands:
        self.vk.vkBeginCommandBuffer(self.handle, self.vk.VkCommandBufferBeginInfo())
        return self

    def end(self) -> None:
        self.vk.vkEndCommandBuffer(self.handle)

    def free(self) -> None:
        """Release the command buffer (the caller knows the GPU is done with it)."""
        if self.handle is not None:
            handle, self.handle = self.handle, None
            self.device.free_command_buffer(handle)

    # --- state ------------------------------------------------------------------------------
    def bind_pipeline(self, pipeline: Any) -> None:
        """Bind a gpu.pipeline.Pipeline; later `bind_sets`/`push` use its layout."""
        vk = self.vk
        vk.vkCmdBindPipeline(self.handle, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline.handle)
        self._layout = pipeline.layout.handle

    def bind_set(self, index: int, descriptor_set: Any) -> None:
        vk = self.vk
        vk.vkCmdBindDescriptorSets(self.handle, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self._layout,
                                   index, 1, [descriptor_set], 0, None)

    def bind_vertex_buffers(self, buffers: list[Buffer]) -> None:
        handles = [b.handle for b in buffers]
        self.vk.vkCmdBindVertexBuffers(self.handle, 0, len(handles), handles, [0] * len(handles))

    def bind_index_buffer(self, buffer: Buffer) -> None:
        self.vk.vkCmdBindIndexBuffer(self.handle, buffer.handle, 0, self.vk.VK_INDEX_TYPE_UINT32)

    def push(self, data: np.ndarray) -> None:
        """Push constants for the vertex and fragment stages, from offset 0."""
        vk = self.vk
        vk.vkCmdPushConstants(self.handle, self._layout,
                              vk.VK_SHADER_STAGE_VERTEX_BIT | vk.VK_SHADER_STAGE_FRAGMENT_BIT,
                              0, data.nbytes, vk.ffi.from_buffer(data))

    # --- draws ------------------------------------------------------------------------------
    def draw_indexed(self, index_count: int, first_index: int, vertex_offset: int,
                     first_instance: int = 0, instances: int = 1) -> None:
        """`instances` instances from `first_instance` (the shader's gl_InstanceIndex: a small
        per-draw index without a push constant, e.g. the shadow passes' matrix and layer)."""
        self.vk.vkCmdDrawIndexed(self.handle, index_count, instances, first_index, vertex_offset,
                                 first_instance)

    def draw_indirect(self, buffer: Buffer) -> None:
        """One VkDrawIndirectCommand at the start of `buffer`."""
        self.vk.vkCmdDrawIndirect(self.handle, buffer.handle, 0, 1, 16)

    # --- queries ----------------------------------------------------------------------------
    def reset_queries(self, pool: Any, first: int, count: int) -> None:
        self.vk.vkCmdResetQueryPool(self.handle, pool, first, count)

    def timestamp(self, pool: Any, query: int, after_all: bool = True) -> None:
        """Write a timestamp once all earlier commands finished (`after_all`), or at once."""
        vk = self.vk
        stage = (vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT if after_all
                 else vk.VK_PIPELINE_STAGE_2_NONE)
        vk.vkCmdWriteTimestamp2(self.handle, stage, pool, query)
