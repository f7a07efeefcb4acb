"""Command recording in the renderer's words: the only way `render/` writes a command buffer.

A `Commands` wraps one primary command buffer. Passes call `bind_pipeline`, `bind_sets`,
`draw_indexed`, ... and never see a Vulkan enum; this keeps every Vulkan call in `gpu/`
(style.md: "Vulkan vocabulary stays in gpu/"). Recording happens once per mode set (command
buffers are reused frame after frame), but a recording is not rare: a walking camera's shadow
cascades redraw other layers and record a frame anew for each new set of layers (17 of 600
frames of bench_shadows' walk), and a first frame, a scene change and a batch of a new size
record too; the frame waits for it while the GPU's queue drains (7-10 ms a Sponza frame on
the H200, benchmarks/results/h200-2026-12-04s22.md). So the commands recorded most (binds,
push constants, dispatches, draws, fills, timestamps) call the C entry points through
`vulkan.lib` (vkCmd* return nothing: no error to translate), with the arguments the binding
would have converted made here once (0.5 us a call against 2.2 through the binding's
wrapper on lavapipe's host), and barriers are built with `ffi.new` (the binding's struct
constructors cost ~20 us each). The per-frame hot path (submit, fences) lives in
gpu/frames.py on raw entry points too.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.compute import LAYOUTS, stage_access
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import _barrier, pipeline_barrier

__all__ = ["Commands"]


class Commands:
    """One primary command buffer being recorded (or recorded, ready to submit)."""

    def __init__(self, device: Device, handle: Any = None) -> None:
        """`handle`: record into a command buffer someone else owns (e.g. one of
        `device.one_time_commands()`); `free()` then leaves it alone."""
        self.device = device
        self.vk = device.vk
        self.lib, self.ffi = device.vk.lib, device.vk.ffi
        self._set = self.ffi.new("VkDescriptorSet[1]")  # (copied by each call: reusable)
        self._owned = handle is None
        self.handle = device.allocate_command_buffer() if handle is None else handle
        self._layout: Any = None  # the pipeline layout of the last bound pipeline
        self._bind_point = device.vk.VK_PIPELINE_BIND_POINT_GRAPHICS
        self._push_stages = device.vk.VK_SHADER_STAGE_VERTEX_BIT | device.vk.VK_SHADER_STAGE_FRAGMENT_BIT

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
            if self._owned:
                self.device.free_command_buffer(handle)

    # --- state ------------------------------------------------------------------------------
    def bind_pipeline(self, pipeline: Any) -> None:
        """Bind a gpu.pipeline.Pipeline or a gpu.compute.ComputePipeline (its `bind_point`);
        later `bind_set`/`push` use its layout and bind point."""
        vk = self.vk
        compute = getattr(pipeline, "bind_point", "graphics") == "compute"
        self._bind_point = (vk.VK_PIPELINE_BIND_POINT_COMPUTE if compute
                            else vk.VK_PIPELINE_BIND_POINT_GRAPHICS)
        self.lib.vkCmdBindPipeline(self.handle, self._bind_point, pipeline.handle)
        self._layout = pipeline.layout.handle
        self._push_stages = getattr(pipeline.layout, "push_stages", self._push_stages)

    def bind_set(self, index: int, descriptor_set: Any) -> None:
        self._set[0] = descriptor_set
        self.lib.vkCmdBindDescriptorSets(self.handle, self._bind_point, self._layout,
                                         index, 1, self._set, 0, self.ffi.NULL)

    def bind_vertex_buffers(self, buffers: list[Buffer]) -> None:
        handles = [b.handle for b in buffers]
        self.vk.vkCmdBindVertexBuffers(self.handle, 0, len(handles), handles, [0] * len(handles))

    def bind_index_buffer(self, buffer: Buffer) -> None:
        self.lib.vkCmdBindIndexBuffer(self.handle, buffer.handle, 0, self.vk.VK_INDEX_TYPE_UINT32)

    def push(self, data: np.ndarray) -> None:
        """Push constants for the bound pipeline layout's stages, from offset 0."""
        self.lib.vkCmdPushConstants(self.handle, self._layout, self._push_stages,
                                    0, data.nbytes, self.ffi.from_buffer(data))

    # --- draws ------------------------------------------------------------------------------
    def draw_indexed(self, index_count: int, first_index: int, vertex_offset: int,
                     first_instance: int = 0, instances: int = 1) -> None:
        """`instances` instances from `first_instance` (the shader's gl_InstanceIndex: a small
        per-draw index without a push constant, e.g. the shadow passes' matrix and layer)."""
        self.lib.vkCmdDrawIndexed(self.handle, index_count, instances, first_index, vertex_offset,
                                  first_instance)

    def draw_indirect(self, buffer: Buffer) -> None:
        """One VkDrawIndirectCommand at the start of `buffer`."""
        self.lib.vkCmdDrawIndirect(self.handle, buffer.handle, 0, 1, 16)

    def draw_indexed_indirect(self, buffer: Buffer, offset: int) -> None:
        """One VkDrawIndexedIndirectCommand (20 bytes) at `offset` of `buffer` (GPU-written)."""
        self.lib.vkCmdDrawIndexedIndirect(self.handle, buffer.handle, offset, 1, 20)

    def draw(self, vertex_count: int, first_vertex: int = 0, instances: int = 1,
             first_instance: int = 0) -> None:
        """Non-indexed draw without vertex buffers (a fullscreen triangle: 3)."""
        self.lib.vkCmdDraw(self.handle, vertex_count, instances, first_vertex, first_instance)

    # --- compute ----------------------------------------------------------------------------
    def dispatch(self, x: int, y: int = 1, z: int = 1) -> None:
        self.lib.vkCmdDispatch(self.handle, x, y, z)

    def dispatch_indirect(self, buffer: Buffer, offset: int = 0) -> None:
        """A dispatch whose group counts are 3 uint32 at `offset` of `buffer` (GPU-written)."""
        self.lib.vkCmdDispatchIndirect(self.handle, buffer.handle, offset)

    def fill(self, buffer: Buffer, value: int = 0, offset: int = 0, size: int | None = None) -> None:
        """Set every uint32 of `buffer` (or of `size` bytes from `offset`) to `value` (a
        transfer write)."""
        self.lib.vkCmdFillBuffer(self.handle, buffer.handle, offset,
                                 buffer.size - offset if size is None else size, value)

    def memory_barrier(self, src: str, dst: str) -> None:
        """A global memory dependency from stages `src` to `dst`, each "|"-joined words of
        "transfer", "compute" (storage reads and writes), "indirect" (dispatch sizes, draws),
        "vertex" (storage reads in vertex shaders), "fragment" (storage reads in fragment
        shaders), "vertex_input" (vertex buffers)."""
        vk = self.vk
        stages = {
            "transfer": (vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT),
            "compute": (vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                        vk.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | vk.VK_ACCESS_2_SHADER_STORAGE_READ_BIT),
            "indirect": (vk.VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                         vk.VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT),
            # Storage buffers read by vertex shaders (a batch's lists of visible views).
            "vertex": (vk.VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT,
                       vk.VK_ACCESS_2_SHADER_STORAGE_READ_BIT),
            # Storage buffers read by fragment shaders (a batch of worlds' shadow maps).
            "fragment": (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                         vk.VK_ACCESS_2_SHADER_STORAGE_READ_BIT),
            # Vertex buffers read by draws (streams a compute kernel wrote).
            "vertex_input": (vk.VK_PIPELINE_STAGE_2_VERTEX_ATTRIBUTE_INPUT_BIT,
                             vk.VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT),
        }

        def mask(words: str) -> tuple[int, int]:
            st = ac = 0
            for w in words.split("|"):
                st, ac = st | stages[w][0], ac | stages[w][1]
            return st, ac

        (ss, sa), (ds, da) = mask(src), mask(dst)
        barrier = self.ffi.new("VkMemoryBarrier2*", {
            "sType": vk.VK_STRUCTURE_TYPE_MEMORY_BARRIER_2, "srcStageMask": ss,
            "srcAccessMask": sa, "dstStageMask": ds, "dstAccessMask": da})
        self.lib.vkCmdPipelineBarrier2(self.handle, self.ffi.new("VkDependencyInfo*", {
            "sType": vk.VK_STRUCTURE_TYPE_DEPENDENCY_INFO, "memoryBarrierCount": 1,
            "pMemoryBarriers": barrier}))

    def image_barrier(self, image: Any, old: str, new: str, src: str, dst: str,
                      base_mip: int = 0, mips: int | None = None) -> None:
        """A layout transition and memory dependency on mips [base_mip, base_mip + mips) of
        every layer. Layouts: "undefined", "general", "shader_read", "transfer_src",
        "transfer_dst", "color_attachment"; stages: "none", "compute", "fragment", "sampled" (fragment +
        compute shaders), "transfer", "color" (gpu.compute)."""
        vk = self.vk
        n = image.mip_levels - base_mip if mips is None else mips
        pipeline_barrier(vk, self.handle, [_barrier(
            vk, image, getattr(vk, LAYOUTS[old]), getattr(vk, LAYOUTS[new]),
            stage_access(vk, src), stage_access(vk, dst), base_mip, n,
            getattr(image, "layers", 1))])

    def blit_mips(self, image: Any, final: str = "shader_read", dst_stage: str = "sampled",
                  level0: tuple[str, str] = ("general", "compute"),
                  last_read: str = "none") -> None:
        """Make levels 1.. of every layer by linear blits from level 0, which is in layout
        level0[0] after writes in stage level0[1] (GENERAL after compute writes, by default);
        leaves the whole chain in `final`. `last_read`: the stage that last read levels 1..
        (an image remade every frame: its previous frame's sampling), ordered before the blits."""
        vk = self.vk
        layers = getattr(image, "layers", 1)
        self.image_barrier(image, level0[0], "transfer_src", level0[1], "transfer", 0, 1)
        if image.mip_levels > 1:
            self.image_barrier(image, "undefined", "transfer_dst", last_read, "transfer", 1)
        w, h = image.width, image.height
        for level in range(1, image.mip_levels):
            nw, nh = max(w // 2, 1), max(h // 2, 1)
            vk.vkCmdBlitImage(
                self.handle, image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                [vk.VkImageBlit(
                    srcSubresource=vk.VkImageSubresourceLayers(
                        aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=level - 1,
                        baseArrayLayer=0, layerCount=layers),
                    srcOffsets=[vk.VkOffset3D(0, 0, 0), vk.VkOffset3D(w, h, 1)],
                    dstSubresource=vk.VkImageSubresourceLayers(
                        aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=level,
                        baseArrayLayer=0, layerCount=layers),
                    dstOffsets=[vk.VkOffset3D(0, 0, 0), vk.VkOffset3D(nw, nh, 1)],
                )],
                vk.VK_FILTER_LINEAR,
            )
            self.image_barrier(image, "transfer_dst", "transfer_src", "transfer", "transfer",
                               level, 1)
            w, h = nw, nh
        self.image_barrier(image, "transfer_src", final, "transfer", dst_stage)

    # --- queries ----------------------------------------------------------------------------
    def reset_queries(self, pool: Any, first: int, count: int) -> None:
        self.lib.vkCmdResetQueryPool(self.handle, pool, first, count)

    def timestamp(self, pool: Any, query: int, after_all: bool = True) -> None:
        """Write a timestamp once all earlier commands finished (`after_all`), or at once."""
        vk = self.vk
        stage = (vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT if after_all
                 else vk.VK_PIPELINE_STAGE_2_NONE)
        self.lib.vkCmdWriteTimestamp2(self.handle, stage, pool, query)
