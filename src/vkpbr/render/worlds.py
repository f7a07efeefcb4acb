"""A batch of worlds on the GPU: each frame slot's draw records for W worlds.

`Renderer.render_batch(worlds=...)` (docs/batch.md "Worlds") renders views that each see
one of W worlds: the scene with its own poses of the N slot nodes (vkpbr.scene.worlds).
Every step that places geometry reads a draw's matrices from Instances at
`views[view].instance_base + draw` (generated.glsl's ViewRecord): 0 for frames and plain
batches, whose Instances are the scene state's records (render/scene_state.py). A batch of
worlds binds instead its slot's buffer here,

    [the state's D records | world 0's D records | world 1's | ...],

and gives view b the base (1 + world_of_view[b]) * D. What reads record `draw` without a
view (the shadow maps) reads the state's, so shadow maps are the renderer's state's, shared
by every world, unless the worlds move casters (render/world_shadows.py: each world's own). Each slot has its own buffer (host-visible,
device-local where the GPU has it), written after the slot's fence as GpuSceneState's is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import ComputePipeline
from vkpbr.gpu.compute import groups as work_groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import Step
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.scene_state import RECORD_BYTES
from vkpbr.scene.worlds import WorldSlots

__all__ = ["WorldBuffers", "WorldCall", "GpuWorlds", "WorldKernel"]


@dataclass(frozen=True)
class GpuWorlds:
    """Worlds whose poses the GPU expands (worlds.comp): `worlds` worlds of `slots`, poses
    of `pose_floats` (7 or 16) floats each, written into the kernel's inputs by `fill`
    (given the WorldKernel: from NumPy into its host-visible inputs, or from CUDA tensors)."""

    slots: WorldSlots
    worlds: int
    pose_floats: int
    wxyz: bool
    has_visible: bool
    fill: Callable[[Any], None]
    cuda: bool = False  # the inputs come from CUDA tensors (exported memory)
    local: bool = False  # poses relative to each node's parent in the state (WorldSlots.frame)

    @property
    def key(self) -> tuple:
        """What the recorded commands depend on (the kernel's push constants)."""
        return ("gpu", self.worlds, len(self.slots), self.pose_floats, self.wxyz, self.has_visible,
                self.local)


@dataclass(frozen=True)
class WorldCall:
    """One render_batch call's worlds: the world each view sees ((B,) int64), and either
    every world's draw records made on the host ((W * D, 2, 4, 4) float32: `records`) or
    poses the GPU expands (`gpu`)."""

    world_of_view: np.ndarray
    records: np.ndarray | None = None
    gpu: GpuWorlds | None = None
    factors: np.ndarray | None = None  # (W, S, 4) float32 WorldFactors blocks (worlds.glsl)
    moved: np.ndarray | None = None  # (D,) bool: the draws `records` move (world_shadows.py)

    @property
    def poses(self) -> bool:
        """The worlds pose nodes (else only their materials differ)."""
        return self.records is not None or self.gpu is not None

    @property
    def key(self) -> tuple:
        return (self.gpu.key if self.gpu is not None else ("host", self.poses),
                self.factors is not None)


class WorldBuffers:
    """Per frame slot, a buffer of the state's and `capacity` worlds' draw records (grown,
    never shrunk)."""

    def __init__(self, device: Device, slots: int, draws: int) -> None:
        self.device, self.draws = device, max(draws, 1)
        self.capacity = 0
        self.buffers: list[Buffer] = []
        self.slots = slots
        self._base: tuple[np.ndarray, np.ndarray] | None = None  # instance_base's last

    def ensure(self, worlds: int) -> bool:
        """Room for `worlds` worlds; True when the buffers were (re)made (their sets must be
        rebound and the recordings that named the old ones freed)."""
        if worlds <= self.capacity:
            return False
        self.device.wait_idle()
        self.destroy()
        self.capacity = max(worlds, 2 * self.capacity)
        size = (1 + self.capacity) * self.draws * RECORD_BYTES
        self.buffers = [Buffer(self.device, size, "storage", host_visible=True, device_local=True,
                               name=f"world records {i}") for i in range(self.slots)]
        return True

    def region(self, slot: int) -> tuple[Buffer, int, int]:
        """(buffer, offset, size) of slot `slot`'s records: what its sets bind."""
        b = self.buffers[slot]
        return b, 0, b.size

    def write(self, slot: int, state_records: np.ndarray, world_records: np.ndarray) -> None:
        """Slot `slot`'s records: the state's (D, 2, 4, 4), then the worlds' (W * D, 2, 4, 4)
        float32 (vkpbr.scene.worlds.world_records), after the slot's fence."""
        out = self.buffers[slot].array(np.float32, state_records.size + world_records.size)
        out[:state_records.size] = state_records.ravel()
        out[state_records.size:] = world_records.ravel()

    def instance_base(self, world_of_view: np.ndarray) -> np.ndarray:
        """(B,) uint32: where each view's world's records start (in records of a draw); the
        same array again for the same read-only `world_of_view` (render/batch_cache.py keeps
        it: a loop's steps then compare their view records by identity, not by value)."""
        last = self._base
        if last is not None and last[0] is world_of_view:
            return last[1]
        base = ((np.asarray(world_of_view, np.int64) + 1) * self.draws).astype(np.uint32)
        if isinstance(world_of_view, np.ndarray) and not world_of_view.flags.writeable:
            base.flags.writeable = False
            self._base = (world_of_view, base)
        return base

    def destroy(self) -> None:
        for b in self.buffers:
            b.destroy()
        self.buffers = []


class WorldKernel:
    """worlds.comp and its inputs: the poses (and visibility) of a call's worlds, the draws'
    anchors and relative transforms (from WorldSlots), a set per frame slot naming them and
    the slot's WorldBuffers region. `cuda`: the inputs are exportable device memory that CUDA
    writes (gpu/cuda.py), else host-visible memory NumPy writes."""

    def __init__(self, device: Device, slots: int) -> None:
        self.device, self.slot_count = device, slots
        self._objects: list[Any] = []
        names = ("WorldRecords", "WorldPoses", "WorldVisible", "WorldDraws", "WorldCovers",
                 "WorldErrors")
        self.layout = self._own(DescriptorSetLayout(device, [
            BindingSpec(i, "storage", ("compute",), n) for i, n in enumerate(names)]))
        self.pipeline = self._own(ComputePipeline(device, SPV_DIR / "worlds.comp.spv",
                                                  [self.layout], push_bytes=32))
        pool = self._own(DescriptorPool(device, [(self.layout, slots)]))
        self.sets = [pool.allocate(self.layout) for _ in range(slots)]
        self.inputs: list[Buffer] = []  # poses, visible
        self.tables: list[Buffer] = []  # draws, covers
        self.cuda = False
        self._input_floats = 0
        self._slots: WorldSlots | None = None
        self._bound: tuple = ()
        self.generation = 0  # bumped when the sets change (recordings name them)
        self._imports: list[Any] = []  # gpu/cuda.py CudaImport of the inputs (cuda)
        # Imports of inputs since replaced whose poses view a caller holds (`input_view`):
        # kept mapped until `destroy`, so a tensor handed out never views freed memory.
        self._lent: list[Any] = []
        # worlds.comp's report of poses that are none (count, lowest world), per slot
        self._error_stride = max(8, int(device.limits.minStorageBufferOffsetAlignment))
        self.errors = Buffer(device, self._error_stride * slots, "storage", host_visible=True,
                             name="world errors")
        self._errors = self.errors.array(np.uint32, self._error_stride // 4 * slots).reshape(
            slots, -1)[:, :2]
        self._errors[:] = (0, 0xFFFFFFFF)
        # (the counts read as Python ints through a memoryview: a step's check of its slot's
        # report costs an index, not a NumPy row and its tolist)
        self._counts = memoryview(self.errors.array(np.uint32, self._error_stride // 4 * slots))
        self._words = self._error_stride // 4
        self.order: Any = None  # render/cuda_order.py CudaOrder of the call, if any

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    def prepare(self, gw: GpuWorlds, buffers: WorldBuffers, cuda: bool) -> None:
        """Inputs for `gw`, the slots' tables, the sets bound; then `gw.fill(self)`."""
        floats = gw.worlds * len(gw.slots) * gw.pose_floats
        if floats > self._input_floats or cuda != self.cuda:
            self.device.wait_idle()
            self._close_imports()
            for b in self.inputs:
                b.destroy()
            self._input_floats = max(floats, 2 * self._input_floats)
            flags = {"exportable": True} if cuda else {"host_visible": True}
            self.inputs = [Buffer(self.device, 4 * self._input_floats, "storage", name="world poses", **flags),
                           Buffer(self.device, 4 * max(self._input_floats // 7, 1), "storage",
                                  name="world visibility", **flags)]
            self.cuda = cuda
        if self._slots is not gw.slots:
            self._write_tables(gw.slots)
        bound = (tuple(id(b) for b in (*self.inputs, *self.tables)), tuple(id(b) for b in buffers.buffers))
        if bound != self._bound:
            self.device.wait_idle()
            w = DescriptorWriter(self.device)
            for slot, dset in enumerate(self.sets):
                buf, at, size = buffers.region(slot)
                w.storage(dset, 0, buf, size, at)
                for i, b in enumerate((*self.inputs, *self.tables)):
                    w.storage(dset, 1 + i, b)
                w.storage(dset, 5, self.errors, 8, self._error_stride * slot)
            w.update()
            self._bound = bound
            self.generation += 1
        gw.fill(self)

    def _write_tables(self, slots: WorldSlots) -> None:
        d = len(slots.anchor)
        words = -(-len(slots) // 32)
        draws = np.zeros(max(d, 1), np.dtype([("relative", "<f4", (4, 4)), ("frame", "<f4", (4, 4)),
                                              ("anchor", "<i4"), ("identity", "<u4"),
                                              ("covers_at", "<u4"), ("pad", "<u4")]))
        draws["relative"][:d] = np.swapaxes(slots.relative, -1, -2)  # GLSL columns
        has = slots.anchor >= 0
        draws["frame"][:d] = np.eye(4, dtype=np.float32)
        draws["frame"][:d][has] = np.swapaxes(slots.frame[slots.anchor[has]], -1, -2)
        draws["anchor"][:d] = slots.anchor
        draws["identity"][:d] = slots.identity
        draws["covers_at"][:d] = np.arange(d) * words
        bits = np.zeros((max(d, 1), words), np.uint32)
        for n in range(len(slots)):  # per slot node (a few): its bit in every draw's words
            bits[:d, n // 32] |= slots.covers[n].astype(np.uint32) << np.uint32(n % 32)
        for b in self.tables:
            b.destroy()
        self.tables = [Buffer(self.device, draws.nbytes, "storage", host_visible=True, name="world draws"),
                       Buffer(self.device, bits.nbytes, "storage", host_visible=True, name="world covers")]
        self.tables[0].array(np.uint8, draws.nbytes)[:] = draws.view(np.uint8).ravel()
        self.tables[1].array(np.uint32, bits.size)[:] = bits.ravel()
        self._slots = slots

    def take_errors(self, slot: int) -> tuple[int, int]:
        """(records whose pose was none, the lowest such world) of slot `slot`'s last batch
        (after its fence), and the report reset for its next."""
        count = self._counts[slot * self._words]
        if not count:  # (as reset: the kernel writes only where a pose is none)
            return 0, 0xFFFFFFFF
        world = self._counts[slot * self._words + 1]
        self._errors[slot] = (0, 0xFFFFFFFF)
        return count, world

    def write_numpy(self, poses: np.ndarray, visible: np.ndarray | None) -> None:
        """NumPy inputs: (W, N, 7 or 16) poses and (W, N) visibility into the host-visible
        inputs (GpuWorlds.fill's for NumPy arrays)."""
        # (converted as copied into the mapped inputs: one pass, no float32 temporary)
        np.copyto(self.inputs[0].array(np.float32, poses.size), poses.reshape(-1),
                  casting="same_kind")
        if visible is not None:
            np.copyto(self.inputs[1].array(np.uint32, visible.size), visible.reshape(-1),
                      casting="unsafe")

    def input_view(self, shape: tuple[int, ...]) -> Any:
        """A float32 CUDA tensor of `shape` viewing the exported poses input itself: poses
        written there (on torch's current stream) are read by the next batch given this
        tensor, without `write_cuda`'s copy. Valid while the renderer lives (inputs replaced
        for a bigger batch stay mapped: `_lent`). Needs the CUDA inputs made (a CUDA batch
        of at least these poses ran)."""
        count = int(np.prod(shape))
        if not self._imports or count > self._input_floats:
            return None
        self._imports[0].lent = True
        return self._imports[0].tensor(tuple(int(n) for n in shape), "<f4")

    def write_cuda(self, poses: Any, visible: Any) -> None:
        """CUDA inputs: torch tensors (W, N, 7 or 16) and (W, N) copied device to device into
        the exported inputs on torch's current stream, then that stream waited for (the
        host waits; the simulator's work queued before is done by then, as the render needs
        it), so the batch's submission reads them. GpuWorlds.fill's for CUDA tensors."""
        import torch

        if not self._imports:
            from vkpbr.gpu.cuda import CudaImport, cuda_device_for

            index = cuda_device_for(self.device.uuid(), self.device.info.name)
            self._imports = [CudaImport(b.export_fd(), b.allocation_size, index) for b in self.inputs]
        order = self.order
        if order is not None:  # ordered on the GPU (render/cuda_order.py): no host wait
            order.before_inputs()
        # (the inputs viewed in the poses' own shape: no reshape, a torch call less a step;
        # poses that are that view, `input_view`'s, were written in place: no copy)
        inputs = self._imports[0].tensor(poses.shape, "<f4")
        if poses.data_ptr() != inputs.data_ptr():
            inputs.copy_(poses)
        if visible is not None:
            self._imports[1].tensor(visible.shape, "<i4").copy_(visible)
        if order is not None:
            order.inputs_written()
            return
        event = torch.cuda.Event()
        event.record()
        event.synchronize()

    def steps(self, frame_index: int, gw: GpuWorlds, draws: int) -> list[Step]:
        """The batch's first step: every world's records from its poses, then a barrier
        (compute writes -> the culling kernel's, vertex shaders' and compute reads)."""
        push = np.array([gw.worlds, len(gw.slots), draws, gw.pose_floats, int(gw.wxyz),
                         int(gw.has_visible), -(-len(gw.slots) // 32), int(gw.local)], np.uint32)

        def record(cmd: Commands) -> None:
            cmd.bind_pipeline(self.pipeline)
            cmd.bind_set(0, self.sets[frame_index])
            cmd.push(push)
            cmd.dispatch(*work_groups((gw.worlds * draws, 1, 1), (64, 1, 1)))
            cmd.memory_barrier("compute", "vertex|compute")

        return [Step("worlds", record)]

    def _close_imports(self, lent_too: bool = False) -> None:
        for imported in self._imports:
            if imported.lent and not lent_too:
                self._lent.append(imported)  # (a caller's tensor views it: closed at destroy)
            else:
                imported.close()
        self._imports = []
        if lent_too:
            for imported in self._lent:
                imported.close()
            self._lent = []

    def destroy(self) -> None:
        self._close_imports(lent_too=True)
        self.errors.destroy()
        for b in (*self.inputs, *self.tables):
            b.destroy()
        self.inputs, self.tables = [], []
        while self._objects:
            self._objects.pop().destroy()
