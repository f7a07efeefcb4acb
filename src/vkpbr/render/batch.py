"""Batched views: B cameras of one scene drawn in one submission (Renderer.render_batch).

The frame path's passes (render/passes.py) drawn once for many views, GPU-driven:

1. Python writes one view record per view (layouts.VIEW_RECORD: VP, eye, forward, planes,
   layer) with vectorised NumPy (render/views.py, a single frame's maths over arrays): no
   Python per view.
2. batch_cull.comp tests every (view, draw) pair, the draw's world bounding sphere against
   the view's frustum, and writes per (chunk, draw) an indirect command instanced over the
   views that see the draw, with their list (VisibleViews).
3. Each chunk of up to `layers` views is one layered rendering into a BatchTarget
   (gpu/batch_target.py): every pass records its draws once as indirect draws; the BATCH
   builds of pbr.vert / pbr.frag / background.vert read the view of each instance (as
   every shader reads its camera: views[view_index]), draw into its layer and shade with
   its eye. The chunk is copied into its place in the readback buffer; the next chunk
   reuses the images.

Commands are recorded once per (target, views, options, shadow plan, blended order) and
reused, so a batch costs Python a few NumPy calls and one submission however many views it
has. Blended draws need each view's own back-to-front order: the views of a chunk are grouped
by that order (usually one group) and each group draws them in its order, instanced over its
views. What differs from rendering each view alone (docs/batch.md): directional lights'
shadow maps are one map over the whole scene shared by the views (cascades follow one
camera's depth range; thousands of cameras cannot each have theirs).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from vkpbr.gpu.batch_target import BatchTarget
from vkpbr.gpu.buffer import Buffer, upload_buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import ComputePipeline
from vkpbr.gpu.compute import groups as work_groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.frames import Frame, FrameRing
from vkpbr.gpu.graph import BufferResource, Rendering, Step
from vkpbr.render import layouts as L
from vkpbr.render.ao import PREPASS_ROWS, AoSpec
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.deform import draw_sphere
from vkpbr.render.frames import FrameSlot
from vkpbr.render.gpu_scene import Draw, GpuScene
from vkpbr.render.passes import (
    PASSES,
    PassContext,
    pass_makers,
    record_pass,
    record_passes,
    recorded_passes,
)
from vkpbr.render.recorder import FrameRecorder
from vkpbr.render.shadows import ShadowPlan
from vkpbr.render.steps import FrameObjects, FrameSpec, FrameSteps
from vkpbr.render.views import ViewTerms, fill_views
from vkpbr.scene.types import MeshBox, Scene, mesh_box

__all__ = ["BatchViews", "draw_spheres", "MAX_LAYERS"]

MAX_LAYERS = 2048  # views per chunk at most (every device's array-layer limits allow 256+)
_COMMAND_BYTES = 20  # VkDrawIndexedIndirectCommand
_SHADING = tuple(p.name for p in PASSES if not p.prepass)  # (after GTAO's depth pre-pass)


def draw_spheres(scene: Scene, draws: list[Draw], box: MeshBox | None = None) -> np.ndarray:
    """(D, 8) float32 per draw: the bounding sphere (centre, radius) of its mesh's box in the
    mesh's own space (the shaders place it with the draw's model matrix: frustum.glsl
    world_sphere), then (index count, first index, vertex offset, 0) as uint32 bits (what
    batch_cull.comp reads). `box`: each mesh's (min, max) (GpuScene.mesh_box; None: computed)."""
    box = mesh_box(scene) if box is None else box
    out = np.zeros((len(draws), 8), np.float32)
    ranges = out.view(np.uint32)
    for i, d in enumerate(draws):
        out[i, :4] = draw_sphere(d, box)
        ranges[i, 4:7] = (d.index_count, d.first_index, d.vertex_offset & 0xFFFFFFFF)
    return out


class BatchViews:
    """The batch's GPU resources for one Renderer: the culling kernel, the views, the
    indirect commands and lists, a set 0 per frame slot naming them, and recordings."""

    def __init__(self, device: Device, scene: Scene, gpu_scene: GpuScene, ring: FrameRing,
                 slots: list[FrameSlot], set0_layout: DescriptorSetLayout,
                 recorder: FrameRecorder, shadows: Any, gpu_state: Any) -> None:
        # gpu_state: the scene state's copies per slot (render/scene_state.py)
        self.device, self.gpu_scene, self.ring, self.slots = device, gpu_scene, ring, slots
        self.gpu_state = gpu_state
        self.set0_layout, self.recorder, self.shadows = set0_layout, recorder, shadows
        self._objects: list[Any] = []
        self.draw_count = len(gpu_scene.draws)
        self.bounds = self._own(upload_buffer(
            device, draw_spheres(scene, gpu_scene.draws, gpu_scene.mesh_box) if gpu_scene.draws
            else np.zeros(8, np.float32), "storage", name="batch draw bounds"))
        stages = ("compute",)
        self.cull_layout = self._own(DescriptorSetLayout(device, [
            BindingSpec(i, "storage", stages, n)
            for i, n in enumerate(("CullViews", "DrawBounds", "Commands", "CullVisible",
                                   "CullInstances"))]))
        self._cull: ComputePipeline | None = None  # (made with the first batch's kernels)
        # Two of each per slot: the renderer's state, and a batch of worlds' (render/worlds.py)
        self.pool = self._own(DescriptorPool(device, [(self.cull_layout, 2 * len(slots)),
                                                      (set0_layout, 2 * len(slots))]))
        self.cull_sets = [self.pool.allocate(self.cull_layout) for _ in slots]
        self.sets0 = [self.pool.allocate(set0_layout) for _ in slots]
        self.world_cull_sets = [self.pool.allocate(self.cull_layout) for _ in slots]
        self.world_sets0 = [self.pool.allocate(set0_layout) for _ in slots]
        self.worlds: Any = None  # render/worlds.py WorldBuffers once a batch of worlds came
        self.capacity = 0  # views the buffers hold
        self.chunk_views = 0
        self.views: Buffer | None = None
        self._buffers: list[Buffer] = []
        self._identity = 0  # (ensure says)
        self.generation = 0  # its buffers' (recordings name them)
        # A batch of worlds' WorldFactors blocks (shaders/worlds.glsl), grown by
        # set_world_factors; every set 0 binds it (factor_base 0: no view reads it).
        self.factors = Buffer(device, 48, "storage", host_visible=True, name="world factors")

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    # --- buffers ----------------------------------------------------------------------------
    def ensure(self, views: int, chunk_views: int) -> None:
        """Buffers for `views` views drawn `chunk_views` at a time (grown, never shrunk)."""
        if views <= self.capacity and chunk_views == self.chunk_views:
            return
        self.device.wait_idle()
        self.free_recordings()
        self.generation += 1
        for b in self._buffers:
            b.destroy()
        dev, d = self.device, max(self.draw_count, 1)
        self.capacity, self.chunk_views = max(views, self.capacity), chunk_views
        chunks = -(-self.capacity // chunk_views)  # any batch up to the capacity fits
        self.views = Buffer(dev, self.capacity * L.VIEW_RECORD.size, "storage", host_visible=True,
                            device_local=True, name="batch views")
        self.commands = Buffer(dev, chunks * d * _COMMAND_BYTES, "storage|indirect|transfer_dst",
                               name="batch indirect draws")
        # The culling kernel's lists, then the blended draws' groups of views (written here:
        # host-visible, a uint a view).
        self.tail = chunks * d * chunk_views
        self.visible = Buffer(dev, (self.tail + self.capacity) * 4, "storage", host_visible=True,
                              name="batch visible views")
        self.group_lists = self.visible.array(np.uint32, self.capacity, self.tail * 4)
        self._identity = 0  # group_lists[:_identity] hold 0, 1, 2... (_one_group_each)
        self._buffers = [self.views, self.commands, self.visible]
        self.records = self.views.array(np.uint8, self.capacity * L.VIEW_RECORD.size).view(
            L.VIEW_RECORD.dtype)
        self._bind(self.sets0, self.cull_sets, self.gpu_state.region)
        if self.worlds is not None:
            self.bind_worlds(self.worlds)

    def bind_worlds(self, worlds: Any) -> None:
        """Point the worlds' sets at `worlds` (render/worlds.py WorldBuffers: each slot's
        state and worlds' records); after it grew, its recordings are stale (freed)."""
        if self.worlds is not None and self.views is not None:
            self.free_recordings()
        self.worlds = worlds
        if self.views is not None:
            self._bind(self.world_sets0, self.world_cull_sets, worlds.region)

    def _bind(self, sets0: list[Any], cull_sets: list[Any], instances: Any) -> None:
        """Write each slot's set 0 and culling set: the views, lists and `instances(slot)`
        ((buffer, offset, size) of the draw records its views read)."""
        writer = DescriptorWriter(self.device)
        for slot, set0, cull in zip(self.slots, sets0, cull_sets, strict=True):
            state_buf, state_at, state_size = instances(slot.index)
            for binding, buf in enumerate((self.views, self.bounds, self.commands, self.visible)):
                writer.storage(cull, binding, buf)
            writer.storage(cull, 4, state_buf, state_size, state_at)
            settings_buf, settings_at = slot.block_ranges["Settings"]  # a frame's, the batch's views
            writer.storage(set0, 0, self.views)
            writer.uniform(set0, 1, settings_buf, L.SETTINGS.size, settings_at)
            writer.storage(set0, 2, self.visible)
            writer.storage(set0, 3, state_buf, state_size, state_at)
            writer.storage(set0, 4, self.factors)
        writer.update()

    def set_world_factors(self, factors: np.ndarray) -> bool:
        """Write a batch of worlds' WorldFactors blocks ((K, 4) float32, shaders/worlds.glsl);
        True when the buffer grew (every set 0 rebound, the recordings naming them freed)."""
        grew = factors.nbytes > self.factors.size
        if grew:
            self.device.wait_idle()
            self.free_recordings()
            self.factors.destroy()
            self.factors = Buffer(self.device, max(factors.nbytes, 2 * self.factors.size),
                                  "storage", host_visible=True, name="world factors")
            writer = DescriptorWriter(self.device)
            for set0 in (*self.sets0, *self.world_sets0):
                writer.storage(set0, 4, self.factors)
            writer.update()
        self.factors.array(np.float32, factors.size)[:] = factors.ravel()
        return grew

    def set0(self, frame_index: int, worlds: bool) -> Any:
        """Frame slot `frame_index`'s set 0 of a batch (of worlds, with `worlds`)."""
        return (self.world_sets0 if worlds else self.sets0)[frame_index]

    def write_views(self, terms: ViewTerms, size: tuple[int, int], rows: int = 0,
                    instance_base: np.ndarray | None = None,
                    factor_base: np.ndarray | None = None,
                    shadow_base: np.ndarray | None = None) -> None:
        """The batch's view records (`terms`: views.batch_view_terms) for views of `size`
        (W, H): each in its layer of its chunk of the layered target, or (`rows` > 0) in its
        tile of a compute batch's column-major atlas, `rows` tiles a column; in a batch of
        worlds, where each view's world's draw records (`instance_base`, (N,)) and material
        factors (`factor_base`, (N,), render/worlds.py) start."""
        n = len(terms.znear)
        w, h = size
        index = np.arange(n, dtype=np.uint32)
        viewport = np.zeros((n, 4), np.uint32)
        viewport[:, 2:] = w, h
        if rows:
            viewport[:, 0], viewport[:, 1] = index // rows * w, index % rows * h
        layer = 0 if rows else index % self.chunk_views
        fill_views(self.records[:n], terms, viewport, layer)
        if instance_base is not None:
            self.records["instance_base"][:n] = instance_base
        if factor_base is not None:
            self.records["factor_base"][:n] = factor_base
        if shadow_base is not None:  # each view's world's own shadow maps (world_shadows.py)
            self.records["shadow_base"][:n] = shadow_base

    def write_blend_groups(self, orders: np.ndarray) -> tuple[tuple[tuple[tuple[int, ...], int, int], ...], ...]:
        """Group each chunk's views by their blended draws' back-to-front order (`orders`:
        (B, blended draws) indices, farthest first) and list the groups' views; per chunk,
        ((order, first instance, instances), ...) for PassContext.blend_groups."""
        n = len(orders)
        if orders.shape[1] == 0:  # no blended draws (most scenes): one group a chunk
            return self._one_group_each(n)
        self._identity = 0
        unique, inverse = np.unique(orders, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        chunks = []
        c = self.chunk_views
        for start in range(0, n, c):
            ids = inverse[start:start + c]
            perm = np.argsort(ids, kind="stable")
            self.group_lists[start:start + len(ids)] = perm + start
            groups, counts = np.unique(ids, return_counts=True)
            offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
            chunks.append(tuple((tuple(unique[g].tolist()), int(self.tail + start + o), int(k))
                                for g, o, k in zip(groups, offsets, counts, strict=True)))
        return tuple(chunks)

    def _one_group_each(self, n: int) -> tuple:
        """write_blend_groups without blended draws: each chunk's views in their order, as
        one group; the lists written only where the last call did not leave them so (a loop
        of the same views writes nothing: np.unique over B rows cost ~10 ms for 4,096)."""
        c = self.chunk_views
        if self._identity < n:
            self.group_lists[:n] = np.arange(n, dtype=np.uint32)
            self._identity = n
        return tuple((((), int(self.tail + start), min(c, n - start)),)
                     for start in range(0, n, c))

    # --- commands ---------------------------------------------------------------------------
    def command_buffer(self, target: BatchTarget, frame: Frame, views: int, tbn: L.TbnMode,
                       alpha_mask: bool, plan: ShadowPlan, groups: tuple, prepass: bool,
                       redraw: tuple[range, ...] | None = None, worlds: tuple | None = None,
                       extra: dict[str, Any] | None = None, ao: AoSpec | None = None
                       ) -> Commands:
        """The batch's commands (the layered batch's path, render/paths.py; recorded on first
        use): `groups` from write_blend_groups; `redraw`: which shadow entries are drawn
        (ShadowMaps.stale); `worlds`: the views read their worlds' draw records (the key of
        what the worlds' steps depend on, render/worlds.py); `extra`: groups made elsewhere
        (the worlds' kernel); `ao`: each chunk's GTAO (render/ao.py) between a depth pre-pass
        and its passes."""
        # (the groups are the recording's blended order, not its key: a new order re-records
        # the slot's commands in place, where a key per order had kept every one recorded)
        spec = FrameSpec("layered_batch", tbn, alpha_mask, plan, redraw,
                         batch=(views, prepass, self.generation, worlds), ao=ao)
        on = worlds is not None

        def chunks(fs: FrameSteps) -> list[Step]:
            return self._chunk_steps(fs, target, views, tbn, fs.objects.blend_order, prepass, on)

        made = {"cull": lambda fs: self._cull_steps(fs, views, on), "chunks": chunks, **(extra or {})}
        return self.recorder.command_buffer(target, frame, 0, spec, FrameObjects(groups),
                                            groups=made)

    def cull_kernel(self) -> ComputePipeline:
        """The culling kernel (made on first use: by the frame graph, with the batch's other
        kernels at once)."""
        if self._cull is None:
            self._cull = self._own(ComputePipeline(self.device, SPV_DIR / "batch_cull.comp.spv",
                                                   [self.cull_layout], push_bytes=12))
        return self._cull

    def _cull_steps(self, fs: FrameSteps, views: int, worlds: bool) -> list[Step]:
        """The culling kernel: per view and draw, whether the view sees it, into the chunks'
        indirect draws and lists of views."""
        fs.resources.update(commands=BufferResource(self.commands),
                            visible=BufferResource(self.visible))

        def record(cmd: Commands) -> None:
            cmd.bind_pipeline(self.cull_kernel())
            cmd.bind_set(0, (self.world_cull_sets if worlds else self.cull_sets)[fs.frame_index])
            cmd.push(np.array([views, self.draw_count, self.chunk_views], np.uint32))
            cmd.dispatch(*work_groups((views * self.draw_count, 1, 1), (64, 1, 1)))

        return [Step("cull_clear", lambda cmd: cmd.fill(self.commands),
                     (("commands", "transfer_dst"),), timed=False),
                Step("cull", record, (("commands", "storage"), ("visible", "storage")),
                     kernels=(self.cull_kernel,))]

    def _chunk_steps(self, fs: FrameSteps, target: BatchTarget, views: int, tbn: L.TbnMode,
                     groups: tuple, prepass: bool, worlds: bool) -> list[Step]:
        """Each chunk of views: every pass in one layered rendering, then its copy out; the
        last copy is timed ("views": the drawing of every chunk)."""
        gs, slot, c = self.gpu_scene, self.slots[fs.frame_index], self.chunk_views
        chunks = -(-views // c)
        steps = []
        for chunk in range(chunks):
            n = min(c, views - chunk * c)
            ctx = PassContext(
                draws=gs.draws, classes=fs.classes,
                pipeline=lambda p: self.recorder.pipeline(target, tbn, p, prepass, batch=True),
                frame_sets=(self.set0(fs.frame_index, worlds), slot.set2),
                material_sets=fs.material_sets,
                vertex_buffers=[gs.streams[name] for name in fs.streams],
                index_buffer=gs.index_buffer, prepass=prepass, shadow_set=fs.shadow_set,
                indirect=self.commands, indirect_base=chunk * self.draw_count,
                views=(chunk * c, n), blend_groups=groups[chunk])
            if fs.spec.ao is not None:
                steps += self._ao_chunk_steps(fs, target, ctx, tbn, chunk, n)
            else:
                rendering = Rendering("color", "depth", target.clear_color, 0.0,
                                      layers=target.layers)
                steps.append(Step(f"chunk{chunk}", lambda cmd, ctx=ctx: record_passes(cmd, ctx),
                                  (("commands", "indirect"), ("visible", "vertex_read")),
                                  rendering, timed=False,
                                  kernels=pass_makers(ctx, recorded_passes(ctx))))
            last = chunk == chunks - 1
            steps.append(target.chunk_copy_step("views" if last else f"chunk{chunk}_copy",
                                                chunk, n, timed=last))
        return steps

    def _ao_chunk_steps(self, fs: FrameSteps, target: BatchTarget, ctx: PassContext,
                        tbn: L.TbnMode, chunk: int, n: int) -> list[Step]:
        """A chunk with ambient occlusion, as the fragment path's frame (paths.py
        "forward_outputs"): the depth of every layer (render/ao.py PREPASS_ROWS, a layered
        rendering), GTAO on every layer in one dispatch of each kernel, then the passes over
        that depth (testing it, writing none) reading their layer's GTAO."""
        reads = (("commands", "indirect"), ("visible", "vertex_read"))
        pre = dataclasses.replace(ctx, pipeline=lambda p: self.recorder.pipeline(
            target, tbn, p, False, batch=True))
        depth = Rendering("color", "depth", target.clear_color, 0.0, layers=target.layers)
        steps = [Step(f"chunk{chunk}_depth", lambda cmd: [record_pass(cmd, pre, p)
                                                          for p in PREPASS_ROWS],
                      reads, depth, timed=False, kernels=pass_makers(pre, PREPASS_ROWS))]
        steps += self.recorder.ao.steps(fs.resources, ctx.frame_sets[0], fs.frame_index,
                                        fs.spec.ao, target.extent, None, False, False,
                                        layered=(chunk * self.chunk_views, n))
        over = dataclasses.replace(ctx, prepass=True, pipeline=lambda p: self.recorder.pipeline(
            target, tbn, p, True, batch=True))
        shade = Rendering("color", "depth", target.clear_color, None, layers=target.layers)
        return [*steps, Step(f"chunk{chunk}", lambda cmd: record_passes(cmd, over, _SHADING),
                             (*reads, ("ao", "sampled")), shade, timed=False,
                             kernels=pass_makers(over, recorded_passes(over, _SHADING)))]

    def free_recordings(self) -> None:
        """The batches' recordings (they name these buffers and sets); the frames' stay."""
        self.recorder.free(paths=("layered_batch", "compute_batch"))

    def destroy(self) -> None:
        self.free_recordings()
        for b in (*self._buffers, self.factors):
            b.destroy()
        self._buffers = []
        while self._objects:
            self._objects.pop().destroy()
