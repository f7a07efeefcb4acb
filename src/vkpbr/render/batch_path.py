"""The batch path: what `Renderer.render_batch` runs per submission.

`BatchPath` owns the batch's targets (gpu/batch_target.py, by size, chunk, colour kind and
copies), its GPU resources (render/batch.py BatchViews) and, for `device="cuda"`, the CUDA
imports of the targets' exported memory (gpu/cuda.py). Per submission it does what
`Renderer.draw` does for one frame, for many views: the frame's lights, environment and
shadow maps (directional ones over the whole scene), the blocks the views share, every
view's record (render/views.py) and blended order, the recorded commands, one submit, one
wait, one readback (or one device-to-device clone into torch). It is given the frame parts
it draws with (render/parts.py FrameParts), as the frame path is.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.batch_target import BatchTarget
from vkpbr.gpu.target import COPY_COLOR, COPY_DEPTH
from vkpbr.render import layouts as L
from vkpbr.render.ao import prepare_ao
from vkpbr.render.batch import MAX_LAYERS, BatchViews
from vkpbr.render.camera import linear_depth
from vkpbr.render.frame_path import read_timings
from vkpbr.render.frames import FrameStats, summed_stats, write_frame_blocks
from vkpbr.render.lighting import LightsArg
from vkpbr.render.options import RenderOptions
from vkpbr.render.parts import FrameParts
from vkpbr.render.post import batch_draw_size, batch_post
from vkpbr.render.steps import FrameObjects, FrameSpec
from vkpbr.render.views import ViewTerms, batch_view_terms
from vkpbr.scene.camera_batch import CameraBatch

__all__ = ["BatchPath", "COMPUTE_BYTES"]

# Device bytes a pixel of a compute batch's atlas needs besides its colour: depth 4, the
# visibility image 8, the rasteriser's depth|triangle 8, the pixel list 4, the big list ~1.
COMPUTE_BYTES = 25
ATLASES_KEPT = 2  # compute-batch atlases kept between calls (BatchPath._atlas)


class BatchPath:
    """The batch path of frames drawn with `parts` (its GPU objects made on the first
    batch, destroyed by `close`). `stats`: the last call's timings, its submissions' summed."""

    def __init__(self, parts: FrameParts) -> None:
        self.parts = parts
        self.stats = FrameStats()
        self.views: BatchViews | None = None
        self.targets: dict[tuple, BatchTarget] = {}
        self._cuda_imports: dict[int, Any] = {}  # gpu/cuda.py CudaImport by target
        self._cuda_events: dict[int, Any] = {}  # torch.cuda.Event of a buffer's last clone
        self._exports: dict[int, Any] = {}  # the compute batch's exported colour, by atlas
        # The compute batch's atlases, by (extent, linear), least recently used first: two
        # are kept (a job's full batches and its last, shorter one), older ones destroyed.
        self._atlases: OrderedDict[tuple, Any] = OrderedDict()
        self._submissions = 0  # of the render_batch call under way (its stats summed)
        self._t_start = 0.0  # when the submission under way began (its Python time)

    # --- whole batches ----------------------------------------------------------------------
    def run(self, route: str, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
            opts: RenderOptions, linear: bool, depth: bool, batch: int | str,
            out: np.ndarray | None = None) -> tuple[Any, np.ndarray | None]:
        """A render_batch call taking `route` (render/batch_route.py; not "views"): the colour
        (a torch tensor for "cuda") and the depth or None; the call's timings in `stats`."""
        if route == "cuda":
            return self.render_cuda(views, size, lights, opts, linear, batch), None
        if route == "compute":
            return self.render_compute(views, size, lights, opts, linear, depth, batch, out=out)
        return self.render(views, size, lights, opts, linear, depth, batch, out)

    def render(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
               opts: RenderOptions, linear: bool, depth: bool, batch: int | str,
               out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """Colour (and depth) of every view, in submissions of `per_submission` views; the
        colour into `out` where given."""
        per = self.per_submission(size, linear, depth, batch)
        self._submissions = 0
        colors, depths = [], []
        for start in range(0, len(views), per):
            stop = min(start + per, len(views))
            color, dist = self._submit(_slice(views, start, stop), size, lights, opts, linear,
                                       depth, into=None if out is None else out[start:stop])
            colors.append(color)
            depths.append(dist)
        return _joined(colors, out), (None if depths[0] is None else _joined(depths))

    def render_compute(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
                       opts: RenderOptions, linear: bool, depth: bool, batch: int | str,
                       cuda: bool = False, out: np.ndarray | None = None
                       ) -> tuple[Any, np.ndarray | None]:
        """The compute batch: each submission's views tiled in one atlas target, rasterised
        and shaded in compute shaders (render/compute_path.py's kernels, BATCH builds).
        `cuda`: the colour as one torch tensor (the atlas's tiles copied into exported memory
        that CUDA imports, as the layered batch's)."""
        limits = self.parts.device.limits
        most = int(limits.maxImageDimension2D)
        # (a lens batch draws its views' wider source pinholes: render/post.py batch_post)
        w, h = batch_draw_size(views, (int(size[0]), int(size[1])), most)
        # The atlas fits the image size limit, and its rasteriser buffer (8 bytes a pixel) one
        # storage-buffer binding; sized for this call's views, not more.
        per = min(self.per_submission(size, linear, depth, batch, COMPUTE_BYTES),
                  (most // w) * (most // h), int(limits.maxStorageBufferRange) // (8 * w * h),
                  len(views))
        if per < 1:
            raise UsageError(f"views of {w}x{h} are too large for the compute batch here; "
                             "use pipeline='forward'")
        # Tiles column-major, `rows` to a column (a column is one copy into view-major
        # memory: gpu/rendering.py tile_regions), about square, within the size limit.
        rows = max(1, min(per, most // h, max(math.ceil(math.sqrt(per)), -(-per // (most // w)))))
        cols = -(-per // rows)
        self._submissions = 0
        colors, depths = [], []
        for start in range(0, len(views), per):
            stop = min(start + per, len(views))
            color, dist = self._submit_compute(_slice(views, start, stop),
                                               (int(size[0]), int(size[1])), (cols, rows),
                                               lights, opts, linear, depth, cuda,
                                               None if out is None else out[start:stop])
            colors.append(color)
            depths.append(dist)
        if cuda:
            import torch

            return (colors[0] if len(colors) == 1 else torch.cat(colors)), None
        return _joined(colors, out), (_joined(depths) if depth else None)

    def _submit_compute(self, views: CameraBatch, size: tuple[int, int], grid: tuple[int, int],
                        lights: LightsArg, opts: RenderOptions, linear: bool, depth: bool,
                        cuda: bool = False, into: np.ndarray | None = None
                        ) -> tuple[Any, np.ndarray | None]:
        p, n = self.parts, len(views)
        (w, h), (cols, rows) = size, grid
        target = self._atlas((cols * w, rows * h), linear)
        external = self._exported(target, cols * rows * w * h) if cuda else None
        # The compute batch reads only the ViewRecords: keep whatever chunking the buffers
        # have (a new one reallocates them).
        chunk = self.views.chunk_views if self.views is not None else 0
        bv = self._views(n, chunk or max(1, min(n, MAX_LAYERS)))
        self._t_start = time.perf_counter()
        copy = (COPY_COLOR, COPY_DEPTH) if depth else (COPY_COLOR,)
        # Post steps (render/post.py batch_post: colour noise, a lens): drawn into an HDR atlas.
        post = batch_post(p, opts, views, size, grid, target, copy, linear)
        ao = prepare_ao(p.ao, p.recorder, opts, post.drawn or target, p.bounds.radius, False)
        shading_ao = ao is not None and ao.shading
        frame, plan, terms = self._begin(post.views, post.size, lights, post.shading,
                                         post.linear, rows, shading_ao)
        set0 = bv.sets0[frame.index]
        self._run(frame, plan, opts, lambda redraw: p.recorder.command_buffer(
            target, frame, 0, FrameSpec(
                "compute_batch", opts.tbn, opts.alpha_mask, plan, redraw, copy,
                variant=p.lighting.shade_variant(opts, shading_ao), tiles=(n, *post.size, rows),
                set0_id=id(set0), external_id=id(external), batch=(bv.generation,), ao=ao,
                post=post.post, post_tonemap=post.tonemap, lens=post.lens),
            FrameObjects(set0=set0, external=external), drawn=post.drawn),
            (lambda: self._cuda_wait(external)) if cuda else None)
        if cuda:
            p.device.check_validation()
            return self._cuda_tensor(external, (n, h, w, 4), linear), None
        t_read = time.perf_counter()
        color = target.read_tiles(frame.index, n, size, into=into)
        dist = None
        if depth:
            dist = linear_depth(target.read_tiles(frame.index, n, size, depth=True),
                                terms.znear[:, None, None])
        self.stats.readback_ms += 1e3 * (time.perf_counter() - t_read)
        p.device.check_validation()
        return color, dist

    def render_cuda(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
                    opts: RenderOptions, linear: bool, batch: int | str) -> Any:
        """The colour of every view as one torch tensor on the renderer's GPU."""
        from vkpbr.gpu.cuda import cuda_unavailable

        dev = self.parts.device
        why = cuda_unavailable()
        if why is None and not dev.external_memory_fd:
            why = f"{dev.info.name} cannot export memory (VK_KHR_external_memory_fd)"
        compute = self.parts.paths.takes_compute_batch(opts)
        if why is None and not compute and not dev.batch_views:
            why = f"{dev.info.name} lacks layered rendering for batches"
        if why is not None:
            raise UsageError(f"device='cuda' is not available here: {why}")
        if compute:  # the compute batch, its atlas's tiles into exported memory
            return self.render_compute(views, size, lights, opts, linear, False, batch,
                                       cuda=True)[0]
        import torch

        per = self.per_submission(size, linear, False, batch)
        self._submissions = 0
        parts = [self._submit(_slice(views, s, min(s + per, len(views))), size, lights, opts,
                              linear, False, cuda=True)[0] for s in range(0, len(views), per)]
        return parts[0] if len(parts) == 1 else torch.cat(parts)

    def per_submission(self, size: tuple[int, int], linear: bool, depth: bool,
                       batch: int | str, pixel_extra: int = 4) -> int:
        """Views per submission: `batch`, checked against the free memory, or for "auto" as
        many as fit in a quarter of it (device and host-visible readback), at most 65,536.
        `pixel_extra`: device bytes a pixel besides its colour (the layered batch's depth, or
        COMPUTE_BYTES)."""
        w, h = int(size[0]), int(size[1])
        pixel = 16 if linear else 4
        local, host = self.parts.device.memory_available()
        device_view = (w * h * (pixel + pixel_extra) + L.VIEW_RECORD.size
                       + 4 * len(self.parts.gpu_scene.draws))
        host_view = w * h * (pixel + (4 if depth else 0))
        fits = max(1, min(local // device_view, host // host_view))  # all of the free memory
        if batch == "auto":
            return max(1, min(fits // 4, 1 << 16))
        if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
            raise UsageError(f"batch {batch!r}: expected a positive number of views or 'auto'")
        if batch > fits:
            raise UsageError(f"batch {batch}: {batch:,} views of {w}x{h} need more memory than "
                             f"is free ({fits:,} fit); give batch='auto' or at most {fits // 2:,}")
        return batch

    # --- one submission ---------------------------------------------------------------------
    def _submit(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
                opts: RenderOptions, linear: bool, depth: bool, cuda: bool = False,
                into: np.ndarray | None = None) -> tuple[Any, np.ndarray | None]:
        p, n = self.parts, len(views)
        limits = p.device.limits
        layers = max(1, min(n, MAX_LAYERS, int(limits.maxFramebufferLayers),
                            int(limits.maxImageArrayLayers)))
        target = self._target(size, layers, n, linear, depth, cuda)
        self._t_start = time.perf_counter()
        bv = self._views(n, layers)
        frame, plan, terms = self._begin(views, size, lights, opts, linear)
        groups = bv.write_blend_groups(p.blend.orders(views.eye))
        self._run(frame, plan, opts, lambda redraw: bv.command_buffer(
            target, frame, n, opts.tbn, opts.alpha_mask, plan, groups, p.paths.prepass_for(target),
            redraw), (lambda: self._cuda_wait(target.color_readback)) if cuda else None)
        t_read = time.perf_counter()
        color = self._cuda_view(target, n, linear) if cuda else target.read_color(n, into)
        dist = linear_depth(target.read_depth(n), terms.znear[:, None, None]) if depth else None
        self.stats.readback_ms += 1e3 * (time.perf_counter() - t_read)
        p.device.check_validation()
        return color, dist

    def _views(self, n: int, chunk_views: int) -> BatchViews:
        """The batch's ViewRecords and draw lists, made on first use, holding `n` views."""
        p = self.parts
        if self.views is None:
            self.views = BatchViews(p.device, p.scene, p.gpu_scene, p.ring, p.slots,
                                    p.set_layouts[0], p.recorder, p.shadow_frames.maps,
                                    p.gpu_state)
        self.views.ensure(n, chunk_views)
        return self.views

    def _begin(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
               opts: RenderOptions, linear: bool, atlas_rows: int = 0, ao: bool = False
               ) -> tuple[Any, Any, ViewTerms]:
        """A submission's frame of the ring with what every batch writes: the frame's lights,
        environment and shadow matrices (directional ones over the whole scene), the blocks
        the views share and every view's record (`atlas_rows`: a compute batch's tiles a
        column, BatchViews.write_views; `ao`: its shading reads GTAO). Returns the frame, the shadow plan and the views'
        terms (views.batch_view_terms)."""
        p = self.parts
        frame_lights = p.lighting.frame_lights(opts, lights)
        p.environments.bind_for(opts)
        terms = batch_view_terms(views, size, p.bounds.corners, p.bounds.radius)
        frame = p.ring.begin()
        slot = p.slots[frame.index]
        p.gpu_state.write(frame.index)
        plan = p.shadow_frames.prepare(frame_lights, opts)
        rows = p.shadow_frames.write_scene(slot, plan, frame_lights)
        write_frame_blocks(slot, frame_lights, opts, linear, p.lighting.frame_lighting(opts, ao),
                           rows)
        self.views.write_views(terms, size, atlas_rows)  # type: ignore[union-attr]
        return frame, plan, terms

    def _run(self, frame: Any, plan: Any, opts: RenderOptions,
             record: Callable[[tuple[bool, ...]], Any], before_submit: Callable[[], None] | None = None
             ) -> None:
        """Record (given which shadow maps to redraw), submit and wait for a submission; its
        timings into `stats`. The shadow maps' record is forgotten if it fails."""
        p = self.parts
        shadows = p.shadow_frames.maps
        redraw = p.shadow_frames.stale(frame.index, plan, opts.alpha_mask)
        try:
            cmd = record(redraw)
            if before_submit is not None:
                before_submit()
            frame.submit(cmd)
        except BaseException:
            shadows.forget()
            raise
        frame.stamped = p.ring.query_pool is not None
        t_submitted = time.perf_counter()
        frame.wait()
        # The Python side up to the submit and the readback are added by the caller
        # (`_timed`); the wait is this submission's.
        stats = dataclasses.replace(read_timings(p.ring, frame, p.slots[frame.index]),
                                    cpu_ms=1e3 * (t_submitted - self._t_start), wait_ms=1e3 * (
                                        time.perf_counter() - t_submitted), readback_ms=0.0,
                                    driver_ms=0.0)
        # One call's timings: every submission's summed (a batch split by memory).
        self.stats = summed_stats(self.stats, stats) if self._submissions else stats
        self._submissions += 1

    def _target(self, size: tuple[int, int], layers: int, views: int, linear: bool,
                depth: bool, cuda: bool) -> BatchTarget:
        key = (tuple(size), layers, linear, depth, cuda)
        target = self.targets.get(key)
        if target is not None and target.capacity >= views:
            return target
        if target is not None:
            self.parts.device.wait_idle()
            self.free_recordings()
            self._forget_cuda(target)
            target.destroy()
        target = BatchTarget(self.parts.device, size, layers, views, "float" if linear else "srgb",
                             depth, clear_color=(*self.parts.targets.background, 0.0),
                             external=cuda)
        self.targets[key] = target
        return target

    # --- CUDA -------------------------------------------------------------------------------
    def _cuda_view(self, target: BatchTarget, views: int, linear: bool) -> Any:
        """A torch tensor of the first `views` views of an external target's colour."""
        w, h = target.extent
        return self._cuda_tensor(target.color_readback, (views, h, w, 4), linear)

    def _cuda_tensor(self, buf: Any, shape: tuple[int, ...], linear: bool) -> Any:
        """A torch tensor of `shape` from exported buffer `buf`: a clone (on torch's current
        stream) of the imported Vulkan memory; the next batch into the buffer waits for the
        clone (`_cuda_wait`)."""
        import torch

        from vkpbr.gpu.cuda import CudaImport, cuda_device_for

        imported = self._cuda_imports.get(id(buf))
        if imported is None:
            dev = self.parts.device
            index = cuda_device_for(dev.uuid(), dev.info.name)
            imported = CudaImport(buf.export_fd(), buf.allocation_size, index)
            self._cuda_imports[id(buf)] = imported
        out = imported.tensor(shape, "<f4" if linear else "|u1").clone()
        event = torch.cuda.Event()
        event.record()
        self._cuda_events[id(buf)] = event
        return out

    def _atlas(self, extent: tuple[int, int], linear: bool) -> Any:
        """The compute batch's atlas target of `extent`, made on first use; the least
        recently used beyond ATLASES_KEPT is destroyed with what was made for it."""
        key = (extent, linear)
        target = self._atlases.pop(key, None)
        if target is None:
            while len(self._atlases) >= ATLASES_KEPT:
                self._drop_atlas(self._atlases.popitem(last=False)[1])
            target = self.parts.targets.new(extent, linear)
        self._atlases[key] = target
        return target

    def _drop_atlas(self, target: Any) -> None:
        buf = self._exports.pop(id(target), None)
        if buf is not None:
            self._cuda_wait(buf)
            imported = self._cuda_imports.pop(id(buf), None)
            if imported is not None:
                imported.close()
        self.parts.targets.drop(target)  # waits for the device
        if buf is not None:
            buf.destroy()

    def _exported(self, target: Any, pixels: int) -> Any:
        """The compute batch's exported colour buffer for atlas `target` (`pixels` of it),
        made on first use: device-local memory CUDA imports (VK_KHR_external_memory_fd)."""
        from vkpbr.gpu.buffer import Buffer

        buf = self._exports.get(id(target))
        if buf is None:
            buf = Buffer(self.parts.device, pixels * target.pixel_bytes, "transfer_dst",
                         name="compute batch colour for CUDA", exportable=True)
            self._exports[id(target)] = buf
        return buf

    def _cuda_wait(self, owner: Any) -> None:
        """Before a batch writes an external target (or exported buffer): CUDA has finished
        copying the last one."""
        event = self._cuda_events.pop(id(owner), None)
        if event is not None:
            event.synchronize()

    def _forget_cuda(self, target: BatchTarget) -> None:
        self._cuda_wait(target.color_readback)
        imported = self._cuda_imports.pop(id(target.color_readback), None)
        if imported is not None:
            imported.close()

    # --- lifetime ---------------------------------------------------------------------------
    def free_recordings(self) -> None:
        if self.views is not None:
            self.views.free_recordings()

    def close(self) -> None:
        if self.views is not None:
            self.views.destroy()
            self.views = None
        for target in self.targets.values():
            self._forget_cuda(target)
            target.destroy()
        self.targets = {}
        while self._atlases:  # with the compute batch's exported colour
            self._drop_atlas(self._atlases.popitem(last=False)[1])


def _joined(parts: list[np.ndarray], out: np.ndarray | None = None) -> np.ndarray:
    """The submissions' arrays as one (`out` itself when they were written into it)."""
    if out is not None:
        return out
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _slice(views: CameraBatch, start: int, stop: int) -> CameraBatch:
    def part(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else a[start:stop]

    return CameraBatch(views.eye[start:stop], views.target[start:stop], views.up[start:stop],
                       views.yfov_deg[start:stop], part(views.intrinsics), part(views.znear),
                       part(views.zfar),
                       None if views.lenses is None else views.lenses[start:stop])
