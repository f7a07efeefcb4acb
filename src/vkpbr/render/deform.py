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

Culling: each frame a deformed record gets a sphere that holds its posed vertices
(`DeformLayout.frames`): for a skinned record, the union of its joints' spheres (each joint's
sphere around the bind-space vertices it moves, computed once at load, placed by the joint
matrix and grown by its largest stretch), which holds every blend of them since the weights
are convex; for a morphed one, the rest sphere grown by sum |weight| x the target's largest
displacement. The deform step writes the posed vertices relative to that sphere, (p - c) / r,
and the record's model matrix takes them back (translate(c) x scale(r)): the culling kernels,
which place each record's mesh-space sphere (here the unit sphere) with its model matrix, then
cull deformed records like any other, on every path and in the shadow maps, with no extra
buffer per frame slot. A skin whose weights are not convex (negative or not summing to one)
keeps an unbounded sphere (never culled). The QTangent and packed TBN paths (the course's
debug modes) read the rest frames of deformed meshes.
"""

from __future__ import annotations

import functools
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
from vkpbr.scene.draw_table import blocks
from vkpbr.scene.types import Mesh, MeshBox, Scene, points_box

__all__ = ["draw_sphere", "Deformed", "deformed_records", "DeformLayout", "DeformKernel", "UNBOUNDED_RADIUS",
           "convex_weights", "DEFORMED_RADIUS"]

UNBOUNDED_RADIUS = 3.0e38  # a sphere no frustum test culls
# A deformed record's mesh-space sphere: the unit sphere (its posed vertices are written
# within it, `DeformLayout.frames`), with room for float32 rounding.
DEFORMED_RADIUS = 1.0 + 1e-4
_GROW = 1.0 + 1e-5  # the frames' spheres, grown for float32 rounding of the posed vertices
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
    """The scene's deformed draw records, in draw-record order (gpu_scene.draw_nodes)."""
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
    """Where each deformed record's joint matrices, weights and frame lie in the scene
    state's deform floats (a frame slot's copy), and what the state computes them from. The
    joint matrices of every skinned record are one contiguous run (record order), made per
    frame by one gather and one batched product over all of them; the weights follow, then
    one frame (centre, 1 / radius) per record (the sphere its posed vertices are written in).
    """

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
        # The frames start at a multiple of 4 floats: deform.comp reads each as one vec4.
        self.weight_at, self.frames_at = weight_at, (at + 3) // 4 * 4
        self.floats = self.frames_at + 4 * len(records)
        self._bounds_tables(scene)
        self._joints: np.ndarray | None = None
        self._frames = np.zeros((len(records), 4))  # (centre, 1 / radius) per record
        self._frames[:, 3] = 1.0

    def _bounds_tables(self, scene: Scene) -> None:
        """What the frames are made from, once: each skinned record's joints' bind-space
        spheres (in joint-run order), each record's rest sphere and largest displacement per
        morph target, and which records are bounded at all."""
        rs = self.records
        self.skinned = np.array([r.skin is not None for r in rs], bool)
        self.tree_nodes = np.array([r.tree for r in rs], np.int64)
        convex = {m: convex_weights(scene.meshes[m]) for m in {r.mesh for r in rs if r.skin is not None}}
        self.bounded = np.array([r.skin is None or convex[r.mesh] for r in rs], bool)
        spheres = {m: rest_sphere(scene.meshes[m]) for m in {r.mesh for r in rs}}
        self.rest_centre = np.array([spheres[r.mesh][0] for r in rs]).reshape(-1, 3)
        self.rest_radius = np.array([spheres[r.mesh][1] for r in rs])
        reach = {m: target_reach(scene.meshes[m]) for m in {r.mesh for r in rs}}
        self._reach = [(k, r.tree, scene.meshes[r.mesh].morph_weights, reach[r.mesh])
                       for k, r in enumerate(rs) if len(reach[r.mesh])]
        skinned = [r for r in rs if r.skin is not None]
        counts = [len(scene.skins[r.skin].joints) for r in skinned]
        # Once a mesh and joint count (a crowd's instances share theirs: 1.5 ms each, 1.5 s
        # for 1,000 CesiumMan when each record computed its own)
        spheres_of = functools.cache(lambda m, n: joint_spheres(scene.meshes[m], n))
        mine = [spheres_of(r.mesh, n) for r, n in zip(skinned, counts, strict=True)]
        self.joint_centre = (np.concatenate([c for c, _ in mine]) if skinned
                             else np.zeros((0, 3)))
        self.joint_radius = (np.concatenate([rad for _, rad in mine]) if skinned
                             else np.zeros(0))
        self.joint_starts = np.cumsum([0] + counts[:-1]).astype(np.int64)
        self.joint_record = np.repeat(np.flatnonzero(self.skinned), counts).astype(np.int64)

    def affected(self, touched: np.ndarray) -> np.ndarray:
        """(records,) bool: the records whose frame or joint matrices a change of the tree
        nodes `touched` (bool, with their subtrees) moves: a joint, or the node whose morph
        weights the record takes."""
        hit = touched[self.tree_nodes]
        if len(self.joint_nodes):
            hit[self.skinned] |= np.logical_or.reduceat(touched[self.joint_nodes], self.joint_starts)
        return hit

    def frames(self, world: np.ndarray, weights: dict[int, np.ndarray]) -> np.ndarray:
        """(records, 4, 4) each record's frame for this pose: translate(c) x scale(r) of a
        sphere (c, r) holding its posed vertices (world space for a skinned record, mesh
        space for a morphed one; identity for an unbounded one). Keeps the joint matrices
        for `values`."""
        extent = self._extents(weights)
        centre, radius = self.rest_centre.copy(), self.rest_radius + extent
        if len(self.joint_nodes):
            joints = np.empty((len(self.joint_nodes), 4, 4))
            for b in blocks(len(joints)):  # (cache-sized blocks: scene/draw_table.py)
                np.matmul(world[self.joint_nodes[b]], self.inverse_bind[b], out=joints[b])
            self._joints = joints
            c, r = joint_union(joints, self.joint_centre,
                               self.joint_radius + extent[self.joint_record], self.joint_starts)
            centre[self.skinned], radius[self.skinned] = c, r
        radius = np.maximum(radius * _GROW, 1e-6 * (1.0 + np.abs(centre).max(axis=1, initial=0.0)))
        centre[~self.bounded], radius[~self.bounded] = 0.0, 1.0
        out = np.zeros((len(self.records), 4, 4))
        out[:, 0, 0] = out[:, 1, 1] = out[:, 2, 2] = radius
        out[:, :3, 3], out[:, 3, 3] = centre, 1.0
        self._frames = np.concatenate([centre, 1.0 / radius[:, None]], axis=1)
        return out

    def _extents(self, weights: dict[int, np.ndarray]) -> np.ndarray:
        """(records,) how far morph targets can move a vertex at these weights:
        sum |w_t| x the target's largest displacement."""
        out = np.zeros(len(self.records))
        for k, tree, default, reach in self._reach:
            w = weights.get(tree, default)
            if w is not None:
                w = np.abs(np.asarray(w, np.float64).reshape(-1))[:len(reach)]
                out[k] = float(w @ reach[:len(w)])
        return out

    def values(self, world: np.ndarray, weights: dict[int, np.ndarray]) -> np.ndarray:
        """(floats,) float32: every record's joint matrices (world[joints] @ inverse bind,
        column-major), morph weights (`weights` by tree node, else the mesh's) and frame
        (centre, 1 / radius), as the last `frames` made them."""
        out = np.zeros(max(self.floats, 1), np.float32)
        if len(self.joint_nodes):
            joints = self._joints if self._joints is not None else world[self.joint_nodes] @ self.inverse_bind
            # (column-major: one transposing, converting pass, no float64 temporary)
            out[:joints.size].reshape(-1, 4, 4)[:] = np.swapaxes(joints, -1, -2)
        for tree, at, t, default in self.morphed:
            w = weights.get(tree, default)
            if w is not None:
                out[at:at + t] = np.asarray(w, np.float64)[:t]
        out[self.frames_at:self.frames_at + self._frames.size] = self._frames.ravel()
        return out


def joint_union(joints: np.ndarray, centre: np.ndarray, radius: np.ndarray, starts: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Per run of joints (each skinned record's, from `starts`): the sphere around the box of
    its joints' posed spheres. Joint j's bind-space sphere (centre, radius; radius < 0: it
    moves no vertex) goes to joints[j] x centre with radius x the matrix's largest stretch
    (bounded by the square root of the largest row sum of |A^T A|: exact for a rotation
    times a uniform scale)."""
    lo, hi = np.empty((len(joints), 3)), np.empty((len(joints), 3))
    for b in blocks(len(joints)):
        # Components as contiguous rows (m[i][k]: row i, column k), centres as columns.
        m = np.ascontiguousarray(joints[b, :3].transpose(1, 2, 0))
        p = np.ascontiguousarray(centre[b].T)
        c = np.stack([m[i, 0] * p[0] + m[i, 1] * p[1] + m[i, 2] * p[2] + m[i, 3] for i in range(3)], 1)
        g = {(k, j): _column_dot(m, k, j) for k, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))}
        g01, g02, g12 = np.abs(g[0, 1]), np.abs(g[0, 2]), np.abs(g[1, 2])  # (symmetric)
        rows = [g[0, 0] + g01 + g02, g01 + g[1, 1] + g12, g02 + g12 + g[2, 2]]
        r = (radius[b] * np.sqrt(np.maximum(np.maximum(rows[0], rows[1]), rows[2])))[:, None]
        used = (radius[b] >= 0)[:, None]
        lo[b] = np.where(used, c - r, np.inf)
        hi[b] = np.where(used, c + r, -np.inf)
    lo, hi = np.minimum.reduceat(lo, starts), np.maximum.reduceat(hi, starts)
    empty = ~np.all(lo <= hi, axis=1)  # a skin none of whose joints moves a vertex
    lo[empty], hi[empty] = 0.0, 0.0
    return (lo + hi) / 2, np.linalg.norm(hi - lo, axis=1) / 2


def _column_dot(m: np.ndarray, k: int, j: int) -> np.ndarray:
    """Columns k and j of the 3x3 parts (m[row][column]: component rows) dotted."""
    return m[0, k] * m[0, j] + m[1, k] * m[1, j] + m[2, k] * m[2, j]


def convex_weights(mesh: Mesh) -> bool:
    """Whether every vertex's skin weights are >= 0 and sum to 1 (the loader renormalises):
    then a posed vertex is a blend of its joints' placements and lies in their spheres."""
    w = np.asarray(mesh.weights, np.float64)
    return bool(len(w) == 0 or (w.min() >= 0.0 and np.abs(w.sum(axis=1) - 1.0).max() <= 1e-3))


def draw_sphere(d: Any, box: MeshBox) -> tuple[float, float, float, float]:
    """A draw's bounding sphere (centre, radius) in its mesh's space, as the culling kernels
    test it (frustum.glsl world_sphere): its mesh's box's (`box(mesh)`: min, max), a little
    widened; a deformed draw's the unit sphere its posed vertices are written in, unbounded
    (never culled) without one. One rule for the batch's and the shadow raster's tables."""
    if d.deformed:
        return (0.0, 0.0, 0.0, UNBOUNDED_RADIUS if d.unbounded else DEFORMED_RADIUS)
    lo, hi = (v.astype(np.float64) for v in box(d.mesh))
    return (*((lo + hi) / 2), float(np.linalg.norm(hi - lo) / 2 * (1 + 1e-5) + 1e-6))


def rest_sphere(mesh: Mesh) -> tuple[np.ndarray, float]:
    """A mesh's rest vertices' sphere: its box's centre and the farthest vertex from it."""
    p = np.asarray(mesh.positions, np.float64)
    if not len(p):
        return np.zeros(3), 0.0
    lo, hi = points_box(p)
    c = (lo + hi) / 2
    return c, float(np.sqrt(((p - c) ** 2).sum(axis=1).max()))


def target_reach(mesh: object) -> np.ndarray:
    """(T,) the largest position displacement of each morph target of a mesh."""
    targets = (getattr(mesh, "morph_targets", None) or {}).get("POSITION")
    if targets is None:
        return np.zeros(target_count(mesh))
    d = np.asarray(targets, np.float64)[:, :, :3]
    reach = np.sqrt((d * d).sum(axis=2).max(axis=1, initial=0.0))
    return np.concatenate([reach, np.zeros(max(target_count(mesh) - len(reach), 0))])


def joint_spheres(mesh: Mesh, joints: int) -> tuple[np.ndarray, np.ndarray]:
    """(J, 3) centres and (J,) radii of the bind-space spheres around the vertices each of a
    skin's `joints` moves (weight > 0); radius -1 for a joint that moves none."""
    p = np.asarray(mesh.positions, np.float64)
    ji = np.asarray(mesh.joints, np.int64)
    w = np.asarray(mesh.weights)
    v, k = np.nonzero(w > 0)
    j = ji[v, k]
    lo = np.full((joints, 3), np.inf)
    hi = np.full((joints, 3), -np.inf)
    np.minimum.at(lo, j, p[v])
    np.maximum.at(hi, j, p[v])
    used = np.all(lo <= hi, axis=1)
    centre = np.where(used[:, None], (lo + hi) / 2, 0.0)
    radius = np.full(joints, -1.0)
    d = np.sqrt(((p[v] - centre[j]) ** 2).sum(axis=1))
    np.maximum.at(radius, j, d)
    return centre, radius


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
        self.jobs, self.frames_at = len(layout.records), layout.frames_at
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
                                                  [self.set_layout], push_bytes=8))
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
        reads of the streams), which every later step draws after.

        Before it, "deform_wait" records nothing but is timed: the posed streams are every
        frame slot's, so their first use in a frame waits for all earlier commands (the
        previous frame still drawing from them: gpu/graph.py); its timestamp falls when
        that wait ends, and FrameStats.pass_ms["deform"] is the kernel alone
        (pass_ms["deform_wait"]: the previous frame's tail, and the frame's start)."""
        def record(cmd: Commands) -> None:
            cmd.bind_pipeline(self.pipeline)
            cmd.bind_set(0, self.sets[frame_index])
            cmd.push(np.array([self.first_posed, self.frames_at], np.uint32))
            cmd.dispatch(work_groups((self.max_vertices, 1, 1), (_GROUP, 1, 1))[0], self.jobs)
            cmd.memory_barrier("compute", "vertex_input|vertex|compute")

        uses = (("posed", "storage"), ("prev_posed", "storage"))
        return [Step("deform_wait", lambda cmd: None, uses), Step("deform", record, uses)]

    def resources(self) -> dict[str, BufferResource]:
        return {"posed": BufferResource(self.streams["positions"]),
                "prev_posed": BufferResource(self.prev_positions)}

    def destroy(self) -> None:
        while self._objects:
            self._objects.pop().destroy()
