"""New instances of a loaded mesh, and materials of a node's own: what grows the draw table.

`add_instances(mesh, matrices)` gives a mesh already on the GPU new draw records (its
vertices and indices are never uploaded again), each below a new root node of the state's
tree, so `move_instances` (or set_poses / set_visible on its node) moves it like any node:
one buffer write a frame, nothing re-recorded. Their instance ids (the `instance` output's,
index + 1) come after every existing one, so the ids of the file's draws and of earlier
instances never change. `remove_instances(ids)` hides them; a later add_instances of the same
mesh takes the freed records first (their ids come back).

Growing the table (more records than the mesh has free) re-records once: the frame slots'
state buffers, the compute path's tables and the batch culling's are made again for the new
count (render/parts.py's draw-dependent parts; geometry, textures, pipelines, environments
and shadow maps stay), and every recorded command buffer is dropped. It grows by at least as
many records as the mesh already has, so repeated small adds re-record O(log n) times.

`node_material(node)` gives a node's draws a copy of their material (set_material(node=)):
per-node factors, as dataset randomisers set them, beside the per-material ones. Making the
copy re-records once too (the material blocks' buffers grow by one); setting its factors
later is one buffer write, as for any material.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.render.blend_order import BlendOrder
from vkpbr.render.deform import DeformKernel
from vkpbr.render.frames import bind_instances
from vkpbr.render.parts import FrameParts, lazy_compute
from vkpbr.render.scene_state import GpuSceneState
from vkpbr.render.transmission import transmits

__all__ = ["InstanceTable", "instance_api"]


@dataclasses.dataclass
class InstanceTable:
    """The records add_instances made: by mesh, which are free (removed or spare) and which
    are shown."""

    made: dict[int, list[int]] = dataclasses.field(default_factory=dict)  # mesh -> draws
    free: dict[int, list[int]] = dataclasses.field(default_factory=dict)  # mesh -> draws
    live: set[int] = dataclasses.field(default_factory=set)  # draws
    node_materials: dict[int, int] = dataclasses.field(default_factory=dict)  # copy -> source
    _mask: tuple[int, np.ndarray] | None = None  # (size, live as a mask), made on demand
    made_mask: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, bool))

    def live_mask(self, n: int) -> np.ndarray:
        """(n,) bool: the live records (cached until live changes: add and remove reset it)."""
        if self._mask is None or self._mask[0] != n:
            mask = np.zeros(n, bool)
            mask[list(self.live)] = True
            self._mask = (n, mask)
        return self._mask[1]


def instance_api(renderer: Any) -> tuple[Any, ...]:
    """The Renderer's add_instances, move_instances, remove_instances and set_material (with
    `node=`), bound to it (render/renderer.py _expose)."""
    if not hasattr(renderer, "_instance_table"):
        renderer._instance_table = InstanceTable()

    def add_instances(mesh: int | str, matrices: np.ndarray) -> np.ndarray:
        """New instances of loaded mesh `mesh` (index or name) at (N, 4, 4) world matrices
        or (N, 7) position + quaternion x, y, z, w rows; returns their (N,) instance ids."""
        return _add(renderer, mesh, matrices)

    def move_instances(ids: Any, matrices: np.ndarray) -> None:
        """Place instances `ids` (from add_instances) at new world matrices or (N, 7) rows."""
        draws = _live(renderer, ids)
        renderer.state.set_poses(renderer.state.draw_tree[draws], matrices)

    def remove_instances(ids: Any) -> None:
        """Remove instances `ids` (from add_instances): hidden, their records free for the
        next add_instances of their mesh."""
        table: InstanceTable = renderer._instance_table
        draws = _live(renderer, ids)
        renderer.state.set_visible(renderer.state.draw_tree[draws], False)
        table.live.difference_update(draws.tolist())
        table._mask = None
        for d in draws.tolist():
            table.free.setdefault(renderer.gpu_scene.draws[d].mesh, []).append(d)

    def set_material(material: int | str | None = None, base_color: Any = None,
                     metallic: float | None = None, roughness: float | None = None,
                     emissive: Any = None, node: Any = None) -> None:
        """SceneState.set_material; with `node` (index, name or path) the factors of that
        node's own copy of its draws' material (made on first use: it re-records once)."""
        if node is None:
            if material is None:
                raise UsageError("set_material: name a material, or a node with node=")
            return renderer.state.set_material(material, base_color, metallic, roughness, emissive)
        for m in _node_materials(renderer, node, material):
            renderer.state.override_material(m, base_color, metallic, roughness, emissive)
        return None

    return add_instances, move_instances, remove_instances, set_material


def _mesh_index(renderer: Any, mesh: int | str) -> int:
    meshes = renderer.scene.meshes
    if isinstance(mesh, (int, np.integer)) and not isinstance(mesh, bool):
        if 0 <= mesh < len(meshes):
            return int(mesh)
        raise UsageError(f"add_instances: mesh {mesh} is out of range: the scene has {len(meshes)}")
    names = [m.name for m in meshes]
    if mesh in names:
        return names.index(mesh)
    shown = ", ".join(repr(n) for n in names[:8]) + (" ..." if len(names) > 8 else "")
    raise UsageError(f"add_instances: no mesh is named {mesh!r} (the scene's: {shown})")


def _add(renderer: Any, mesh: int | str, matrices: np.ndarray) -> np.ndarray:
    from vkpbr.scene.state import _check_matrices, _check_rows, _poses_of, pose_matrices

    m = _mesh_index(renderer, mesh)
    gs = renderer.gpu_scene
    if any(r.mesh == m for r in gs.deformed):
        raise UsageError(f"add_instances: mesh {renderer.scene.meshes[m].name!r} is skinned or "
                         "morphed: its instances need their own posed vertices (not supported)")
    if not len(renderer.scene.meshes[m].indices):
        raise UsageError(f"add_instances: mesh {renderer.scene.meshes[m].name!r} has no triangles")
    p = np.asarray(matrices, np.float64)
    n = len(p) if p.ndim in (2, 3) else 1
    p = _poses_of(p, n)
    if p.shape[-1] == 7:
        _check_rows(p)
        p = pose_matrices(p)
    else:
        _check_matrices(p)
    table: InstanceTable = renderer._instance_table
    free = table.free.setdefault(m, [])
    if len(free) < n:  # at least doubles the mesh's records: few regrowths
        _grow(renderer, m, max(n - len(free), len(table.made.get(m, []))))
    draws, table.free[m] = np.array(free[:n], np.int64), free[n:]
    table.live.update(draws.tolist())
    table._mask = None
    state = renderer.state
    state.set_poses(state.draw_tree[draws], p)  # roots: local = world
    state.set_visible(state.draw_tree[draws], True)
    return draws + 1


def _live(renderer: Any, ids: Any) -> np.ndarray:
    """The draws of instance ids `ids`, every one made by add_instances and not removed;
    a one-line error naming the first that is not (nothing changes)."""
    arr = np.asarray(ids).reshape(-1)
    if arr.dtype.kind not in "iu":
        raise UsageError(f"instance ids must be integers, got {arr.dtype}")
    table: InstanceTable = renderer._instance_table
    d = arr.astype(np.int64) - 1
    made = table.made_mask
    inside = (d >= 0) & (d < len(made))
    bad = ~inside | ~made[np.where(inside, d, 0)]
    if bad.any():
        raise UsageError(f"instance {int(arr[bad][0])} was not made by add_instances (a "
                         "file's draw: hide its node with set_visible)")
    gone = ~table.live_mask(len(made))[d]
    if gone.any():
        raise UsageError(f"instance {int(arr[gone][0])} was removed already")
    if len(d) > 1 and np.bincount(d, minlength=len(made)).max() > 1:
        raise UsageError("instance ids repeat")
    return d


def _node_materials(renderer: Any, node: Any, material: int | str | None) -> list[int]:
    """The own materials of `node`'s draws (made on first use), those of `material` alone
    when given."""
    state, gs = renderer.state, renderer.gpu_scene
    table: InstanceTable = renderer._instance_table
    nodes = state.tree.indices(node)
    draws = np.flatnonzero(np.isin(state.draw_tree, nodes))
    if not len(draws):
        raise UsageError(f"set_material: node {node!r} draws nothing")
    wanted = None if material is None else state._material_index(material)
    out = []
    for d in draws.tolist():
        mat = gs.draws[d].material
        if wanted is not None and table.node_materials.get(mat, mat) != wanted and mat != wanted:
            continue
        if mat not in table.node_materials:  # the draw still has the shared one: copy it
            own = gs.copy_material(mat)
            table.node_materials[own] = mat
            if mat in state.materials:  # the copy starts as the shared one is now
                state.materials[own] = dict(state.materials[mat])
            gs.draws[d].material = own
            _rebuild(renderer)
            mat = own
        out.append(mat)
    return sorted(set(out))


def _grow(renderer: Any, mesh: int, count: int) -> None:
    """`count` more records of `mesh`, free, then the draw-dependent parts made again."""
    gs, state = renderer.gpu_scene, renderer.state
    first = len(gs.draws)
    gs.draws.extend(gs.instance_draws(mesh, count))
    ids = range(first + 1, first + count + 1)
    p = renderer.scene.meshes[mesh].positions
    box = np.array([p.min(axis=0), p.max(axis=0)]) if len(p) else np.zeros((2, 3))
    state.grow(count, box, [f"instance {i}" for i in ids])
    table: InstanceTable = renderer._instance_table
    new = list(range(first, first + count))
    table.made.setdefault(mesh, []).extend(new)
    table.made_mask = np.concatenate([table.made_mask, np.zeros(first + count - len(table.made_mask), bool)])
    table.made_mask[first:] = True
    table.free.setdefault(mesh, []).extend(new)
    same = [i for i, d in enumerate(gs.draws[:first]) if d.mesh == mesh]
    sem = renderer.parts.semantic_ids[same[0]] if same else mesh + 1
    ids_now = np.concatenate([renderer.parts.semantic_ids, np.full(count, sem, np.uint32)])
    _rebuild(renderer, ids_now)


def _rebuild(renderer: Any, semantic_ids: np.ndarray | None = None) -> None:
    """Make again what depends on the number of draws or materials (render/parts.py); the
    geometry, textures, pipelines, environments, shadow maps and frame slots stay."""
    from vkpbr.render.batch_path import BatchPath
    from vkpbr.render.frame_path import FramePath

    p: FrameParts = renderer.parts
    dev, gs, state = p.device, p.gpu_scene, p.state
    dev.wait_idle()
    renderer.batch_path.close()
    p.recorder.free()
    p.gpu_state.destroy()
    gpu_state = GpuSceneState(dev, state, p.ring.count, p.scene, state.deform)  # type: ignore[arg-type]
    gpu_state.first_posed, gpu_state.gpu_scene = min(gs.posed_offsets, default=0), gs
    bind_instances(dev, [s.set0 for s in p.slots], [gpu_state.region(s.index) for s in p.slots])
    deform = p.deform
    if deform is not None:
        deform.destroy()
        deform = DeformKernel(dev, p.scene, gs, state.deform,
                              [gpu_state.deform_region(s.index) for s in p.slots])
    ids = p.semantic_ids if semantic_ids is None else semantic_ids
    if p.compute.made is not None:
        p.compute.made.destroy()
    compute = lazy_compute(dev, p.scene, gs, p.set_layouts, p.slots, ids, gpu_state, deform)
    p.recorder.compute_scene, p.recorder.deform, p.targets.compute = compute, deform, compute
    p.opaque_copies.transmissive = transmits(gs)
    p.opaque_copies.present = any(p.opaque_copies.transmissive)
    blend = BlendOrder(gs.draws, state)
    p.paths.blended = len(blend) > 0
    p.shadow_frames.casters = np.array([d.casts_shadows for d in gs.draws], bool)
    maps = p.shadow_frames.maps  # the compute-drawn maps' caster tables name the draws
    if getattr(maps, "_raster", None) is not None:
        maps._raster.destroy()
        maps._raster = None
    parts = dataclasses.replace(p, gpu_state=gpu_state, deform=deform, semantic_ids=ids,
                                compute=compute, blend=blend)
    renderer.parts = parts
    renderer.frame_path, renderer.batch_path = FramePath(parts), BatchPath(parts)
    renderer._expose(parts)
