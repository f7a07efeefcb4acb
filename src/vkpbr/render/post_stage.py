"""The post stage: steps on a frame's HDR radiance after shading, and the encode ending them.

A frame with a post step on (its RenderOptions field, render/options.py POST_OPTIONS, is not
0) draws its path into the renderer's float target of its size: "color" holds the exposed
radiance (the shading multiplies by the exposure and tone maps nothing, as for
`linear=True`). The "post" group of the path (render/paths.py) then runs the enabled steps in
POST_OPTIONS' order on "color", and `encode` tone maps it into the output target
("out.color"): shaders/post_encode.comp where a compute shader can store into it, else
post_encode.frag as a fullscreen pass (a window's swapchain image, a multisampled target);
the overlay and the target's copies follow. A frame without post
steps tone maps and encodes in its shading (frame_output.glsl): one full-size image fewer to
write and read, as Filament skips its post-processing when none is enabled.

A post step is a `PostStep` subclass in render/post.py (the post steps, one class each),
its kernel shaders/post_<name>.comp (compiled by render/codegen.py, found by name) and its
row in POST_OPTIONS (the RenderOptions field and its flag). Its `steps` declare what they
read and write ("color", their own transient images from `PostKernels.transient`);
gpu/graph.py orders them.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.compute import ComputePipeline, groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import ImageResource, Rendering, Step
from vkpbr.gpu.image import Image, ImageView
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec
from vkpbr.render import layouts as L
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.options import POST_OPTIONS, RenderOptions

__all__ = ["PostStep", "PostKernels", "PostContext", "enabled_post",
           "encode_step", "encode_tonemap", "post_unavailable", "check_post"]

_SETS_PER_POOL = 64
KEY_BYTES = 128  # noise.glsl FrameKey
MAX_FRAME_SLOTS = 16  # frame slots with a key (gpu/frames.py rings have 3)
HDR_FORMAT = "VK_FORMAT_R32G32B32A32_SFLOAT"  # the target's float colour, and transients


class PostStep:
    """A post step: `option` names its RenderOptions field (a POST_OPTIONS row); `steps`
    makes its gpu/graph.py steps for one frame, reading and writing "color"."""

    option: ClassVar[str]

    def steps(self, ctx: PostContext, value: float) -> list[Step]:
        raise NotImplementedError


def enabled_post(options: RenderOptions) -> tuple[tuple[str, float], ...]:
    """(option, value) of the post steps `options` turn on, in POST_OPTIONS' order.
    VKPBR_HDR_FRAMES=1 (benchmarks/bench_post.py) sends frames without one through the HDR
    target and the encode all the same ("hdr", no step): what that costs, measured."""
    out = tuple((row.field, getattr(options, row.field) if row.parse else float(getattr(options, row.field)))
                for row in POST_OPTIONS if getattr(options, row.field))
    if not out and os.environ.get("VKPBR_HDR_FRAMES") == "1":
        return (("hdr", 0.0),)
    return out


def post_unavailable(target: Any, compute_path: bool) -> str | None:
    """Why frames of `target` cannot take post steps here, or None."""
    if not compute_path:
        return "this device lacks the compute path's features (storage image writes)"
    return None


class PostKernels:
    """A renderer's post kernels (a pipeline each; set layouts of N storage images, two for
    most kernels: source and destination), their descriptor sets and the steps' transient
    images (made on first use, kept)."""

    def __init__(self, device: Device) -> None:
        self.device = device
        self._layouts: dict[int, DescriptorSetLayout] = {}
        self.layout = self.set_layout(2)
        self._graphics_layout: PipelineLayout | None = None
        self._graphics: dict[tuple, Pipeline] = {}
        self._pools: dict[int, list[DescriptorPool]] = {}
        self._free: dict[int, int] = {}
        self._pipelines: dict[str, ComputePipeline] = {}
        self._sets: dict[tuple[int, ...], Any] = {}
        # Sets `forget` dropped (their views destroyed, nothing pending names them), by
        # their view count: the next image_set's, so that new sizes make no new pools.
        self._spare: dict[int, list[Any]] = {}
        # by (name, extent, format, owner: the frame size it serves; `release`)
        self._images: dict[tuple, tuple[Image, ImageView]] = {}
        self._keys: tuple[DescriptorSetLayout, Any, Buffer, DescriptorPool] | None = None
        # A compute batch's rows a view ("keys", "lens"; one batch is in flight at a time: its
        # submission is waited for): name -> (capacity in views, set, buffer, pool).
        self._view_buffers: dict[str, tuple[int, Any, Buffer, DescriptorPool]] = {}

    def set_layout(self, count: int) -> DescriptorSetLayout:
        """The set layout of `count` storage images (bindings 0..count-1), made on first use."""
        if count not in self._layouts:
            self._layouts[count] = DescriptorSetLayout(self.device, [
                BindingSpec(b, "storage_image", ("compute", "fragment")) for b in range(count)])
        return self._layouts[count]

    def pipeline(self, name: str, push_bytes: int, images: int = 2,
                 keys: bool = False) -> ComputePipeline:
        """Kernel shaders/spv/<name>.comp.spv, binding `images` storage images (set 0) and,
        with `keys`, the frames' keys (set 1: noise.glsl FrameKeys)."""
        if name not in self._pipelines:
            layouts = [self.set_layout(images)] + ([self.keys()[0]] if keys else [])
            self._pipelines[name] = ComputePipeline(self.device, SPV_DIR / f"{name}.comp.spv",
                                                    layouts, push_bytes=push_bytes)
        return self._pipelines[name]

    def keys(self) -> tuple[DescriptorSetLayout, Any, Buffer]:
        """The frames' keys (noise.glsl FrameKey, KEY_BYTES a frame slot, host-visible: each
        frame writes its own before it is submitted): (set layout, set, buffer), made once."""
        if self._keys is None:
            layout = DescriptorSetLayout(self.device, [BindingSpec(0, "storage", ("compute",))])
            pool = DescriptorPool(self.device, [(layout, 1)])
            buffer = Buffer(self.device, KEY_BYTES * MAX_FRAME_SLOTS,
                            self.device.vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, host_visible=True,
                            device_local=True, name="post frame keys")
            dset = pool.allocate(layout)
            writer = DescriptorWriter(self.device)
            writer.storage(dset, 0, buffer)
            writer.update()
            self._keys = (layout, dset, buffer, pool)
        return self._keys[:3]

    def write_key(self, frame_index: int, key: np.ndarray) -> None:
        """Frame slot `frame_index`'s key (KEY_BYTES: noise.glsl FrameKey), written before
        its submission (its previous one has finished: the ring waited for it)."""
        if frame_index >= MAX_FRAME_SLOTS:
            raise ValueError(f"frame slot {frame_index}: at most {MAX_FRAME_SLOTS}")
        self.keys()[2].write(np.ascontiguousarray(key).view(np.uint8), frame_index * KEY_BYTES)

    def view_keys_stale(self, views: int, name: str = "keys") -> bool:
        """Whether a batch of `views` views needs a larger buffer `name` ("keys": the noise's
        keys, "lens": the camera models' constants) than the one made (the caller then
        waits for the device and drops the recordings that bind it)."""
        made = self._view_buffers.get(name)
        return made is None or made[0] < views

    def write_view_keys(self, keys: np.ndarray, name: str = "keys") -> Any:
        """A compute batch's rows of `name` ((views, 32) float32 keys: noise.glsl FrameKey;
        or (views, 20) lens constants: lens.glsl LensParams) into its buffer (made or grown
        to fit: see view_keys_stale), bound as a set of the keys' layout; the set returned."""
        n, row = len(keys), np.ascontiguousarray(keys, np.float32).view(np.uint8)
        if self.view_keys_stale(n, name):
            self._destroy_view_buffer(name)
            capacity = 1 << max(6, (n - 1).bit_length())
            layout = self.keys()[0]
            pool = DescriptorPool(self.device, [(layout, 1)])
            buffer = Buffer(self.device, row.shape[1] * capacity,
                            self.device.vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, host_visible=True,
                            name=f"post batch {name}")
            dset = pool.allocate(layout)
            writer = DescriptorWriter(self.device)
            writer.storage(dset, 0, buffer)
            writer.update()
            self._view_buffers[name] = (capacity, dset, buffer, pool)
        _, dset, buffer, _ = self._view_buffers[name]
        buffer.write(row, 0)
        return dset

    def view_key_set(self, name: str = "keys") -> Any:
        """Buffer `name`'s set (write_view_keys made it), or None before the first."""
        made = self._view_buffers.get(name)
        return None if made is None else made[1]

    def _destroy_view_buffer(self, name: str) -> None:
        made = self._view_buffers.pop(name, None)
        if made is not None:
            made[3].destroy()
            made[2].destroy()

    def fragment_pipeline(self, name: str, target: Any, push_bytes: int) -> Pipeline:
        """Fragment shader shaders/spv/<name>.frag.spv over a fullscreen triangle, drawn into
        `target`'s formats (its colour; its depth attached, neither tested nor written)."""
        key = (name, target.color_format, target.depth_format, target.samples)
        if key not in self._graphics:
            if self._graphics_layout is None:
                self._graphics_layout = PipelineLayout(self.device, [self.layout], push_bytes,
                                                       stages=("fragment",))
            spec = PipelineSpec(vertex_shader="post_fullscreen.vert.spv",
                                fragment_shader=f"{name}.frag.spv", streams=(),
                                color_format=target.color_format,
                                depth_format=target.depth_format, samples=target.samples,
                                cull="none", depth_test=False, depth_write=False)
            self._graphics[key] = Pipeline(self.device, spec, self._graphics_layout, SPV_DIR)
        return self._graphics[key]

    def image_set(self, *views: Any) -> Any:
        """The set binding `views` (VkImageViews) as storage images 0, 1, ...: a kernel's
        source(s) then destination(s)."""
        key = tuple(int(self.device.vk.ffi.cast("uintptr_t", v)) for v in views)
        if key not in self._sets:
            spare = self._spare.get(len(views))
            dset = spare.pop() if spare else self._new_set(len(views))
            writer = DescriptorWriter(self.device)
            for binding, view in enumerate(views):
                writer.storage_image(dset, binding, _Handle(view))
            writer.update()
            self._sets[key] = dset
        return self._sets[key]

    def _new_set(self, n: int) -> Any:
        """A set of `n` storage images from the pools (a new pool when they are full)."""
        layout = self.set_layout(n)
        if not self._free.get(n):
            self._pools.setdefault(n, []).append(
                DescriptorPool(self.device, [(layout, _SETS_PER_POOL)]))
            self._free[n] = _SETS_PER_POOL
        self._free[n] -= 1
        return self._pools[n][-1].allocate(layout)

    def forget(self, view: Any) -> None:
        """Drop the sets naming `view` (a VkImageView about to be destroyed: a later view may
        get its handle value, and the cache is keyed by it)."""
        handle = int(self.device.vk.ffi.cast("uintptr_t", view))
        for key in [k for k in self._sets if handle in k]:
            # (the set stays in its pool, for the next image_set of as many views)
            self._spare.setdefault(len(key), []).append(self._sets.pop(key))

    def transient(self, name: str, extent: tuple[int, int], fmt: str = HDR_FORMAT,
                  owner: tuple[int, int] | None = None) -> tuple[Image, ImageView]:
        """Transient image `name` of `extent` (`fmt`: RGBA32F unless told, storage), made on
        first use, for frames of size `owner` (`release`). Frames in flight share it: a
        frame's first use waits for the frames before (gpu/graph.py)."""
        key = (name, extent, fmt, owner)
        if key not in self._images:
            vk = self.device.vk
            image = Image(self.device, extent[0], extent[1], getattr(vk, fmt),
                          vk.VK_IMAGE_USAGE_STORAGE_BIT, name=f"post {name}")
            self._images[key] = (image, ImageView(image))
        return self._images[key]

    def release(self, owner: tuple[int, int]) -> None:
        """Destroy the transient images made for frames of size `owner`, whose HDR target
        render/targets.py destroyed (the device idle, its recordings dropped), and recycle
        the sets naming them: a loop of ever new sizes keeps none."""
        for key in [k for k in self._images if k[3] == owner]:
            image, view = self._images.pop(key)
            self.forget(view.handle)
            view.destroy()
            image.destroy()

    def destroy(self) -> None:
        for image, view in self._images.values():
            view.destroy()
            image.destroy()
        self._images.clear()
        for p in [*self._pipelines.values(), *self._graphics.values()]:
            p.destroy()
        self._pipelines.clear()
        self._graphics.clear()
        if self._graphics_layout is not None:
            self._graphics_layout.destroy()
            self._graphics_layout = None
        for pools in self._pools.values():
            for pool in pools:
                pool.destroy()
        self._pools, self._sets, self._free, self._spare = {}, {}, {}, {}
        for layout in self._layouts.values():
            layout.destroy()
        self._layouts.clear()
        for name in list(self._view_buffers):
            self._destroy_view_buffer(name)
        if self._keys is not None:
            layout, _, buffer, pool = self._keys
            pool.destroy()
            layout.destroy()
            buffer.destroy()
            self._keys = None


@dataclass
class _Handle:
    """A raw VkImageView where DescriptorWriter takes an ImageView (`.handle`)."""

    handle: Any


@dataclass
class PostContext:
    """What a frame's post steps are made from: the kernels, the frame's size and
    resources (a step adds its transient images there), the HDR colour's view."""

    kernels: PostKernels
    extent: tuple[int, int]
    resources: dict[str, Any]
    color_view: Any  # the HDR "color" image's storage view (a VkImageView)
    # The graph resource holding the radiance the next steps read: "color", or a step's own
    # image where it changes the size (the camera models' resample: render/post.py Lens).
    color_name: str = "color"
    frame_index: int = 0  # the frame slot (its key: PostKernels.write_key)
    outputs: bool = False  # whether the frame copies out the dataset outputs
    outputs_prefix: str = ""  # where they are: the HDR target's, or "out." (a lens frame's)
    # A compute batch's atlas (views, tile width, height, tiles a column; None: one frame)
    # and its keys' set (PostKernels.write_view_keys: a key a view, from 0).
    tiles: tuple[int, int, int, int] | None = None
    key_set: Any = None
    # Calls that make the kernels `dispatch` handed out (the frame graph makes them at once:
    # render/steps.py gives them to the post group's first step as its Step.kernels)
    makers: list[Callable[[], ComputePipeline]] = field(default_factory=list)

    def view_tiles(self) -> tuple[int, int, int, int]:
        """(views, tile width, height, tiles a column): the atlas's, or the frame as one."""
        return self.tiles if self.tiles is not None else (1, *self.extent, 1)

    def first_key(self) -> int:
        """The index of the first view's key: the frame slot's, or 0 in a batch's keys."""
        return 0 if self.key_set is not None else self.frame_index

    def transient(self, name: str, extent: tuple[int, int], fmt: str = HDR_FORMAT) -> Any:
        """Transient image `name` as a graph resource (added to the frame's); its view."""
        image, view = self.kernels.transient(name, extent, fmt, self.extent)
        self.resources[name] = ImageResource(image.handle, view=view.handle, extent=extent)
        return view.handle

    def dispatch(self, name: str, push: np.ndarray, src: Any, dst: Any,
                 extent: tuple[int, int], *more: Any, keys: bool = False,
                 set1: Any = None) -> Callable[[Any], None]:
        """A recorder of kernel `name` over `extent` with views `src`, `dst` (and `more`
        views after them: bindings 2, 3, ...) and `push`; `keys`: the frames' keys as set 1
        (`set1`: another set of that layout, a batch's lens constants)."""
        kernels = self.kernels
        dset = kernels.image_set(src, dst, *more)
        make = functools.partial(kernels.pipeline, name, push.nbytes, 2 + len(more),
                                 keys or set1 is not None)
        self.makers.append(make)
        key_set = set1 if set1 is not None else (
            (self.key_set or kernels.keys()[1]) if keys else None)

        def record(cmd: Any) -> None:
            cmd.bind_pipeline(make())
            cmd.bind_set(0, dset)
            if key_set is not None:
                cmd.bind_set(1, key_set)
            cmd.push(push)
            cmd.dispatch(*groups((*extent, 1), (8, 8, 1)))
        return record


def encode_tonemap(options: RenderOptions, linear: bool) -> int:
    """The encode's tone map for frames with `options` (into a `linear` target or not): the
    frame's, none in debug views (they show values as they are)."""
    return int(options.tonemap_for(linear) if options.view == L.View.FINAL else L.Tonemap.NONE)


def encode_step(ctx: PostContext, out: Any, tonemap: int) -> Step:
    """"encode": "color" through `tonemap` (TONEMAP_*) into the output target `out`
    ("out.color"): stored by post_encode.comp where a compute shader can store into it (an
    offscreen single-sample target: sRGB-encoded by the kernel for an 8-bit one), else drawn
    by post_encode.frag (a window's image, a multisampled target: the attachment encodes)."""
    srgb = getattr(out, "color_kind", "srgb") == "srgb"
    push = np.array([tonemap, int(srgb)], np.int32)
    if getattr(out, "compute", False):
        record = ctx.dispatch("post_encode", push, ctx.color_view, out.storage_view.handle,
                              ctx.extent)
        return Step("encode", record, ((ctx.color_name, "storage_read"), ("out.color", "storage")))
    pipe = ctx.kernels.fragment_pipeline("post_encode", out, push.nbytes)
    dset = ctx.kernels.image_set(ctx.color_view, ctx.color_view)  # (binding 1 unread)

    def record(cmd: Any) -> None:
        cmd.bind_pipeline(pipe)
        cmd.bind_set(0, dset)
        cmd.push(push)
        cmd.draw(3)

    rendering = Rendering("out.color", "out.depth", None, None, store_depth=out.stores_depth)
    return Step("encode", record, ((ctx.color_name, "fragment_storage_read"),), rendering)


def check_post(options: RenderOptions, target: Any, compute_path: bool) -> bool:
    """Whether frames of `target` with `options` take post steps (UsageError where one is
    asked for and cannot be)."""
    wanted = enabled_post(options)
    if not wanted:
        return False
    why = post_unavailable(target, compute_path)
    if why is not None:
        flags = ", ".join(row.flag for row in POST_OPTIONS if row.field in dict(wanted))
        raise UsageError(f"{flags} not available here: {why}")
    return True
