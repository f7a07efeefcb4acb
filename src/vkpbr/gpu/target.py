"""Frame targets: what a frame is drawn into. One protocol, two kinds.

`FrameTarget` is all the frame path (render/renderer.py) knows of a target, in the manner of
Khronos Vulkan-Samples' RenderContext, which serves swapchains and offscreen images alike:
  acquire(frame)                         -> image index to draw into (None: recreate first)
  record_begin(cmd, image)               transitions, begin rendering (clear)
  record_end(cmd, image, frame, copy)    end rendering, copy into `frame`'s readback buffers
  submit(frame, cmd, image)              queue it (and present it); False: recreate
plus `color_format`, `depth_format`, `samples` (pipelines are built for them), `extent` and
`generation` (bumped when the images are recreated: recorded command buffers are stale).

`OffscreenTarget` is one colour + D32 depth pair (optionally 4x MSAA, resolved) with a pair
of persistently mapped readback buffers per frame in flight, so reading frame i never races
frame i+1's copy. Frames in flight share the images; the barrier at the start of each frame
orders its writes after the previous frame's copy. The swapchain is gpu/swapchain.py.
Depth is cleared to 0: the renderer uses reversed-Z (0 = infinitely far).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Protocol

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.frames import Frame
from vkpbr.gpu.image import Image, ImageView
from vkpbr.gpu.rendering import (
    Attachments,
    attachment_stage,
    barriers,
    begin_rendering,
    buffer_barrier,
    compute_storage,
    copy_buffer_to_image,
    copy_image_to_buffer,
    copy_out_barriers,
    end_rendering,
    external_ownership,
    host_read_barrier,
    image_barrier,
    redraw_barriers,
)

__all__ = ["FrameTarget", "OffscreenTarget", "ComputeSteps", "COLOR_FORMATS", "COPY_COLOR", "COPY_DEPTH", "COPY_OUTPUTS"]

# Colour formats by name: "srgb" for display images, "float" for linear HDR values.
COLOR_FORMATS = {"srgb": ("VK_FORMAT_R8G8B8A8_SRGB", 4), "float": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16)}
COPY_COLOR, COPY_DEPTH, COPY_OUTPUTS = "color", "depth", "outputs"
# The dataset outputs' images (render/layouts.py OUTPUT_IMAGES): Vulkan format names and
# bytes a pixel, by GLSL name; their clear values: ids 0, normals 0, distances +inf.
_INF = float("inf")


class FrameTarget(Protocol):
    color_format: int
    depth_format: int
    samples: int
    extent: tuple[int, int]
    generation: int

    def acquire(self, frame: Frame) -> int | None: ...

    def record_begin(self, cmd: Commands, image: int) -> None: ...

    def record_end(self, cmd: Commands, image: int, frame: Frame, copy: tuple[str, ...]) -> None: ...

    def submit(self, frame: Frame, cmd: Commands, image: int) -> bool: ...


class ComputeSteps:
    """The compute path's steps over a target's images (render/compute_path.py), shared by
    the offscreen target and the transmission's copy (gpu/mip_target.py). The includer has
    `device`, `extent`, `color` (mip 0 is written), `depth`, `visibility` (+ `_view`),
    `attachments` and `clear_color`, and says in `_color_last_use` which stages last used
    the colour image (a frame's copy and attachment writes by default)."""

    def _color_last_use(self, vk: Any) -> tuple[int, int]:
        """(stages, accesses) of the colour image's previous use, ordered before its writes."""
        stage, access, _ = attachment_stage(vk, False)
        return (stage | vk.VK_PIPELINE_STAGE_2_COPY_BIT,
                access & ~vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT)

    def record_visibility_begin(self, cmd: Commands, image: int) -> None:
        """Begin rendering the visibility image (cleared to 0: nothing) over the cleared
        depth buffer; the colour image goes to GENERAL for the compute shader's writes."""
        vk = self.device.vk
        color_stage, color_access, color_layout = attachment_stage(vk, False)
        depth_stage, depth_access, depth_layout = attachment_stage(vk, True)
        copy = vk.VK_PIPELINE_STAGE_2_COPY_BIT
        compute = compute_storage(vk)
        no_reads = ~(vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT
                     | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT)
        barriers(cmd, [
            # The previous frame's passes and copies of these images come first.
            image_barrier(vk, self.visibility.handle, False, vk.VK_IMAGE_LAYOUT_UNDEFINED,
                          color_layout, (compute[0], 0), (color_stage, color_access)),
            image_barrier(vk, self.depth.handle, True, vk.VK_IMAGE_LAYOUT_UNDEFINED, depth_layout,
                          (depth_stage | copy, depth_access & no_reads), (depth_stage, depth_access)),
            image_barrier(vk, self.color.handle, False, vk.VK_IMAGE_LAYOUT_UNDEFINED,
                          vk.VK_IMAGE_LAYOUT_GENERAL, self._color_last_use(vk), compute),
        ])
        begin_rendering(cmd, Attachments(self.visibility_view.handle, self.attachments.depth,
                                         self.extent), (0.0, 0.0, 0.0, 0.0), 0.0)

    def record_raster_end(self, cmd: Commands, depths: Buffer, copy_depth: bool = True) -> None:
        """After the compute rasteriser, instead of a visibility pass: its depths (`depths`,
        a float a pixel, written by its resolve) copied into the depth buffer for what tests
        it afterwards (the blended draws) and depth readback, then ready for those (without
        `copy_depth`, when nothing reads it, only made an attachment again: its contents
        undefined). The visibility and colour images stay in GENERAL (record_raster_begin),
        readable and writable by the shading (record_raster's last barrier)."""
        vk = self.device.vk
        depth_stage, depth_access, depth_layout = attachment_stage(vk, True)
        copy = vk.VK_PIPELINE_STAGE_2_COPY_BIT
        compute = compute_storage(vk)
        write, read = vk.VK_ACCESS_2_TRANSFER_WRITE_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT
        # The previous frame's passes and copies of the depth buffer come first.
        before = (depth_stage | copy, depth_access & ~vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT)
        if not copy_depth:
            barriers(cmd, [image_barrier(vk, self.depth.handle, True,
                                         vk.VK_IMAGE_LAYOUT_UNDEFINED, depth_layout,
                                         before, (depth_stage, depth_access))])
            return
        dst = vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
        barriers(cmd, [image_barrier(vk, self.depth.handle, True, vk.VK_IMAGE_LAYOUT_UNDEFINED,
                                     dst, before, (copy, write))],
                 [buffer_barrier(vk, depths, compute, (copy, read))])
        copy_buffer_to_image(cmd, depths, self.depth.handle, True, self.extent)
        barriers(cmd, [image_barrier(vk, self.depth.handle, True, dst, depth_layout,
                                     (copy, write), (depth_stage, depth_access))],
                 [buffer_barrier(vk, depths, (copy, read), (compute[0], 0))])

    def record_shading_begin(self, cmd: Commands) -> None:
        """End the visibility pass: its image becomes readable by the compute shader."""
        vk = self.device.vk
        end_rendering(cmd)
        stage, access, layout = attachment_stage(vk, False)
        barriers(cmd, [image_barrier(
            vk, self.visibility.handle, False, layout, vk.VK_IMAGE_LAYOUT_GENERAL,
            (stage, vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT),
            (vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, vk.VK_ACCESS_2_SHADER_STORAGE_READ_BIT))])

    def record_resume(self, cmd: Commands, clear: bool = False) -> None:
        """After the compute steps: render on into the colour image (the shaded one, or
        `clear`ed for the fragment path's passes) over the visibility pass's depth."""
        vk = self.device.vk
        stage, access, layout = attachment_stage(vk, False)
        barriers(cmd, [image_barrier(
            vk, self.color.handle, False, vk.VK_IMAGE_LAYOUT_GENERAL, layout,
            (vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, vk.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT),
            (stage, access))])
        begin_rendering(cmd, self.attachments, self.clear_color if clear else None, None)


class OffscreenTarget(ComputeSteps):
    """Offscreen colour + depth of `size` = (width, height); `color` is "srgb" or "float"."""

    generation = 0  # never recreated

    def __init__(self, device: Device, size: tuple[int, int], color: str = "srgb",
                 samples: int = 1, clear_color: tuple[float, float, float, float] = (0, 0, 0, 1),
                 compute: bool = False) -> None:
        vk = device.vk
        self.device = device
        self.extent = (int(size[0]), int(size[1]))
        w, h = self.extent
        self.samples, self.color_kind, self.clear_color = samples, color, clear_color
        fmt_name, self.pixel_bytes = COLOR_FORMATS[color]
        self.color_format = getattr(vk, fmt_name)
        self.depth_format = vk.VK_FORMAT_D32_SFLOAT
        self._objects: list[Any] = []
        src = vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        attach = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | src
        # The compute path (render/compute_path.py) also writes the colour image from a
        # compute shader, through a storage view: UNORM for the sRGB image (a mutable image),
        # and renders a visibility image with the same depth buffer.
        self.compute = bool(compute and samples == 1)
        storage = vk.VK_IMAGE_USAGE_STORAGE_BIT if self.compute else 0
        mutable = self.compute and color == "srgb"
        self.color = self._own(Image(device, w, h, self.color_format, attach | storage,
                                     mutable=mutable))
        # The compute rasteriser's depths are copied in (record_raster_end).
        depth_in = vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT if self.compute else 0
        self.depth = self._own(Image(device, w, h, self.depth_format,
                                     vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | src | depth_in))
        views = [self._own(ImageView(self.color, usage=attach if mutable else None)),
                 self._own(ImageView(self.depth, aspect="depth"))]
        if self.compute:
            unorm = vk.VK_FORMAT_R8G8B8A8_UNORM if color == "srgb" else None
            self.storage_view = self._own(ImageView(
                self.color, format=unorm, usage=vk.VK_IMAGE_USAGE_STORAGE_BIT if mutable else None))
            self.visibility = self._own(Image(
                device, w, h, vk.VK_FORMAT_R32G32_UINT,
                vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_STORAGE_BIT,
                name="visibility"))
            self.visibility_view = self._own(ImageView(self.visibility))
        self._images = [(self.color, False), (self.depth, True)]
        self.attachments = Attachments(views[0].handle, views[1].handle, self.extent)
        if samples > 1:
            transient = vk.VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT
            mc = self._own(Image(device, w, h, self.color_format,
                                 vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | transient, samples=samples))
            md = self._own(Image(device, w, h, self.depth_format,
                                 vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | transient,
                                 samples=samples))
            self._images += [(mc, False), (md, True)]
            self.attachments.msaa_color = self._own(ImageView(mc)).handle
            self.attachments.msaa_depth = self._own(ImageView(md, aspect="depth")).handle
        self._readbacks: dict[int, tuple[Buffer, Buffer]] = {}

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    def readback(self, frame_index: int) -> tuple[Buffer, Buffer]:
        """The (colour, depth) readback buffers of frame `frame_index`, made on first use."""
        if frame_index not in self._readbacks:
            vk = self.device.vk
            n = self.extent[0] * self.extent[1]
            usage = vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
            self._readbacks[frame_index] = (
                self._own(Buffer(self.device, n * self.pixel_bytes, usage, host_visible=True,
                                 name=f"color readback {frame_index}")),
                self._own(Buffer(self.device, n * 4, usage, host_visible=True,
                                 name=f"depth readback {frame_index}")),
            )
        return self._readbacks[frame_index]

    # --- the protocol -----------------------------------------------------------------------
    def acquire(self, frame: Frame) -> int:
        return 0  # one image; frames in flight are ordered by the barriers below

    def record_begin(self, cmd: Commands, image: int) -> None:
        barriers(cmd, redraw_barriers(self.device.vk, [(i.handle, d) for i, d in self._images]))
        begin_rendering(cmd, self.attachments, self.clear_color, 0.0)

    # --- the compute path's steps, instead of record_begin -------------------------------------
    def record_raster_begin(self, cmd: Commands) -> None:
        """Before the compute rasteriser resolves into the visibility image (and the clear
        colour into the colour image where nothing covers a pixel): both GENERAL for storage
        writes, after the previous frame's uses (contents discarded)."""
        vk = self.device.vk
        compute = compute_storage(vk)
        barriers(cmd, [image_barrier(vk, self.visibility.handle, False,
                                     vk.VK_IMAGE_LAYOUT_UNDEFINED, vk.VK_IMAGE_LAYOUT_GENERAL,
                                     (compute[0], 0), compute),
                       image_barrier(vk, self.color.handle, False, vk.VK_IMAGE_LAYOUT_UNDEFINED,
                                     vk.VK_IMAGE_LAYOUT_GENERAL, self._color_last_use(vk), compute)])

    # --- dataset outputs (render/compute_path.py writes them) ---------------------------------
    outputs: dict[str, tuple[Image, ImageView]] | None = None

    def ensure_outputs(self, formats: dict[str, tuple[str, int]]) -> bool:
        """Make the outputs' images (`formats`: GLSL name -> (Vulkan format name, bytes a
        pixel)) on first use; True when they were made now."""
        if self.outputs is not None:
            return False
        vk = self.device.vk
        w, h = self.extent
        usage = (vk.VK_IMAGE_USAGE_STORAGE_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
                 | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT)
        self.outputs = {}
        self._output_bytes = {}
        for name, (fmt, nbytes) in formats.items():
            image = self._own(Image(self.device, w, h, getattr(vk, fmt), usage, name=name))
            self.outputs[name] = (image, self._own(ImageView(image)))
            self._output_bytes[name] = nbytes
        self._output_readbacks: dict[int, dict[str, Buffer]] = {}
        return True

    def record_outputs_clear(self, cmd: Commands) -> None:
        """Clear the outputs (ids and normals 0, distances +inf) for this frame's writes, after
        the previous frame's copies of them."""
        vk = self.device.vk
        transfer = vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT
        general = vk.VK_IMAGE_LAYOUT_GENERAL
        images = [img for img, _ in self.outputs.values()]  # type: ignore[union-attr]
        barriers(cmd, [image_barrier(vk, img.handle, False, vk.VK_IMAGE_LAYOUT_UNDEFINED, general,
                                     (transfer, 0), (transfer, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT))
                       for img in images])
        full = vk.VkImageSubresourceRange(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0,
                                          levelCount=1, baseArrayLayer=0, layerCount=1)
        for name, (img, _) in self.outputs.items():  # type: ignore[union-attr]
            value = (vk.VkClearColorValue(uint32=[0, 0, 0, 0]) if name == "out_ids" else
                     vk.VkClearColorValue(float32=[_INF, _INF, 0.0, 0.0]) if name == "out_depth_range"
                     else vk.VkClearColorValue(float32=[0.0, 0.0, 0.0, 0.0]))
            vk.vkCmdClearColorImage(cmd.handle, img.handle, general, value, 1, [full])
        compute = (vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, vk.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT)
        barriers(cmd, [image_barrier(vk, img.handle, False, general, general,
                                     (transfer, vk.VK_ACCESS_2_TRANSFER_WRITE_BIT), compute)
                       for img in images])

    def _record_outputs_copy(self, cmd: Commands, frame: Frame) -> None:
        vk = self.device.vk
        general = vk.VK_IMAGE_LAYOUT_GENERAL
        xfer = (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
        compute = (vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, vk.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT)
        outputs = self.outputs or {}
        barriers(cmd, [image_barrier(vk, img.handle, False, general, general, compute, xfer)
                       for img, _ in outputs.values()])
        buffers = self._outputs_readback(frame.index)
        for name, (img, _) in outputs.items():
            copy_image_to_buffer(cmd, img.handle, False, buffers[name], self.extent, general=True)
        barriers(cmd, [], [host_read_barrier(vk, b) for b in buffers.values()])

    def _outputs_readback(self, frame_index: int) -> dict[str, Buffer]:
        if frame_index not in self._output_readbacks:
            n = self.extent[0] * self.extent[1]
            usage = self.device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
            self._output_readbacks[frame_index] = {
                name: self._own(Buffer(self.device, n * nbytes, usage, host_visible=True,
                                       name=f"{name} readback {frame_index}"))
                for name, nbytes in self._output_bytes.items()}
        return self._output_readbacks[frame_index]

    def read_outputs(self, frame_index: int, dtypes: dict[str, tuple[str, int]]) -> dict[str, np.ndarray]:
        """Copies of the frame's outputs: GLSL name -> (H, W, channels) array of `dtypes`'
        (NumPy dtype name, channels)."""
        w, h = self.extent
        buffers = self._outputs_readback(frame_index)
        return {name: buffers[name].array(np.dtype(dt), w * h * ch).reshape(h, w, ch).copy()
                for name, (dt, ch) in dtypes.items()}

    def record_end(self, cmd: Commands, image: int, frame: Frame, copy: tuple[str, ...],
                   tiles: tuple[int, int, int, int] | None = None, external: Any = None) -> None:
        """End the frame's rendering and copy out what `copy` names; `tiles` (an atlas of a
        compute batch: views, tile width, height, tiles a column): colour and depth view by view
        (read_tiles); `external`: the colour into that exported buffer instead (for CUDA:
        taken back from the external queue family before the copy, released after it)."""
        end_rendering(cmd)
        if COPY_OUTPUTS in copy:
            self._record_outputs_copy(cmd, frame)
            copy = tuple(c for c in copy if c != COPY_OUTPUTS)
        if not copy:
            return
        vk = self.device.vk
        color_buf, depth_buf = self.readback(frame.index)
        wanted = [(self.color, False, external or color_buf, COPY_COLOR),
                  (self.depth, True, depth_buf, COPY_DEPTH)]
        wanted = [w for w in wanted if w[3] in copy]
        family = self.device.queue_family
        barriers(cmd, copy_out_barriers(vk, [(img.handle, depth) for img, depth, _, _ in wanted]),
                 [external_ownership(vk, family, external, True)] if external is not None else [])
        for img, depth, buf, _ in wanted:
            copy_image_to_buffer(cmd, img.handle, depth, buf, self.extent, tiles=tiles,
                                 pixel_bytes=4 if depth else self.pixel_bytes)
        barriers(cmd, [], [external_ownership(vk, family, w[2], False) if w[2] is external
                           else host_read_barrier(vk, w[2]) for w in wanted])

    def submit(self, frame: Frame, cmd: Commands, image: int) -> bool:
        frame.submit(cmd)
        return True

    # --- readback ---------------------------------------------------------------------------
    def read_color(self, frame_index: int) -> np.ndarray:
        """A copy of the frame's colour: (H, W, 4) uint8 ("srgb") or float32 ("float")."""
        dtype = np.uint8 if self.color_kind == "srgb" else np.float32
        w, h = self.extent
        return copy_out(self.readback(frame_index)[0].array(dtype, w * h * 4).reshape(h, w, 4))

    def read_tiles(self, frame_index: int, views: int, size: tuple[int, int],
                   depth: bool = False, into: np.ndarray | None = None) -> np.ndarray:
        """A copy of an atlas frame's colour (views, H, W, 4), or its depth (views, H, W),
        copied out tile by tile (record_end's `tiles`); the colour written into `into` where
        given (an array of that shape and type)."""
        w, h = size
        if depth:
            return copy_out(self.readback(frame_index)[1].array(np.float32, views * w * h)
                            .reshape(views, h, w))
        dtype = np.uint8 if self.color_kind == "srgb" else np.float32
        return copy_out(self.readback(frame_index)[0].array(dtype, views * w * h * 4).reshape(
            views, h, w, 4), into)

    def read_depth(self, frame_index: int) -> np.ndarray:
        """A copy of the frame's depth buffer: (H, W) float32 window depth in [0, 1]."""
        w, h = self.extent
        return self.readback(frame_index)[1].array(np.float32, w * h).reshape(h, w).copy()

    def destroy(self) -> None:
        while self._objects:
            self._objects.pop().destroy()


# Big readbacks are copied by several threads: a copy into a fresh array is bound by page
# faults, which one thread takes one at a time (256 MiB: 85 ms on one core, 46 ms on two; NumPy
# releases the GIL in copyto). Below PARALLEL_BYTES the threads cost more than they save.
PARALLEL_BYTES = 8 << 20
_COPY_THREADS = max(1, min(8, os.cpu_count() or 1))
_copy_pool: ThreadPoolExecutor | None = None


def _forget_copy_pool() -> None:
    global _copy_pool
    _copy_pool = None  # a forked child (multiprocessing, Ray's workers) has none of its threads


os.register_at_fork(after_in_child=_forget_copy_pool)


def copy_out(mapped: np.ndarray, into: np.ndarray | None = None) -> np.ndarray:
    """`mapped` (a view of readback memory) copied into `into`, or into a new array; split
    along the first axis over threads when it is big."""
    out = np.empty_like(mapped) if into is None else into
    parts = min(_COPY_THREADS, len(mapped)) if mapped.nbytes >= PARALLEL_BYTES else 1
    if parts <= 1:
        np.copyto(out, mapped)
        return out
    global _copy_pool
    if _copy_pool is None:
        _copy_pool = ThreadPoolExecutor(_COPY_THREADS, thread_name_prefix="vkpbr-readback")
    step = -(-len(mapped) // parts)
    spans = [slice(i, i + step) for i in range(0, len(mapped), step)]
    for done in [_copy_pool.submit(np.copyto, out[s], mapped[s]) for s in spans]:
        done.result()
    return out
