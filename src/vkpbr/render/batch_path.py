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

import math
import time
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.batch_target import BatchTarget
from vkpbr.gpu.target import COPY_COLOR, COPY_DEPTH, COPY_OUTPUTS
from vkpbr.render import layouts as L
from vkpbr.render.ao import ao_pixel_bytes, prepare_ao
from vkpbr.render.batch import MAX_LAYERS, BatchViews
from vkpbr.render.batch_replay import Replays, StepStats, replay, replay_key
from vkpbr.render.camera import linear_depth
from vkpbr.render.cuda_order import CudaOrder
from vkpbr.render.frames import FrameStats, summed_stats, write_frame_blocks
from vkpbr.render.lighting import LightsArg
from vkpbr.render.options import RenderOptions
from vkpbr.render.parts import FrameParts
from vkpbr.render.post import batch_draw_size, batch_post, batch_post_bytes
from vkpbr.render.steps import FrameObjects, FrameSpec
from vkpbr.render.views import ViewTerms, batch_view_terms
from vkpbr.render.world_shadows import WorldShadows, world_plan
from vkpbr.render.worlds import WorldBuffers, WorldCall, WorldKernel
from vkpbr.scene.camera_batch import CameraBatch

__all__ = ["BatchPath", "COMPUTE_BYTES"]

# Device bytes a pixel of a compute batch's atlas needs besides its colour: depth 4, the
# visibility image 8, the rasteriser's depth|triangle 8, the pixel list 4, the big list ~1.
COMPUTE_BYTES = 25
# ... and with dataset outputs: their images (layouts.OUTPUT_IMAGES), as many bytes of
# host-visible readback.
OUTPUT_BYTES = sum(nbytes for _, nbytes, _, _ in L.OUTPUT_IMAGES.values())
ATLASES_KEPT = 2  # compute-batch atlases kept between calls (BatchPath._atlas)
BATCH_TARGETS_KEPT = 2  # layered-batch targets kept between calls (BatchPath._target)
MEMORY_AGE_S = 0.5  # how long a free-memory query serves the calls after it (per_submission)


# _cuda_events' mark of a buffer handed out as the frames themselves (frames='view'), not cloned
VIEWED = object()


class BatchPath:
    """The batch path of frames drawn with `parts` (its GPU objects made on the first
    batch, destroyed by `close`). `stats`: the last call's timings, its submissions' summed;
    `images`: the last compute batch's dataset output images asked for, GLSL name -> (views,
    H, W, channels), and "camera_rotation" (views, 3, 3), each view's rotation of world
    normals into its camera's axes (None where it asked none)."""

    def __init__(self, parts: FrameParts) -> None:
        self.parts = parts
        self.stats = FrameStats()
        self.images: dict[str, np.ndarray] | None = None
        self.views: BatchViews | None = None
        self.targets: dict[tuple, BatchTarget] = {}
        self._cuda_imports: dict[int, Any] = {}  # gpu/cuda.py CudaImport by target
        self._cuda_events: dict[int, Any] = {}  # torch.cuda.Event of a buffer's last clone
        self._cuda_made_events: dict[int, Any] = {}  # the event of each buffer, made once
        self._exports: dict[int, Any] = {}  # the compute batch's exported colour, by atlas
        # The compute batch's atlases, by (extent, linear), least recently used first: two
        # are kept (a job's full batches and its last, shorter one), older ones destroyed.
        self._atlases: OrderedDict[tuple, Any] = OrderedDict()
        self.world_buffers: WorldBuffers | None = None
        self.world_kernel: WorldKernel | None = None
        self.world_call: WorldCall | None = None  # the call under way's worlds, if any
        self._world_writes: list[int] = []  # per slot: which call's worlds it holds
        self.world_shadows: WorldShadows | None = None  # each world's maps (world_shadows.py)
        self._wshadow: tuple[Any, Any] | None = None  # the submission's (world plan, WorldJob)
        self._factor_writes = 0  # which call's factors the compute scene holds
        self._calls = 0
        self.cuda_order: CudaOrder | None = None  # made on the first CUDA-ordered call
        self._pending: tuple[Any, float] | None = None  # (frame, its Python ms) not waited for
        self._pending_stats = FrameStats()  # the last waited CUDA-ordered submission's
        self._ordered = False  # the submission under way is CUDA-ordered
        # BatchStep(frames='view'): the CUDA frames as a view of the exported memory (no clone)
        self.frames_view = False
        self._last_views: tuple | None = None  # (batch, key, instance bases, terms) written
        self._submissions = 0  # of the render_batch call under way (its stats summed)
        self._t_start = 0.0  # when the submission under way began (its Python time)
        self._memory: tuple[float, int, tuple[int, int]] | None = None  # _memory_available's
        self.replays = Replays()  # the steps a loop's next ones replay (render/batch_replay.py)
        self._replay: tuple | None = None  # replay_key's arguments of the call under way

    # --- whole batches ----------------------------------------------------------------------
    def run(self, route: str, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
            opts: RenderOptions, linear: bool, depth: bool, batch: int | str,
            out: np.ndarray | None = None, worlds: WorldCall | None = None,
            outputs: tuple[str, ...] = ()) -> tuple[Any, np.ndarray | None]:
        """A render_batch call taking `route` (render/batch_route.py; not "views"): the colour
        (a torch tensor for "cuda") and the depth or None; the call's timings in `stats`.
        `worlds`: each view sees its world (render/worlds.py); `outputs` (the compute batch):
        these dataset output images too (layouts.OUTPUT_IMAGES' names), into `images`."""
        self._calls += 1
        self._finish_pending()
        self._ordered = False
        self.world_call = worlds
        self.images = None
        try:
            key = None if outputs else replay_key(self, route, views, size, lights, opts, linear,
                                                  depth, batch)
            got = None if key is None else replay(self, key, out)
            if got is not None:
                return got
            # (the full path leaves its recording for the next step of the plan: _run)
            self._replay = None if key is None else (route, views, size, lights, opts, linear,
                                                     depth, batch)
            return self._run_route(route, views, size, lights, opts, linear, depth, batch, out,
                                   outputs)
        finally:
            self.world_call = None
            self._replay = None

    def _run_route(self, route: str, views: CameraBatch, size: tuple[int, int],
                   lights: LightsArg, opts: RenderOptions, linear: bool, depth: bool,
                   batch: int | str, out: np.ndarray | None, outputs: tuple[str, ...] = ()
                   ) -> tuple[Any, np.ndarray | None]:
        if route == "cuda":
            return self.render_cuda(views, size, lights, opts, linear, batch), None
        if route == "compute":
            return self.render_compute(views, size, lights, opts, linear, depth, batch, out=out,
                                       outputs=outputs)
        return self.render(views, size, lights, opts, linear, depth, batch, out)

    def render(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
               opts: RenderOptions, linear: bool, depth: bool, batch: int | str,
               out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """Colour (and depth) of every view, in submissions of `per_submission` views; the
        colour into `out` where given."""
        ao = ao_pixel_bytes(opts, len(self.parts.slots))  # (GTAO's images, each chunk's layers)
        per = self.per_submission(size, linear, depth, batch, 4 + ao)
        self._submissions = 0
        colors, depths = [], []
        for start in range(0, len(views), per):
            stop = min(start + per, len(views))
            color, dist = self._submit(_slice(views, start, stop), size, lights, opts, linear,
                                       depth, into=None if out is None else out[start:stop],
                                       start=start)
            colors.append(color)
            depths.append(dist)
        return _joined(colors, out), (None if depths[0] is None else _joined(depths))

    def render_compute(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
                       opts: RenderOptions, linear: bool, depth: bool, batch: int | str,
                       cuda: bool = False, out: np.ndarray | None = None,
                       outputs: tuple[str, ...] = ()) -> tuple[Any, np.ndarray | None]:
        """The compute batch: each submission's views tiled in one atlas target, rasterised
        and shaded in compute shaders (render/compute_path.py's kernels, BATCH builds).
        `cuda`: the colour as one torch tensor (the atlas's tiles copied into exported memory
        that CUDA imports, as the layered batch's); `outputs`: these dataset output images
        too (`images`, their tiles read back as the colour's)."""
        limits = self.parts.device.limits
        most = int(limits.maxImageDimension2D)
        # (a lens batch draws its views' wider source pinholes: render/post.py batch_post)
        w, h = batch_draw_size(views, (int(size[0]), int(size[1])), most)
        # The atlas fits the image size limit, and its rasteriser buffer (8 bytes a pixel) one
        # storage-buffer binding; sized for this call's views, not more.
        extra = (COMPUTE_BYTES + batch_post_bytes(opts, views, size, (w, h))
                 + ao_pixel_bytes(opts, len(self.parts.slots)) + (OUTPUT_BYTES if outputs else 0))
        read = sum(L.OUTPUT_IMAGES[n][1] for n in outputs)  # (readback bytes a pixel)
        per = min(self.per_submission(size, linear, depth, batch, extra, read),
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
        colors, depths, images = [], [], []
        for start in range(0, len(views), per):
            stop = min(start + per, len(views))
            color, dist = self._submit_compute(_slice(views, start, stop),
                                               (int(size[0]), int(size[1])), (cols, rows),
                                               lights, opts, linear, depth, cuda,
                                               None if out is None else out[start:stop], start,
                                               outputs)
            colors.append(color)
            depths.append(dist)
            images.append(self.images)
        if outputs:  # (each submission's, joined as the colours)
            self.images = {n: _joined([got[n] for got in images]) for n in images[0]}
        if cuda:
            import torch

            return (colors[0] if len(colors) == 1 else torch.cat(colors)), None
        return _joined(colors, out), (_joined(depths) if depth else None)

    def _submit_compute(self, views: CameraBatch, size: tuple[int, int], grid: tuple[int, int],
                        lights: LightsArg, opts: RenderOptions, linear: bool, depth: bool,
                        cuda: bool = False, into: np.ndarray | None = None, start: int = 0,
                        outputs: tuple[str, ...] = ()) -> tuple[Any, np.ndarray | None]:
        p, n = self.parts, len(views)
        (w, h), (cols, rows) = size, grid
        target = self._atlas((cols * w, rows * h), linear)
        if outputs:  # (before any recording: making them rebuilds the atlas's compute set)
            p.targets.ensure_outputs(target)
            target.read_back_only(outputs)
        external = self._exported(target, cols * rows * w * h) if cuda else None
        # The compute batch reads only the ViewRecords: keep whatever chunking the buffers
        # have (a new one reallocates them).
        chunk = self.views.chunk_views if self.views is not None else 0
        bv = self._views(n, chunk or max(1, min(n, MAX_LAYERS)))
        self._t_start = time.perf_counter()
        copy = (COPY_COLOR, COPY_DEPTH) if depth else (COPY_COLOR,)
        copy = (*copy, COPY_OUTPUTS, *outputs) if outputs else copy  # (only the images read)
        # Post steps (render/post.py batch_post: colour noise, bloom, a lens): drawn into an
        # HDR atlas.
        post = batch_post(p, opts, views, size, grid, target, copy, linear)
        ao = prepare_ao(p.ao, p.recorder, opts, post.drawn or target, p.bounds,
                        "out_ao" in outputs, post.size)
        shading_ao = ao is not None and ao.shading
        order = self._order(cuda)
        self._ordered = order is not None  # (the worlds' inputs are written in _begin)
        frame, plan, terms = self._begin(post.views, post.size, lights, post.shading,
                                         post.linear, rows, shading_ao, start)
        set0 = bv.set0(frame.index, self.world_call is not None and self.world_call.poses)
        # Blended draws: each group of views sharing a back-to-front order draws them into
        # its views' tiles (the layered batch's groups, every chunk's in one atlas).
        groups = (tuple(g for chunk in bv.write_blend_groups(self._blend_orders(post.views, start))
                        for g in chunk) if len(p.blend) else ())

        def finish(fr: Any, into: np.ndarray | None, order: CudaOrder | None
                   ) -> tuple[Any, np.ndarray | None]:
            return self._compute_result(fr, target, n, size, into, terms if depth else None,
                                        external, linear, order,
                                        (terms, outputs) if outputs else None)

        # (replayable: render/batch_replay.py)
        whole = post.drawn is None and not depth and not outputs
        self._run(frame, plan, opts, lambda redraw: p.recorder.command_buffer(
            target, frame, 0, FrameSpec(
                "compute_batch", opts.tbn, opts.alpha_mask, plan, redraw, copy,
                variant=p.lighting.shade_variant(opts, shading_ao, self._hand_reads()),
                tiles=(n, *post.size, rows),
                set0_id=id(set0), external_id=id(external), batch=(bv.generation, *self._world_key()),
                ao=ao, post=post.post, post_tonemap=post.tonemap, lens=post.lens),
            FrameObjects(groups, set0=set0, external=external), self._world_groups(),
            drawn=post.drawn),
            external, order, finish if whole and self._whole(views) else None)
        return finish(frame, into, order)

    def _compute_result(self, frame: Any, target: Any, n: int, size: tuple[int, int],
                        into: np.ndarray | None, terms: ViewTerms | None, external: Any,
                        linear: bool, order: CudaOrder | None,
                        outputs: tuple[ViewTerms, tuple[str, ...]] | None = None
                        ) -> tuple[Any, np.ndarray | None]:
        """A compute batch's submission's colour (a torch tensor where `external`: its
        exported copy) and depth (where `terms`), once submitted; with `outputs` (the views'
        terms, the output images copied) those images into `images`."""
        p = self.parts
        if external is not None:
            p.device.check_validation()
            if order is not None:
                order.frames_ready()
            w, h = size
            return self._cuda_tensor(external, (n, h, w, 4), linear), None
        t_read = time.perf_counter()
        color = target.read_tiles(frame.index, n, size, into=into)
        dist = None
        if terms is not None:
            dist = linear_depth(target.read_tiles(frame.index, n, size, depth=True),
                                terms.znear[:, None, None])
        if outputs is not None:
            views, names = outputs
            dtypes = {name: L.OUTPUT_IMAGES[name][2:] for name in names}
            self.images = target.read_output_tiles(frame.index, n, size, dtypes)
            self.images["camera_rotation"] = view_rotations(views, n)
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

        per = self.per_submission(size, linear, False, batch,
                                  4 + ao_pixel_bytes(opts, len(self.parts.slots)))
        self._submissions = 0
        parts = [self._submit(_slice(views, s, min(s + per, len(views))), size, lights, opts,
                              linear, False, cuda=True, start=s)[0]
                 for s in range(0, len(views), per)]
        return parts[0] if len(parts) == 1 else torch.cat(parts)

    def per_submission(self, size: tuple[int, int], linear: bool, depth: bool,
                       batch: int | str, pixel_extra: int = 4, host_extra: int = 0) -> int:
        """Views per submission: `batch`, checked against the free memory, or for "auto" as
        many as fit in a quarter of it (device and host-visible readback), at most 65,536.
        `pixel_extra`: device bytes a pixel besides its colour (the layered batch's depth, or
        COMPUTE_BYTES); `host_extra`: readback bytes a pixel besides the colour and depth."""
        w, h = int(size[0]), int(size[1])
        pixel = 16 if linear else 4
        local, host = self._memory_available()
        device_view = (w * h * (pixel + pixel_extra) + L.VIEW_RECORD.size
                       + 4 * len(self.parts.gpu_scene.draws))
        host_view = w * h * (pixel + (4 if depth else 0) + host_extra)
        fits = max(1, min(local // device_view, host // host_view))  # all of the free memory
        if batch == "auto":
            return max(1, min(fits // 4, 1 << 16))
        if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
            raise UsageError(f"batch {batch!r}: expected a positive number of views or 'auto'")
        if batch > fits:
            raise UsageError(f"batch {batch}: {batch:,} views of {w}x{h} need more memory than "
                             f"is free ({fits:,} fit); give batch='auto' or at most {fits // 2:,}")
        return batch

    def _memory_available(self) -> tuple[int, int]:
        """Device.memory_available, asked again once MEMORY_AGE_S has passed or vkpbr's own
        allocations changed (a loop's steps would query the driver's budget each call: tens
        of microseconds through the Vulkan binding on NVIDIA)."""
        dev, now = self.parts.device, time.perf_counter()
        count = dev.live_children  # (a buffer or image made or destroyed changes it)
        last = self._memory
        if last is None or now - last[0] > MEMORY_AGE_S or last[1] != count:
            last = self._memory = (now, count, dev.memory_available())
        return last[2]

    # --- one submission ---------------------------------------------------------------------
    def _submit(self, views: CameraBatch, size: tuple[int, int], lights: LightsArg,
                opts: RenderOptions, linear: bool, depth: bool, cuda: bool = False,
                into: np.ndarray | None = None, start: int = 0) -> tuple[Any, np.ndarray | None]:
        p, n = self.parts, len(views)
        limits = p.device.limits
        layers = max(1, min(n, MAX_LAYERS, int(limits.maxFramebufferLayers),
                            int(limits.maxImageArrayLayers)))
        target = self._target(size, layers, n, linear, depth, cuda)
        self._t_start = time.perf_counter()
        bv = self._views(n, layers)
        ao = prepare_ao(p.ao, p.recorder, opts, target, p.bounds, False)
        frame, plan, terms = self._begin(views, size, lights, opts, linear,
                                         ao=ao is not None and ao.shading, start=start)
        groups = bv.write_blend_groups(self._blend_orders(views, start))

        def finish(fr: Any, into: np.ndarray | None, order: Any) -> tuple[Any, np.ndarray | None]:
            return self._layered_result(target, n, into, terms if depth else None, cuda, linear)

        self._run(frame, plan, opts, lambda redraw: bv.command_buffer(
            target, frame, n, opts.tbn, opts.alpha_mask, plan, groups, p.paths.prepass_for(target),
            redraw, self._world_key() if self.world_call is not None and self.world_call.poses else None,
            self._world_groups(), ao), target.color_readback if cuda else None, None,
            None if depth or not self._whole(views) else finish)
        return finish(frame, into, None)

    def _blend_orders(self, views: CameraBatch, start: int) -> np.ndarray:
        """The blended draws' back-to-front order of each of `views` (the call's views from
        `start` on): placed by its world's draw records where the host made them (as `render`
        of that world orders them), else as the renderer's state places them (worlds the GPU
        expands: docs/batch.md)."""
        blend, call = self.parts.blend, self.world_call
        if call is not None and call.records is not None:
            return blend.world_orders(views.eye, call.records,
                                      call.world_of_view[start:start + len(views)])
        return blend.orders(views.eye)

    def _layered_result(self, target: BatchTarget, n: int, into: np.ndarray | None,
                        terms: ViewTerms | None, cuda: bool, linear: bool
                        ) -> tuple[Any, np.ndarray | None]:
        """A layered batch's submission's colour (a torch tensor for `cuda`) and depth
        (where `terms`), once submitted."""
        t_read = time.perf_counter()
        color = self._cuda_view(target, n, linear) if cuda else target.read_color(n, into)
        dist = None if terms is None else linear_depth(target.read_depth(n),
                                                       terms.znear[:, None, None])
        self.stats.readback_ms += 1e3 * (time.perf_counter() - t_read)
        self.parts.device.check_validation()
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
               opts: RenderOptions, linear: bool, atlas_rows: int = 0, ao: bool = False,
               start: int = 0) -> tuple[Any, Any, ViewTerms]:
        """A submission's frame of the ring with what every batch writes: the frame's lights,
        environment and shadow matrices (directional ones over the whole scene), the blocks
        the views share and every view's record (`atlas_rows`: a compute batch's tiles a
        column, BatchViews.write_views; `ao`: its shading reads GTAO; `start`: the first
        view's index in the call, for its worlds). Returns the frame, the shadow plan and the
        views' terms (views.batch_view_terms)."""
        p = self.parts
        frame_lights = p.lighting.frame_lights(opts, lights)
        p.environments.bind_for(opts)
        plan = p.shadow_frames.prepare(frame_lights, opts)
        ws = self._shadow_worlds(plan, opts)  # (its errors come before any GPU work)
        frame = p.ring.begin()
        slot = p.slots[frame.index]
        p.gpu_state.write(frame.index)
        if ws is None:
            rows = p.shadow_frames.write_scene(slot, plan, frame_lights)
        else:  # each world's own maps (render/world_shadows.py)
            rows = p.shadow_frames.write_worlds(slot, ws[0], frame_lights, opts.world_shadow_resolution,
                                                (ws[1].stride, ws[1].cube_base))
        write_frame_blocks(slot, frame_lights, opts, linear, p.lighting.frame_lighting(opts, ao),
                           rows)
        base = self._write_worlds(frame.index, start, len(views))
        if ws is not None and ws[1].kept is not None:  # (after the state's records: the kept map's)
            assert self.world_shadows is not None and self.views is not None
            self.world_shadows.prepare_kept(p, self.views.set0(frame.index, True), frame.index,
                                            ws[0], ws[1], ws[2], opts.alpha_mask)
        shadow_base = None  # each view's world's own maps: 1 + its world
        if ws is not None and self.world_call is not None:
            shadow_base = (1 + self.world_call.world_of_view[start:start + len(views)]).astype(np.uint32)
        base = (*base, shadow_base)
        return frame, plan, self._view_records(views, size, atlas_rows, base)

    def _shadow_worlds(self, plan: Any, opts: RenderOptions) -> tuple[Any, Any] | None:
        """A batch of worlds that moves shadow casters: its world plan and maps (WorldJob,
        render/world_shadows.py), kept for the submission; None (the state's maps, shared)
        for other batches."""
        p, call = self.parts, self.world_call
        self._wshadow = None
        if call is None or not plan.entries or not call.poses:
            return None
        if self.world_shadows is None:
            self.world_shadows = WorldShadows(p.shadow_frames.maps)
        ws = self.world_shadows
        moved = ws.moved_casters(call, p.gpu_scene.draws)  # (None: not known which: all)
        if moved is not None and not moved.any():  # the state's maps hold every world's
            return None
        d = max(len(p.gpu_scene.draws), 1)
        worlds = call.gpu.worlds if call.gpu is not None else len(call.records) // d  # type: ignore[arg-type]
        wplan = world_plan(plan)
        job, made = ws.job(wplan, opts.world_shadow_resolution, worlds, d)
        if made:  # set 3 rewritten: every recording that binds it
            p.recorder.free()
            self.free_recordings()
        self._wshadow = (wplan, ws.with_kept(job, p.gpu_scene.draws, moved), moved)
        return self._wshadow

    def _view_records(self, views: CameraBatch, size: tuple[int, int], atlas_rows: int,
                      base: tuple[Any, Any]) -> ViewTerms:
        """Write the views' records, unless they hold these already: the same batch (a
        CameraBatch never changes), size, tiling, scene bounds and worlds as the last
        submission's (a simulator's loop renders the same cameras every step)."""
        p = self.parts
        key = (size, atlas_rows, p.bounds.corners, p.bounds.radius, self.views.generation)  # type: ignore[union-attr]
        last = self._last_views
        if (last is not None and last[0] is views and last[1] == key
                and all(_same(a, b) for a, b in zip(base, last[2], strict=True))):
            return last[3]
        terms = batch_view_terms(views, size, p.bounds.corners, p.bounds.radius)
        self.views.write_views(terms, size, atlas_rows, *base)  # type: ignore[union-attr]
        self._last_views = (views, key, base, terms)
        return terms

    def _write_worlds(self, slot: int, start: int, n: int) -> tuple[Any, Any]:
        """In a batch of worlds: slot `slot`'s world records and the worlds' material
        factors (once a call); the instance_base and factor_base of views start..start+n
        (each None where the worlds do not have it)."""
        call = self.world_call
        if call is None:
            return None, None
        index = call.world_of_view
        if start or n != len(index):  # (the whole array itself where it is: its identity
            index = index[start:start + n]  # keys what was made of it)
        factor_base = None
        if call.factors is not None:
            if self._factor_writes != self._calls:
                assert self.views is not None  # (made before the submission's frame)
                self.views.set_world_factors(call.factors.reshape(-1, 4))
                self._factor_writes = self._calls
            stride = call.factors.shape[1]  # a world's block (shaders/worlds.glsl)
            factor_base = (1 + index * stride).astype(np.uint32)
        if not call.poses:
            return None, factor_base
        return self._write_poses(slot, index), factor_base

    def _write_poses(self, slot: int, index: np.ndarray) -> np.ndarray:
        call = self.world_call
        assert call is not None
        p, bv = self.parts, self.views
        assert bv is not None
        if self.world_buffers is None:
            self.world_buffers = WorldBuffers(p.device, len(p.slots), len(p.gpu_scene.draws))
            self._world_writes = [0] * len(p.slots)
        wb = self.world_buffers
        gpu = call.gpu
        worlds = gpu.worlds if gpu is not None else len(call.records) // wb.draws
        if wb.ensure(worlds) or bv.worlds is not wb:
            bv.bind_worlds(wb)
            self._world_writes = [0] * len(p.slots)
        if gpu is not None and self._world_writes.count(self._calls) == 0:
            if self.world_kernel is None:
                self.world_kernel = WorldKernel(p.device, len(p.slots))
            kernel = self.world_kernel
            before = kernel.generation
            kernel.order = self.cuda_order if self._ordered else None
            kernel.prepare(gpu, wb, gpu.cuda)  # the call's poses into its inputs
            if kernel.generation != before:
                self.free_recordings()
        if self._world_writes[slot] != self._calls:
            state = p.gpu_state.state.draw_matrices()
            wb.write(slot, state, call.records if gpu is None else np.zeros(0, np.float32))
            self._world_writes[slot] = self._calls
        return wb.instance_base(index)

    def _order(self, cuda: bool) -> CudaOrder | None:
        """The GPU-side ordering of a call whose inputs are CUDA tensors and whose frames go to
        torch, where the driver shares semaphores (else None: the host waits, as before)."""
        call = self.world_call
        if not (cuda and call is not None and call.gpu is not None and call.gpu.cuda):
            return None
        if not CudaOrder.available(self.parts.device):
            return None
        if self.cuda_order is None:
            self.cuda_order = CudaOrder(self.parts.device)
        return self.cuda_order

    def _finish_pending(self) -> None:
        """Wait for the last CUDA-ordered submission (its host-written buffers are then free)
        and keep its GPU timings for the next such call's stats."""
        if self._pending is None:
            return
        frame, cpu_ms = self._pending
        self._pending = None
        frame.wait()
        self._world_errors(frame.index, "the last step's ")
        self._pending_stats = StepStats.of(self.parts.ring, frame,
                                           self.parts.slots[frame.index], cpu_ms, 0.0)

    def _world_errors(self, slot: int, which: str) -> None:
        """After a batch's fence: its worlds kernel's report of poses that are none (CUDA
        tensors are not read back before the batch), as one UsageError line."""
        if self.world_kernel is None:
            return
        count, world = self.world_kernel.take_errors(slot)
        if count:
            raise UsageError(f"worlds: {which}world {world} has a pose with NaN or infinity, or "
                             f"a quaternion of length 0 ({count} draw records of such worlds "
                             "were hidden)")

    def _hand_reads(self) -> bool:
        """Whether the batch's shading reads shadow maps by hand: its worlds' own maps, or the
        frame's compute-drawn maps from their buffer (after `_run`'s stale chose)."""
        return self._wshadow is not None or self.parts.shadow_frames.maps.hand_reads

    def _world_key(self) -> tuple:
        """What a batch's recording of worlds depends on (nothing without worlds)."""
        call = self.world_call
        if call is None:
            return ()
        kernel = self.world_kernel
        ws = self._wshadow
        shadows = () if ws is None else (ws[0], ws[1].worlds, ws[1].stride, ws[1].generation,
                                         None if ws[1].kept is None else (id(ws[1].kept), ws[2].tobytes()))
        return (*call.key, kernel.generation if kernel is not None and call.gpu else 0, shadows)

    def _world_groups(self) -> dict[str, Any] | None:
        """The worlds' kernel step of a call whose poses the GPU expands; the worlds' own
        shadow maps (render/world_shadows.py) where the call moves casters."""
        call, kernel, ws = self.world_call, self.world_kernel, self._wshadow
        out: dict[str, Any] = {}
        if ws is not None:
            raster = self.parts.shadow_frames.maps.compute_raster(self.parts.gpu_scene)
            bv = self.views
            assert bv is not None  # (its set 0 names the worlds' records, either batch's)
            out["shadows"] = lambda fs: raster.world_steps(
                fs.frame_index, ws[0], ws[1], fs.classes, fs.material_sets,
                bv.set0(fs.frame_index, True), fs.resources, ws[2])
        if call is not None and call.gpu is not None and kernel is not None:
            d = self.world_buffers.draws  # type: ignore[union-attr]
            out["worlds"] = lambda fs: kernel.steps(fs.frame_index, call.gpu, d)
        return out or None

    def _run(self, frame: Any, plan: Any, opts: RenderOptions,
             record: Callable[[tuple[bool, ...]], Any], cuda_owner: Any = None,
             order: CudaOrder | None = None, finish: Callable[..., Any] | None = None) -> None:
        """Record (given which shadow maps to redraw), submit and wait for a submission; its
        timings into `stats`. The shadow maps' record is forgotten if it fails. With `order`
        (render/cuda_order.py) the submission waits for and signals CUDA's timelines and the
        host does not wait: the next call does, and reads its timings then. `cuda_owner`:
        what CUDA's last clone read (waited for before the submission, unless ordered);
        `finish`: how the step's results come back, where a later step may replay it."""
        p = self.parts
        shadows = p.shadow_frames.maps
        # (a batch of worlds' own maps are drawn whole, every submission; the images are not)
        redraw = None if self._wshadow else p.shadow_frames.stale(frame.index, plan, opts.alpha_mask)
        try:
            cmd = record(redraw)
            self._submit_cmd(frame, cmd, order, cuda_owner)
        except BaseException:
            shadows.forget()
            raise
        if self._replay is not None:  # (batch_replay.py: the slot's next step may replay it)
            keep = finish is not None and not any(redraw or ())
            self.replays.stepped(p.ring, replay_key(self, *self._replay), frame, cmd,
                                 finish if keep else None, cuda_owner, order is not None)
        self._submitted(frame, order)

    def _whole(self, views: CameraBatch) -> bool:
        """Whether a submission's `views` are the whole call's (one submission: replayable)."""
        return self._replay is not None and views is self._replay[1]

    def _submit_cmd(self, frame: Any, cmd: Any, order: CudaOrder | None, cuda_owner: Any) -> None:
        """Submit `cmd` from `frame`'s slot (after CUDA's last clone of `cuda_owner`, unless
        the submission is ordered on the GPU by `order`)."""
        if cuda_owner is not None and order is None:
            self._cuda_wait(cuda_owner)
        if order is None:
            frame.submit(cmd)
        else:
            frame.submit(cmd, wait=order.inputs.handle, signal=order.done.handle,
                         values=order.submit_values())
        frame.stamped = self.parts.ring.query_pool is not None

    def _submitted(self, frame: Any, order: CudaOrder | None) -> None:
        """After a submission: wait for it (unless CUDA-ordered: the next call does) and
        keep its timings in `stats`."""
        p = self.parts
        t_submitted = time.perf_counter()
        if order is not None:
            self._pending = (frame, 1e3 * (t_submitted - self._t_start))
            last = self._pending_stats  # (the last step's timings, read when asked for)
            self.stats = last.with_cpu(self._pending[1]) if isinstance(last, StepStats) else \
                FrameStats(self._pending[1])
            return
        frame.wait()
        self._world_errors(frame.index, "")
        # The Python side up to the submit and the readback are added by the caller
        # (`_timed`); the wait is this submission's.
        stats = StepStats.of(p.ring, frame, p.slots[frame.index],
                             1e3 * (t_submitted - self._t_start),
                             1e3 * (time.perf_counter() - t_submitted))
        # One call's timings: every submission's summed (a batch split by memory).
        self.stats = summed_stats(self.stats, stats) if self._submissions else stats
        self._submissions += 1

    def _target(self, size: tuple[int, int], layers: int, views: int, linear: bool,
                depth: bool, cuda: bool) -> BatchTarget:
        """The layered batch's target for these views, made (or grown) on first use; the
        BATCH_TARGETS_KEPT most recently used are kept, older ones destroyed (a dataset that
        batches every image at its own size had kept one per size)."""
        key = (tuple(size), layers, linear, depth, cuda)
        target = self.targets.pop(key, None)
        if target is not None and target.capacity >= views:
            self.targets[key] = target  # (the most recently used last)
            return target
        if target is not None:
            self._drop_target(target)
        target = BatchTarget(self.parts.device, size, layers, views, "float" if linear else "srgb",
                             depth, clear_color=(*self.parts.targets.background, 0.0),
                             external=cuda)
        while len(self.targets) >= BATCH_TARGETS_KEPT:
            self._drop_target(self.targets.pop(next(iter(self.targets))))
        self.targets[key] = target
        return target

    def _drop_target(self, target: BatchTarget) -> None:
        """Destroy layered target `target` once the device is idle, with its recordings,
        CUDA imports and GTAO's sets naming its depth view (a later view may get its handle
        value: a set kept for it would read the destroyed one)."""
        self.parts.device.wait_idle()
        self.free_recordings()
        self._forget_cuda(target)
        if self.parts.recorder.ao is not None:
            self.parts.recorder.ao.forget(target.attachments.depth)
        target.destroy()

    # --- CUDA -------------------------------------------------------------------------------
    def _cuda_view(self, target: BatchTarget, views: int, linear: bool) -> Any:
        """A torch tensor of the first `views` views of an external target's colour."""
        w, h = target.extent
        return self._cuda_tensor(target.color_readback, (views, h, w, 4), linear)

    def _cuda_tensor(self, buf: Any, shape: tuple[int, ...], linear: bool) -> Any:
        """A torch tensor of `shape` from exported buffer `buf`: a clone (on torch's current
        stream) of the imported Vulkan memory; the next batch into the buffer waits for the
        clone (`_cuda_wait`)."""
        imported = self._cuda_imports.get(id(buf))
        if imported is None:  # (the imports only here: a step's call does none)
            from vkpbr.gpu.cuda import CudaImport, cuda_device_for

            dev = self.parts.device
            index = cuda_device_for(dev.uuid(), dev.info.name)
            imported = CudaImport(buf.export_fd(), buf.allocation_size, index)
            self._cuda_imports[id(buf)] = imported
        view = imported.tensor(shape, "<f4" if linear else "|u1")
        if self.frames_view:  # (valid until the next step: docs/batch.md "frames='view'")
            self._cuda_events[id(buf)] = VIEWED  # (the next batch waits for torch's stream)
            return view
        out = view.clone()
        event = self._cuda_made_events.get(id(buf))
        if event is None:  # (one a buffer, recorded again each call: no new event a step)
            import torch

            event = self._cuda_made_events[id(buf)] = torch.cuda.Event()
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
            target = self.parts.targets.atlas(extent, linear)  # (a scene before's, if kept)
        self._atlases[key] = target
        return target

    def _drop_atlas(self, target: Any, keep: bool = False) -> None:
        """Destroy atlas `target` with what was made for it (`keep`: give it back to the
        targets instead, for the next scene: render/targets.py give_atlas)."""
        buf = self._exports.pop(id(target), None)
        if buf is not None:
            self._cuda_wait(buf)
            self._cuda_made_events.pop(id(buf), None)
            imported = self._cuda_imports.pop(id(buf), None)
            if imported is not None:
                imported.close()
        if keep:
            self.parts.targets.give_atlas(target)
        else:
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
        if event is VIEWED:  # (frames='view': what torch queued reading them since, done)
            import torch

            torch.cuda.current_stream().synchronize()
        elif event is not None:
            event.synchronize()

    def _forget_cuda(self, target: BatchTarget) -> None:
        self._cuda_wait(target.color_readback)
        self._cuda_made_events.pop(id(target.color_readback), None)
        imported = self._cuda_imports.pop(id(target.color_readback), None)
        if imported is not None:
            imported.close()

    # --- lifetime ---------------------------------------------------------------------------
    def free_recordings(self) -> None:
        if self.views is not None:
            self.views.free_recordings()

    def close(self) -> None:
        self._finish_pending()
        if self.cuda_order is not None:
            self.cuda_order.destroy()
            self.cuda_order = None
        if self.views is not None:
            self.views.destroy()
            self.views = None
        if self.world_buffers is not None:
            self.world_buffers.destroy()
            self.world_buffers = None
        if self.world_kernel is not None:
            self.world_kernel.destroy()
            self.world_kernel = None
        if self.world_shadows is not None:
            self.world_shadows.destroy()
            self.world_shadows = None
        for target in self.targets.values():
            self._forget_cuda(target)
            target.destroy()
        self.targets = {}
        while self._atlases:  # with the compute batch's exported colour; kept, where kept
            self._drop_atlas(self._atlases.popitem(last=False)[1], keep=True)


def view_rotations(terms: ViewTerms, n: int) -> np.ndarray:
    """(n, 3, 3) float32: each view's rotation of row vectors from world axes into its
    camera's (`normal @ R`), as `render` applies its slot's to the normal_camera output."""
    columns = [np.broadcast_to(np.asarray(v, np.float64), (n,)) for v in terms.rotation]
    return np.stack(columns, -1).reshape(n, 3, 3).transpose(0, 2, 1).astype(np.float32)


def _joined(parts: list[np.ndarray], out: np.ndarray | None = None) -> np.ndarray:
    """The submissions' arrays as one (`out` itself when they were written into it)."""
    if out is not None:
        return out
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    return a is b or ((a is None) == (b is None) and (a is None or np.array_equal(a, b)))


def _slice(views: CameraBatch, start: int, stop: int) -> CameraBatch:
    if start == 0 and stop == len(views):
        return views  # (the same batch: its records may be written already)
    def part(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else a[start:stop]

    return CameraBatch(views.eye[start:stop], views.target[start:stop], views.up[start:stop],
                       views.yfov_deg[start:stop], part(views.intrinsics), part(views.znear),
                       part(views.zfar),
                       None if views.lenses is None else views.lenses[start:stop])
