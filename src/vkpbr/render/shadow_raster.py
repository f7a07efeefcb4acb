"""Shadow maps drawn by compute shaders (RenderOptions.shadow_raster; shaders/shadow_raster.comp).

A moving caster, or a camera the sun's cascades follow, redraws shadow maps every frame, and
through the raster units that is the H200's ceiling: 4 of its 132 SMs rasterise (4.45 ms for
Sponza's 262 k triangles x 4 cascades). Here every caster triangle x every redrawn layer of a
light is one invocation of one dispatch (cascades, a spot map, a cube's six faces alike:
a layer is named by its matrix in ShadowData), writing its depth with a 32-bit atomicMax
into a buffer of every layer's texels (reversed-Z: the largest depth is the nearest to the
light; depths >= 0, so their float bits order as the depths).

Where the shading reads them is chosen a frame at a time (render/shadows.py
ShadowMaps._choose_reads): a frame that redraws every layer (casters moving every frame)
reads that buffer as it is, by hand (shaders/shadow_sampling.glsl hand_compare, the one
filter a batch of worlds' maps use too, with the images' sampler's compare, border and
filter: nearest on lavapipe, which cannot filter D32 linearly, linear with 1/256 weights on
NVIDIA; its 3 x 3 taps from their 4 x 4 texels, hand_pcf_linear); a frame that redraws some
layers or none copies the redrawn ones into the images (`_copy`) and compares in hardware,
with shading pipelines built without the by-hand code (specialisation constant 3,
SHADOW_HAND_READS 0: compute_path.ShadeVariant.hand_reads, recorder.FrameRecorder.pipeline).
On the H200 (runs p, q): copying Sponza's 4 x 2048^2 texels into optimal-tiled D32 layers
takes 0.73 ms, a quarter of the shadow work of a frame that redraws them all, while reading
them by hand cost every frame's shading 0.04-0.07 ms (the still frame 0.88 -> 0.95 ms).
- Layout: the buffer mirrors the images (`fit`): 2D layer l's texels from l x size^2, row
  by row; then, from ShadowMaps.compute_cube_base(), cube c's face f (+X -X +Y -Y +Z -Z) at
  (6c + f) x cube_size^2 - where a layer's matrix (ShadowData.layer_vp) puts its texels
  here (`_spans`) and where shadow_sampling.glsl compare_2d / compare_cube read them.
- The shading knows from ShadowData's header (ShadowMaps.write, bit 0 set per frame by
  ShadowMaps._choose_reads): world_layout.z bit 0 (read the buffer, set 3's ShadowDepths),
  .w the cubes' first texel; clear: the images, compared by the sampler.
- Layers not redrawn (ShadowMaps.stale's cache) keep their texels: only the redrawn layers
  start anew, so a cached layer is valid in the buffer as it was in the images. How a
  redrawn layer starts is its row after the matrices in ShadowData (render/shadows.py CLIP_AT,
  written by ShadowMaps.stale; the move kernel, "shadows.move"): cleared; kept (unchanged,
  within a redrawn span); or, where a walking camera moved a cascade by whole texels
  (shadow_math.layer_scroll), its texels moved (saved into `scratch` first, "shadows.save")
  and only the strips that came into view drawn: the drawing kernels clip each layer's
  texels to its row's (shadow_raster.comp clip_box). Rows are data, so a scrolled frame replays the recording of
  a redrawn one. A switch
  between the compute kernels and the raster units (RenderOptions.shadow_raster, or "auto"
  following render/path_choice.py's measured choice) forgets the cache (ShadowFrames.
  choose_raster): the new side redraws every layer, nothing stale is read. New buffers (new
  images, a new scene) rebind ShadowDepths and forget it too (ShadowMaps.bind_frame_depths),
  before the frame's `stale`: ShadowFrames.prepare fits them (`fit`).
- Frames in flight share the one buffer, as they share the images. The last step,
  "shadows" (the copy, where the frame copies), declares the buffer read by compute and
  fragment shaders (their sets bind it either way): the frame graph puts
  the barrier from the kernels' writes before it, so every shading step after it (fragment
  passes, compute shading, the transmission's copy, a batch's) sees the maps without each
  naming them. The next frame's save (or move, where it draws no 2D layer) is the buffer's
  first use in its recording, which the graph orders after every earlier command
  (gpu/graph.py: ALL_COMMANDS), this frame's reads included; a frame
  that redraws nothing touches it not at all and reads what the last drawing frame made
  visible.

Triangles whose box exceeds BIG_AREA texels (a floor under a whole cascade) are listed as
bands of rows and drawn by work groups, as the main compute rasteriser does (raster.comp);
alpha-masked and blended casters are drawn one dispatch a draw with their material bound,
alpha-tested per texel where they would win (foliage casts leaf shadows), their big
triangles covered by the whole work group. The depth bias is the raster pipelines'
(shadows.DEPTH_BIAS, Vulkan's slope-scaled formula); the normal offset stays in
shadow_sampling.glsl. Vertices are the scene's posed ones (the deform step writes them in
place, before) placed by the frame's Instances, as every other step reads them.

A batch of worlds whose poses move casters (render/world_shadows.py) draws every world's
maps in the same dispatches (`world_steps`): a dispatch's z is (world, layer), a caster's
matrices are its world's records in Instances, its texels its world's in the worlds'
buffer, which the shading reads as it is (no copy: image layers could not hold thousands).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer, upload_buffer
from vkpbr.gpu.compute import ComputePipeline
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.graph import BufferResource, Step
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.deform import UNBOUNDED_RADIUS, draw_sphere

__all__ = ["ShadowRaster", "WorldJob", "wants_compute", "SET_ROWS", "big_list_bytes"]

SMALL_GROUP = 64  # shadow_small / shadow_masked: one (triangle, layer) an invocation
MAX_GROUPS_X = 65535
BIG_AREA, BIG_CHUNK = 256, 16384  # raster.comp's opaque split (compute_path.RasterTuning)
BIG_ENTRY = 24  # uints a listed band: its triangle set up (shadow_raster.comp store_band)
MASKED_AREA = 64  # masked triangles over this many box texels: the work group covers them
PUSH_BYTES = 128  # shadow_raster.comp's push constants
MAX_Z = 65535  # a dispatch's (world, layer) invocations in z
MAX_LOOP_LAYERS = 32  # shadow_small's layers of a dispatch (a bit each in a uint)
# Set 4: generated.glsl's compute-path bindings of the streams, then the kernels' own.
SET_ROWS = ((3, "Indices"), (4, "Positions"), (5, "Texcoords0"), (6, "Texcoords1"),
            (7, "Colors"), (40, "ShadowMatrices"), (41, "Casters"), (42, "Depths"), (43, "Big"),
            (44, "Scratch"))
TEXEL_GROUP = 256 * 16  # shadow_save / shadow_move: texels a work group (runs of 256: TEXEL_RUN)
_OPAQUE, _MASKED = ("opaque", "opaque_double"), ("mask", "blend")
_KINDS = ("directional", "spot", "point")  # shadow_raster.comp's bias index
# Timestamps after each kernel (benchmarks/bench_shadows.py --steps): FrameStats.pass_ms then
# has "shadows.small", "shadows.big", "shadows.masked" and "shadows" (after the last kernel:
# the barrier to the shading only) apart. Off: one timestamp, "shadows", for them all.
TIMED_STEPS = False


@dataclass(frozen=True)
class WorldJob:
    """A batch of worlds' maps (render/world_shadows.py): `worlds` worlds of `draws` records
    each (world w's from record (1 + w) * draws), every world's maps in `depths`, `stride`
    texels a world (its 2D layers of `map_size`, then from `cube_base` its cubes' faces of
    `cube_size`); `big` / `big_capacity`: their big triangles' list."""

    depths: Buffer
    big: Buffer
    big_capacity: int
    worlds: int
    draws: int
    stride: int
    cube_base: int
    map_size: int
    cube_size: int
    generation: int = 0  # of the buffers (render/world_shadows.py): the sets made for them
    # The kept map of the casters the worlds do not move (one world's layout), which every
    # world's maps copy before the moved casters are drawn (WorldShadows.kept), or None: all
    # casters drawn in every world.
    kept: Buffer | None = None
    first_record: int | None = None  # the first world's first record (None: `draws`)


def wants_compute(choice: Any, device: Any, measured: bool | None = None) -> bool:
    """Whether a frame's shadow maps are drawn by compute shaders: "compute" always,
    "hardware" never, "auto" as the main path's own choice of rasteriser for the view
    (`measured`: render/path_choice.py's measured or recorded compute_raster for the device;
    the same raster units draw both), else by its rule: on GPUs (a datacenter GPU's few raster
    units are the limit of a redrawn map), never on CPUs (lavapipe rasterises faster than it
    runs these kernels)."""
    name = getattr(choice, "name", str(choice)).lower()
    if name == "auto":  # never on a CPU: even where its main view measured the compute
        # rasteriser faster, lavapipe draws maps 5x slower in these kernels (every test's
        # first frame with shadows paid it)
        return device.info.kind != "cpu" and (measured if measured is not None else True)
    return name == "compute"


def big_list_bytes(capacity: int) -> int:
    """Bytes of a big-triangle list of `capacity` bands: its count and dispatch size, then
    the entries (shadow_raster.comp's Big)."""
    return 4 * (4 + BIG_ENTRY * capacity)


def _chunks(firsts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(row, first triangle, triangles, 0) for each run of up to SMALL_GROUP triangles of
    each row (rows of `counts` triangles from `firsts`): shadow_small's work groups."""
    per_row = -(-counts // SMALL_GROUP)
    rows = np.repeat(np.arange(len(counts), dtype=np.int64), per_row)
    k = np.arange(len(rows)) - np.repeat(np.cumsum(per_row) - per_row, per_row)
    out = np.zeros((len(rows), 4), np.uint32)
    out[:, 0] = rows
    out[:, 1] = firsts[rows] + SMALL_GROUP * k
    out[:, 2] = np.minimum(counts[rows] - SMALL_GROUP * k, SMALL_GROUP)
    return out


class _Table:
    """The caster draws of one draw classification: opaque rows first (their triangles
    numbered from 0 over the table), then one row a masked or blended draw; a row is (first
    triangle, first index, vertex offset, record in Instances), then its mesh's bounding
    sphere in the mesh's space (float32 bits; a deformed draw's never culls). After the
    rows, the opaque rows' chunks (`_chunks`) from uvec4 `chunks_at`."""

    def __init__(self, device: Any, gs: Any, classes: Sequence[str],
                 only: np.ndarray | None = None) -> None:
        casters = [(i, d, c) for i, (d, c) in enumerate(zip(gs.draws, classes, strict=True))
                   if getattr(d, "casts_shadows", True) and d.index_count >= 3
                   and (only is None or only[i])]
        opaque = [(i, d) for i, d, c in casters if c in _OPAQUE]
        masked = [(i, d) for i, d, c in casters if c in _MASKED]
        rows = np.zeros((max(len(opaque) + len(masked), 1), 8), np.uint32)
        spheres = rows.view(np.float32)[:, 4:]
        spheres[:, 3] = UNBOUNDED_RADIUS
        first = 0
        self.masked: list[tuple[int, int, int]] = []  # (row, material, triangles)
        for row, (i, d) in enumerate(opaque + masked):
            rows[row, :4] = first, d.first_index, d.vertex_offset, i
            spheres[row] = draw_sphere(d, gs.mesh_box)
            if row >= len(opaque):
                self.masked.append((row, d.material, d.index_count // 3))
            first += d.index_count // 3
        n = len(opaque)
        chunks = _chunks(rows[:n, 0].astype(np.int64),
                         np.array([d.index_count // 3 for _, d in opaque], np.int64))
        self.chunks_at, self.chunks = 2 * len(rows), len(chunks)
        table = np.concatenate([rows.reshape(-1, 4), chunks]) if len(chunks) else rows
        self.buffer = upload_buffer(device, table, "storage", name="shadow caster table")


def raster_layouts(device: Any, frame_layout: DescriptorSetLayout,
                   material_layout: DescriptorSetLayout) -> list[DescriptorSetLayout]:
    """The kernels' set layouts: sets 0 and 1 (Instances; a masked draw's material), two
    empty ones, then set 4 (SET_ROWS). Kept handles: kernels made ahead
    (render/kernels_ahead.py) are the maps' own."""
    empty = DescriptorSetLayout(device, [])
    own = DescriptorSetLayout(device, [BindingSpec(b, "storage", ("compute",), name)
                                       for b, name in SET_ROWS])
    return [frame_layout, material_layout, empty, empty, own]


def raster_kernel(device: Any, layouts: list[DescriptorSetLayout], name: str) -> ComputePipeline:
    """Kernel `name` (KERNELS) of shaders/shadow_raster.comp."""
    return ComputePipeline(device, SPV_DIR / f"shadow_{name}.comp.spv", layouts,
                           push_bytes=PUSH_BYTES)


def _whole(plan: Any) -> tuple[range, ...]:
    """Every layer of each plan entry."""
    return tuple(range(e.count) for e in plan.entries)


def _jobs(plan: Any, redraw: Sequence[range]) -> list[tuple[int, int, Any]]:
    """(first matrix, layers, entry) of each plan entry's drawn range."""
    return [(e.matrix_base + r.start, len(r), e) for e, r in zip(plan.entries, redraw, strict=True)
            if len(r)]


KERNELS = ("clear", "save", "move", "small", "args", "big", "masked")  # the last only where masked draws cast


class ShadowRaster:
    """The compute side of a renderer's ShadowMaps (`maps`) for the scene `gs` (GpuScene).

    Parameters
    ----------
    frame_layout, material_layout : sets 0 and 1 (Instances; a masked draw's material).
    slots : frames in flight (a descriptor set each, over the slot's shadow matrices).
    max_layers, depth_bias : render/shadows.py's MAX_LAYERS (the first cube matrix) and
        DEPTH_BIAS (per light kind: the pipelines' (constant, slope)).
    """

    def __init__(self, device: Any, maps: Any, gs: Any, frame_layout: DescriptorSetLayout,
                 material_layout: DescriptorSetLayout, slots: int, max_layers: int,
                 depth_bias: dict[str, tuple[float, float]]) -> None:
        self.device, self.maps, self.gs, self.slots = device, maps, gs, slots
        self.max_layers, self.depth_bias = max_layers, depth_bias
        self._owned: list[Any] = []
        self.layouts = raster_layouts(device, frame_layout, material_layout)
        self.set_layout = self._own(self.layouts[-1])
        self._own(self.layouts[2])
        self._pipelines: dict[str, ComputePipeline] = {}
        self._tables: dict[tuple, _Table] = {}
        self._sets: dict[tuple, Any] = {}  # (table key, slot) -> set, for the buffers below
        self._pools: list[Any] = []
        self._images: tuple[int, int] | None = None  # the maps' images the buffers fit
        self.depths: Buffer | None = None
        self.big: Buffer | None = None
        self.scratch: Buffer | None = None
        self.kept: Buffer | None = None  # (`_kept_depths`)
        self.big_capacity = 0

    def _own(self, obj: Any) -> Any:
        self._owned.append(obj)
        return obj

    def _pipeline(self, name: str) -> ComputePipeline:
        if name not in self._pipelines:
            self._pipelines[name] = self._own(raster_kernel(self.device, self.layouts, name))
        return self._pipelines[name]

    # --- resources -------------------------------------------------------------------------
    def fit(self) -> bool:
        """Buffers for the maps' current images (every layer's texels; the big triangles'
        list); the sets made for older ones are dropped (the maps' `ensure` waited for the
        device when it remade the images). True when they were made: the new depth buffer is
        bound as set 3's ShadowDepths (and the maps' cache forgotten), so recordings made
        before are stale."""
        maps, cubes = self.maps.maps, self.maps.cubes
        key = (id(maps), id(cubes), maps.layers, maps.size, cubes.layers, cubes.size)
        if self._images == key:
            return False
        for buffer in (self.depths, self.big, self.scratch, self.kept):
            if buffer is not None:
                self._owned.remove(buffer)
                buffer.destroy()
        self.kept = None
        for pool in self._pools:
            self._owned.remove(pool)
            pool.destroy()
        self._pools.clear()
        self._sets.clear()
        self.cube_base = self.maps.compute_cube_base()
        texels = self.cube_base + cubes.layers * cubes.size * cubes.size
        self.depths = self._own(Buffer(self.device, 4 * texels, "storage|transfer_dst|transfer_src",
                                       name="shadow depths"))
        # A scrolled cascade's texels while they move (the 2D layers', as in `depths`).
        self.scratch = self._own(Buffer(self.device, 4 * max(self.cube_base, 1), "storage",
                                        name="shadow scroll scratch"))
        # Bands of ~BIG_CHUNK texels (96 bytes each: the band and its triangle's set-up);
        # what does not fit is drawn by the invocation that found it. Sponza's 4 cascades
        # at 2048 list ~111 k of the 262 k.
        self.big_capacity = max(1 << 16, texels // 64)  # (6 MiB at the least)
        self.big = self._own(Buffer(self.device, big_list_bytes(self.big_capacity),
                                    "storage|transfer_dst|indirect", name="shadow big triangles"))
        self._images = key
        self.maps.bind_frame_depths(self.depths)
        return True

    def _table(self, classes: Sequence[str], only: np.ndarray | None = None) -> tuple[tuple, _Table]:
        """The caster table of `classes` (of `only` those draws where given), made once."""
        key = (len(self.gs.draws), tuple(classes), None if only is None else only.tobytes())
        if key not in self._tables:
            table = _Table(self.device, self.gs, classes, only)
            self._own(table.buffer)
            self._tables[key] = table
        return key, self._tables[key]

    def _set(self, key: tuple, table: _Table, slot: int, job: WorldJob | None = None,
             role: str = "frame") -> Any:
        """Slot `slot`'s set 4 for `table`: into the frame's maps ("frame"), the kept maps of
        the still casters ("kept", `Redraw`), or the frame's over those ("moved":
        their Scratch), or a batch of worlds' (`job`)."""
        depths, big = (self.depths, self.big) if job is None else (job.depths, job.big)
        # (a batch of worlds' maps never scroll: their scratch is the kept map they copy)
        scratch = self.scratch if job is None else job.kept if job.kept is not None else big
        if role == "kept":
            depths = self._kept_depths()
        elif role == "moved":
            scratch = self._kept_depths()
        key = (*key, role) if job is None else (*key, "worlds", job.generation, id(job.depths),
                                                 id(job.kept))
        if (key, slot) not in self._sets:
            pool = self._own(DescriptorPool(self.device, [(self.set_layout, self.slots)]))
            self._pools.append(pool)
            streams = self.gs.streams
            buffers = {"Indices": self.gs.index_buffer, "Positions": streams["positions"],
                       "Texcoords0": streams["texcoords"], "Texcoords1": streams["texcoords1"],
                       "Colors": streams["colors"], "Casters": table.buffer,
                       "Depths": depths, "Big": big, "Scratch": scratch}
            w = DescriptorWriter(self.device)
            for s in range(self.slots):
                dset = pool.allocate(self.set_layout)
                for binding, name in SET_ROWS:
                    if name == "ShadowMatrices":  # the slot's ShadowData
                        w.storage(dset, binding, self.maps.buffer, self.maps.matrix_bytes,
                                  s * self.maps.stride)
                    else:
                        w.storage(dset, binding, buffers[name])
                self._sets[(key, s)] = dset
            w.update()
        return self._sets[(key, slot)]

    def _kept_depths(self) -> Buffer:
        """The kept maps of the still casters (`Redraw`): laid out as `depths`,
        made on first use (the buffers' `fit` lets them go with the others)."""
        if self.kept is None:
            self.kept = self._own(Buffer(self.device, self.depths.size, "storage",
                                         name="shadow kept depths"))
        return self.kept

    def resources(self) -> dict[str, BufferResource]:
        """The graph resources the steps name (after `steps` made them); the depths
        `copied`: a frame that redraws some layers copies them into the images last."""
        out = {"shadow_depths": BufferResource(self.depths, copied=True),
               "shadow_big": BufferResource(self.big),
               "shadow_scratch": BufferResource(self.scratch)}
        if self.kept is not None:
            out["shadow_kept"] = BufferResource(self.kept)
        return out

    # --- steps -----------------------------------------------------------------------------
    def _push(self, plan: Any, table: _Table, job: WorldJob | None = None,
              rows: int | None = None) -> np.ndarray:
        """The kernels' push constants; `rows`: the set of clip rows they read (by default
        the frame's, and none for a batch of worlds)."""
        push = np.zeros(PUSH_BYTES // 4, np.uint32)
        spot = 0
        for e in plan.entries:
            if e.kind == "spot":
                spot |= 1 << e.first
        sizes = ((self.maps.maps.size, self.maps.cubes.size, self.cube_base, self.big_capacity)
                 if job is None else (job.map_size, job.cube_size, job.cube_base, job.big_capacity))
        push[:16] = (0, 0, 0, 0, sizes[0], sizes[1],
                     sizes[2], self.max_layers, sizes[3], int(self.gs.has_colors), BIG_AREA,
                     BIG_CHUNK, MASKED_AREA, spot, table.chunks_at, table.chunks)
        push[29] = rows if rows is not None else 0 if job is not None else self.maps.clip_at  # world_at.y
        bias = push.view(np.float32)
        for k, kind in enumerate(_KINDS):
            bias[16 + k], bias[20 + k] = self.depth_bias[kind]
        return push

    def steps(self, slot: int, plan: Any, redraw: Sequence[range] | None, classes: Sequence[str],
              material_sets: Sequence[Any], set0: Any, copy: bool = False) -> list[Step]:
        """The steps that draw `plan`'s layers `redraw` (per entry, a range of its layers)
        for frame `slot` into the depth buffer, and with `copy` into the images too (where
        the shading reads this frame: ShadowMaps.stale); the last, "shadows", is timed (all
        of them: the steps before it take no timestamp). The buffers were fitted before the
        frame's `stale` (ShadowFrames.prepare)."""
        if redraw is None:
            redraw = tuple(range(e.count) for e in plan.entries)
        if self._images is None:  # (prepare fits them: new ones here would forget `redraw`)
            raise RuntimeError("ShadowRaster.steps before fit()")
        # Per drawn entry: its first matrix, layers, and where they go in the images.
        jobs = _jobs(plan, redraw)
        split = getattr(redraw, "split", None)  # (render/shadows.py Redraw)
        if split is None:
            key, table = self._table(classes)
            record = self._records(table, self._set(key, table, slot), self._push(plan, table),
                                   jobs, material_sets, set0)
            out = self._steps(record, table, "shadow_depths", "shadow_big", "shadow_scratch")
        else:
            out = self._split_steps(slot, plan, redraw, jobs, classes, material_sets, set0)
        if copy:  # the images the shading compares in hardware get the redrawn layers
            # (the buffer stays declared read by the shaders too: their descriptor set binds
            # it, and synchronization validation counts a bound buffer as read)
            out[-1] = Step("shadows", lambda cmd: self._copy(cmd, jobs),
                           (("shadow_depths", "transfer_src|storage_read|fragment_storage_read"),))
        return out

    def _split_steps(self, slot: int, plan: Any, redraw: Any, jobs: list[tuple[int, int, Any]],
                     classes: Sequence[str], material_sets: Sequence[Any], set0: Any) -> list[Step]:
        """A `Redraw`'s steps: the kept maps' layers `redraw.kept` drawn from the casters
        that did not move lately (their rows the second set: kept, scrolled or cleared), then every
        drawn layer copied from them (the first set's CLIP_COPY rows) and the casters that
        moved drawn over it."""
        moved = redraw.split[1]
        out = []
        kept_jobs = _jobs(plan, redraw.kept)
        if kept_jobs:
            key, table = self._table(classes, ~moved)
            record = self._records(table, self._set(key, table, slot, role="kept"),
                                   self._push(plan, table, rows=self.maps.kept_clip_at), kept_jobs,
                                   material_sets, set0)
            out += self._steps(record, table, "shadow_kept", "shadow_big", "shadow_scratch",
                               "shadows.kept.")[:-1]
        key, table = self._table(classes, moved)
        record = self._records(table, self._set(key, table, slot, role="moved"),
                               self._push(plan, table), jobs, material_sets, set0)
        record.pop("save", None)  # (copied in: nothing scrolls)
        return out + self._steps(record, table, "shadow_depths", "shadow_big", "shadow_kept")

    def _steps(self, record: dict[str, Callable[[Any], None]], table: _Table, depths: str,
               big_list: str, scratch: str | None = None, prefix: str = "shadows.") -> list[Step]:
        """`scratch`: a frame's drawn layers start as their rows say, by the save and move
        kernels (cleared, kept, scrolled or copied from `scratch`); without it (a batch of
        worlds) they are filled. `prefix`: the steps' names' (the last, "shadows", aside)."""
        apart = TIMED_STEPS
        made = {name: (functools.partial(self._pipeline, name),) for name in KERNELS}
        out = []
        if scratch is None:
            out.append(Step(prefix + "clear", record["clear"],
                            ((depths, "transfer_dst"), (big_list, "transfer_dst")), timed=False))
        else:
            if "save" in record:
                out.append(Step(prefix + "save", record["save"], ((depths, "storage_read"),
                                                                  (scratch, "storage")),
                                timed=False, kernels=made["save"]))
            out += [Step(prefix + "clear", record["clear"], ((big_list, "storage"),), timed=False,
                         kernels=made["clear"]),
                    Step(prefix + "move", record["move"], ((depths, "storage"), (scratch, "storage_read")),
                         timed=False, kernels=made["move"])]
        out += [
               Step(prefix + "small", record["small"], ((depths, "storage"), (big_list, "storage")),
                    timed=apart, kernels=made["small"]),
               Step(prefix + "args", record["args"], ((big_list, "storage"),), timed=False,
                    kernels=made["args"]),
               Step(prefix + "big", record["big"], ((depths, "storage"), (big_list, "storage|indirect")),
                    timed=apart, kernels=made["big"])]
        if table.masked:
            out.append(Step(prefix + "masked", record["masked"], ((depths, "storage"),), timed=apart,
                            kernels=made["masked"]))
        # Nothing to record: its declared read puts the barrier from the kernels' writes to
        # every shader that reads the maps after it (the module's docstring).
        out.append(Step("shadows", uses=((depths, "storage_read|fragment_storage_read"),)))
        return out

    def _records(self, table: _Table, dset: Any, push: np.ndarray,
                 jobs: list[tuple[int, int, Any]], material_sets: Sequence[Any], set0: Any,
                 world: WorldJob | None = None) -> dict[str, Callable[[Any], None]]:
        """Each step's commands: `jobs` are (first matrix, layers, entry) of the drawn ranges;
        `world`: every world's layers of each job (`world_steps`)."""
        big_buffer = self.big if world is None else world.big
        dispatch = self._dispatcher(push, world)

        def bind(cmd: Any, name: str) -> None:
            cmd.bind_pipeline(self._pipeline(name))
            cmd.bind_set(0, set0)
            cmd.bind_set(4, dset)

        def clear(cmd: Any) -> None:
            if world is not None and world.kept is None:
                self._clear(cmd, world)
                return
            bind(cmd, "clear")  # the big list emptied (a kernel: shadow_raster.comp KERNEL 7)
            cmd.push(push)
            cmd.dispatch(1)

        def small(cmd: Any) -> None:
            bind(cmd, "small")
            for matrix, layers, _ in jobs:
                if table.chunks:  # a work group a chunk, its layers in a loop (at most 32)
                    assert layers <= MAX_LOOP_LAYERS, layers
                    dispatch(cmd, matrix, layers, table.chunks, layers_in_z=False)

        def args(cmd: Any) -> None:
            bind(cmd, "args")
            cmd.push(push)
            cmd.dispatch(1)

        def big(cmd: Any) -> None:
            bind(cmd, "big")
            cmd.push(push)
            cmd.dispatch_indirect(big_buffer, 4)

        def masked(cmd: Any) -> None:
            bind(cmd, "masked")
            for matrix, layers, _ in jobs:
                for row, material, triangles in table.masked:
                    cmd.bind_set(1, material_sets[material])
                    push[0], push[2] = triangles, row
                    dispatch(cmd, matrix, layers, -(-triangles // SMALL_GROUP))

        out = {"clear": clear, "small": small, "args": args, "big": big, "masked": masked}
        if world is not None and world.kept is None:
            return out  # (filled: `_clear`)
        return {**out, **self._starts(jobs, bind, dispatch, world)}

    def _starts(self, jobs: list[tuple[int, int, Any]], bind: Callable[[Any, str], None],
                dispatch: Callable[..., None], world: WorldJob | None = None
                ) -> dict[str, Callable[[Any], None]]:
        """A frame's "move" (every drawn layer starts as its row says: 2D layers kept,
        scrolled, cleared or copied) and, where 2D layers are drawn, its "save" (a scrolled
        layer's texels into `scratch` first); a batch of worlds' "move" alone (every world's
        layers copied from the kept map)."""
        flat = [j for j in jobs if j[2].kind != "point"] if world is None else []

        def texel_groups(e: Any) -> int:
            if world is not None:
                size = world.cube_size if e.kind == "point" else world.map_size
            else:
                size = (self.maps.cubes if e.kind == "point" else self.maps.maps).size
            return -(-size * size // TEXEL_GROUP)

        def run(name: str, drawn: list[tuple[int, int, Any]]) -> Callable[[Any], None]:
            def record(cmd: Any) -> None:
                bind(cmd, name)
                for matrix, layers, e in drawn:
                    dispatch(cmd, matrix, layers, texel_groups(e))
            return record

        return {"move": run("move", jobs), **({"save": run("save", flat)} if flat else {})}

    def _dispatcher(self, push: np.ndarray, world: WorldJob | None
                    ) -> Callable[[Any, int, int, int], None]:
        """dispatch(cmd, first matrix, layers, groups[, layers_in_z]): the layers of every
        world (one without `world`), z = (world, layer) (or the world alone where the kernel
        loops over the layers), at most MAX_Z a dispatch (worlds in runs)."""
        worlds = 1 if world is None else world.worlds

        def dispatch(cmd: Any, matrix: int, layers: int, groups: int, layers_in_z: bool = True) -> None:
            push[3] = matrix
            run = max(1, MAX_Z // layers)
            for w0 in range(0, worlds, run):
                n = min(run, worlds - w0)
                if world is not None:
                    first = world.draws if world.first_record is None else world.first_record
                    push[24:29] = (world.draws, first, world.stride, layers, w0)
                else:
                    push[27] = layers
                cmd.push(push)
                cmd.dispatch(min(groups, MAX_GROUPS_X), -(-groups // MAX_GROUPS_X),
                             n * layers if layers_in_z else n)

        return dispatch

    def _clear(self, cmd: Any, world: WorldJob) -> None:
        """A batch of worlds' maps at depth 0, the farthest (reversed-Z), as the passes
        clear (after the last submission's reads), and their big list emptied. A frame's
        drawn layers are cleared, kept or scrolled by the move kernel instead, and so are
        the worlds' maps that copy a kept map (their big list: the clear kernel)."""
        cmd.memory_barrier("compute|fragment", "transfer")
        cmd.fill(world.depths, 0, 0, 4 * world.worlds * world.stride)
        cmd.fill(world.big, 0, 0, 16)

    def world_steps(self, slot: int, plan: Any, job: WorldJob, classes: Sequence[str],
                    material_sets: Sequence[Any], set0: Any, resources: dict[str, Any],
                    moved: np.ndarray | None = None) -> list[Step]:
        """The steps that draw every layer of `plan` (render/world_shadows.py's plan: one
        layer a directional light) for each of `job`'s worlds into `job.depths`; the last,
        "shadows", orders them before the shading's reads (as `steps`'). With `job.kept`,
        every world's layers copy that kept map first (the clip rows' CLIP_COPY: ShadowMaps.
        write_world_rows) and only the casters `moved` (a bool per draw) are drawn over it."""
        key, table = self._table(classes, moved if job.kept is not None else None)
        dset = self._set(key, table, slot, job)
        push = self._push(plan, table, job, self.maps.clip_at if job.kept is not None else None)
        record = self._records(table, dset, push, _jobs(plan, _whole(plan)), material_sets, set0, job)
        resources.update({"shadow_world_depths": BufferResource(job.depths),
                          "shadow_world_big": BufferResource(job.big)})
        if job.kept is None:
            return self._steps(record, table, "shadow_world_depths", "shadow_world_big")
        resources["shadow_world_kept"] = BufferResource(job.kept)
        return self._steps(record, table, "shadow_world_depths", "shadow_world_big",
                           "shadow_world_kept")

    def world_kept_steps(self, slot: int, plan: Any, job: WorldJob, classes: Sequence[str],
                         material_sets: Sequence[Any], set0: Any, resources: dict[str, Any],
                         moved: np.ndarray) -> list[Step]:
        """The steps that draw `job.kept`, the map every world of `job` copies: `plan`'s
        layers from the casters the worlds do not move (not `moved`), placed by the state's
        own records (every world's record of such a caster is the state's: render/worlds.py),
        as one world's maps."""
        kept = dataclasses.replace(job, depths=job.kept, worlds=1, first_record=0, kept=None)
        key, table = self._table(classes, ~moved)
        dset = self._set(key, table, slot, kept)
        record = self._records(table, dset, self._push(plan, table, kept),
                               _jobs(plan, _whole(plan)), material_sets, set0, kept)
        resources.update({"shadow_world_kept": BufferResource(job.kept),
                          "shadow_world_big": BufferResource(job.big)})
        return self._steps(record, table, "shadow_world_kept", "shadow_world_big",
                           prefix="shadows.kept.")

    def _spans(self, jobs: list[tuple[int, int, Any]]) -> list[tuple[int, int]]:
        """(byte offset, bytes) of the drawn layers' depths in `depths`, a span a job."""
        out = []
        for matrix, layers, e in jobs:
            if e.kind == "point":
                n = self.maps.cubes.size ** 2
                out.append((4 * (self.cube_base + (matrix - self.max_layers) * n), 4 * layers * n))
            else:
                n = self.maps.maps.size ** 2
                out.append((4 * matrix * n, 4 * layers * n))
        return out

    def _copy(self, cmd: Any, jobs: list[tuple[int, int, Any]]) -> None:
        """The drawn layers into the maps' images (ShadowMaps' layered images keep the others)."""
        maps, cubes = self.maps.maps, self.maps.cubes
        regions: dict[str, list[tuple[int, int, int]]] = {"maps": [], "cubes": []}
        for (matrix, layers, e), (offset, _) in zip(jobs, self._spans(jobs), strict=True):
            point = e.kind == "point"
            regions["cubes" if point else "maps"].append(
                (offset, matrix - self.max_layers if point else matrix, layers))
        for name, image in (("maps", maps), ("cubes", cubes)):
            if regions[name]:
                image.record_copy(cmd, self.depths, regions[name])

    def read_depths(self) -> np.ndarray:
        """The depth buffer as float32 (tests; waits for the device)."""
        from vkpbr.gpu.buffer import download_buffer

        self.device.wait_idle()
        return download_buffer(self.device, self.depths, np.float32)

    def destroy(self) -> None:
        if self.depths is not None and self.maps.frame_depths is self.depths:
            self.maps.bind_frame_depths(None)  # (set 3 must not name a destroyed buffer)
        while self._owned:
            self._owned.pop().destroy()


def make_steps(maps: Any, recorder: Any, frame_index: int, plan: Any, redraw: Sequence[range] | None,
               classes: Sequence[str], material_sets: Sequence[Any], set0: Any,
               resources: dict[str, Any], copy: bool = False) -> list[Step]:
    """render/steps.py's "shadows" group when the maps are drawn by compute shaders: the
    renderer's ShadowRaster (made on first use) and its steps, its buffers added to
    `resources`."""
    raster = maps.compute_raster(recorder.gpu_scene)
    out = raster.steps(frame_index, plan, redraw, classes, material_sets, set0, copy)
    resources.update(raster.resources())
    return out

