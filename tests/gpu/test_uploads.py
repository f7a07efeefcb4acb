"""Uploads in few submissions. TextureUploader's batches (gpu/image.py): buffers of parts
(`add_buffer`: their bytes the parts' concatenation) and images; two staging buffers take turns, a batch copied
into one while the GPU uploads the other's. Every level of every image read back equals
what was given (level 0 of each, its chain then blitted), under the validation layer's
synchronization checks (a staging buffer reused before the GPU is done with it is a hazard)."""

from __future__ import annotations

import numpy as np

from vkpbr.gpu.buffer import Buffer, download_buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image, TextureUploader, mip_levels


def _read(device: Device, image: Image, level: int) -> np.ndarray:
    """Level `level` of an RGBA8 image in shader-read layout."""
    vk = device.vk
    w, h = max(image.width >> level, 1), max(image.height >> level, 1)
    dst = Buffer(device, w * h * 4, "transfer_dst", host_visible=True)
    try:
        with device.one_time_commands() as raw:
            cmd = Commands(device, raw)
            cmd.image_barrier(image, "shader_read", "transfer_src", "compute", "transfer", level, 1)
            vk.vkCmdCopyImageToBuffer(raw, image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                      dst.handle, 1, [vk.VkBufferImageCopy(
                                          bufferOffset=0,
                                          imageSubresource=vk.VkImageSubresourceLayers(
                                              aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT,
                                              mipLevel=level, baseArrayLayer=0, layerCount=1),
                                          imageExtent=vk.VkExtent3D(width=w, height=h, depth=1))])
            cmd.image_barrier(image, "transfer_src", "shader_read", "transfer", "compute", level, 1)
        return dst.array(np.uint8, w * h * 4).reshape(h, w, 4).copy()
    finally:
        dst.destroy()


def test_batches_take_turns_and_every_image_arrives() -> None:
    rng = np.random.default_rng(3)
    with Device(validation=True, sync_validation=True) as device:
        # Each image larger than half a batch: a batch each, so the two buffers take turns
        # (six batches), and the last, smaller one gets a buffer of its own size. Chains
        # blitted on the GPU (their images can be read back: transfer-source usage).
        uploader = TextureUploader(device, batch_bytes=2048)
        given = [rng.integers(0, 256, (size, size + 4, 4), np.uint8) for size in (16, 16, 20, 16, 16, 8)]
        images = [uploader.add(px, "unorm", name=f"t{k}") for k, px in enumerate(given)]
        assert len(uploader._in_flight) == 2  # batches went ahead without waiting
        uploader.flush()
        assert uploader._in_flight == [] and uploader._free == []
        for image, px in zip(images, given, strict=True):
            assert image.mip_levels == mip_levels(px.shape[1], px.shape[0])
            np.testing.assert_array_equal(_read(device, image, 0), px)
        for image in images:
            image.destroy()
        device.check_validation()


def test_buffers_ride_in_the_texture_batches() -> None:
    """TextureUploader.add_buffer (a scene's vertex streams, render/gpu_scene.py): parts of
    any dtype joined in one batch with images, one flush; under synchronization validation
    (the batch's barrier orders the copies before the download's read)."""
    rng = np.random.default_rng(6)
    parts = [[rng.random((7, 3), np.float32), rng.random((1, 3), np.float32)],
             [np.arange(5, dtype=np.uint32)], [rng.integers(0, 9, (3, 4), np.uint16)]]
    px = rng.integers(0, 256, (6, 5, 4), np.uint8)
    with Device(validation=True, sync_validation=True) as device:
        uploader = TextureUploader(device)
        made = [uploader.add_buffer(p, "storage|transfer_src", f"b{i}") for i, p in enumerate(parts)]
        image = uploader.add(px, "unorm", name="t")
        made.append(uploader.add_buffer([np.zeros(0, np.float32)], "vertex"))  # empty: no copy
        uploader.submit()
        assert len(uploader._in_flight) == 1 and uploader._pending == []
        uploader.flush()
        for buffer, p in zip(made, parts, strict=False):
            want = np.concatenate([a.reshape(-1).view(np.uint8) for a in p])
            np.testing.assert_array_equal(download_buffer(device, buffer)[: want.nbytes], want)
        np.testing.assert_array_equal(_read(device, image, 0), px)
        assert set(uploader.stats) == {"create", "copy", "record", "wait"}
        for obj in (*made, image):
            obj.destroy()
        device.check_validation()
