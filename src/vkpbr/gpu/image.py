"""Images, image views (with component swizzles), samplers, and texture upload with mips.

Textures are uploaded in batches: many images share one command buffer and one of two
bounded staging buffers (one filled while the GPU reads the other). An image whose mip chain was made beforehand (a baked file's, vkpbr.scene.mips) is
copied level by level; otherwise its chain is made by successive linear blits on the GPU.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.copy_threads import pool
from vkpbr.gpu.device import Device, DeviceObject, before_later_commands

__all__ = ["Image", "ImageView", "Sampler", "SamplerSpec", "mip_levels", "TextureUploader"]


def mip_levels(width: int, height: int) -> int:
    return int(max(width, height)).bit_length()


# VK_IMAGE_CREATE_EXTENDED_USAGE_BIT (core in Vulkan 1.1): the binding has only the KHR alias,
# whose value it leaves as None.
_EXTENDED_USAGE = 0x00000100


class Image:
    """A 2D VkImage with dedicated memory; `layers` > 1 makes an array, `cube` (layers a
    multiple of 6) lets cube views see it."""

    def __init__(
        self,
        device: Device,
        width: int,
        height: int,
        format: int,
        usage: int,
        mip_levels: int = 1,
        samples: int = 1,
        name: str = "",
        layers: int = 1,
        cube: bool = False,
        mutable: bool = False,
    ) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height, self.format = width, height, format
        self.mip_levels, self.samples, self.name = mip_levels, samples, name
        self.layers, self.cube = layers, cube
        self.memory = None
        self.handle = vk.vkCreateImage(
            device.handle,
            vk.VkImageCreateInfo(
                # mutable: views of another format of the same size (a UNORM storage view of
                # an sRGB image), with usages only such views support.
                flags=(vk.VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT if cube else 0)
                | (vk.VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT | _EXTENDED_USAGE if mutable else 0),
                imageType=vk.VK_IMAGE_TYPE_2D,
                format=format,
                extent=vk.VkExtent3D(width=width, height=height, depth=1),
                mipLevels=mip_levels,
                arrayLayers=layers,
                samples=samples,
                tiling=vk.VK_IMAGE_TILING_OPTIMAL,
                usage=usage,
                sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
            ),
            None,
        )
        device.track(self)
        req = vk.vkGetImageMemoryRequirements(device.handle, self.handle)
        mtype = device.memory_type(req.memoryTypeBits, vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)
        self.bytes = int(req.size)
        self._alloc: Any = None
        try:  # (no memory for it: the image goes now, not half-made at the device's close)
            self._alloc = device.memory.allocate(int(req.size), mtype, False)  # (gpu/memory.py)
            self.memory = self._alloc.memory
            vk.vkBindImageMemory(device.handle, self.handle, self.memory, 0)
        except BaseException:
            self.destroy()
            raise

    def destroy(self) -> None:
        if self.handle is None:
            return
        vk, dev = self.device.vk, self.device.handle
        handle, self.handle = self.handle, None
        vk.vkDestroyImage(dev, handle, None)
        if self._alloc is not None:
            self.device.memory.release(self._alloc)
            self._alloc = None
        self.memory = None
        self.device.untrack(self)


class ImageView(DeviceObject):
    """A view of an image; `swizzle` maps (r, g, b, a) to source channels, e.g. "bbbb" makes
    a scalar map out of the blue channel (glTF metalness) without copying the image.

    `kind` is "2d" (layer `base_layer`), "2d_array", "cube" or "cube_array" over `layer_count`
    layers from `base_layer` (None: all the image's layers from there); `base_mip` and `mips`
    (None: the rest of the chain) pick levels, e.g. one level for a storage view."""

    _destroy_fn = "vkDestroyImageView"

    _SWZ = {"r": "R", "g": "G", "b": "B", "a": "A", "1": "ONE", "0": "ZERO", "i": "IDENTITY"}

    def __init__(
        self,
        image: Image,
        aspect: str = "color",
        swizzle: str = "iiii",
        format: int | None = None,
        kind: str = "2d",
        base_mip: int = 0,
        mips: int | None = None,
        base_layer: int = 0,
        layer_count: int | None = None,
        usage: int | None = None,
    ) -> None:
        device = image.device
        vk = device.vk
        self.device = device
        self.image = image
        comps = [getattr(vk, f"VK_COMPONENT_SWIZZLE_{self._SWZ[c]}") for c in swizzle]
        aspect_bit = (
            vk.VK_IMAGE_ASPECT_DEPTH_BIT if aspect == "depth" else vk.VK_IMAGE_ASPECT_COLOR_BIT
        )
        view_type = {"2d": vk.VK_IMAGE_VIEW_TYPE_2D, "2d_array": vk.VK_IMAGE_VIEW_TYPE_2D_ARRAY,
                     "cube": vk.VK_IMAGE_VIEW_TYPE_CUBE,
                     "cube_array": vk.VK_IMAGE_VIEW_TYPE_CUBE_ARRAY}[kind]
        if layer_count is not None:
            layers = layer_count
        else:
            layers = 1 if kind == "2d" else getattr(image, "layers", 1) - base_layer
        self.kind = kind
        self.handle = vk.vkCreateImageView(
            device.handle,
            vk.VkImageViewCreateInfo(
                # `usage`: what this view is used for, a subset of the image's (a mutable
                # image's sRGB view must not claim the storage usage of its UNORM view).
                pNext=None if usage is None else vk.VkImageViewUsageCreateInfo(usage=usage),
                image=image.handle,
                viewType=view_type,
                format=image.format if format is None else format,
                components=vk.VkComponentMapping(*comps),
                subresourceRange=vk.VkImageSubresourceRange(
                    aspectMask=aspect_bit,
                    baseMipLevel=base_mip,
                    levelCount=image.mip_levels - base_mip if mips is None else mips,
                    baseArrayLayer=base_layer,
                    layerCount=layers,
                ),
            ),
            None,
        )
        device.track(self)



@dataclass(frozen=True)
class SamplerSpec:
    """Sampler state in plain words (the scene layer's Sampler maps onto this)."""

    wrap_u: str = "repeat"  # repeat | clamp | mirror | border (transparent black: 0)
    wrap_v: str = "repeat"
    mag: str = "linear"  # linear | nearest
    min: str = "linear"
    mipmaps: bool = True
    anisotropy: float = 16.0  # clamped to the device limit; 1 disables
    # Depth comparison (shadow maps): None, or the op as in "greater_or_equal"; a sample is
    # then 1 where `ref OP stored` holds, filtered (2x2 PCF) when linear.
    compare: str | None = None


class Sampler(DeviceObject):
    _destroy_fn = "vkDestroySampler"

    _WRAP = {"repeat": "REPEAT", "clamp": "CLAMP_TO_EDGE", "mirror": "MIRRORED_REPEAT",
             "border": "CLAMP_TO_BORDER"}

    def __init__(self, device: Device, spec: SamplerSpec = SamplerSpec()) -> None:
        vk = device.vk
        self.device = device
        aniso = min(spec.anisotropy, float(device.limits.maxSamplerAnisotropy))
        use_aniso = device.anisotropy and aniso > 1.0 and spec.mipmaps
        filt = {"linear": vk.VK_FILTER_LINEAR, "nearest": vk.VK_FILTER_NEAREST}
        nearest = spec.mag == spec.min == "nearest" and not spec.mipmaps
        self.handle = self._kept_handle(spec, lambda: vk.vkCreateSampler(
            device.handle,
            vk.VkSamplerCreateInfo(
                magFilter=filt[spec.mag],
                minFilter=filt[spec.min],
                # Nearest throughout for a point sampler without mips (a depth texture read
                # by texelFetch: D32 need not filter linearly).
                mipmapMode=vk.VK_SAMPLER_MIPMAP_MODE_NEAREST if nearest
                else vk.VK_SAMPLER_MIPMAP_MODE_LINEAR,
                addressModeU=getattr(vk, f"VK_SAMPLER_ADDRESS_MODE_{self._WRAP[spec.wrap_u]}"),
                addressModeV=getattr(vk, f"VK_SAMPLER_ADDRESS_MODE_{self._WRAP[spec.wrap_v]}"),
                addressModeW=vk.VK_SAMPLER_ADDRESS_MODE_REPEAT,
                anisotropyEnable=vk.VK_TRUE if use_aniso else vk.VK_FALSE,
                maxAnisotropy=aniso if use_aniso else 1.0,
                compareEnable=vk.VK_TRUE if spec.compare else vk.VK_FALSE,
                compareOp=getattr(vk, f"VK_COMPARE_OP_{(spec.compare or 'never').upper()}"),
                minLod=0.0,
                maxLod=1000.0 if spec.mipmaps else 0.0,
                # A compare sampler's border is depth 0: the farthest depth under reversed-Z.
                borderColor=vk.VK_BORDER_COLOR_FLOAT_TRANSPARENT_BLACK if spec.compare
                else vk.VK_BORDER_COLOR_FLOAT_OPAQUE_BLACK,
            ),
            None,
        ))
        device.track(self)



def _aligned(nbytes: int) -> int:
    """A staging slot's size: copies from a buffer start at multiples of the texel block."""
    return -(-nbytes // 16) * 16


def _slot_bytes(target: Image | Buffer, arrays: list[np.ndarray]) -> int:
    """Staging bytes of one queued upload: an image's levels each aligned, a buffer's parts
    joined (TextureUploader._copy_in)."""
    if isinstance(target, Buffer):
        return _aligned(sum(a.nbytes for a in arrays))
    return sum(_aligned(a.nbytes) for a in arrays)


def _barrier(vk: Any, image: Image, old: int, new: int, src: tuple, dst: tuple,
             base_mip: int = 0, mips: int = 1, layers: int = 1) -> Any:
    return vk.VkImageMemoryBarrier2(
        srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
        oldLayout=old, newLayout=new,
        srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
        dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
        image=image.handle,
        subresourceRange=vk.VkImageSubresourceRange(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=base_mip, levelCount=mips,
            baseArrayLayer=0, layerCount=layers,
        ),
    )


def pipeline_barrier(vk: Any, cmd: Any, image_barriers: list, buffer_barriers: list = ()) -> None:
    vk.vkCmdPipelineBarrier2(
        cmd,
        vk.VkDependencyInfo(
            pImageMemoryBarriers=list(image_barriers) or None,
            imageMemoryBarrierCount=len(image_barriers),
            pBufferMemoryBarriers=list(buffer_barriers) or None,
            bufferMemoryBarrierCount=len(buffer_barriers),
        ),
    )


# A batch at least this large is copied into the staging buffer on threads (a scene's 64 MiB
# batches: one thread's memcpy of them was a share of Sponza's texture upload).
_PARALLEL_COPY_BYTES = 16 << 20


class TextureUploader:
    """Uploads RGBA8 images with full mip chains (and BC7 ones with theirs: `add_blocks`),
    batching many into one submission; buffers too (`add_buffer`: a scene's vertex streams
    ride in the textures' first batch, so a scene's upload waits once, at `flush`).

    Staging memory is bounded by twice `batch_bytes`: when a batch would exceed it, the batch
    is submitted and the next one copied into a second staging buffer while the GPU uploads
    it (the two take turns); `flush` waits for them all.
    """

    def __init__(self, device: Device, batch_bytes: int = 64 << 20) -> None:
        self.device = device
        self.batch_bytes = batch_bytes
        self._pending: list[tuple[Image | Buffer, list[np.ndarray]]] = []
        self._pending_bytes = 0
        # Seconds in each part of the upload (benchmarks/bench_load.py): creating images and
        # buffers, copying into staging memory (with its allocation), recording and
        # submitting, waiting for the GPU.
        self.stats = {"create": 0.0, "copy": 0.0, "record": 0.0, "wait": 0.0}
        # Staging buffers: free ones, and (command buffer, fence, buffer) of submitted batches
        # not yet waited for (at most two: see _staging_for).
        self._free: list[Buffer] = []
        self._in_flight: list[tuple[Any, Any, Buffer]] = []

    def add(self, pixels: np.ndarray, format: int | str, mipmaps: bool = True, name: str = "",
            mips: Sequence[np.ndarray] = ()) -> Image:
        """Queue one image for upload (sent by `flush`, or earlier when the batch is full).

        Parameters
        ----------
        pixels : (H, W, 4) uint8, level 0.
        format : "srgb" or "unorm" (8-bit RGBA), or a VkFormat.
        mipmaps : give the image a full mip chain; ignored when `mips` are given.
        mips : levels 1.. of a full chain made beforehand (vkpbr.scene.mips), each
            (max(H >> k, 1), max(W >> k, 1), 4) uint8: copied as they are, no blits.
        """
        vk = self.device.vk
        if isinstance(format, str):
            format = {"srgb": vk.VK_FORMAT_R8G8B8A8_SRGB, "unorm": vk.VK_FORMAT_R8G8B8A8_UNORM}[format]
        levels_data = [np.ascontiguousarray(a, dtype=np.uint8) for a in (pixels, *mips)]
        h, w = levels_data[0].shape[:2]
        if mips:
            levels = mip_levels(w, h)
            shapes = [(max(h >> k, 1), max(w >> k, 1), 4) for k in range(levels)]
            if [a.shape for a in levels_data] != shapes:
                raise ValueError(f"texture {name!r}: mips are not the full chain below {w}x{h}")
        else:
            levels = mip_levels(w, h) if mipmaps else 1
        usage = vk.VK_IMAGE_USAGE_SAMPLED_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
        if levels > len(levels_data):  # the blits read the level above
            usage |= vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        t = time.perf_counter()
        image = Image(self.device, w, h, format, usage, mip_levels=levels, name=name)
        self.stats["create"] += time.perf_counter() - t
        nbytes = sum(a.nbytes for a in levels_data)
        if self._pending_bytes + nbytes > self.batch_bytes:
            self._submit()
        self._pending.append((image, levels_data))
        self._pending_bytes += nbytes
        return image

    def add_blocks(self, levels: Sequence[np.ndarray], size: tuple[int, int], format: str,
                   name: str = "") -> Image:
        """Queue a BC7 image with its whole mip chain (vkpbr.scene.gltf_codecs.ktx2_blocks):
        `levels` (blocks high, blocks wide, 16) uint8 each, largest first, of a `size` (W, H)
        image; `format` "srgb" or "unorm". Only where `Device.bc7_textures`."""
        vk = self.device.vk
        w, h = size
        if len(levels) != mip_levels(w, h):
            raise ValueError(f"texture {name!r}: {len(levels)} block levels, not the full chain below {w}x{h}")
        fmt = {"srgb": vk.VK_FORMAT_BC7_SRGB_BLOCK, "unorm": vk.VK_FORMAT_BC7_UNORM_BLOCK}[format]
        image = Image(self.device, w, h, fmt, vk.VK_IMAGE_USAGE_SAMPLED_BIT
                      | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT, mip_levels=len(levels), name=name)
        data = [np.ascontiguousarray(a, dtype=np.uint8) for a in levels]
        nbytes = sum(_aligned(a.nbytes) for a in data)
        if self._pending_bytes + nbytes > self.batch_bytes:
            self._submit()
        self._pending.append((image, data))
        self._pending_bytes += nbytes
        return image

    def add_buffer(self, parts: Sequence[np.ndarray], usage: int | str, name: str = "") -> Buffer:
        """A device-local buffer of `usage` (gpu.buffer.buffer_usage) holding `parts` one after
        another (their concatenation, each copied once into the staging memory), queued like
        an image; readable by any command submitted after `flush` (or after this batch)."""
        from vkpbr.gpu.buffer import buffer_usage

        vk = self.device.vk
        data = [np.ascontiguousarray(a) for a in parts]
        nbytes = sum(a.nbytes for a in data)
        t = time.perf_counter()
        buffer = Buffer(self.device, nbytes, buffer_usage(vk, usage)
                        | vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, name=name)
        self.stats["create"] += time.perf_counter() - t
        if nbytes == 0:
            return buffer
        if self._pending_bytes + nbytes > self.batch_bytes:
            self._submit()
        self._pending.append((buffer, data))
        self._pending_bytes += _aligned(nbytes)
        return buffer

    def submit(self) -> None:
        """Send what is queued to the GPU now, without waiting (`flush` waits)."""
        self._submit()

    def abandon(self) -> None:
        """After an error: drop what is queued, wait for what was sent, free the staging."""
        self._pending.clear()
        self._pending_bytes = 0
        self.flush()

    def flush(self) -> None:
        """Upload what is queued (and wait for every batch); the staging buffers are freed."""
        try:
            self._submit()
            while self._in_flight:
                self._retire()
        finally:
            while self._in_flight:  # (an error: still wait before freeing what the GPU reads)
                self._retire(check=False)
            for staging in self._free:
                staging.destroy()
            self._free.clear()

    def _staging_for(self, total: int) -> Buffer:
        """A staging buffer the GPU is done with: two take turns, so that one batch is copied
        into one while the GPU uploads the other's (a batch of at least half `batch_bytes`
        gets `batch_bytes`, so the next full ones fit; a small one-off upload what it needs)."""
        if not self._free and len(self._in_flight) >= 2:
            self._retire()  # the older batch: its buffer comes back
        for i, staging in enumerate(self._free):
            if staging.size >= total:
                return self._free.pop(i)
        for staging in self._free:
            staging.destroy()
        self._free.clear()
        size = max(total, self.batch_bytes) if 2 * total >= self.batch_bytes else total
        return Buffer(self.device, size, self.device.vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                      host_visible=True)

    def _retire(self, check: bool = True) -> None:
        """Wait for the oldest batch in flight; its command buffer and fence go, its staging
        buffer is free again."""
        cmd, fence, staging = self._in_flight.pop(0)
        vk, device = self.device.vk, self.device
        t = time.perf_counter()
        try:
            if check:
                device.wait_fences(vk.ffi.new("VkFence[1]", [fence]), "an upload")
            else:
                device.wait_idle()
        except BaseException:
            vk.vkDestroyFence(device.handle, fence, None)  # (not known to be signalled)
            fence = None
            raise
        finally:
            if fence is not None:
                device.give_fence(fence)  # (kept for the next batch: gpu/device.py)
            device.free_command_buffer(cmd)
            self._free.append(staging)
            self.stats["wait"] += time.perf_counter() - t

    def _submit(self) -> None:
        """Copy the queued levels into a staging buffer (on threads when large: NumPy
        releases the GIL), record their copies (and mip blits) and submit them, without
        waiting: `flush` (or the batch after next, for its buffer) waits."""
        if not self._pending:
            return
        device, vk = self.device, self.device.vk
        try:
            t, waited = time.perf_counter(), self.stats["wait"]
            total = sum(_slot_bytes(target, levels) for target, levels in self._pending)
            staging = self._staging_for(total)  # (it may wait for the batch before last)
            offsets_of = self._copy_in(staging, total)
            t_copied = time.perf_counter()
            self.stats["copy"] += t_copied - t - (self.stats["wait"] - waited)
            cmd = device.allocate_command_buffer()
            fence = None
            try:
                vk.vkBeginCommandBuffer(cmd, vk.VkCommandBufferBeginInfo(
                    flags=vk.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
                buffers, images = False, []
                for (target, levels), offsets in zip(self._pending, offsets_of, strict=True):
                    if isinstance(target, Buffer):
                        vk.vkCmdCopyBuffer(cmd, staging.handle, target.handle, 1, [vk.VkBufferCopy(
                            srcOffset=offsets[0], dstOffset=0, size=sum(a.nbytes for a in levels))])
                        buffers = True
                    else:
                        images.append((target, offsets))
                _record_images(vk, cmd, staging.handle, images)
                if buffers:  # the copies before any later submission's uses of them
                    before_later_commands(vk, cmd, vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                                          vk.VK_ACCESS_2_TRANSFER_WRITE_BIT)
                vk.vkEndCommandBuffer(cmd)
                fence = device.take_fence()
                vk.vkQueueSubmit(device.queue, 1, [vk.VkSubmitInfo(pCommandBuffers=[cmd])], fence)
            except BaseException:
                if fence is not None:
                    vk.vkDestroyFence(device.handle, fence, None)
                device.free_command_buffer(cmd)
                self._free.append(staging)
                raise
            self._in_flight.append((cmd, fence, staging))
            self.stats["record"] += time.perf_counter() - t_copied
        finally:
            self._pending.clear()
            self._pending_bytes = 0

    def _copy_in(self, staging: Buffer, total: int) -> list[list[int]]:
        """The queued levels copied into `staging`; each image's levels' offsets."""
        dst = staging.array(np.uint8, total)
        copies, offsets_of, offset = [], [], 0
        for target, levels in self._pending:  # offsets multiples of 16: a BC7 block (RGBA8: 4)
            offsets_of.append([])
            joined = isinstance(target, Buffer)  # a buffer's parts: one after another
            for a in levels:
                copies.append((offset, a))
                offsets_of[-1].append(offset)
                offset += a.nbytes if joined else _aligned(a.nbytes)
            offset = _aligned(offset)

        def copy(job: tuple[int, np.ndarray]) -> None:
            at, a = job
            dst[at : at + a.nbytes] = a.reshape(-1).view(np.uint8)  # (any dtype: buffers)

        if total >= _PARALLEL_COPY_BYTES and len(copies) > 1:
            list(pool().map(copy, copies))
        else:
            for job in copies:
                copy(job)
        return offsets_of


# --- a batch's images, recorded with cffi's own struct initialisers --------------------------
# The binding's struct constructors cost ~10 us of Python each, and a texture's mip chain takes
# a barrier and a blit (7 structs) per level: Sponza's 72 images were ~0.1 s of recording.
# Here each level's barriers of every image of the batch are one call, and the structs are
# cffi initialisers from dicts (C speed); the commands are those recorded one image at a time
# before (the same blits: the same texels).
_COLOR = 0x1  # VK_IMAGE_ASPECT_COLOR_BIT


def _subresource(level: int) -> dict:
    return {"aspectMask": _COLOR, "mipLevel": level, "baseArrayLayer": 0, "layerCount": 1}


def _barriers(vk: Any, cmd: Any, rows: list[tuple]) -> None:
    """One vkCmdPipelineBarrier2 of image barriers, each (image, old, new, (src stage, access),
    (dst stage, access), base level, levels)."""
    if not rows:
        return
    ffi, ignored = vk.ffi, vk.VK_QUEUE_FAMILY_IGNORED
    arr = ffi.new("VkImageMemoryBarrier2[]", [{
        "sType": vk.VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2, "srcStageMask": src[0],
        "srcAccessMask": src[1], "dstStageMask": dst[0], "dstAccessMask": dst[1],
        "oldLayout": old, "newLayout": new, "srcQueueFamilyIndex": ignored,
        "dstQueueFamilyIndex": ignored, "image": image.handle,
        "subresourceRange": {"aspectMask": _COLOR, "baseMipLevel": base, "levelCount": count,
                             "baseArrayLayer": 0, "layerCount": 1}}
        for image, old, new, src, dst, base, count in rows])
    vk.vkCmdPipelineBarrier2(cmd, ffi.new("VkDependencyInfo*", {
        "sType": vk.VK_STRUCTURE_TYPE_DEPENDENCY_INFO, "imageMemoryBarrierCount": len(rows),
        "pImageMemoryBarriers": arr}))


def _record_images(vk: Any, cmd: Any, staging: Any, images: list[tuple[Image, list[int]]]) -> None:
    """Each image's given levels copied from `staging` (at their offsets), the rest of its
    chain made by linear blits from the level above; every level then shader-readable."""
    if not images:
        return
    top = (vk.VK_PIPELINE_STAGE_2_NONE, vk.VK_ACCESS_2_NONE)
    xfer_w = (vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT)
    xfer_r = (vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
    frag = (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
            vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT)
    undef, dst_l = vk.VK_IMAGE_LAYOUT_UNDEFINED, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
    src_l, ro = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
    _barriers(vk, cmd, [(im, undef, dst_l, top, xfer_w, 0, im.mip_levels) for im, _ in images])
    ffi = vk.ffi
    for im, offsets in images:
        regions = ffi.new("VkBufferImageCopy[]", [{
            "bufferOffset": off, "imageSubresource": _subresource(k),
            "imageExtent": {"width": max(im.width >> k, 1), "height": max(im.height >> k, 1),
                            "depth": 1}} for k, off in enumerate(offsets)])
        vk.vkCmdCopyBufferToImage(cmd, staging, im.handle, dst_l, len(offsets), regions)
    blitted = [im for im, offsets in images if im.mip_levels > len(offsets)]
    for level in range(1, max((im.mip_levels for im in blitted), default=1)):
        now = [im for im in blitted if im.mip_levels > level]
        # Level - 1 becomes a blit source; level stays a transfer destination.
        _barriers(vk, cmd, [(im, dst_l, src_l, xfer_w, xfer_r, level - 1, 1) for im in now])
        for im in now:
            w, h = max(im.width >> (level - 1), 1), max(im.height >> (level - 1), 1)
            blit = ffi.new("VkImageBlit[1]", [{
                "srcSubresource": _subresource(level - 1), "srcOffsets": [(0, 0, 0), (w, h, 1)],
                "dstSubresource": _subresource(level),
                "dstOffsets": [(0, 0, 0), (max(w // 2, 1), max(h // 2, 1), 1)]}])
            vk.vkCmdBlitImage(cmd, im.handle, src_l, im.handle, dst_l, 1, blit, vk.VK_FILTER_LINEAR)
    final = []
    for im, offsets in images:
        n = im.mip_levels
        if n > len(offsets):  # levels 0..n-2 were blit sources; the last one a destination
            final.append((im, dst_l, ro, xfer_w, frag, n - 1, 1))
            if n > 1:
                final.append((im, src_l, ro, xfer_r, frag, 0, n - 1))
        else:
            final.append((im, dst_l, ro, xfer_w, frag, 0, n))
    _barriers(vk, cmd, final)
