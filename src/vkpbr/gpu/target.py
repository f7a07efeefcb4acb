"""Frame targets: what a frame is drawn into. One protocol, two kinds.

`FrameTarget` is all the frame path (render/frame_path.py) knows of a target, in the manner of
Khronos Vulkan-Samples' RenderContext, which serves swapchains and offscreen images alike:
  acquire(frame)                       -> image index to draw into (None: recreate first)
  resources(image, frame_index)        its images and buffers as frame-graph resources
                                       (gpu/graph.py): "color", "depth", ...
  finish_steps(image, frame_index, copy)  the frame's last steps: copies out, or present
  submit(frame, cmd, image)            queue it (and present it); False: recreate
plus `color_format`, `depth_format`, `samples` (pipelines are built for them), `extent`,
`clear_color`, `stores_depth` and `generation` (bumped when the images are recreated:
recorded command buffers are stale). The barriers between steps come from the graph.

`OffscreenTarget` is one colour + D32 depth pair (optionally 4x MSAA, resolved) with a pair
of persistently mapped readback buffers per frame in flight, so reading frame i never races
frame i+1's copy. Frames in flight share the images; a frame's first use of each waits for
the frames before it (gpu/graph.py). The swapchain is gpu/swapchain.py.
"""

from __future__ import annotations

import contextlib
from typing import Any, Protocol

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.copy_threads import THREADS, pool
from vkpbr.gpu.device import Device
from vkpbr.gpu.frames import Frame
from vkpbr.gpu.graph import BufferResource, ImageResource, Step
from vkpbr.gpu.image import Image, ImageView
from vkpbr.gpu.rendering import Attachments, barriers, copy_image_to_buffer, external_ownership

__all__ = ["FrameTarget", "OffscreenTarget", "COLOR_FORMATS", "COPY_COLOR", "COPY_DEPTH", "COPY_OUTPUTS"]

# Colour formats by name: "srgb" for display images, "float" for linear HDR values.
COLOR_FORMATS = {"srgb": ("VK_FORMAT_R8G8B8A8_SRGB", 4), "float": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16)}
COPY_COLOR, COPY_DEPTH, COPY_OUTPUTS = "color", "depth", "outputs"


class FrameTarget(Protocol):
    color_format: int
    depth_format: int
    samples: int
    extent: tuple[int, int]
    generation: int
    clear_color: tuple[float, float, float, float]
    stores_depth: bool

    def acquire(self, frame: Frame) -> int | None: ...

    def resources(self, image: int, frame_index: int) -> dict[str, Any]: ...

    def finish_steps(self, image: int, frame_index: int, copy: tuple[str, ...]) -> list[Step]: ...

    def submit(self, frame: Frame, cmd: Commands, image: int) -> bool: ...


class OffscreenTarget:
    """Offscreen colour + depth of `size` = (width, height); `color` is "srgb" or "float"."""

    generation = 0  # never recreated
    stores_depth = True

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
        # A multisampled target's resolved colour is a storage image too where the device
        # can (post steps read and write it: render/post_stage.py).
        storage = vk.VK_IMAGE_USAGE_STORAGE_BIT if compute else 0
        mutable = bool(compute) and color == "srgb"
        self.color = self._own(Image(device, w, h, self.color_format, attach | storage,
                                     mutable=mutable))
        # The compute rasteriser's depths are copied in (render/compute_path.py); ambient
        # occlusion samples the depth (render/ao.py; a multisampled target's resolved one).
        self.depth_sampled = bool(compute)
        depth_in = (vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
                    if compute else 0)
        self.depth = self._own(Image(device, w, h, self.depth_format,
                                     vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | src | depth_in))
        views = [self._own(ImageView(self.color, usage=attach if mutable else None)),
                 self._own(ImageView(self.depth, aspect="depth"))]
        self.storage_view = None
        if compute:
            unorm = vk.VK_FORMAT_R8G8B8A8_UNORM if color == "srgb" else None
            self.storage_view = self._own(ImageView(
                self.color, format=unorm, usage=vk.VK_IMAGE_USAGE_STORAGE_BIT if mutable else None))
        if self.compute:
            self.visibility = self._own(Image(
                device, w, h, vk.VK_FORMAT_R32G32_UINT,
                vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_STORAGE_BIT,
                name="id image"))
            self.visibility_view = self._own(ImageView(self.visibility))
        self.attachments = Attachments(views[0].handle, views[1].handle, self.extent)
        if samples > 1:
            transient = vk.VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT
            mc = self._own(Image(device, w, h, self.color_format,
                                 vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | transient, samples=samples))
            md = self._own(Image(device, w, h, self.depth_format,
                                 vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | transient,
                                 samples=samples))
            self._msaa = (mc, md)
            self.attachments.msaa_color = self._own(ImageView(mc)).handle
            self.attachments.msaa_depth = self._own(ImageView(md, aspect="depth")).handle
        self._readbacks: dict[int, tuple[Buffer, Buffer]] = {}

    # The device's for its life (Device.keeping): what it makes later is too (a renderer's
    # targets outlive its scenes, render/targets.py).
    kept = False
    # Open frame streams drawing into it (render/frame_path.py stream): a renderer keeps its
    # targets of a few sizes and destroys the least recently used, never one a stream holds.
    streams = 0

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    def _making(self) -> Any:
        """Where what it makes on first use belongs: the device's if `kept`, else the caller's."""
        return self.device.keeping() if self.kept else contextlib.nullcontext()

    def readback(self, frame_index: int) -> tuple[Buffer, Buffer]:
        """The (colour, depth) readback buffers of frame `frame_index`, made on first use."""
        if frame_index not in self._readbacks:
            with self._making():
                self._readbacks[frame_index] = self._readback_buffers(frame_index)
        return self._readbacks[frame_index]

    def _readback_buffers(self, frame_index: int) -> tuple[Buffer, Buffer]:
        return (self._host_buffer(self.pixel_bytes, f"color readback {frame_index}"),
                self._host_buffer(4, f"depth readback {frame_index}"))

    def _host_buffer(self, pixel_bytes: int, name: str) -> Buffer:
        """A host-visible transfer destination of `pixel_bytes` a pixel of the target."""
        n = self.extent[0] * self.extent[1]
        return self._own(Buffer(self.device, n * pixel_bytes,
                                self.device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                host_visible=True, name=name))

    # --- the protocol -----------------------------------------------------------------------
    def acquire(self, frame: Frame) -> int:
        return 0  # one image; frames in flight are ordered by the barriers below

    def resources(self, image: int, frame_index: int) -> dict[str, ImageResource | BufferResource]:
        """The images and readback buffers of frame `frame_index` as graph resources:
        "color", "depth" (with their MSAA images), "ids" (the compute path's visibility image),
        "color_readback", "depth_readback" and the outputs' images by their names (all but
        "ids" `copied`: the frame's readback copies them last)."""
        color = ImageResource(self.color.handle, view=self.attachments.color, copied=True)
        depth = ImageResource(self.depth.handle, depth=True, view=self.attachments.depth,
                              copied=True)
        if self.samples > 1:
            color.msaa = ImageResource(self._msaa[0].handle, view=self.attachments.msaa_color)
            depth.msaa = ImageResource(self._msaa[1].handle, depth=True,
                                       view=self.attachments.msaa_depth)
        out: dict[str, ImageResource | BufferResource] = {"color": color, "depth": depth}
        if self.compute:
            out["ids"] = ImageResource(self.visibility.handle,
                                              view=self.visibility_view.handle)
        color_buf, depth_buf = self.readback(frame_index)
        out["color_readback"] = BufferResource(color_buf, copied=True)
        out["depth_readback"] = BufferResource(depth_buf, copied=True)
        if self.outputs:
            buffers = self._outputs_readback(frame_index)
            for name, (img, view) in self.outputs.items():
                out[name] = ImageResource(img.handle, view=view.handle, copied=True)
                if name in buffers:
                    out[name + "_readback"] = BufferResource(buffers[name], copied=True)
        return out

    def finish_steps(self, image: int, frame_index: int, copy: tuple[str, ...],
                     tiles: tuple[int, int, int, int] | None = None, external: Any = None,
                     prefix: str = "", sources: OffscreenTarget | None = None) -> list[Step]:
        """"copy": what `copy` names copied into frame `frame_index`'s readback buffers
        (COPY_OUTPUTS: every output image, or those of them `copy` names too)
        (`tiles`, an atlas of a compute batch (views, tile width, height, tiles a column):
        colour and depth view by view, read_tiles; `external`: the colour into that exported
        buffer instead, for CUDA: taken back from the external queue family before the copy,
        released after it), then made visible to the host ("readback", untimed). `prefix`:
        this target's resource names' (`resources`); `sources`: the target whose depth and
        outputs are copied, under plain names (the frame drew into it: post steps)."""
        if not copy:
            return []
        src = self if sources is None else sources
        p, q = prefix, "" if sources is not None else prefix
        color_buf, depth_buf = self.readback(frame_index)
        images = []
        if COPY_COLOR in copy:
            images.append((p + "color", self.color, False, external or color_buf,
                           self.pixel_bytes, p + "color_readback"))
        if COPY_DEPTH in copy:
            images.append((q + "depth", src.depth, True, depth_buf, 4, p + "depth_readback"))
        outputs = self._outputs_readback(frame_index) if COPY_OUTPUTS in copy else {}
        named = [n for n in copy if n in outputs]  # (`copy` may name the images it reads)
        outputs = {n: outputs[n] for n in named} if named else outputs
        family, vk = self.device.queue_family, self.device.vk

        def record(cmd: Commands) -> None:
            if external is not None:
                barriers(cmd, [], [external_ownership(vk, family, external, True)])
            for _, img, depth, buf, nbytes, _ in images:
                copy_image_to_buffer(cmd, img.handle, depth, buf, self.extent, tiles=tiles,
                                     pixel_bytes=nbytes)
            for name, buf in outputs.items():  # (an atlas's: view by view, as the colour)
                copy_image_to_buffer(cmd, src.outputs[name][0].handle, False, buf,  # type: ignore[index]
                                     self.extent, tiles=tiles,
                                     pixel_bytes=src._output_bytes[name])
            if external is not None:
                barriers(cmd, [], [external_ownership(vk, family, external, False)])

        uses = [(name, "transfer_src") for name, *_ in images]
        uses += [(readback, "transfer_dst") for _, _, _, buf, _, readback in images
                 if buf is not external]
        uses += [(q + n, "transfer_src") for n in outputs]
        uses += [(f"{p}{n}_readback", "transfer_dst") for n in outputs]
        host = tuple((n, "host_read") for n, u in uses if u == "transfer_dst")
        return [Step("copy", record, tuple(uses)), Step("readback", uses=host, timed=False)]

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
        with self._making():
            for name, (fmt, nbytes) in formats.items():
                image = self._own(Image(self.device, w, h, getattr(vk, fmt), usage, name=name))
                self.outputs[name] = (image, self._own(ImageView(image)))
                self._output_bytes[name] = nbytes
        self._output_readbacks: dict[int, dict[str, Buffer]] = {}
        self._read_names: set[str] | None = None  # (None: every output is read back)
        return True

    def read_back_only(self, names: tuple[str, ...]) -> None:
        """Make readback buffers only for the output images `names` (and those named
        before): a compute batch's atlas, whose 60 bytes a pixel of outputs would take
        gigabytes of host memory a frame slot for images nobody asked for."""
        self._read_names = (self._read_names or set()) | set(names)

    def _outputs_readback(self, frame_index: int) -> dict[str, Buffer]:
        """The frame's outputs' readback buffers (of `read_back_only`'s names), made on
        first use."""
        names = self._output_bytes if self._read_names is None else self._read_names
        have = self._output_readbacks.setdefault(frame_index, {})
        missing = [n for n in names if n not in have]
        if missing:
            with self._making():
                have.update({n: self._host_buffer(self._output_bytes[n], f"{n} readback {frame_index}")
                             for n in missing})
        return have

    def read_outputs(self, frame_index: int, dtypes: dict[str, tuple[str, int]]) -> dict[str, np.ndarray]:
        """Copies of the frame's outputs: GLSL name -> (H, W, channels) array of `dtypes`'
        (NumPy dtype name, channels): `read_output_tiles` of the one view the frame is."""
        return {name: tiles[0] for name, tiles in
                self.read_output_tiles(frame_index, 1, self.extent, dtypes).items()}

    def read_output_tiles(self, frame_index: int, views: int, size: tuple[int, int],
                          dtypes: dict[str, tuple[str, int]]) -> dict[str, np.ndarray]:
        """Copies of an atlas frame's outputs (record_end's `tiles`): GLSL name -> (views,
        H, W, channels) array of `dtypes`' (NumPy dtype name, channels)."""
        w, h = size
        buffers = self._outputs_readback(frame_index)
        return {name: buffers[name].array(np.dtype(dt), views * w * h * ch)
                .reshape(views, h, w, ch).copy() for name, (dt, ch) in dtypes.items()}

    def submit(self, frame: Frame, cmd: Commands, image: int) -> bool:
        frame.submit(cmd)
        return True

    # --- readback ---------------------------------------------------------------------------
    def read_color(self, frame_index: int, split: bool = True) -> np.ndarray:
        """A copy of the frame's colour: (H, W, 4) uint8 ("srgb") or float32 ("float"),
        copied on the copy threads where it is big, unless not `split` (`copy_out`)."""
        dtype = np.uint8 if self.color_kind == "srgb" else np.float32
        w, h = self.extent
        return copy_out(self.readback(frame_index)[0].array(dtype, w * h * 4).reshape(h, w, 4),
                        split=split)

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
# releases the GIL in copyto). Below PARALLEL_BYTES the threads cost more than they save: on
# the H200's host (16 cores, benchmarks/bench_copy_out.py, 2026-12-04 run e) a 1080p RGBA8
# frame (7.9 MiB) took 0.64 ms on one thread, 0.45 on four; 3.5 MiB gained nothing. On two
# cores two threads lost at 7.9 MiB (0.28 -> 0.43 ms) and broke even at 31.6 MiB.
PARALLEL_BYTES = (6 << 20) if THREADS >= 4 else (32 << 20)


# A caller that is itself a thread beside the one that draws (render_many's collector) copies
# a frame below this alone: the copy threads' hand-offs took the GIL from the drawing thread
# (H200, Sponza 1080p RGBA8, 7.9 MiB: 0.68 -> 0.81 ms a copy split, the draws slower too);
# a bigger one (4K, float32 frames) still splits, or one thread's copy would outlast a frame.
ALONE_BYTES = 24 << 20


def copy_out(mapped: np.ndarray, into: np.ndarray | None = None, split: bool = True) -> np.ndarray:
    """`mapped` (a view of readback memory) copied into `into`, or into a new array; split
    along the first axis over threads when it is big (with `split` False, only from
    ALONE_BYTES)."""
    out = np.empty_like(mapped) if into is None else into
    big = mapped.nbytes >= (PARALLEL_BYTES if split else max(PARALLEL_BYTES, ALONE_BYTES))
    parts = min(THREADS, len(mapped)) if big else 1
    if parts <= 1:
        np.copyto(out, mapped)
        return out
    step = -(-len(mapped) // parts)
    spans = [slice(i, i + step) for i in range(0, len(mapped), step)]
    for done in [pool().submit(np.copyto, out[s], mapped[s]) for s in spans]:
        done.result()
    return out
