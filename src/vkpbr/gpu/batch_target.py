"""The batch target: many views of one size drawn in one submission (render/batch.py).

A `BatchTarget` is a colour + D32 depth pair of 2D-array images, `layers` deep: one layer a
view, drawn by layered rendering (the vertex shader writes gl_Layer). A batch larger than
`layers` is drawn a chunk of `layers` views at a time into the same images, each chunk
copied out into its place in one persistently mapped readback buffer of `capacity` views,
so a whole batch comes back with one fence wait and one host copy. Depth is cleared to 0
(reversed-Z), as in OffscreenTarget, whose formats it shares: pipelines built for one serve
the other.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import BufferResource, ImageResource, Step
from vkpbr.gpu.image import Image, ImageView
from vkpbr.gpu.rendering import Attachments, barriers, copy_image_to_buffer, external_ownership
from vkpbr.gpu.target import COLOR_FORMATS, copy_out

__all__ = ["BatchTarget"]


class BatchTarget:
    """`layers` views of `size` = (width, height) per chunk, read back `capacity` at a time.

    color : "srgb" (8-bit sRGB-encoded) or "float" (linear float32), as OffscreenTarget.
    depth : also copy the depth of every view out (Renderer.render_batch(depth=True)).
    external : the colour goes into device-local memory exported as a file descriptor
        (`color_readback.export_fd()`, for CUDA: gpu/cuda.py) instead of host memory; the
        batch hands it to the external queue family at its end and takes it back at its
        start.
    """

    generation = 0  # never recreated
    samples = 1
    depth_sampled = True

    def __init__(self, device: Device, size: tuple[int, int], layers: int, capacity: int,
                 color: str = "srgb", depth: bool = False,
                 clear_color: tuple[float, float, float, float] = (0, 0, 0, 1),
                 external: bool = False) -> None:
        vk = device.vk
        self.device, self.clear_color = device, clear_color
        self.extent = (int(size[0]), int(size[1]))
        self.layers, self.capacity, self.color_kind = int(layers), int(capacity), color
        w, h = self.extent
        fmt_name, self.pixel_bytes = COLOR_FORMATS[color]
        self.color_format = getattr(vk, fmt_name)
        self.depth_format = vk.VK_FORMAT_D32_SFLOAT
        self._objects: list[Any] = []
        src = vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        self.color = self._own(Image(device, w, h, self.color_format,
                                     vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | src,
                                     layers=self.layers, name="batch color"))
        # (sampled: ambient occlusion reads each view's layer, render/ao.py)
        self.depth = self._own(Image(device, w, h, self.depth_format,
                                     vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | src
                                     | vk.VK_IMAGE_USAGE_SAMPLED_BIT,
                                     layers=self.layers, name="batch depth"))
        color_view = self._own(ImageView(self.color, kind="2d_array"))
        depth_view = self._own(ImageView(self.depth, aspect="depth", kind="2d_array"))
        self.attachments = Attachments(color_view.handle, depth_view.handle, self.extent)
        usage = vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
        self.external = external
        self.color_readback = self._own(Buffer(device, self.capacity * w * h * self.pixel_bytes,
                                               usage, host_visible=not external,
                                               name="batch color readback", exportable=external))
        self.depth_readback = self._own(Buffer(device, self.capacity * w * h * 4, usage,
                                               host_visible=True, name="batch depth readback")
                                        ) if depth else None

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    stores_depth = True

    def resources(self, image: int = 0, frame_index: int = 0
                  ) -> dict[str, ImageResource | BufferResource]:
        """Its images ("color", "depth": every layer) and readback buffers as graph
        resources (gpu/graph.py). The external colour buffer is not one: its steps hand it
        between queue families themselves."""
        out: dict[str, ImageResource | BufferResource] = {
            "color": ImageResource(self.color.handle, layers=self.layers,
                                   view=self.attachments.color, copied=True),
            "depth": ImageResource(self.depth.handle, depth=True, layers=self.layers,
                                   view=self.attachments.depth, copied=True)}
        if not self.external:
            out["color_readback"] = BufferResource(self.color_readback, copied=True)
        if self.depth_readback is not None:
            out["depth_readback"] = BufferResource(self.depth_readback, copied=True)
        return out

    def chunk_copy_step(self, name: str, chunk: int, views: int, timed: bool) -> Step:
        """A step copying the chunk's first `views` layers into their place in the readback
        buffers (views chunk * layers on); an external colour buffer is taken back from the
        external queue family first (CUDA read the last batch)."""
        w, h = self.extent
        wanted = [(self.color, False, self.color_readback, self.pixel_bytes)]
        if self.depth_readback is not None:
            wanted.append((self.depth, True, self.depth_readback, 4))

        def record(cmd: Commands) -> None:
            if self.external and chunk == 0:
                barriers(cmd, [], [self._ownership(external_to_ours=True)])
            for img, depth, buf, nbytes in wanted:
                copy_image_to_buffer(cmd, img.handle, depth, buf, self.extent, layers=views,
                                     offset=chunk * self.layers * w * h * nbytes)

        uses = [("color", "transfer_src")]
        if self.depth_readback is not None:
            uses.append(("depth", "transfer_src"))
        uses += [(n, "transfer_dst") for n in ("color_readback", "depth_readback")
                 if n in self.resources()]
        return Step(name, record, tuple(uses), timed=timed)

    def finish_steps(self, image: int, frame_index: int, copy: tuple[str, ...]) -> list[Step]:
        """The frame's last step: the chunks' copies (chunk_copy_step) made visible."""
        return [self.readback_step()]

    def readback_step(self) -> Step:
        """Every chunk's copy made visible to the host once the fence is waited (an external
        colour buffer: released to the external queue family, for CUDA)."""
        def record(cmd: Commands) -> None:
            if self.external:
                barriers(cmd, [], [self._ownership(external_to_ours=False)])

        names = [n for n in ("color_readback", "depth_readback") if n in self.resources()]
        return Step("readback", record, tuple((n, "host_read") for n in names), timed=False)

    def _ownership(self, external_to_ours: bool) -> Any:
        return external_ownership(self.device.vk, self.device.queue_family, self.color_readback,
                                  external_to_ours)

    def read_color(self, views: int, into: np.ndarray | None = None) -> np.ndarray:
        """A copy of the first `views` views: (views, H, W, 4) uint8 or float32, written into
        `into` where given (an array of that shape and type: no new pages to fault in)."""
        dtype = np.uint8 if self.color_kind == "srgb" else np.float32
        w, h = self.extent
        return copy_out(self.color_readback.array(dtype, views * w * h * 4).reshape(views, h, w, 4),
                        into)

    def read_depth(self, views: int) -> np.ndarray:
        """A copy of the first `views` views' window depth: (views, H, W) float32."""
        w, h = self.extent
        assert self.depth_readback is not None, "made without depth"
        return copy_out(self.depth_readback.array(np.float32, views * w * h).reshape(views, h, w))

    def destroy(self) -> None:
        while self._objects:
            self._objects.pop().destroy()
