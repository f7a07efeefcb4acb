"""Layered depth images: a 2D array or a cube array of depth maps, drawn a range of layers at
a time (layered rendering: the vertex shader writes gl_Layer) and sampled with depth comparison (shadow maps).

`LayeredDepth` owns the image, one sampled view of all its layers ("2d_array" or
"cube_array"), a 2D-array attachment view per drawn layer range, and the barriers around a
frame's drawing: every layer goes UNDEFINED -> depth attachment before the passes (the old
contents are never read: each frame redraws every layer it samples) and back to
shader-read-only after, the layout the descriptors name. Between frames in flight on one
queue, the first barrier also orders this frame's writes after the previous frame's reads.
"""

from __future__ import annotations

import contextlib
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image, ImageView
from vkpbr.gpu.rendering import (
    barriers,
    begin_depth_rendering,
    end_rendering,
    host_read_barrier,
    image_barrier,
)

__all__ = ["LayeredDepth"]


class LayeredDepth:
    """A (layers, size, size) D32_SFLOAT image; `cube`: a cube array (layers = 6 * cubes).

    Parameters
    ----------
    device : the device.
    size : width = height of each layer, in texels.
    layers : array layers (a multiple of 6 for a cube array).
    cube : sample it as a cube-map array (needs the device's imageCubeArray).
    readable : also usable as a copy source (`read`, for tests).
    """

    def __init__(self, device: Device, size: int, layers: int, cube: bool = False,
                 readable: bool = False, name: str = "") -> None:
        vk = device.vk
        if cube and layers % 6:
            raise ValueError(f"cube array {name!r}: {layers} layers is not a multiple of 6")
        self.device, self.size, self.layers, self.cube = device, int(size), int(layers), cube
        self.format = vk.VK_FORMAT_D32_SFLOAT
        # (transfer destination: compute-drawn maps are copied in, record_copy)
        usage = (vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
                 | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT)
        if readable:
            usage |= vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        self.image = Image(device, self.size, self.size, self.format, usage, name=name,
                           layers=self.layers, cube=cube)
        self.view = ImageView(self.image, aspect="depth",
                              kind="cube_array" if cube else "2d_array")
        # Every layer as a 2D array (a cube's faces one by one): shaders that pick the face
        # themselves gather from it (shaders/shadow_sampling.glsl compare_cube).
        self.faces = ImageView(self.image, aspect="depth", kind="2d_array") if cube else self.view
        self._attachments: dict[tuple[int, int], ImageView] = {}
        # The device's for its life (render/shadow_images.py): its views made later are too.
        self.kept = False
        # Hardware 2x2 PCF needs linear filtering of the depth format (NVIDIA, lavapipe: yes).
        self.filterable = device.format_supports(self.format, "SAMPLED_IMAGE_FILTER_LINEAR")
        with device.one_time_commands() as handle:  # the layout descriptors name, from the start
            barriers(Commands(device, handle), [self._barrier(
                vk.VK_IMAGE_LAYOUT_UNDEFINED, vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                (vk.VK_PIPELINE_STAGE_2_NONE, vk.VK_ACCESS_2_NONE),
                (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT
                 | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                 vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT))])

    def _barrier(self, old: int, new: int, src: tuple[int, int], dst: tuple[int, int]) -> Any:
        return image_barrier(self.device.vk, self.image.handle, True, old, new, src, dst,
                             layers=self.layers)

    def attachment(self, base: int, count: int) -> ImageView:
        """A 2D-array view of layers [base, base + count), to draw them in one rendering."""
        key = (base, count)
        if key not in self._attachments:
            if base < 0 or count < 1 or base + count > self.layers:
                raise ValueError(f"layers {base}..{base + count - 1} outside 0..{self.layers - 1}")
            with self.device.keeping() if self.kept else contextlib.nullcontext():
                self._attachments[key] = ImageView(self.image, aspect="depth", kind="2d_array",
                                                   base_layer=base, layer_count=count)
        return self._attachments[key]

    # --- recording ---------------------------------------------------------------------------
    def record_begin_writes(self, cmd: Commands, keep: bool = False) -> None:
        """Before this frame's passes: every layer becomes a depth attachment, after earlier
        submissions' shader reads; `keep`: the layers this frame does not draw keep their
        contents (otherwise every layer's are discarded)."""
        vk = cmd.vk
        old = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL if keep else vk.VK_IMAGE_LAYOUT_UNDEFINED
        stages = (vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT
                  | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT)
        access = (vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
                  | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT)
        barriers(cmd, [self._barrier(
            old, vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
            (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
             | stages, vk.VK_ACCESS_2_NONE),
            (stages, access))])

    def begin(self, cmd: Commands, base: int, count: int) -> None:
        """Begin drawing layers [base, base + count) at once (gl_Layer 0 is `base`), cleared
        to depth 0 (the farthest under reversed-Z)."""
        begin_depth_rendering(cmd, self.attachment(base, count).handle, (self.size, self.size),
                              layers=count, clear_depth=0.0)

    def end(self, cmd: Commands) -> None:
        end_rendering(cmd)

    def record_end_writes(self, cmd: Commands) -> None:
        """After this frame's passes: every layer readable by the fragment shaders."""
        vk = cmd.vk
        barriers(cmd, [self._barrier(
            vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
            vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
            (vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT
             | vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
             vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT),
            (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT
                | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT))])

    def record_copy(self, cmd: Commands, buffer: Any, regions: list[tuple[int, int, int]]) -> None:
        """Copy depths drawn elsewhere (float32, layer after layer, rows of `size` texels) from
        `buffer` into layers of the image: `regions` (byte offset in the buffer, first layer,
        layers). The other layers keep their contents; every layer is left readable by the
        fragment and compute shaders, as after `record_end_writes`."""
        vk = cmd.vk
        sampled = (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT
                   | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT)
        ro, dst = (vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                   vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL)
        copy = (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT)
        barriers(cmd, [self._barrier(ro, dst, (sampled, vk.VK_ACCESS_2_NONE), copy)])
        vk.vkCmdCopyBufferToImage(cmd.handle, buffer.handle, self.image.handle, dst, len(regions), [
            vk.VkBufferImageCopy(
                bufferOffset=offset, imageSubresource=vk.VkImageSubresourceLayers(
                    aspectMask=vk.VK_IMAGE_ASPECT_DEPTH_BIT, mipLevel=0, baseArrayLayer=first,
                    layerCount=count),
                imageExtent=vk.VkExtent3D(width=self.size, height=self.size, depth=1))
            for offset, first, count in regions])
        barriers(cmd, [self._barrier(dst, ro, copy, (sampled, vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT))])

    # --- readback (tests, debugging) -----------------------------------------------------------
    def read(self) -> np.ndarray:
        """Every layer's depth: (layers, size, size) float32. Waits for the device to idle;
        the image must have been made `readable`."""
        device, vk = self.device, self.device.vk
        device.wait_idle()
        n = self.size * self.size
        buf = Buffer(device, n * 4 * self.layers, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                     host_visible=True, name="layered depth readback")
        ro, src = (vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                   vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)
        frag = (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT
                | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT)
        xfer = (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
        try:
            with device.one_time_commands() as handle:
                cmd = Commands(device, handle)

                def barrier(old: int, new: int, a: tuple, b: tuple) -> None:
                    barriers(cmd, [self._barrier(old, new, a, b)])
                barrier(ro, src, frag, xfer)
                vk.vkCmdCopyImageToBuffer(handle, self.image.handle, src, buf.handle, 1, [
                    vk.VkBufferImageCopy(
                        bufferOffset=0, imageSubresource=vk.VkImageSubresourceLayers(
                            aspectMask=vk.VK_IMAGE_ASPECT_DEPTH_BIT, mipLevel=0,
                            baseArrayLayer=0, layerCount=self.layers),
                        imageExtent=vk.VkExtent3D(width=self.size, height=self.size, depth=1))])
                barrier(src, ro, xfer, frag)
                barriers(cmd, [], [host_read_barrier(vk, buf)])
            return buf.array(np.float32, n * self.layers).reshape(
                self.layers, self.size, self.size).copy()
        finally:
            buf.destroy()

    def destroy(self) -> None:
        for view in self._attachments.values():
            view.destroy()
        self._attachments.clear()
        if self.faces is not self.view:
            self.faces.destroy()
        self.view.destroy()
        self.image.destroy()
