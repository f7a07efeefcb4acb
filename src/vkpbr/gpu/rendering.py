"""Dynamic rendering and the barriers around it, shared by every frame target.

Offscreen targets and swapchains differ only in where their images come from and where a
finished frame goes (a readback buffer, the presentation engine); beginning a rendering over
a colour + depth pair, and the layout transitions in and out of it, are written once here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.commands import Commands

__all__ = ["Attachments", "begin_rendering", "begin_depth_rendering", "end_rendering", "image_barrier", "buffer_barrier", "barriers",
           "copy_image_to_buffer", "host_read_barrier", "redraw_barriers", "copy_out_barriers"]


@dataclass
class Attachments:
    """Views rendered into: colour and depth, plus their MSAA images when `samples` > 1
    (rendered into, then resolved into colour/depth)."""

    color: Any
    depth: Any
    extent: tuple[int, int]
    msaa_color: Any = None
    msaa_depth: Any = None


def image_barrier(vk: Any, image: Any, depth: bool, old: int, new: int, src: tuple[int, int],
                  dst: tuple[int, int], layers: int = 1, levels: int = 1) -> Any:
    """A VkImageMemoryBarrier2 over mips 0..`levels`-1, layers 0..`layers`-1 of `image` (a
    VkImage handle), made with `ffi.new` (a recording makes dozens: the binding's struct
    constructor costs ~20 us each, this ~2)."""
    ignored = vk.VK_QUEUE_FAMILY_IGNORED
    return vk.ffi.new("VkImageMemoryBarrier2*", {
        "sType": vk.VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2, "srcStageMask": src[0],
        "srcAccessMask": src[1], "dstStageMask": dst[0], "dstAccessMask": dst[1],
        "oldLayout": old, "newLayout": new, "srcQueueFamilyIndex": ignored,
        "dstQueueFamilyIndex": ignored, "image": image,
        "subresourceRange": {
            "aspectMask": vk.VK_IMAGE_ASPECT_DEPTH_BIT if depth else vk.VK_IMAGE_ASPECT_COLOR_BIT,
            "baseMipLevel": 0, "levelCount": levels, "baseArrayLayer": 0, "layerCount": layers}})


def buffer_barrier(vk: Any, buffer: Any, src: tuple[int, int], dst: tuple[int, int]) -> Any:
    """A VkBufferMemoryBarrier2 over the whole of `buffer` (a gpu.buffer.Buffer), made with
    `ffi.new` (as `image_barrier`)."""
    ignored = vk.VK_QUEUE_FAMILY_IGNORED
    return vk.ffi.new("VkBufferMemoryBarrier2*", {
        "sType": vk.VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2, "srcStageMask": src[0],
        "srcAccessMask": src[1], "dstStageMask": dst[0], "dstAccessMask": dst[1],
        "srcQueueFamilyIndex": ignored, "dstQueueFamilyIndex": ignored,
        "buffer": buffer.handle, "offset": 0, "size": buffer.size})


def redraw_barriers(vk: Any, images: list[tuple[Any, bool]], layers: int = 1) -> list[Any]:
    """Barriers taking (VkImage, is_depth) attachments from whatever they held to drawing:
    the previous frame drew into them and may have copied them out, so both are ordered
    before this frame's writes (write-after-write, write-after-read); the old contents are
    discarded (UNDEFINED: every frame clears)."""
    out = []
    for image, depth in images:
        stage, access, layout = attachment_stage(vk, depth)
        src = (stage | vk.VK_PIPELINE_STAGE_2_COPY_BIT,
               access & ~(vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT
                          | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT))
        out.append(image_barrier(vk, image, depth, vk.VK_IMAGE_LAYOUT_UNDEFINED, layout, src,
                                 (stage, access), layers=layers))
    return out


def copy_out_barriers(vk: Any, images: list[tuple[Any, bool]], layers: int = 1) -> list[Any]:
    """Barriers taking drawn (VkImage, is_depth) attachments to TRANSFER_SRC for a copy."""
    xfer = (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
    out = []
    for image, depth in images:
        stage, access, layout = attachment_stage(vk, depth)
        out.append(image_barrier(vk, image, depth, layout, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                 (stage, access), xfer, layers=layers))
    return out


def barriers(cmd: Commands, images: list[Any], buffers: list[Any] = ()) -> None:
    """One vkCmdPipelineBarrier2 of `images` and `buffers` barriers (`image_barrier`'s and
    `buffer_barrier`'s pointers, or the binding's structs), through the C entry point."""
    if not images and not buffers:
        return
    vk, ffi = cmd.vk, cmd.ffi
    info = ffi.new("VkDependencyInfo*", {"sType": vk.VK_STRUCTURE_TYPE_DEPENDENCY_INFO})
    keep = [_array(ffi, "VkImageMemoryBarrier2", images),
            _array(ffi, "VkBufferMemoryBarrier2", buffers)]
    info.imageMemoryBarrierCount, info.pImageMemoryBarriers = len(images), keep[0]
    info.bufferMemoryBarrierCount, info.pBufferMemoryBarriers = len(buffers), keep[1]
    cmd.lib.vkCmdPipelineBarrier2(cmd.handle, info)


def _array(ffi: Any, ctype: str, items: list[Any]) -> Any:
    """`items` (pointers to or structs of `ctype`) copied into one C array (NULL for none)."""
    if not items:
        return ffi.NULL
    arr = ffi.new(f"{ctype}[]", len(items))
    for i, item in enumerate(items):
        arr[i] = item[0] if ffi.typeof(item).kind == "pointer" else item
    return arr


def attachment_stage(vk: Any, depth: bool) -> tuple[int, int, int]:
    """(stages, accesses, layout) of a colour or depth attachment being drawn."""
    if depth:
        return (vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT
                | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
                | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
                vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL)
    return (vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
            vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT,
            vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL)


def compute_storage(vk: Any) -> tuple[int, int]:
    """(stages, accesses) of compute shaders reading and writing storage images and buffers."""
    return (vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
            vk.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | vk.VK_ACCESS_2_SHADER_STORAGE_READ_BIT)


def begin_rendering(cmd: Commands, att: Attachments, clear_color: tuple[float, ...] | None,
                    clear_depth: float | None, store_depth: bool = True, layers: int = 1) -> None:
    """Begin dynamic rendering over `att` (cleared, or loaded where a clear value is None),
    and set the viewport and scissor to the whole extent. `layers` > 1: layered rendering
    into 2D-array views (the vertex shader picks the layer, gl_Layer)."""
    vk = cmd.vk
    store, dont = vk.VK_ATTACHMENT_STORE_OP_STORE, vk.VK_ATTACHMENT_STORE_OP_DONT_CARE
    clear, load = vk.VK_ATTACHMENT_LOAD_OP_CLEAR, vk.VK_ATTACHMENT_LOAD_OP_LOAD
    color_l = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
    depth_l = vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL
    cc = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(clear_color or (0.0,) * 4)))
    cd = vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(
        depth=0.0 if clear_depth is None else clear_depth, stencil=0))
    c_load = load if clear_color is None else clear
    d_load = load if clear_depth is None else clear
    if att.msaa_color is not None:
        color = vk.VkRenderingAttachmentInfo(
            imageView=att.msaa_color, imageLayout=color_l,
            resolveMode=vk.VK_RESOLVE_MODE_AVERAGE_BIT, resolveImageView=att.color,
            resolveImageLayout=color_l, loadOp=c_load, storeOp=dont, clearValue=cc)
        depth = vk.VkRenderingAttachmentInfo(
            imageView=att.msaa_depth, imageLayout=depth_l,
            resolveMode=vk.VK_RESOLVE_MODE_SAMPLE_ZERO_BIT, resolveImageView=att.depth,
            resolveImageLayout=depth_l, loadOp=d_load, storeOp=dont, clearValue=cd)
    else:
        color = vk.VkRenderingAttachmentInfo(imageView=att.color, imageLayout=color_l,
                                             loadOp=c_load, storeOp=store, clearValue=cc)
        depth = vk.VkRenderingAttachmentInfo(imageView=att.depth, imageLayout=depth_l,
                                             loadOp=d_load, storeOp=store if store_depth else dont,
                                             clearValue=cd)
    w, h = att.extent
    area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(w, h))
    vk.vkCmdBeginRendering(cmd.handle, vk.VkRenderingInfo(
        renderArea=area, layerCount=layers, pColorAttachments=[color], pDepthAttachment=depth))
    vk.vkCmdSetViewport(cmd.handle, 0, 1, [vk.VkViewport(
        x=0, y=0, width=w, height=h, minDepth=0.0, maxDepth=1.0)])
    vk.vkCmdSetScissor(cmd.handle, 0, 1, [area])


def begin_depth_rendering(cmd: Commands, depth_view: Any, extent: tuple[int, int],
                          layers: int = 1, clear_depth: float = 0.0) -> None:
    """Begin a depth-only rendering (no colour attachment) into the `layers` layers of
    `depth_view`, cleared to `clear_depth` and stored (layered rendering: the vertex shader
    picks the layer, gl_Layer). Sets the viewport and scissor."""
    vk = cmd.vk
    depth = vk.VkRenderingAttachmentInfo(
        imageView=depth_view, imageLayout=vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
        loadOp=vk.VK_ATTACHMENT_LOAD_OP_CLEAR, storeOp=vk.VK_ATTACHMENT_STORE_OP_STORE,
        clearValue=vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(
            depth=clear_depth, stencil=0)))
    w, h = extent
    area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(w, h))
    vk.vkCmdBeginRendering(cmd.handle, vk.VkRenderingInfo(
        renderArea=area, layerCount=layers, colorAttachmentCount=0,
        pDepthAttachment=depth))
    vk.vkCmdSetViewport(cmd.handle, 0, 1, [vk.VkViewport(
        x=0, y=0, width=w, height=h, minDepth=0.0, maxDepth=1.0)])
    vk.vkCmdSetScissor(cmd.handle, 0, 1, [area])


def end_rendering(cmd: Commands) -> None:
    cmd.vk.vkCmdEndRendering(cmd.handle)


def copy_image_to_buffer(cmd: Commands, image: Any, depth: bool, buffer: Any,
                         extent: tuple[int, int], general: bool = False, layers: int = 1,
                         offset: int = 0, tiles: tuple[int, int, int, int] | None = None,
                         pixel_bytes: int = 4) -> None:
    """Copy mip 0 of `image` (in TRANSFER_SRC layout, or GENERAL), layers 0..`layers`-1,
    tightly packed into `buffer` from byte `offset` on. `tiles` (views, width, height, tiles a
    column): an atlas's tiles one after another instead, view-major (`pixel_bytes` a pixel)."""
    vk = cmd.vk
    aspect = vk.VK_IMAGE_ASPECT_DEPTH_BIT if depth else vk.VK_IMAGE_ASPECT_COLOR_BIT
    layout = vk.VK_IMAGE_LAYOUT_GENERAL if general else vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
    sub = vk.VkImageSubresourceLayers(aspectMask=aspect, mipLevel=0, baseArrayLayer=0,
                                      layerCount=layers)
    if tiles is None:
        regions = [vk.VkBufferImageCopy(
            bufferOffset=offset, imageSubresource=sub,
            imageExtent=vk.VkExtent3D(width=extent[0], height=extent[1], depth=1))]
    else:
        regions = tile_regions(vk, tiles, offset, pixel_bytes, aspect, layers)
    vk.vkCmdCopyImageToBuffer(cmd.handle, image, layout, buffer.handle, len(regions), regions)


def copy_buffer_to_image(cmd: Commands, buffer: Any, image: Any, depth: bool,
                         extent: tuple[int, int]) -> None:
    """Copy `buffer`, tightly packed, into mip 0 of `image` (in TRANSFER_DST layout)."""
    vk = cmd.vk
    aspect = vk.VK_IMAGE_ASPECT_DEPTH_BIT if depth else vk.VK_IMAGE_ASPECT_COLOR_BIT
    region = vk.VkBufferImageCopy(
        bufferOffset=0, imageSubresource=vk.VkImageSubresourceLayers(
            aspectMask=aspect, mipLevel=0, baseArrayLayer=0, layerCount=1),
        imageExtent=vk.VkExtent3D(width=extent[0], height=extent[1], depth=1))
    vk.vkCmdCopyBufferToImage(cmd.handle, buffer.handle, image,
                              vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, [region])


def tile_regions(vk: Any, tiles: tuple[int, int, int, int], offset: int, pixel_bytes: int,
                 aspect: int, layers: int = 1) -> Any:
    """The VkBufferImageCopy array copying an atlas's `tiles` (views, width, height, tiles a
    column: view v at column v // rows, row v % rows) one view after another from byte
    `offset`: one region a column of tiles, whose rows are already view after view (a region
    a tile cost the H200's driver ~3 us each: 13 ms for 4,096 views). Filled through a NumPy
    view of the C array (the binding's per-struct constructors cost ~50 us each)."""
    n, w, h, rows = tiles
    columns = -(-n // rows)
    ffi, name = vk.ffi, "VkBufferImageCopy"
    regions = ffi.new(f"{name}[]", columns)  # zeroed: bufferRowLength, bufferImageHeight 0 (tight)
    fields = np.dtype({"names": ["offset", "sub", "pos", "ext"],
                       "formats": ["<u8", ("<u4", 4), ("<i4", 3), ("<u4", 3)],
                       "offsets": [ffi.offsetof(name, f) for f in (
                           "bufferOffset", "imageSubresource", "imageOffset", "imageExtent")],
                       "itemsize": ffi.sizeof(name)})
    table = np.frombuffer(ffi.buffer(regions), fields)
    c = np.arange(columns, dtype=np.int64)
    table["offset"] = offset + c * rows * (w * h * pixel_bytes)
    table["sub"] = (aspect, 0, 0, layers)
    table["pos"] = np.stack([c * w, np.zeros_like(c), np.zeros_like(c)], axis=1)
    table["ext"] = np.stack([np.full_like(c, w), np.minimum(rows, n - c * rows) * h,
                             np.ones_like(c)], axis=1)
    return regions


def external_ownership(vk: Any, queue_family: int, buffer: Any, external_to_ours: bool) -> Any:
    """A buffer's hand-over between this queue family and the external one (CUDA reads it):
    taken back before this submission's copies write it, or released after them."""
    ext = vk.VK_QUEUE_FAMILY_EXTERNAL
    copy, write = vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT
    none = (vk.VK_PIPELINE_STAGE_2_NONE, vk.VK_ACCESS_2_NONE)
    src, dst = (none, (copy, write)) if external_to_ours else ((copy, write), none)
    return vk.VkBufferMemoryBarrier2(
        srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
        srcQueueFamilyIndex=ext if external_to_ours else queue_family,
        dstQueueFamilyIndex=queue_family if external_to_ours else ext,
        buffer=buffer.handle, offset=0, size=buffer.size)


def host_read_barrier(vk: Any, buffer: Any) -> Any:
    """Make a copy into `buffer` visible to the host once the frame's fence is waited."""
    return buffer_barrier(vk, buffer,
                          (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT),
                          (vk.VK_PIPELINE_STAGE_2_HOST_BIT, vk.VK_ACCESS_2_HOST_READ_BIT))
