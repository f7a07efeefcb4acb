"""Textured, coloured quads drawn over a frame: the GPU half of the viewer's HUD.

One alpha-blended pipeline (shaders/hud.vert, hud.frag), one atlas texture, and per slot (one
per frame in flight) a host-visible vertex buffer plus a VkDrawIndirectCommand. The vertex
count lives in the indirect buffer, so a command buffer recorded once keeps drawing whatever
text the CPU last wrote into the slot: changing the text re-records nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import ImageView, Sampler, SamplerSpec, TextureUploader
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream

__all__ = ["QuadOverlay", "VERTEX_FLOATS"]

VERTEX_FLOATS = 8  # x, y (pixels), u, v, r, g, b, a (linear)


class QuadOverlay:
    """Draws up to `max_vertices` vertices (6 per quad) of `VERTEX_FLOATS` floats.

    Parameters
    ----------
    atlas : (H, W, 4) uint8 RGBA; the fragment shader uses R as coverage.
    color_format, depth_format : the attachments it draws into (no depth test or write).
    shader_dir : folder of hud.vert.spv / hud.frag.spv.
    """

    def __init__(self, device: Device, atlas: np.ndarray, color_format: int, depth_format: int,
                 shader_dir: Any, max_vertices: int = 6 * 4096) -> None:
        vk = device.vk
        self.device, self.max_vertices = device, max_vertices
        self._objects: list[Any] = []
        uploader = TextureUploader(device)
        image = uploader.add(atlas, vk.VK_FORMAT_R8G8B8A8_UNORM, mipmaps=False, name="hud atlas")
        uploader.flush()
        self._objects.append(image)
        view = self._own(ImageView(image))
        sampler = self._own(Sampler(device, SamplerSpec(
            wrap_u="clamp", wrap_v="clamp", mag="nearest", min="nearest", mipmaps=False,
            anisotropy=1.0)))
        self.set_layout = self._own(DescriptorSetLayout(
            device, [BindingSpec(0, "sampler", ("fragment",), "atlas")]))
        self.layout = self._own(PipelineLayout(device, [self.set_layout], 16))
        pool = self._own(DescriptorPool(device, [(self.set_layout, 1)]))
        self.set = pool.allocate(self.set_layout)
        w = DescriptorWriter(device)
        w.sampler(self.set, 0, view, sampler)
        w.update()
        spec = PipelineSpec(
            vertex_shader="hud.vert.spv", fragment_shader="hud.frag.spv",
            streams=(VertexStream(0, 0, "vec4"), VertexStream(1, 1, "vec4")),
            color_format=color_format, depth_format=depth_format, cull="none",
            depth_test=False, depth_write=False, blend=True)
        self.pipeline = self._own(Pipeline(device, spec, self.layout, shader_dir))
        self._slots: list[tuple[Buffer, Buffer, np.ndarray, np.ndarray, np.ndarray]] = []

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    def ensure_slots(self, n: int) -> None:
        """Have at least `n` slots (one per swapchain image)."""
        vk = self.device.vk
        while len(self._slots) < n:
            m = self.max_vertices
            vbuf = self._own(Buffer(self.device, m * 32, vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
                                    host_visible=True, name="hud vertices"))
            ibuf = self._own(Buffer(self.device, 16, vk.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                                    host_visible=True, name="hud draw"))
            draw = ibuf.array(np.uint32, 4)
            draw[:] = (0, 1, 0, 0)  # vertexCount, instanceCount, firstVertex, firstInstance
            pos = vbuf.array(np.float32, 4 * m).reshape(m, 4)
            col = vbuf.array(np.float32, 4 * m, 16 * m).reshape(m, 4)
            self._slots.append((vbuf, ibuf, pos, col, draw))

    def write(self, slot: int, vertices: np.ndarray) -> None:
        """Copy (N, 8) float32 vertices into `slot` (N is clipped to `max_vertices`). Call only
        when the GPU is not reading the slot (its frame's fence has been waited)."""
        _, _, pos, col, draw = self._slots[slot]
        n = min(len(vertices) // 6 * 6, self.max_vertices)
        pos[:n] = vertices[:n, :4]
        col[:n] = vertices[:n, 4:]
        draw[0] = n

    def record(self, cmd: Commands, slot: int, size: tuple[int, int]) -> None:
        """Draw `slot`'s quads inside a dynamic rendering over an attachment of `size`."""
        vbuf, ibuf = self._slots[slot][:2]
        cmd.bind_pipeline(self.pipeline)
        cmd.bind_set(0, self.set)
        cmd.push(np.array([2.0 / size[0], 2.0 / size[1], -1.0, -1.0], dtype=np.float32))
        handles = [vbuf.handle, vbuf.handle]
        cmd.vk.vkCmdBindVertexBuffers(cmd.handle, 0, 2, handles, [0, 16 * self.max_vertices])
        cmd.draw_indirect(ibuf)

    def destroy(self) -> None:
        while self._objects:
            self._objects.pop().destroy()
        self._slots.clear()
