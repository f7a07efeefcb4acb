"""Offscreen render target: colour + D32 depth (optionally 4x MSAA, resolved), with
persistently mapped readback buffers so a frame reaches NumPy with one memcpy.

`record_begin` / `record_end` put the layout transitions, the dynamic-rendering begin/end and
the copies to the readback buffers into a command buffer that is recorded once and reused.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image, ImageView, pipeline_barrier

__all__ = ["RenderTarget", "COLOR_FORMATS"]

# Colour formats by name: "srgb" for display images, "float" for linear HDR values.
COLOR_FORMATS = {"srgb": ("VK_FORMAT_R8G8B8A8_SRGB", 4), "float": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16)}


class RenderTarget:
    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        color: str = "srgb",
        samples: int = 1,
        clear_color: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0),
    ) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height, self.samples = width, height, samples
        self.color_kind = color
        fmt_name, self.pixel_bytes = COLOR_FORMATS[color]
        self.color_format = getattr(vk, fmt_name)
        self.depth_format = vk.VK_FORMAT_D32_SFLOAT
        self.clear_color = clear_color
        self._objects: list[Any] = []
        usage_c = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        usage_d = (
            vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        )
        self.color = self._own(Image(device, width, height, self.color_format, usage_c))
        self.depth = self._own(Image(device, width, height, self.depth_format, usage_d))
        self.color_view = self._own(ImageView(self.color))
        self.depth_view = self._own(ImageView(self.depth, aspect="depth"))
        self.msaa_color = self.msaa_depth = None
        if samples > 1:
            transient = vk.VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT
            self.msaa_color = self._own(Image(
                device, width, height, self.color_format,
                vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | transient, samples=samples))
            self.msaa_depth = self._own(Image(
                device, width, height, self.depth_format,
                vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | transient, samples=samples))
            self.msaa_color_view = self._own(ImageView(self.msaa_color))
            self.msaa_depth_view = self._own(ImageView(self.msaa_depth, aspect="depth"))
        self._readbacks: dict[int, tuple[Buffer, Buffer]] = {}

    def readback(self, slot: int = 0) -> tuple[Buffer, Buffer]:
        """The (colour, depth) readback buffers of frame slot `slot`, made on first use: each
        frame in flight copies into its own pair, so reading one never races another."""
        if slot not in self._readbacks:
            vk = self.device.vk
            n = self.width * self.height
            usage = vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
            self._readbacks[slot] = (
                self._own(Buffer(self.device, n * self.pixel_bytes, usage, host_visible=True,
                                 name=f"color readback {slot}")),
                self._own(Buffer(self.device, n * 4, usage, host_visible=True,
                                 name=f"depth readback {slot}")),
            )
        return self._readbacks[slot]

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    # --- recording --------------------------------------------------------------------------
    def _image_barriers(self, to_attachment: bool) -> list[Any]:
        vk = self.device.vk
        out = []
        color_imgs = [self.color] + ([self.msaa_color] if self.msaa_color else [])
        depth_imgs = [self.depth] + ([self.msaa_depth] if self.msaa_depth else [])
        for img, is_depth in [(i, False) for i in color_imgs] + [(i, True) for i in depth_imgs]:
            aspect = vk.VK_IMAGE_ASPECT_DEPTH_BIT if is_depth else vk.VK_IMAGE_ASPECT_COLOR_BIT
            if is_depth:
                att_stage = (vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT
                             | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT)
                att_access = (vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
                              | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT)
                att_layout = vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL
            else:
                att_stage = vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT
                att_access = (vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT
                              | vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT)
                att_layout = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
            xfer = (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
            if to_attachment:
                # The previous frame's copy read this image: order that read before our writes.
                src, dst = xfer, (att_stage, att_access)
                old, new = vk.VK_IMAGE_LAYOUT_UNDEFINED, att_layout
            else:
                if img.samples > 1:
                    continue  # MSAA images are resolved, never copied
                src, dst = (att_stage, att_access), xfer
                old, new = att_layout, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
            out.append(vk.VkImageMemoryBarrier2(
                srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0],
                dstAccessMask=dst[1], oldLayout=old, newLayout=new,
                srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED, image=img.handle,
                subresourceRange=vk.VkImageSubresourceRange(
                    aspectMask=aspect, baseMipLevel=0, levelCount=1, baseArrayLayer=0,
                    layerCount=1),
            ))
        return out

    def record_begin(self, cmd: Any) -> None:
        """Transition the attachments, begin rendering (clear), set viewport and scissor."""
        vk = self.device.vk
        pipeline_barrier(vk, cmd, self._image_barriers(to_attachment=True))
        clear_c = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(self.clear_color)))
        clear_d = vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=1.0, stencil=0))
        store, dont = vk.VK_ATTACHMENT_STORE_OP_STORE, vk.VK_ATTACHMENT_STORE_OP_DONT_CARE
        if self.samples > 1:
            color_att = vk.VkRenderingAttachmentInfo(
                imageView=self.msaa_color_view.handle,
                imageLayout=vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                resolveMode=vk.VK_RESOLVE_MODE_AVERAGE_BIT,
                resolveImageView=self.color_view.handle,
                resolveImageLayout=vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR, storeOp=dont, clearValue=clear_c)
            depth_att = vk.VkRenderingAttachmentInfo(
                imageView=self.msaa_depth_view.handle,
                imageLayout=vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                resolveMode=vk.VK_RESOLVE_MODE_SAMPLE_ZERO_BIT,
                resolveImageView=self.depth_view.handle,
                resolveImageLayout=vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR, storeOp=dont, clearValue=clear_d)
        else:
            color_att = vk.VkRenderingAttachmentInfo(
                imageView=self.color_view.handle,
                imageLayout=vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR, storeOp=store, clearValue=clear_c)
            depth_att = vk.VkRenderingAttachmentInfo(
                imageView=self.depth_view.handle,
                imageLayout=vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR, storeOp=store, clearValue=clear_d)
        area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0),
                           extent=vk.VkExtent2D(self.width, self.height))
        vk.vkCmdBeginRendering(cmd, vk.VkRenderingInfo(
            renderArea=area, layerCount=1, pColorAttachments=[color_att],
            pDepthAttachment=depth_att))
        vk.vkCmdSetViewport(cmd, 0, 1, [vk.VkViewport(
            x=0, y=0, width=self.width, height=self.height, minDepth=0.0, maxDepth=1.0)])
        vk.vkCmdSetScissor(cmd, 0, 1, [area])

    def record_end(self, cmd: Any, slot: int = 0) -> None:
        """End rendering and copy colour and depth into slot `slot`'s mapped readback buffers."""
        vk = self.device.vk
        color_buf, depth_buf = self.readback(slot)
        vk.vkCmdEndRendering(cmd)
        pipeline_barrier(vk, cmd, self._image_barriers(to_attachment=False))
        extent = vk.VkExtent3D(width=self.width, height=self.height, depth=1)
        for img, buf, aspect in (
            (self.color, color_buf, vk.VK_IMAGE_ASPECT_COLOR_BIT),
            (self.depth, depth_buf, vk.VK_IMAGE_ASPECT_DEPTH_BIT),
        ):
            vk.vkCmdCopyImageToBuffer(
                cmd, img.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buf.handle, 1,
                [vk.VkBufferImageCopy(
                    bufferOffset=0,
                    imageSubresource=vk.VkImageSubresourceLayers(
                        aspectMask=aspect, mipLevel=0, baseArrayLayer=0, layerCount=1),
                    imageExtent=extent)])
        host = [
            vk.VkBufferMemoryBarrier2(
                srcStageMask=vk.VK_PIPELINE_STAGE_2_COPY_BIT,
                srcAccessMask=vk.VK_ACCESS_2_TRANSFER_WRITE_BIT,
                dstStageMask=vk.VK_PIPELINE_STAGE_2_HOST_BIT,
                dstAccessMask=vk.VK_ACCESS_2_HOST_READ_BIT,
                srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                buffer=buf.handle, offset=0, size=buf.size)
            for buf in (color_buf, depth_buf)
        ]
        pipeline_barrier(vk, cmd, [], host)

    # --- readback ---------------------------------------------------------------------------
    def read_color(self, slot: int = 0) -> np.ndarray:
        """A copy of slot `slot`'s last colour: (H, W, 4) uint8, or float32 for "float"."""
        dtype = np.uint8 if self.color_kind == "srgb" else np.float32
        n = self.width * self.height * 4
        return self.readback(slot)[0].array(dtype, n).reshape(self.height, self.width, 4).copy()

    def read_depth(self, slot: int = 0) -> np.ndarray:
        """A copy of slot `slot`'s last depth buffer: (H, W) float32 in [0, 1]."""
        n = self.width * self.height
        return self.readback(slot)[1].array(np.float32, n).reshape(self.height, self.width).copy()

    def destroy(self) -> None:
        while self._objects:
            self._objects.pop().destroy()
