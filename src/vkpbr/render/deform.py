"""Skins and morph targets: which draw records deform, and the kernel that poses them.

A draw record whose mesh is skinned (JOINTS/WEIGHTS and a node with a `skin`) or has morph
targets is *deformed*: at set-up GpuScene gives it its own region of the scene's vertex
streams (a copy of its mesh's vertices: one stream per deformed instance, never per view),
and points the record's vertex offset there. Each frame, the "deform" step (deform.comp)
writes the posed positions, normals and tangents into those regions from the rest vertices,
the morph weights and the joint matrices of the frame slot's scene state
(render/scene_state.py), before anything draws. Every later step reads the posed vertices as
any other (one place, no per-path copy). A skinned record's model matrix is the identity:
skinned positions are world positions (glTF 3.7.3).

Culling: a deformed record's bounding sphere is unbounded (it is never culled), since its
vertices move beyond its mesh's rest bounds. The QTangent and packed TBN paths (the course's
debug modes) read the rest frames of deformed meshes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer, upload_buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import ComputePipeline
from vkpbr.gpu.compute import groups as work_groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import BufferResource, Step
from vkpbr.render.codegen import SPV_DIR
from vkpbr.scene.types import Scene

__all__ = ["Deformed", "deformed_records", "DeformLayout", "DeformKernel", "UNBOUNDED_RADIUS"]

UNBOUNDED_RADIUS = 3.0e38  # a sphere no frustum test culls
_NO_SKIN = 0xFFFFFFFF
_GROUP = 64  # deform.comp's local size


@dataclass(frozen=True)
class Deformed:
    """One deformed draw record: scene node, instance (-1: none), mesh, skin (index into
    Scene.skins, or None) and the tree node whose morph weights it takes."""

    node: int
    instance: int
    mesh: int
    skin: int | None
    tree: int


def deformed_records(scene: Scene) -> list[Deformed]:
    """The scene's deformed draw records, in draw-record order (GpuScene's _draw_nodes)."""
    tree = scene.node_tree()
    out: list[Deformed] = []
    for i, node in enumerate(scene.nodes):
        if not 0 <= node.mesh < len(scene.meshes):
            continue
        mesh = scene.meshes[node.mesh]
        skin = tree.skin.get(node.tree) if getattr(mesh, "joints", None) is not None else None
        skin = skin if skin is not None and 0 <= skin < len(getattr(scene, "skins", [])) else None
        if skin is None and not getattr(mesh, "morph_targets", None):
            continue
        for k in range(node.instance_count):
            out.append(Deformed(i, k if node.instances is not None else -1, node.mesh, skin,
                                node.tree))
    return out


class DeformLayout:
    """Where each deformed record's joint matrices and weights lie in the scene state's
    deform floats (a frame slot's copy), and what the state computes them from. The joint
    matrices of every skinned record are one contiguous run (record order), made per frame by
    one gather and one batched product over all of them; the weights follow."""

    def __init__(self, scene: Scene, records: list[Deformed]) -> None:
        self.records = records
        skins = [scene.skins[r.skin] for r in records if r.skin is not None]
        self.joint_nodes = np.concatenate([s.joints for s in skins]) if skins else np.zeros(0, np.int64)
        self.inverse_bind = (np.concatenate([s.inverse_bind for s in skins]) if skins
                             else np.zeros((0, 4, 4)))
        # Each record's first joint float (its skin's run; 0 for an unskinned record).
        joint_at, at = [], 0
        for r in records:
            joint_at.append(at)
            at += 16 * len(scene.skins[r.skin].joints) if r.skin is not None else 0
        self.joint_at = joint_at
        # (record, tree node, first float, targets, the mesh's default weights) of the morphed.
        self.morphed: list[tuple[int, int, int, np.ndarray | None]] = []
        weight_at = []
        for r in records:
            weight_at.append(at)
            t = target_count(scene.meshes[r.mesh])
            if t:
                self.morphed.append((r.tree, at, t, scene.meshes[r.mesh].morph_weights))
            at += t
        self.weight_at, self.floats = weight_at, at

    def values(self, world: np.ndarray, weights: dict[int, np.ndarray]) -> np.ndarray:
        """(floats,) float32: every record's joint matrices (world[joints] @ inverse bind,
        column-major) and morph weights (`weights` by tree node, else the mesh's)."""
        out = np.zeros(max(self.floats, 1), np.float32)
        if len(self.joint_nodes):
            joints = world[self.joint_nodes] @ self.inverse_bind
            out[:joints.size] = np.swapaxes(joints, -1, -2).ravel()
        for tree, at, t, default in self.morphed:
            w = weights.get(tree, default)
            if w is not None:
                out[at:at + t] = np.asarray(w, np.float64)[:t]
        return out


def target_count(mesh: object) -> int:
    """How many morph targets a mesh has (0: none)."""
    targets = getattr(mesh, "morph_targets", None) or {}
    return max((len(a) for a in targets.values()), default=0)


def _targets(scene: Scene, mesh: int) -> np.ndarray:
    """(T, N, 9) float32: a mesh's morph displacements (position, normal, tangent), zeros for
    an attribute its targets lack; (0, N, 9) without targets."""
    m = scene.meshes[mesh]
    targets = getattr(m, "morph_targets", None) or {}
    t = max((len(a) for a in targets.values()), default=0)
    out = np.zeros((t, m.vertex_count, 9), np.float32)
    for j, name in enumerate(("POSITION", "NORMAL", "TANGENT")):
        if name in targets:
            out[:, :, 3 * j:3 * j + 3] = np.asarray(targets[name], np.float32)[:, :, :3]
    return out


class DeformKernel:
    """deform.comp with its buffers: each mesh's skin vertices and morph displacements
    (once per mesh), the jobs (one per deformed record) and a set per frame slot."""

    def __init__(self, device: Device, scene: Scene, gs: Any, layout: DeformLayout,
                 state_regions: list[tuple[Buffer, int, int]]) -> None:
        self._objects: list[Any] = []
        skin_rows, deltas, jobs = self._tables(scene, gs, layout)
        self.jobs = len(layout.records)
        self.max_vertices = max((scene.meshes[r.mesh].vertex_count for r in layout.records), default=1)
        bufs = [self._own(upload_buffer(device, a, "storage", name=n)) for a, n in
                ((skin_rows, "skin vertices"), (deltas, "morph displacements"), (jobs, "deform jobs"))]
        names = ("DeformPositions", "DeformNormals", "DeformTangents", "SkinVertices",
                 "MorphDeltas", "DeformJobs", "DeformState", "DeformPrev")
        self.first_posed = min(gs.posed_offsets, default=0)
        posed = max(gs.vertex_count - self.first_posed, 1)
        # The previous frame's posed positions (the motion output reads them).
        self.prev_positions = self._own(Buffer(device, 12 * posed, "storage",
                                               name="previous posed positions"))
        self.set_layout = self._own(DescriptorSetLayout(device, [
            BindingSpec(i, "storage", ("compute",), n) for i, n in enumerate(names)]))
        self.pipeline = self._own(ComputePipeline(device, SPV_DIR / "deform.comp.spv",
                                                  [self.set_layout], push_bytes=4))
        pool = self._own(DescriptorPool(device, [(self.set_layout, len(state_regions))]))
        self.sets = [pool.allocate(self.set_layout) for _ in state_regions]
        self.streams = gs.streams
        w = DescriptorWriter(device)
        for s, (buf, offset, size) in zip(self.sets, state_regions, strict=True):
            for i, name in enumerate(("positions", "normals", "tangents")):
                w.storage(s, i, gs.streams[name])
            for i, b in enumerate(bufs):
                w.storage(s, 3 + i, b)
            w.storage(s, 6, buf, size, offset)
            w.storage(s, 7, self.prev_positions)
        w.update()

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    @staticmethod
    def _tables(scene: Scene, gs: Any, layout: DeformLayout) -> tuple[np.ndarray, ...]:
        """The skin rows (3 uvec4 a rest vertex: 8 uint16 joints, 8 float weights), the
        morph displacements and the jobs (2 uvec4 each: deform.comp)."""
        skin_at: dict[int, int] = {}
        delta_at: dict[int, int] = {}
        skin_rows: list[np.ndarray] = []
        deltas: list[np.ndarray] = []
        rows, floats = 0, 0
        jobs = np.zeros((max(len(layout.records), 1), 2, 4), np.uint32)
        for k, r in enumerate(layout.records):
            mesh = scene.meshes[r.mesh]
            if r.skin is not None and r.mesh not in skin_at:
                skin_at[r.mesh] = rows
                block = np.zeros((mesh.vertex_count, 3, 4), np.uint32)
                block[:, 0] = np.ascontiguousarray(mesh.joints, np.uint16).view(np.uint32).reshape(-1, 4)
                block[:, 1:] = np.ascontiguousarray(mesh.weights, np.float32).view(np.uint32).reshape(-1, 2, 4)
                skin_rows.append(block)
                rows += mesh.vertex_count
            if r.mesh not in delta_at:
                delta_at[r.mesh] = floats
                d = _targets(scene, r.mesh)
                deltas.append(d.ravel())
                floats += d.size
            jobs[k, 0] = (gs.vertex_offsets[r.mesh], gs.posed_offsets[k], mesh.vertex_count,
                          skin_at[r.mesh] if r.skin is not None else _NO_SKIN)
            jobs[k, 1] = (delta_at[r.mesh], target_count(mesh), layout.joint_at[k],
                          layout.weight_at[k])
        skin = np.concatenate(skin_rows).ravel() if skin_rows else np.zeros(12, np.uint32)
        delta = np.concatenate(deltas) if deltas and floats else np.zeros(9, np.float32)
        return skin, delta.astype(np.float32), jobs.ravel()

    def steps(self, frame_index: int) -> list[Step]:
        """The frame's deform step: every deformed record's vertices posed from the slot's
        state. It ends with its own barrier (compute writes -> vertex input and shader
        reads of the streams), which every later step draws after."""
        def record(cmd: Commands) -> None:
            cmd.bind_pipeline(self.pipeline)
            cmd.bind_set(0, self.sets[frame_index])
            cmd.push(np.array([self.first_posed], np.uint32))
            cmd.dispatch(work_groups((self.max_vertices, 1, 1), (_GROUP, 1, 1))[0], self.jobs)
            cmd.memory_barrier("compute", "vertex_input|vertex|compute")

        return [Step("deform", record, (("posed", "storage"), ("prev_posed", "storage")))]

    def resources(self) -> dict[str, BufferResource]:
        return {"posed": BufferResource(self.streams["positions"]),
                "prev_posed": BufferResource(self.prev_positions)}

    def destroy(self) -> None:
        while self._objects:
            self._objects.pop().destroy()
