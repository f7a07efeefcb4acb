"""Draw a Renderer's scene (plus an overlay) into swapchain images, for the interactive viewer.

Per swapchain image this keeps a frame slot of its own (render/frames.py: uniform blocks,
the descriptor sets pointing at them), a pair of timestamp queries, and command buffers
recorded once per mode set (TBN path, alpha masking, blended-draw order) with the renderer's
own `record_draws` and pipelines, so a window frame shows exactly the bytes
`Renderer.render` returns. A frame's Python work is `write_uniforms` into the image's slot
and a dictionary lookup for the command buffer.

Why a slot per image: with two frames in flight the GPU may still read frame N's uniforms
while the CPU writes frame N+1's; an image's slot is rewritten only after that image's last
frame has finished (`Swapchain.acquire` waits for it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.swapchain import Swapchain
from vkpbr.gpu.text_overlay import QuadOverlay
from vkpbr.render import layouts as L
from vkpbr.render.frames import FrameSlot, create_slots
from vkpbr.render.options import RenderOptions
from vkpbr.render.renderer import Renderer
from vkpbr.scene.types import Camera, Light

__all__ = ["WindowRenderer"]


class WindowRenderer:
    """Per-image resources and recorded frames for `renderer` drawing into `swapchain`."""

    def __init__(self, renderer: Renderer, swapchain: Swapchain, overlay: QuadOverlay) -> None:
        self.renderer, self.swapchain, self.overlay = renderer, swapchain, overlay
        self.device = renderer.device
        renderer.build_pipelines(swapchain)  # every TBN path and pass, before any key press
        renderer.gpu_scene.ensure_streams()  # and every path's vertex stream
        self._generation = -1
        self._objects: list[Any] = []
        self._cmds: dict[tuple, tuple[Any, tuple]] = {}
        self._query_pool: Any = None
        self._queried: set[int] = set()
        ffi = self.device.vk.ffi
        self._stamps = ffi.new("uint64_t[2]")
        self._period_ms = float(self.device.limits.timestampPeriod) * 1e-6

    # --- per swapchain generation -----------------------------------------------------------
    def sync(self) -> None:
        """(Re)build per-image resources when the swapchain was recreated."""
        if self._generation == self.swapchain.generation:
            return
        self._free()
        dev, vk, r = self.device, self.device.vk, self.renderer
        n = len(self.swapchain.images)
        self.overlay.ensure_slots(n)
        ubo, pool, self._slots = create_slots(dev, r.set_layouts[0], r.set_layouts[2], n)
        self._objects += [ubo, pool]
        if dev.timestamps:
            self._query_pool = vk.vkCreateQueryPool(dev.handle, vk.VkQueryPoolCreateInfo(
                queryType=vk.VK_QUERY_TYPE_TIMESTAMP, queryCount=2 * n), None)
        self._generation = self.swapchain.generation

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    def _free(self) -> None:
        dev = self.device
        if self._cmds or self._objects or self._query_pool is not None:
            dev.wait_idle()
        for cmd, _ in self._cmds.values():
            dev.free_command_buffer(cmd)
        self._cmds.clear()
        while self._objects:
            self._objects.pop().destroy()
        if self._query_pool is not None:
            dev.vk.vkDestroyQueryPool(dev.handle, self._query_pool, None)
            self._query_pool = None
        self._queried.clear()

    # --- per frame --------------------------------------------------------------------------
    def write_uniforms(self, index: int, camera: Camera, light: Light,
                       options: RenderOptions) -> None:
        """`Renderer.write_uniforms` into image `index`'s slot (call after
        `Swapchain.acquire` returned `index`: its previous frame has finished)."""
        self.renderer.write_uniforms(camera, light, self.swapchain.extent, options, False,
                                     self._slots[index])

    def slot(self, index: int) -> FrameSlot:
        return self._slots[index]

    def gpu_ms(self, index: int) -> float:
        """GPU time of the last finished frame drawn into image `index` (NaN if unknown)."""
        if self._query_pool is None or index not in self._queried:
            return float("nan")
        vk = self.device.vk
        result = vk.lib.vkGetQueryPoolResults(self.device.handle, self._query_pool, 2 * index, 2,
                                              16, self._stamps, 8, vk.VK_QUERY_RESULT_64_BIT)
        if result != vk.VK_SUCCESS:
            return float("nan")
        return (self._stamps[1] - self._stamps[0]) * self._period_ms

    def command_buffer(self, index: int, tbn: L.TbnMode, alpha_mask: bool,
                       blend_order: tuple[int, ...] = ()) -> Any:
        """The command buffer drawing image `index` in these modes; recorded on first use."""
        key = (index, tbn, alpha_mask)
        hit = self._cmds.get(key)
        if hit is not None and hit[1] == blend_order:
            return hit[0]
        if hit is not None:  # blended draws were re-sorted: the old buffer may be pending
            self.swapchain.wait_frame(0)
            self.swapchain.wait_frame(1)
            self.device.free_command_buffer(hit[0])
        cmd = self.record(index, tbn, alpha_mask, blend_order)
        self._cmds[key] = (cmd, blend_order)
        return cmd

    def record(self, index: int, tbn: L.TbnMode, alpha_mask: bool,
               blend_order: tuple[int, ...] = (), screenshot: Buffer | None = None,
               with_overlay: bool = False) -> Any:
        """Record a frame for image `index`; with `screenshot`, the scene (without the
        overlay, unless `with_overlay`) is also copied into that host-visible buffer."""
        dev, vk, r, sc = self.device, self.device.vk, self.renderer, self.swapchain
        cmd = dev.allocate_command_buffer()
        vk.vkBeginCommandBuffer(cmd, vk.VkCommandBufferBeginInfo())
        if self._query_pool is not None:
            vk.vkCmdResetQueryPool(cmd, self._query_pool, 2 * index, 2)
            vk.vkCmdWriteTimestamp2(cmd, vk.VK_PIPELINE_STAGE_2_NONE, self._query_pool, 2 * index)
        sc.record_begin(cmd, index, (*r.background, 1.0))
        r.record_draws(cmd, sc, tbn, alpha_mask, self._slots[index], blend_order)
        if screenshot is not None and not with_overlay:
            vk.vkCmdEndRendering(cmd)
            sc.record_copy(cmd, index, screenshot)
            sc.record_begin(cmd, index, None, transition=False)
        self.overlay.record(cmd, index, sc.extent)
        if screenshot is not None and with_overlay:
            vk.vkCmdEndRendering(cmd)
            sc.record_copy(cmd, index, screenshot)
            sc.record_begin(cmd, index, None, transition=False)
        sc.record_end(cmd, index)
        if self._query_pool is not None:
            vk.vkCmdWriteTimestamp2(cmd, vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                                    self._query_pool, 2 * index + 1)
        vk.vkEndCommandBuffer(cmd)
        self._queried.add(index)
        return cmd

    def read_screenshot(self, buffer: Buffer) -> np.ndarray:
        """(H, W, 4) uint8 RGBA from a buffer filled by a screenshot frame (already waited)."""
        w, h = self.swapchain.extent
        px = buffer.array(np.uint8, w * h * 4).reshape(h, w, 4)
        if self.swapchain.color_format_name.startswith("B8G8R8A8"):
            return px[:, :, [2, 1, 0, 3]].copy()
        return px.copy()

    def screenshot_buffer(self) -> Buffer:
        vk = self.device.vk
        w, h = self.swapchain.extent
        return Buffer(self.device, w * h * 4, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                      host_visible=True, name="screenshot")

    def destroy(self) -> None:
        self._free()
