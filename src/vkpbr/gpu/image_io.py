"""Float images to and from NumPy: half-float RGBA uploads and read-backs of any level/layers.

Used for HDR environments (uploads of panoramas, read-backs of pre-filtered cubes for tests
and the cache). The format is RGBA16F: linear filtering, blits and storage use of it are
required of every Vulkan implementation (unlike RGBA32F's linear filtering).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image

__all__ = ["HALF_MAX", "rgba16f_format", "upload_rgba16f", "read_rgba16f"]

HALF_MAX = 65504.0  # the largest finite half float: brighter pixels are clamped to it


def rgba16f_format(device: Device) -> int:
    return device.vk.VK_FORMAT_R16G16B16A16_SFLOAT


def upload_rgba16f(device: Device, pixels: np.ndarray, usage: int = 0, name: str = "",
                   layers: int = 1, cube: bool = False) -> Image:
    """A sampled RGBA16F image (one level) in the shader-read layout, filled from `pixels`.

    Parameters
    ----------
    pixels : (H, W, 3|4) or (layers, H, W, 3|4) float; alpha 1 when absent; values clamped to
        [-HALF_MAX, HALF_MAX].
    usage : extra VkImageUsageFlags (sampled and transfer src/dst are always set).
    """
    vk = device.vk
    a = np.asarray(pixels, dtype=np.float32)
    if a.ndim == 3:
        a = a[None]
    n, h, w, c = a.shape
    rgba = np.ones((n, h, w, 4), np.float16)
    rgba[..., :c] = np.clip(a, -HALF_MAX, HALF_MAX)
    image = Image(device, w, h, rgba16f_format(device),
                  usage | vk.VK_IMAGE_USAGE_SAMPLED_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
                  | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT,  # read_rgba16f can read it back
                  name=name, layers=n, cube=cube)
    staging = Buffer(device, rgba.nbytes, "transfer_src", host_visible=True)
    try:
        staging.write(rgba)
        with device.one_time_commands() as raw:
            cmd = Commands(device, raw)
            cmd.image_barrier(image, "undefined", "transfer_dst", "none", "transfer")
            vk.vkCmdCopyBufferToImage(raw, staging.handle, image.handle,
                                      vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                                      [_region(vk, 0, n, w, h)])
            cmd.image_barrier(image, "transfer_dst", "shader_read", "transfer", "sampled")
    finally:
        staging.destroy()
    return image


def _region(vk: Any, level: int, layers: int, w: int, h: int) -> Any:
    return vk.VkBufferImageCopy(
        bufferOffset=0,
        imageSubresource=vk.VkImageSubresourceLayers(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=level, baseArrayLayer=0,
            layerCount=layers),
        imageExtent=vk.VkExtent3D(width=w, height=h, depth=1),
    )


def read_rgba16f(device: Device, image: Image, level: int = 0,
                 layout: str = "shader_read") -> np.ndarray:
    """Level `level` of every layer of an RGBA16F image (which is in `layout` and stays so).

    Returns
    -------
    (layers, h, w, 4) float32, h = max(H >> level, 1), w likewise.
    """
    return read_level(device, image, level, layout).astype(np.float32)


def read_level(device: Device, image: Image, level: int = 0, layout: str = "shader_read",
               dtype: Any = np.float16, channels: int = 4) -> np.ndarray:
    """Level `level` of every layer of an image of `channels` components of `dtype` (which
    is in `layout` and stays so; made with the transfer-source usage), as (layers, h, w,
    channels) `dtype`, h = max(H >> level, 1), w likewise."""
    vk = device.vk
    w, h = max(image.width >> level, 1), max(image.height >> level, 1)
    n = getattr(image, "layers", 1)
    count = n * w * h * channels
    dst = Buffer(device, count * np.dtype(dtype).itemsize, "transfer_dst", host_visible=True)
    try:
        with device.one_time_commands() as raw:
            cmd = Commands(device, raw)
            cmd.image_barrier(image, layout, "transfer_src", "compute", "transfer", level, 1)
            vk.vkCmdCopyImageToBuffer(raw, image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                      dst.handle, 1, [_region(vk, level, n, w, h)])
            cmd.image_barrier(image, "transfer_src", layout, "transfer", "compute", level, 1)
        out = dst.array(dtype, count).reshape(n, h, w, channels).copy()
    finally:
        dst.destroy()
    return out
