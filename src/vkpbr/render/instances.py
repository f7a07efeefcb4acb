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

import copy
import dataclasses
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.render.blend_order import BlendOrder
from vkpbr.render.deform import Deformed, DeformKernel, DeformLayout, convex_weights
from vkpbr.render.frames import bind_instances
from vkpbr.render.gpu_scene import LAZY_STREAMS
from vkpbr.render.parts import FrameParts, lazy_compute
from vkpbr.render.scene_state import GpuSceneState
from vkpbr.render.transmission import transmits
from vkpbr.scene.state import NodeCopies, numbers
from vkpbr.scene.types import Skin

__all__ = ["InstanceTable", "instance_api"]


@dataclasses.dataclass
class InstanceTable:
    """The records add_instances made: by mesh, which are free (removed or spare) and which
    are shown."""

    made: dict[int, list[int]] = dataclasses.field(default_factory=dict)  # mesh -> draws
    free: dict[int, list[int]] = dataclasses.field(default_factory=dict)  # mesh -> draws
    live: set[int] = dataclasses.field(default_factory=set)  # draws
    node_materials: dict[int, int] = dataclasses.field(default_factory=dict)  # copy -> source
    # Skinned and morphed meshes' instances: their copied skeletons (mesh -> NodeCopies)
    # and skins (after the scene's: Deformed.skin indexes scene.skins + skins).
    copies: dict[int, NodeCopies] = dataclasses.field(default_factory=dict)
    skins: list[Skin] = dataclasses.field(default_factory=list)
    roots: dict[int, int] = dataclasses.field(default_factory=dict)  # deformed draw -> root
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

    def add_instances(mesh: int | str, matrices: np.ndarray, time_offsets: Any = None) -> np.ndarray:
        """New instances of loaded mesh `mesh` (index or name) at (N, 4, 4) world matrices
        or (N, 7) position + quaternion x, y, z, w rows; returns their (N,) instance ids.
        A skinned or morphed mesh's instance has its own posed vertices and a copy of the
        skeleton (`matrices` place it relative to the file's pose), played at the state's
        time plus its `time_offsets` entry (seconds; default 0)."""
        return _add(renderer, mesh, matrices, time_offsets)

    def move_instances(ids: Any, matrices: np.ndarray) -> None:
        """Place instances `ids` (from add_instances) at new world matrices or (N, 7) rows."""
        draws = _live(renderer, ids)
        renderer.state.set_poses(_roots(renderer, draws), matrices)

    def remove_instances(ids: Any) -> None:
        """Remove instances `ids` (from add_instances): hidden, their records free for the
        next add_instances of their mesh."""
        table: InstanceTable = renderer._instance_table
        draws = _live(renderer, ids)
        renderer.state.set_visible(_roots(renderer, draws), False)
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


def _add(renderer: Any, mesh: int | str, matrices: np.ndarray, time_offsets: Any = None
         ) -> np.ndarray:
    from vkpbr.scene.state import _check_matrices, _check_rows, _poses_of, pose_matrices

    m = _mesh_index(renderer, mesh)
    gs = renderer.gpu_scene
    deformed = any(r.mesh == m for r in gs.deformed)
    if time_offsets is not None and not deformed:
        raise UsageError(f"add_instances: time_offsets: mesh {renderer.scene.meshes[m].name!r} "
                         "is neither skinned nor morphed (nothing of it is animated)")
    if not len(renderer.scene.meshes[m].indices):
        raise UsageError(f"add_instances: mesh {renderer.scene.meshes[m].name!r} has no triangles")
    p = numbers(matrices, "add_instances")
    n = len(p) if p.ndim in (2, 3) and p.shape != (4, 4) else 1  # (one (4, 4) as one (7,))
    p = _poses_of(p, n)
    if p.shape[-1] == 7:
        _check_rows(p)
        p = pose_matrices(p)
    else:
        _check_matrices(p)
    offsets = _offsets(time_offsets, n)
    if not n:  # (no matrices: no instances, nothing grown)
        return np.zeros(0, np.int64)
    table: InstanceTable = renderer._instance_table
    free = table.free.setdefault(m, [])
    if len(free) < n:  # at least doubles the mesh's records: few regrowths
        grow = _grow_deformed if deformed else _grow
        grow(renderer, m, max(n - len(free), len(table.made.get(m, []))))
    draws, table.free[m] = np.array(free[:n], np.int64), free[n:]
    table.live.update(draws.tolist())
    table._mask = None
    state = renderer.state
    roots = _roots(renderer, draws)
    state.set_poses(roots, p)  # roots: local = world
    state.set_visible(roots, True)
    if deformed:  # each instance's time offset, and its pose at the state's time
        copies = table.copies[m]
        copies.offsets[np.searchsorted(copies.roots, roots)] = offsets
        state.pose_copies()
    return draws + 1


def _roots(renderer: Any, draws: np.ndarray) -> np.ndarray:
    """The instance root nodes of instance records `draws` (a deformed mesh's draw hangs
    from its copy of the mesh's node, below the root)."""
    table: InstanceTable = renderer._instance_table
    nodes = renderer.state.draw_tree[draws].copy()
    if table.roots:
        for k, d in enumerate(draws.tolist()):
            nodes[k] = table.roots.get(d, nodes[k])
    return nodes


def _offsets(value: Any, n: int) -> np.ndarray:
    """(n,) time offsets: one number for all, or one each; finite."""
    if value is None:
        return np.zeros(n)
    v = numbers(value, "add_instances: time_offsets").reshape(-1)
    if len(v) == 1:
        v = np.full(n, v[0])
    if len(v) != n or not np.all(np.isfinite(v)):
        raise UsageError(f"add_instances: time_offsets must be one finite number or {n} of "
                         f"them (one per instance), got {len(v)}")
    return v


def _live(renderer: Any, ids: Any) -> np.ndarray:
    """The draws of instance ids `ids`, every one made by add_instances and not removed;
    a one-line error naming the first that is not (nothing changes)."""
    arr = np.asarray(ids).reshape(-1)
    if not arr.size and ids is not None:  # ([] is float64 to NumPy: no ids, nothing to do)
        return np.zeros(0, np.int64)
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
    box = np.array(gs.mesh_box(mesh)) if len(p) else np.zeros((2, 3))
    state.grow(count, box, [f"instance {i}" for i in ids])
    _made(renderer, mesh, first, count)


def _grow_deformed(renderer: Any, mesh: int, count: int) -> None:
    """`count` more instances of a skinned or morphed `mesh`, free: each a new root with a
    copy of the skeleton below it (the skin's joints and their ancestors; none for a morphed
    mesh alone), a skin of its own on those copies, a posed region of its own in the vertex
    streams (which are uploaded again, a stream per deformed instance), a deform record and a
    draw; then the draw-dependent parts made again."""
    gs, state, scene = renderer.gpu_scene, renderer.state, renderer.scene
    table: InstanceTable = renderer._instance_table
    src = next(r for r in gs.deformed if r.mesh == mesh and r.node >= 0)  # the file's record
    copies = table.copies.get(mesh)
    if copies is None:  # the mesh's node, its skeleton and their ancestors
        joints = scene.skins[src.skin].joints if src.skin is not None else []
        nodes = _skeleton(state.tree.parents, np.concatenate([[src.tree], joints]))
        copies = table.copies[mesh] = NodeCopies(nodes, src.tree)
    first, done = len(gs.draws), len(copies.roots)
    ids = range(first + 1, first + count + 1)
    bounded = src.skin is None or convex_weights(scene.meshes[mesh])
    box = np.array([[-1.0] * 3, [1.0] * 3]) if bounded else np.array(gs.mesh_box(mesh))
    roots = state.grow(count, box, [f"instance {i}" for i in ids], copies, deformed=True,
                       skinned=src.skin is not None)
    records = []
    for k in range(count):
        skin = None
        if src.skin is not None:  # the file's skin, on this instance's copies of its joints
            at = {int(s): j for j, s in enumerate(copies.sources)}
            s = scene.skins[src.skin]
            joints = copies.nodes[done + k][[at[int(j)] for j in s.joints]]
            table.skins.append(Skin(s.name, joints, s.inverse_bind, None))
            skin = len(scene.skins) + len(table.skins) - 1
        records.append(Deformed(-1, -1, mesh, skin, int(state.draw_tree[first + k])))
    table.roots.update(zip(range(first, first + count), roots.tolist(), strict=True))
    offsets = _grow_posed(renderer, records)
    gs.draws.extend(dataclasses.replace(d, vertex_offset=o, model=np.eye(4), deformed=True,
                                        skinned=src.skin is not None, unbounded=not bounded)
                    for d, o in zip(gs.instance_draws(mesh, count), offsets, strict=True))
    view = copy.copy(scene)
    view.skins = list(scene.skins) + table.skins
    state.attach_deform(DeformLayout(view, gs.deformed),
                        np.concatenate([state.deform_draws, np.arange(first, first + count)]))
    _made(renderer, mesh, first, count)


def _skeleton(parents: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """The joints and every ancestor of theirs, sorted (parents first)."""
    keep = np.zeros(len(parents), bool)
    todo = list(np.asarray(joints, np.int64).tolist())
    while todo:
        j = todo.pop()
        if j >= 0 and not keep[j]:
            keep[j] = True
            todo.append(int(parents[j]))
    return np.flatnonzero(keep)


def _grow_posed(renderer: Any, records: list[Deformed]) -> list[int]:
    """Posed regions for `records` (appended to GpuScene.deformed): the vertex streams and
    indices are uploaded again with the regions after the others (the earlier ones keep
    their offsets); returns the new regions' first vertices. The old buffers are destroyed
    once the device is idle and nothing recorded names them any more (_rebuild follows)."""
    gs, p = renderer.gpu_scene, renderer.parts
    p.device.wait_idle()
    renderer.batch_path.close()
    p.recorder.free()
    old = {id(b) for b in gs.streams.values()} | {id(gs.index_buffer)}
    lazy = tuple(n for n in LAZY_STREAMS if n in gs.streams)
    for obj in [o for o in gs._owned if id(o) in old]:
        gs._owned.remove(obj)
        obj.destroy()
    first = len(gs.deformed)
    gs.deformed.extend(records)
    gs._upload_geometry()
    if lazy:
        gs.ensure_streams(lazy)
    return list(gs.posed_offsets[first:])


def _made(renderer: Any, mesh: int, first: int, count: int) -> None:
    """Records first .. first + count of `mesh` made, free; their semantic ids the mesh's;
    the draw-dependent parts made again."""
    gs = renderer.gpu_scene
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
