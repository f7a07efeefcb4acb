"""A colour + depth pair drawn into, then mip-mapped and sampled in the same command buffer.

What a pass needs to give a later pass its image as a texture with a full mip chain (the
screen-space transmission's copy of the opaque scene: render/transmission.py). Mip 0 is
drawn with dynamic rendering (cleared), or on the compute path (a visibility image, level 0
written as storage, then the background drawn over it), the levels below made by linear
blits (`mip_step`), and the whole chain left SHADER_READ_ONLY for the fragment and compute shaders that
sample it. Like every frame target it offers `color_format`, `depth_format`, `samples` and
`extent`, so that pipelines are built for it the same way. Depth is cleared to 0
(reversed-Z).
"""

from __future__ import annotations

from typing import Any

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import ImageResource, Step
from vkpbr.gpu.image import Image, ImageView, Sampler, SamplerSpec, mip_levels
from vkpbr.gpu.rendering import Attachments

__all__ = ["MipmappedTarget"]


class MipmappedTarget:
    """`size` (W, H) colour of `color_format` (a VkFormat name that blits and filters
    linearly: RGBA16F) with its whole mip chain, and a D32 depth of the same size.
    `compute`: also drawn on the compute path (its visibility image, level 0 as storage)."""

    samples = 1
    outputs = None  # no dataset outputs (render/compute_path.py binds stand-ins)
    rasterised = False  # its visibility comes from the raster units, never the compute rasteriser

    def __init__(self, device: Device, size: tuple[int, int], color_format: str,
                 name: str = "", clear_color: tuple[float, ...] = (0.0, 0.0, 0.0, 1.0),
                 compute: bool = False) -> None:
        vk = device.vk
        w, h = size
        self.device, self.extent, self.clear_color = device, (w, h), clear_color
        self.color_format = getattr(vk, color_format)
        self.depth_format = vk.VK_FORMAT_D32_SFLOAT
        usage = (vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
                 | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
                 | (vk.VK_IMAGE_USAGE_STORAGE_BIT if compute else 0))
        self._owned: list[Any] = []
        self.color = self._own(Image(device, w, h, self.color_format, usage,
                                     mip_levels=mip_levels(w, h), name=name))
        self.view = self._own(ImageView(self.color))  # every level: what is sampled
        self._level0 = self._own(ImageView(self.color, mips=1))  # what is drawn into
        self.storage_view = self._level0 if compute else None  # what the compute path writes
        self.depth = self._own(Image(device, w, h, self.depth_format,
                                     vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                                     name=f"{name} depth"))
        self._depth_view = self._own(ImageView(self.depth, aspect="depth"))
        self.attachments = Attachments(self._level0.handle, self._depth_view.handle, self.extent)
        if compute:
            self.visibility = self._own(Image(
                device, w, h, vk.VK_FORMAT_R32G32_UINT,
                vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_STORAGE_BIT,
                name=f"{name} visibility"))
            self.visibility_view = self._own(ImageView(self.visibility))
        self.sampler = self._own(Sampler(device, SamplerSpec(wrap_u="clamp", wrap_v="clamp",
                                                             anisotropy=1.0)))

    def _own(self, obj: Any) -> Any:
        self._owned.append(obj)
        return obj

    def resources(self, prefix: str) -> dict[str, ImageResource]:
        """Its images as graph resources (gpu/graph.py), named `prefix` + "color" (level 0:
        what is drawn into; `mip_step` makes the rest), "depth", "ids" (its visibility image)."""
        size = self.extent
        out = {prefix + "color": ImageResource(self.color.handle, view=self.attachments.color,
                                               extent=size),
               prefix + "depth": ImageResource(self.depth.handle, depth=True,
                                               view=self.attachments.depth, extent=size)}
        if self.storage_view is not None:
            out[prefix + "ids"] = ImageResource(self.visibility.handle,
                                                view=self.visibility_view.handle, extent=size)
        return out

    def mip_step(self, name: str, prefix: str) -> Step:
        """A step making levels 1.. from level 0 (drawn as a colour attachment) and leaving
        the whole chain SHADER_READ_ONLY for the shaders that sample it (after the previous
        use's sampling of levels 1..)."""
        def record(cmd: Commands) -> None:
            cmd.blit_mips(self.color, "shader_read", "sampled",
                          level0=("color_attachment", "color"), last_read="sampled")

        # Its own barriers take level 0 from the drawing (the step before it) to the blits.
        return Step(name, record, leaves=((prefix + "color", "sampled"),))

    def destroy(self) -> None:
        while self._owned:
            self._owned.pop().destroy()
