"""The one frame path: a frame drawn into any target, and a stream of them read back.

`FramePath.draw(target, camera, lights, options)` takes the next frame of the ring
(gpu/frames.py; waits for its previous submission), acquires an image of the target
(gpu/target.py: offscreen images, or a window's swapchain), writes the frame's uniform blocks
(render/frames.py), picks the command buffer recorded for this (target image, frame, modes)
or records it (render/recorder.py), and submits it. `stream` is render_many's loop: up to
the ring's count of frames queued, each collected (waited for, its timings and pixels read)
in order. Neither measures nor chooses auto's path: the caller does, before its first frame
(render/path_choice.py FramePaths.choose).

It draws with the renderer's parts (render/parts.py FrameParts), as the batch path does.
"""

from __future__ import annotations

import collections
import dataclasses
import time
from collections.abc import Iterable, Iterator
from concurrent.futures import CancelledError, Future, wait
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.copy_threads import THREADS
from vkpbr.gpu.frames import Frame, FrameRing
from vkpbr.gpu.target import COPY_COLOR, COPY_DEPTH, COPY_OUTPUTS, FrameTarget, OffscreenTarget
from vkpbr.render import layouts as L
from vkpbr.render.ao import AoSpec, prepare_ao
from vkpbr.render.camera import as_camera, linear_depth, validate_camera
from vkpbr.render.frames import FrameSlot, FrameStats, write_frame_blocks, write_frame_view
from vkpbr.render.lens_cube import CubeFrame, draw_cube
from vkpbr.render.options import RenderOptions
from vkpbr.render.outputs import frame_outputs
from vkpbr.render.overlay import TextOverlay
from vkpbr.render.parts import FrameParts
from vkpbr.render.paths import choose_path
from vkpbr.render.post import LensFrame, check_lens, lens_frame, noise_key
from vkpbr.render.post_stage import check_post, enabled_post, encode_tonemap
from vkpbr.render.shadows import ShadowPlan
from vkpbr.render.steps import NO_OBJECTS, FrameObjects, FrameSpec
from vkpbr.scene.types import Camera, Light

__all__ = ["FramePath", "Submitted", "read_timings"]


@dataclass
class Submitted:
    """A frame handed to the GPU: `ok` is False when the target must be recreated (the
    frame was still submitted, or `frame` is None when no image could be acquired)."""

    frame: Frame | None
    image: int
    ok: bool


# Threads that collect a stream's frames, each a whole frame (wait, timestamps, copy out of its
# readback slot): two where there are 4 cores or more, so that consecutive frames' copies run
# side by side. One thread's copy of a 1080p RGBA8 frame out of mapped memory took 0.9-0.98 ms
# on the H200's host (session 25, probe_stream.py), longer than the GPU's 0.82 ms walk frame:
# the stream ran at the copy's rate. Each frame still costs the drawing thread one hand-off.
COLLECTORS = 2 if THREADS >= 4 else 1


def read_timings(ring: FrameRing, frame: Frame, slot: FrameSlot) -> FrameStats:
    """The frame's timestamps: one after each timed step of its recording (its
    `stamp_names`, set when it was looked up) into the slot's stats, returned."""
    names = frame.stamp_names
    t = ring.timings_ms(frame, len(names) + 1)
    slot.stats.gpu_ms = t[-1] if t else float("nan")
    bounds = [0.0, *t]
    slot.stats.pass_ms = {n: bounds[i + 1] - bounds[i] for i, n in enumerate(names)}
    return slot.stats


class FramePath:
    """Frames drawn with `parts` (see the module's docstring)."""

    def __init__(self, parts: FrameParts) -> None:
        self.parts = parts
        self._post_options: tuple[RenderOptions, RenderOptions] | None = None
        self._post: tuple[RenderOptions, tuple] | None = None
        self.cube_prev: dict[tuple, Any] = {}  # each cube face's last view (render/lens_cube.py)
        # An open stream's collects on the collector threads, by frame slot: a frame drawn
        # into that slot meanwhile (a `render()` between the stream's frames) waits for it.
        self._collecting: dict[int, Future] = {}

    def draw(self, target: FrameTarget, camera: Camera, lights: tuple[Light, ...],
             options: RenderOptions, overlay: TextOverlay | None = None, copy: tuple[str, ...] = (),
             linear: bool = False, timings: bool = True, driver_time: bool = False,
             source: tuple | None = None) -> Submitted:
        """Draw one frame into `target` and submit it (Renderer.draw says what each argument
        is); its Python time in the slot's stats.cpu_ms, the driver's in driver_ms. A wide
        fisheye draws a frame a cube face (render/lens_cube.py: `source`, a face's LensFrame)."""
        t0 = time.perf_counter()
        lens = (lens_frame(camera, target.extent, int(self.parts.device.limits.maxImageDimension2D))
                if source is None else LensFrame(source))
        with self.parts.device.lock:  # (the device's queue and ring: one thread's at a time)
            if isinstance(lens, CubeFrame):
                return draw_cube(self, target, camera, lens, lights=lights, options=options,
                                 overlay=overlay, copy=copy, linear=linear, timings=timings,
                                 driver_time=driver_time)
            return self._draw(t0, target, camera, lens, lights, options, overlay, copy, linear,
                              timings, driver_time)

    def _draw(self, t0: float, target: FrameTarget, camera: Camera, lens: LensFrame | None,
              lights: tuple[Light, ...], options: RenderOptions, overlay: TextOverlay | None,
              copy: tuple[str, ...], linear: bool, timings: bool, driver_time: bool
              ) -> Submitted:
        """`draw`'s frame, drawn as `lens` (None: the camera's pinhole) says."""
        p = self.parts
        p.environments.bind_for(options)
        transmission = p.lighting.screen_transmission(options)
        view, extent = (camera, target.extent) if lens is None else (lens.camera, lens.extent)
        if transmission and p.opaque_copies.stale(extent):
            self._fit_opaque_copies(extent)
        clock = time.thread_time if driver_time else _no_clock
        c0 = clock()
        frame = p.ring.begin()  # waits for the frame's previous submission
        self._copied(frame.index)
        slot = p.gpu_state.write(frame.index, p.slots)  # the slot, its scene state up to date
        if timings:
            read_timings(p.ring, frame, slot)
        image = target.acquire(frame)
        driver = clock() - c0
        if image is None:
            return Submitted(None, -1, False)
        plan = p.shadow_frames.prepare(lights, options)
        wanted = self._post_of(options)
        post = bool(wanted) and check_post(options, target, p.device.compute_path)
        if lens is not None:
            check_lens(camera, target, p.device.compute_path)
            post = True
        drawn = p.targets.post(target, copy, extent) if post else target  # (HDR with post steps)
        ao = prepare_ao(p.ao, p.recorder, options, drawn, p.bounds, COPY_OUTPUTS in copy)
        # The camera's maths, once: the shadow cascades take its planes from the slot.
        write_frame_view(slot, view, extent, p.bounds)
        p.gpu_state.write_motion(slot.index, slot.vp, COPY_OUTPUTS in copy)
        write_frame_blocks(slot, lights, self._shading_options(options, post), linear or post,
                           p.lighting.frame_lighting(options, ao is not None and ao.shading),
                           p.shadow_frames.write(slot, plan, lights, view, extent))
        if overlay is not None:
            overlay.prepare(frame.index)
        spec = self._spec(drawn, slot, options, plan, overlay, copy, linear, wanted if post else (),
                          transmission, post, lens.push if lens is not None else (), ao)
        if post and options.noise is not None:  # its random numbers' key: seed and view
            p.post().write_key(frame.index, noise_key(options.noise, camera, target.extent))
        order = p.blend.order(camera.eye)
        objects = FrameObjects(order, overlay) if order or overlay is not None else NO_OBJECTS
        shadows = p.shadow_frames.maps
        try:
            cmd = p.recorder.command_buffer(target, frame, image, spec, objects,
                                            drawn=drawn if post else None)
            c0 = clock()
            ok = target.submit(frame, cmd, image)
        except BaseException:
            shadows.forget()
            raise
        if not ok:
            shadows.forget()
        slot.stats.driver_ms = (driver + clock() - c0) * 1e3
        frame.stamped = p.ring.query_pool is not None
        slot.stats.cpu_ms = (time.perf_counter() - t0) * 1e3
        return Submitted(frame, image, ok)

    def _spec(self, drawn: FrameTarget, slot: FrameSlot, options: RenderOptions,
              plan: ShadowPlan, overlay: TextOverlay | None, copy: tuple[str, ...], linear: bool,
              post: tuple[tuple[str, float], ...], transmission: bool, encode: bool,
              lens: tuple[float, ...], ao: AoSpec | None) -> FrameSpec:
        """What the frame's recording depends on: its path, modes and shadow redraws."""
        p = self.parts
        redraw = p.shadow_frames.stale(slot.index, plan, options.alpha_mask)
        compute = p.paths.uses_compute(drawn, options)
        path = choose_path(compute, compute and p.paths.uses_compute_raster(options, drawn),
                           COPY_OUTPUTS in copy or ao is not None,
                           ao is not None and not getattr(drawn, "compute", False))
        variant = p.lighting.shade_variant(options, ao is not None and ao.shading)
        return FrameSpec(path, options.tbn, options.alpha_mask, plan, redraw, copy,
                         transmission, variant, id(overlay), post=post,
                         post_tonemap=encode_tonemap(options, linear) if encode else 0,
                         lens=lens, ao=ao)

    def _post_of(self, options: RenderOptions) -> tuple[tuple[str, float], ...]:
        """The post steps `options` turn on (the last answer kept: a run of frames has one
        options object)."""
        last = self._post
        if last is None or last[0] is not options:
            last = self._post = (options, enabled_post(options))
        return last[1]

    def _shading_options(self, options: RenderOptions, post: bool) -> RenderOptions:
        """The options the shading sees: with post steps, no tone map (the encode's; the
        last such copy kept: a run of frames has one options object)."""
        if not post or options.tonemap is None:
            return options
        last = self._post_options
        if last is None or last[0] is not options:
            last = self._post_options = (options, dataclasses.replace(options, tonemap=None))
        return last[1]

    def _fit_opaque_copies(self, extent: tuple[int, int]) -> None:
        """Copies of the opaque scene for frames of `extent` (render/transmission.py). Rare (a
        new size class): the old ones may be in use by queued frames and named by recorded
        command buffers, so wait for the device and drop the recordings."""
        p = self.parts
        p.device.wait_idle()
        p.recorder.free()
        if p.compute.made is not None:  # the compute path's buffers and sets for the old
            for old in p.opaque_copies.targets:
                p.compute.made.forget_target(old, destroy=True)
        p.opaque_copies.fit(extent)

    # --- reading frames back ----------------------------------------------------------------
    def stats(self, frame: Frame) -> FrameStats:
        """The stats of the frame slot `frame` (after `draw` with timings, or a collect)."""
        return self.parts.slots[frame.index].stats

    def read_timings(self, frame: Frame) -> FrameStats:
        """The GPU timestamps of `frame` (waited for) into its slot's stats, returned."""
        return read_timings(self.parts.ring, frame, self.parts.slots[frame.index])

    def read_color(self, target: FrameTarget, sub: Submitted) -> np.ndarray:
        """Wait for a frame drawn with copy=(COPY_COLOR,) and return its (H, W, 4) pixels."""
        sub.frame.wait()  # type: ignore[union-attr]
        return target.read_color(sub.frame.index)  # type: ignore[attr-defined, union-attr]

    # --- streams of frames into NumPy -------------------------------------------------------
    def stream(self, cameras: Iterable[Camera | Any], base: Camera, target: OffscreenTarget,
               lights: tuple[Light, ...], options: RenderOptions, linear: bool, depth: bool,
               readback: bool, outputs: tuple[str, ...], driver_time: bool = False
               ) -> Iterator[tuple[Any, FrameStats]]:
        """render_many's frames (None cameras: `base`): (what `collect` reads, the frame's
        stats) per camera, in order, with up to the ring's count of frames queued.
        With `readback`, from the second frame on each frame is collected (waited for, copied
        out) on the device's collector thread as soon as it is submitted (`_later`), while
        this thread draws the next: a frame's draw and the last one's copy into NumPy overlap
        instead of adding up (Sponza's walk with the sun at 1080p on the H200: a draw
        0.15-0.47 ms, a copy 0.57-0.67 ms). The frames still come in order, and a slot is
        drawn again only once its frame was collected."""
        copy = ((COPY_COLOR, COPY_DEPTH) if depth else (COPY_COLOR,)) if readback else ()
        if outputs and readback:
            copy = (*copy, COPY_OUTPUTS)
        pending: collections.deque[Future | _Deferred] = collections.deque()
        noisy = options.noise is not None and options.noise.depth
        target.streams += 1  # (kept while the stream is open: render/targets.py)
        try:
            for camera in cameras:
                camera = base if camera is None else as_camera(camera, base)
                validate_camera(camera)
                # A camera model's depth is its resampled output (render/post.py lens_steps),
                # a noisy one the outputs' (Noise): the depth buffer has neither.
                lens_depth = depth and readback and (camera.model != "pinhole" or noisy)
                cube = isinstance(lens_frame(camera, target.extent, int(
                    self.parts.device.limits.maxImageDimension2D)), CubeFrame)
                while pending and (len(pending) == self.parts.ring.count or cube):
                    # (a cube frame's face frames take the ring's slots: none may be queued)
                    yield self._take(pending.popleft())
                sub = self.draw(target, camera, lights, options,
                                copy=self._lens_copy(target, copy) if lens_depth else copy,
                                linear=linear, timings=False, driver_time=driver_time)
                args = (sub.frame, lens_depth, target, depth, readback, outputs)
                if readback and pending and isinstance(pending[0], _Deferred):  # (a second frame)
                    pending = collections.deque(self._later(d.args) for d in pending)
                pending.append(self._later(args) if readback and pending else _Deferred(self.collect, args))
            while pending:
                yield self._take(pending.popleft())
        finally:
            self._finish(pending)
            target.streams -= 1

    def _copied(self, slot: int) -> None:
        """Wait for an open stream's collect of frame slot `slot`'s last frame, if one is
        still copying out the readback the next frame of the slot draws into."""
        reading = self._collecting.pop(slot, None)
        if reading is not None and not reading.done():
            wait([reading])

    def _take(self, got: Future | _Deferred) -> tuple[Any, FrameStats]:
        """A stream's next frame (`_taken`), its collect no longer one a draw waits for (nor
        one that keeps the frame's arrays alive)."""
        taken = _taken(got)
        for slot, reading in list(self._collecting.items()):
            if reading is got:
                del self._collecting[slot]
        return taken

    def _later(self, args: tuple) -> Future:
        """`collect(*args)` on one of the device's COLLECTORS threads, copying the frame alone
        (not split over the copy threads: their hand-offs took the GIL from the drawing
        thread, H200 run c, 0.68 -> 0.81 ms a copy); the stream takes the results in order.
        The device's: no thread made a stream, and a device closed under an open stream
        finishes the collects under way first (Device.close)."""
        got = self.parts.device.in_background(lambda: self.collect(*args, False), COLLECTORS,
                                              "collect")
        self._collecting[args[0].index] = got
        return got

    def _finish(self, pending: collections.deque) -> None:
        """An abandoned stream: its collects not begun dropped, the one under way finished
        (it reads a slot the next frame may draw into), the frames not handed to the thread
        waited for (a slot's next draw waits for its frame's fence anyway)."""
        for got in pending:
            # (not `wait` on them all: a collect a closed device dropped is cancelled but
            # never "notified", and `wait` would wait for it for ever)
            if isinstance(got, Future) and not got.cancel():
                wait([got])
        if self.parts.device.handle is None:
            return  # (the device was closed under the stream: nothing is left to wait for)
        for got in pending:
            if isinstance(got, _Deferred):
                got.args[0].wait()

    def _lens_copy(self, target: OffscreenTarget, copy: tuple[str, ...]) -> tuple[str, ...]:
        """What a camera model's frame copies for `copy` with depth: the outputs (its depth
        among them) instead of the depth buffer, which it does not draw at its size."""
        self.parts.targets.ensure_outputs(target)
        return (*(c for c in copy if c not in (COPY_DEPTH, COPY_OUTPUTS)), COPY_OUTPUTS)

    def collect(self, frame: Frame, lens_depth: bool, target: OffscreenTarget, depth: bool,
                readback: bool, outputs: tuple[str, ...] = (), split: bool = True
                ) -> tuple[Any, FrameStats]:
        """Wait for `frame`; its timings, and with `readback` its colour (and depth, dataset
        outputs) from `target`: (what `render` returns or None, a copy of its stats).
        `lens_depth`: the depth is the resampled output's (a camera model's frame); `split`:
        a big colour copied on the copy threads (`copy_out`)."""
        slot = self.parts.slots[frame.index]
        stats = slot.stats
        t0 = time.perf_counter()
        frame.wait()
        t1 = time.perf_counter()
        stats.wait_ms = (t1 - t0) * 1e3
        read_timings(self.parts.ring, frame, slot)
        if not readback:
            return None, dataclasses.replace(stats, readback_ms=0.0)
        color = target.read_color(frame.index, split)
        images = None
        if outputs or lens_depth:
            dtypes = {name: (dt, ch) for name, (_, _, dt, ch) in L.OUTPUT_IMAGES.items()}
            images = target.read_outputs(frame.index, dtypes)
        out_depth = None
        if depth:
            out_depth = (images["out_depth_range"][..., 0].copy() if images is not None and lens_depth
                         else linear_depth(target.read_depth(frame.index), slot.znear))
        result: Any = (color, out_depth) if depth else color
        if outputs:
            result = frame_outputs(images, color, outputs,  # type: ignore[arg-type]
                                   np.asarray(slot.camera_rotation).reshape(3, 3).T)
        stats.readback_ms = (time.perf_counter() - t1) * 1e3
        stats = dataclasses.replace(stats)
        self.parts.device.check_validation()
        return result, stats


def _taken(got: Future | _Deferred) -> tuple[Any, FrameStats]:
    """A collect's result; one line where the renderer was closed before it ran."""
    try:
        return got.result()
    except CancelledError:
        raise UsageError("render_many: the renderer was closed while its frames were being "
                         "read; render again with an open renderer") from None


class _Deferred:
    """A frame's collect not handed to a thread (the stream's first, or without readback):
    made when its result is asked for, as a Future's would be."""

    def __init__(self, collect: Any, args: tuple) -> None:
        self.collect, self.args = collect, args

    def result(self) -> tuple[Any, FrameStats]:
        return self.collect(*self.args)


def _no_clock() -> float:
    return 0.0
