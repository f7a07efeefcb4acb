"""The targets a renderer draws into: its offscreen targets, the post stage's HDR targets,
new targets callers own, window swapchains and text overlays.

`Targets` keeps one offscreen target per (size, colour kind) and one HDR target per size for
frames with post steps (render/post_stage.py) in `kept`, the TARGETS_KEPT most recently
used, the device's (render/parts.py
DeviceParts: a Renderer's scenes draw into the same ones; they and what they make on first
use are made under `Device.keeping`, outside a scene's count; what a scene makes for a
target, its recordings and compute sets, is the scene's), checks sizes against the device's limits, makes the
dataset outputs' images of a target on first use, and destroys a caller's target with what
was recorded or made for it (command buffers, the compute path's per-target buffers).
`Lazy` is an object made on first use: the compute path's resources, the post kernels.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Any, Generic, TypeVar

import numpy as np

from vkpbr.gpu.device import Device
from vkpbr.gpu.swapchain import Surface, Swapchain
from vkpbr.gpu.target import COPY_OUTPUTS, FrameTarget, OffscreenTarget
from vkpbr.render import layouts as L
from vkpbr.render.compute_path import ComputeScene
from vkpbr.render.overlay import TextOverlay
from vkpbr.render.post_stage import PostKernels
from vkpbr.render.recorder import FrameRecorder
from vkpbr.scene._checks import frame_size

__all__ = ["Lazy", "Targets", "FREE_ATLASES"]

FREE_ATLASES = 2  # compute-batch atlases kept between scenes (a job's full and last batches)
# Offscreen and HDR targets kept (of different sizes), the least recently used destroyed past
# it: a dataset that renders every image at its own size had kept a target (and its compute
# buffers, GTAO images, recordings) per size until the renderer closed.
TARGETS_KEPT = 6

T = TypeVar("T")


class Lazy(Generic[T]):
    """`make()`'s object, made on the first call and then kept; `made` is None until then."""

    def __init__(self, make: Callable[[], T]) -> None:
        self._make = make
        self.made: T | None = None

    def __call__(self) -> T:
        if self.made is None:
            self.made = self._make()
        return self.made


class Targets:
    """The targets of frames drawn on `device` (see the module's docstring): `msaa` samples,
    `background` (linear RGB) where nothing is drawn, `frames` in flight (overlays have one
    set of quads each); `recorder` and `compute` hold what is recorded and made per target."""

    def __init__(self, device: Device, msaa: int, background: tuple[float, float, float],
                 frames: int, recorder: FrameRecorder, compute: Lazy[ComputeScene],
                 post: Lazy[PostKernels], kept: dict[tuple, OffscreenTarget] | None = None,
                 free_atlases: OrderedDict[tuple, OffscreenTarget] | None = None) -> None:
        self.device, self.msaa, self.background, self.frames = device, msaa, background, frames
        self.recorder, self.compute, self.post_kernels = recorder, compute, post
        self._kept: dict[tuple, OffscreenTarget] = {} if kept is None else kept
        self._device_kept = kept is not None  # (its targets the device's: `_keep`)
        # Compute-batch atlases a scene before gave back (`give_atlas`), the oldest first.
        self._free_atlases: OrderedDict[tuple, OffscreenTarget] = (
            OrderedDict() if free_atlases is None else free_atlases)

    def offscreen(self, size: tuple[int, int], linear: bool = False) -> OffscreenTarget:
        """The offscreen target of `size` (W, H): sRGB uint8, or float32 `linear`."""
        w, h = frame_size(size, int(self.device.limits.maxImageDimension2D))
        return self._keep((w, h, linear))

    def _keep(self, key: tuple) -> OffscreenTarget:
        """The kept target of `key` ((w, h, linear) or (w, h, "post"): float), made now
        (the device's, where `kept` was given) if there is none; the kept ones in the order
        they were last asked for, past TARGETS_KEPT the oldest destroyed."""
        target = self._kept.pop(key, None)
        if target is not None:
            self._kept[key] = target  # (the most recently used last)
            return target
        if not self._device_kept:
            target = self.new(key[:2], key[2] is not False)
        else:
            with self.device.keeping():
                target = self.new(key[:2], key[2] is not False)
            target.kept = True
        self._kept[key] = target
        self._evict()
        return target

    def _evict(self) -> None:
        """Destroy the least recently used kept targets past TARGETS_KEPT that no open
        frame stream draws into (`drop`: waits for the device)."""
        for key in list(self._kept)[:-1]:  # (never the one just made)
            if len(self._kept) <= TARGETS_KEPT:
                return
            if not self._kept[key].streams:
                self.drop(self._kept.pop(key))
                if key[2] == "post" and self.post_kernels.made is not None:
                    self.post_kernels.made.release(key[:2])  # (its post steps' images)

    def new(self, size: tuple[int, int], linear: bool) -> OffscreenTarget:
        """A new offscreen target of `size` the caller owns (the compute batch's atlases:
        render/batch_path.py; give it back with `drop`)."""
        return OffscreenTarget(self.device, size, "float" if linear else "srgb", self.msaa,
                               (*self.background, 0.0), compute=self.device.compute_path)

    def atlas(self, extent: tuple[int, int], linear: bool) -> OffscreenTarget:
        """A compute batch's atlas of `extent` (render/batch_path.py): one a scene before gave
        back, else a new one (the device's where targets are, else the caller's to `drop`)."""
        target = self._free_atlases.pop((*extent, linear), None)
        if target is not None:
            return target
        if not self._device_kept:
            return self.new(extent, linear)
        with self.device.keeping():
            target = self.new(extent, linear)
        target.kept = True
        return target

    def give_atlas(self, target: OffscreenTarget) -> None:
        """Done with atlas `target` (from `atlas`) at a scene's end, the device idle: kept for
        the next scene's batches, at most FREE_ATLASES (the oldest destroyed)."""
        if not target.kept:
            self.drop(target)
            return
        self._free_atlases[(*target.extent, target.color_kind == "float")] = target
        while len(self._free_atlases) > FREE_ATLASES:
            self._free_atlases.popitem(last=False)[1].destroy()

    def post(self, target: FrameTarget, copy: tuple[str, ...],
             extent: tuple[int, int] | None = None) -> OffscreenTarget:
        """The HDR target frames of `target` with post steps draw into (render/post_stage.py): the
        float colour (and depth, ids, outputs) of its size (or `extent`: a camera model's
        wider source, render/post.py lens_frame), kept here."""
        extent = target.extent if extent is None else extent
        hdr = self._keep((*extent, "post"))
        if COPY_OUTPUTS in copy:
            self.ensure_outputs(hdr)
        return hdr

    def drop(self, target: OffscreenTarget) -> None:
        """Destroy a target from `new` and everything recorded or made for it (command
        buffers, the compute path's per-target buffers). Waits for the device."""
        self.device.wait_idle()
        self.recorder.free(id(target))
        if self.compute.made is not None:
            self.compute.made.forget_target(target, destroy=True)
        if self.post_kernels.made is not None and target.storage_view is not None:
            self.post_kernels.made.forget(target.storage_view.handle)  # (its encode's set)
        if self.recorder.ao is not None:  # GTAO's sets name its depth view (render/ao.py)
            self.recorder.ao.forget(target.attachments.depth)
        target.destroy()

    def ensure_outputs(self, target: OffscreenTarget) -> None:
        """The dataset outputs' images of `target`, made on first use."""
        formats = {name: (fmt, nbytes) for name, (fmt, nbytes, _, _) in L.OUTPUT_IMAGES.items()}
        if target.ensure_outputs(formats) and self.compute.made is not None:
            # The target's compute set bound stand-ins: rebuild it and what draws into it.
            self.device.wait_idle()
            self.recorder.free(id(target))
            self.compute.made.forget_target(target)

    def window(self, create_surface: Callable[[Any, Any], int], size: tuple[int, int],
               vsync: bool = True) -> Swapchain:
        """A swapchain target on a window surface. `create_surface(instance, out)` makes the
        VkSurfaceKHR into the pointer `out` and returns a VkResult (GLFW's
        `glfw.create_window_surface(instance, window, None, out)`)."""
        surface = Surface(self.device, create_surface)
        # Alpha 0 where nothing is drawn, as offscreen frames: the window composites opaque
        # (VK_COMPOSITE_ALPHA_OPAQUE), and its screenshots equal `render`'s pixels.
        return Swapchain(self.device, surface, size, vsync=vsync,
                         clear_color=(*self.background, 0.0))

    def overlay(self, atlas: np.ndarray, target: FrameTarget) -> TextOverlay:
        """A textured-quad overlay (the viewer's HUD) drawn over frames of `target`'s formats."""
        return TextOverlay(self.device, atlas, target, self.frames)
