"""The living scene: what changes between frames, as NumPy arrays (no GPU here).

A `SceneState` holds the node tree's local transforms (vkpbr.scene.tree) and which nodes are
shown, and turns them into what the GPU reads per draw: its model and normal matrices
(`draw_matrices`), the world bounds and the draws' centres (culling, the blended draws'
order, the shadow maps' fit). Every change bumps `version` and marks its nodes; the calls
only check and keep what they are given. The frame's first reader (`_update`, once per
version) recomputes the world matrices of the marked nodes' subtrees and the rows of the
draws below them (vkpbr.scene.draw_table), and the renderer copies the rows changed since
a frame slot last held them (render/scene_state.py): a pose change is one buffer write per
frame of what moved, and re-records nothing.

Poses come as (N, 4, 4) matrices or as (N, 7) position + unit quaternion rows; the
quaternion order is "xyzw" (glTF, SciPy) by default, "wxyz" (SAPIEN, MuJoCo, Isaac) on
request. `space="local"` sets the node's transform relative to its parent (glTF's TRS),
`space="world"` its world transform (the parent's is divided out).

A hidden node hides its subtree (as three.js, Blender and the glTF viewers do): its draws get
a zero model matrix, which collapses every triangle to a point that covers no pixel in any
frame path or shadow map, so hiding re-records nothing either.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene._checks import describe, shown
from vkpbr.scene.draw_table import (
    DrawTable,
    blocks,
    determinant_of_parts,
    normal_matrices,
    std140_pairs,
)
from vkpbr.scene.tree import NodeRef, NodeTree, quaternion_matrices
from vkpbr.scene.types import Camera, Light, Scene

__all__ = ["SceneState", "NodeCopies", "quaternion_matrices", "pose_matrices", "normal_matrices", "std140_pairs"]

QUATERNION_ORDERS = ("xyzw", "wxyz")
SPACES = ("local", "world")


class SceneState:
    """The changing part of a scene whose `tree` its draws hang from.

    draw_tree : (D,) tree node of each draw record (render/gpu_scene.py's order).
    draw_local : (D, 4, 4) each draw's transform below its tree node (EXT_mesh_gpu_instancing's
        instance matrix; identity otherwise).
    mesh_boxes : (D, 2, 3) each draw's mesh bounds (min, max) in the mesh's own space.
    rest : (D, 4, 4) the draws' model matrices as loaded: what frames use until the
        state first changes (so an unchanged scene renders bit for bit as before).
    skinned : (D,) bool, draws posed by a skin (their model is the identity).
    """

    def __init__(self, tree: NodeTree, draw_tree: np.ndarray, draw_local: np.ndarray,
                 mesh_boxes: np.ndarray, rest: np.ndarray, skinned: np.ndarray | None = None) -> None:
        self.tree = tree
        self.draw_tree = np.asarray(draw_tree, np.int64)
        self.draw_local = np.asarray(draw_local, np.float64).reshape(-1, 4, 4)
        # Draws below their node by more than the identity (instancing): the others skip
        # the product.
        self._below = np.any(self.draw_local != np.eye(4), axis=(1, 2))
        self.mesh_boxes = np.asarray(mesh_boxes, np.float64).reshape(-1, 2, 3)
        self.rest = np.asarray(rest, np.float64).reshape(-1, 4, 4)
        # Skinned draws are posed in world space by their joints: their model is the frame
        # the deform step poses them in (identity without one; glTF ignores the skinned
        # node's transform).
        self.skinned = (np.zeros(len(self.draw_tree), bool) if skinned is None
                        else np.asarray(skinned, bool))
        self._local = np.array(tree.local, np.float64, copy=True)
        self.visible = np.ones(len(tree), bool)
        # Morph weights by tree node where set (set_weights, animation); the others take the
        # node's or mesh's from the file (render/deform.py).
        self.weights: dict[int, np.ndarray] = {}
        self.scene: Scene | None = None  # what set_time samples (vkpbr.scene.animation)
        # KHR_animation_pointer values set_time gave: pointer -> (channel, value)
        self.pointers: dict[str, tuple[object, np.ndarray]] = {}
        # Material factor overrides: material index -> {Material field: value}
        self.materials: dict[int, dict[str, tuple[float, ...]]] = {}
        self.material_version = 0
        self.time: float | None = None  # the time set_time last posed
        self.version = 0
        self.draw_versions = np.zeros(len(self.draw_tree), np.int64)  # when each last changed
        self._since: tuple[int, object, int] | None = None
        self._cache: dict[str, tuple[int, object]] = {}
        # What changed since the last frame (`_update` makes the frame's arrays from it):
        # nodes set, quaternion rows not yet turned into matrices, whether visibility did.
        self._dirty = np.zeros(len(tree), bool)
        self._any_dirty = self._shown_dirty = False
        self._pending: list[tuple[np.ndarray, np.ndarray, str]] = []
        self._updated = 0
        self._world = tree.world(self._local)
        self._shown = np.ones(len(tree), bool)
        self.table = DrawTable(self.mesh_boxes, self.rest)
        self._direct = self._is_direct()
        self.deform: object | None = None  # render/deform.py's DeformLayout, when attached
        self.deform_draws = np.zeros(0, np.int64)  # the draw of each deformed record
        self._record_of = -np.ones(len(self.draw_tree), np.int64)
        # Copied skeletons of skinned and morphed instances (render/instances.py), which
        # set_time poses at the time plus each copy's offset.
        self.copies: list[NodeCopies] = []
        self._chosen: list[int] | None = None  # the animations set_time last played

    def __len__(self) -> int:
        return len(self.tree)

    # --- changing it ----------------------------------------------------------------------
    @property
    def local(self) -> np.ndarray:
        """(K, 4, 4) float64 local transforms of the tree's nodes (writing into it directly
        changes nothing until `_changed` names the nodes)."""
        self._flush_pending()
        return self._local

    def set_poses(self, nodes: NodeRef | Iterable[NodeRef] | np.ndarray, poses: np.ndarray,
                  space: str = "local", quaternion: str = "xyzw") -> None:
        """Set the transforms of `nodes` (indices, names, paths or patterns: NodeTree.indices)
        from (N, 4, 4) affine matrices or (N, 7) rows of position + unit quaternion
        (`quaternion` "xyzw" or "wxyz"), relative to each node's parent (`space="local"`) or
        in the world (`space="world"`). The call checks and keeps the poses; the frame
        makes the matrices (once, vectorised, only for what changed)."""
        idx = self.tree.indices(nodes)
        if space not in SPACES:
            raise UsageError(f"space {space!r}: choose 'local' or 'world'")
        p = _poses_of(poses, len(idx))
        if p.shape[-1] == 7:
            if quaternion not in QUATERNION_ORDERS:
                raise UsageError(f"quaternion {quaternion!r}: choose 'xyzw' or 'wxyz'")
            _check_rows(p)
            if space == "local":  # the matrices are the frame's to make
                self._pending.append((idx.copy(), p if p is not poses and p.base is None else p.copy(),
                                      quaternion))
                self._mark(idx)
                return
            p = pose_matrices(p, quaternion)
        else:
            _check_matrices(p)
        if space == "world":
            p = self._world_to_local(idx, p)
        self._flush_pending()  # (an earlier call's rows must not land after these)
        self._local[as_slice(idx)] = p
        self._mark(idx)

    def set_pose(self, node: NodeRef, matrix: np.ndarray, space: str = "local") -> None:
        """Set one node's (4, 4) transform, or its (7,) position + quaternion x, y, z, w
        (`set_poses` for many)."""
        self.set_poses([node] if isinstance(node, (int, np.integer)) else self.tree.indices(node)[:1],
                       numbers(matrix, "set_pose")[None], space)

    def set_visible(self, nodes: NodeRef | Iterable[NodeRef] | np.ndarray,
                    mask: bool | Sequence[bool] | np.ndarray = True) -> None:
        """Show (True) or hide (False) `nodes` and their subtrees: one flag or one per node."""
        idx = self.tree.indices(nodes)
        m = np.asarray(mask)
        if m.dtype != bool or m.ndim > 1 or (m.ndim == 1 and len(m) != len(idx)):
            raise UsageError(f"set_visible: the mask must be one bool or {len(idx)} of them "
                             f"(one per node), got {m.dtype} of shape {m.shape}")
        self.visible[idx] = m
        self._shown_dirty = True
        self._mark(idx)

    def set_weights(self, node: NodeRef, weights: Sequence[float] | np.ndarray) -> None:
        """Set the morph target weights of the mesh `node` shows (glTF `weights`)."""
        idx = self.tree.indices(node)
        w = numbers(weights, "set_weights").reshape(-1)
        if not np.all(np.isfinite(w)):
            raise UsageError("set_weights: a weight is NaN or infinite")
        for i in idx:
            self.weights[int(i)] = w
        self._changed(idx)

    def set_time(self, time: float, animation: int | str | Sequence[int | str] | None = None) -> None:
        """Pose the scene as its glTF animations are at `time` seconds (`animation`: a name,
        an index, several, or None for all; vkpbr.scene.animation.sample). Only the nodes
        and morph weights the chosen animations drive change; times outside an animation's
        keyframes clamp to its ends."""
        if self.scene is None:
            raise UsageError("set_time: this state has no scene to animate")
        from vkpbr.scene.animation import animation_indices, animation_time, sample

        time = animation_time(time)  # (checked where nothing is animated too)

        chosen = animation_indices(self.scene, animation)
        nodes = sorted({ch.node for i in chosen for ch in self.scene.animations[i].channels
                        if ch.node is not None and ch.path != "weights"})
        morphed = {ch.node for i in chosen for ch in self.scene.animations[i].channels
                   if ch.node is not None and ch.path == "weights"} | {
            t for i in chosen for ch in self.scene.animations[i].channels if ch.kind == "mesh"
            for t in ch.targets}
        animates_pointers = any(ch.kind in ("light", "camera", "material") for i in chosen
                                for ch in self.scene.animations[i].channels)
        if not nodes and not morphed and not animates_pointers:
            return
        pose = sample(self.scene, float(time), chosen)
        pointed = {ch.pointer: ch for i in chosen for ch in self.scene.animations[i].channels
                   if ch.kind in ("light", "camera") and ch.pointer in pose.pointers}
        if pointed:  # KHR_animation_pointer: lights' and cameras' properties
            self.pointers.update({p: (ch, np.asarray(pose.pointers[p], np.float64).reshape(-1))
                                  for p, ch in pointed.items()})
            self.version += 1
        for ch in (ch for i in chosen for ch in self.scene.animations[i].channels
                   if ch.kind == "material" and ch.pointer in pose.pointers):
            self._pointed_material(ch, np.asarray(pose.pointers[ch.pointer], np.float64).reshape(-1))
        idx = np.asarray(nodes, np.int64)
        self._flush_pending()
        self._local[idx] = pose.local[idx]
        for node in morphed:
            if node in pose.weights:
                self.weights[int(node)] = np.asarray(pose.weights[node], np.float64)
        self.time, self._chosen = float(time), chosen
        self._changed(np.asarray(sorted(set(nodes) | {int(m) for m in morphed}), np.int64))
        self.pose_copies()

    def set_material(self, material: int | str, base_color: Sequence[float] | None = None,
                     metallic: float | None = None, roughness: float | None = None,
                     emissive: Sequence[float] | None = None) -> None:
        """Override a material's factors from the next frame on (randomised datasets; glTF
        animation pointers go through here too): `base_color` RGBA or RGB in [0, 1],
        `metallic` and `roughness` in [0, 1], `emissive` linear RGB >= 0. They multiply the
        material's textures, as glTF's factors do. `material`: index or name."""
        self.override_material(self._material_index(material), base_color, metallic, roughness,
                               emissive)

    def override_material(self, i: int, base_color: Sequence[float] | None = None,
                          metallic: float | None = None, roughness: float | None = None,
                          emissive: Sequence[float] | None = None) -> None:
        """set_material of the renderer's material `i` (an index into GpuScene.materials:
        the file's, then the default, then nodes' own copies: render/instances.py)."""
        given = {"base_color_factor": base_color, "metallic_factor": metallic,
                 "roughness_factor": roughness, "emissive_factor": emissive}
        checked = {f: _factor(f, v) for f, v in given.items() if v is not None}
        self.materials.setdefault(i, {}).update(checked)
        self.material_version += 1
        self.version += 1

    def _pointed_material(self, ch: object, value: np.ndarray) -> None:
        """One KHR_animation_pointer material factor at its sampled value (the emissive
        strength scales the emissive factor, which already holds the file's strength)."""
        member, rest = ch.member, ch.rest  # type: ignore[attr-defined]
        for i in ch.targets:  # type: ignore[attr-defined]
            mat = self.scene.materials[i]  # type: ignore[union-attr]
            if member == "emissive_strength":
                scale = value[0] / rest[0] if rest is not None and rest[0] > 0 else 0.0
                factor = tuple(float(c) * scale for c in mat.emissive_factor)
                self.materials.setdefault(i, {})["emissive_factor"] = factor
            elif member in ("base_color_factor", "metallic_factor", "roughness_factor",
                            "emissive_factor"):
                v = tuple(float(x) for x in value)
                self.materials.setdefault(i, {})[member] = v if len(v) > 1 else (v[0],)
        self.material_version += 1
        self.version += 1

    def _material_index(self, material: int | str) -> int:
        mats = self.scene.materials if self.scene is not None else []
        if isinstance(material, (int, np.integer)) and not isinstance(material, bool):
            if 0 <= material < len(mats):
                return int(material)
            raise UsageError(f"material {material} is out of range: the scene has {len(mats)}")
        names = [m.name for m in mats]
        if material in names:
            return names.index(material)
        raise UsageError(f"no material is named {material!r} (the scene's: "
                         f"{', '.join(names[:8])}{' ...' if len(names) > 8 else ''})")

    def lights(self) -> list[Light]:
        """The scene's lights with what animation pointers set (colour, intensity, range,
        spot cones: KHR_animation_pointer)."""
        lights = list(self.scene.lights) if self.scene is not None else []
        for ch, value in self.pointers.values():
            if getattr(ch, "kind", None) != "light":
                continue
            for i in ch.targets:  # type: ignore[attr-defined]
                if 0 <= i < len(lights):
                    lights[i] = _pointed_light(lights[i], ch.member, value)  # type: ignore[attr-defined]
        return lights

    def cameras(self) -> list[Camera]:
        """The scene's cameras with the field of view animation pointers set."""
        cams = list(self.scene.cameras) if self.scene is not None else []
        for ch, value in self.pointers.values():
            if getattr(ch, "kind", None) == "camera" and ch.member == "yfov":  # type: ignore[attr-defined]
                for i in ch.targets:  # type: ignore[attr-defined]
                    if 0 <= i < len(cams) and 0.0 < value[0] < np.pi:
                        cams[i] = dataclasses.replace(cams[i], yfov_deg=float(np.degrees(value[0])))
        return cams

    def reset(self) -> None:
        """Back to the file's rest pose, everything shown."""
        self._pending.clear()
        self._local[:] = self.tree.local
        self.visible[:] = True
        self._shown_dirty = True
        self.weights.clear()
        self.pointers.clear()
        self.time = None
        if self.materials:
            self.materials.clear()
            self.material_version += 1
        self._changed(np.arange(len(self.tree)))

    def touch_draws(self, draws: np.ndarray) -> None:
        """Count `draws` as changed though no node did (render/scene_state.py: a masked or
        blended material's alpha factor, whose cutoff shapes their shadows): what follows the
        draws' versions (the shadow maps' caches, their moving casters) redraws them."""
        self.version += 1
        self.draw_versions[np.asarray(draws, np.int64)] = self.version

    def _changed(self, idx: np.ndarray) -> None:
        """Nodes whose local transform, visibility or weights changed (their subtrees'
        draws follow at the next frame)."""
        self._mark(np.asarray(idx, np.int64))

    def _mark(self, idx: np.ndarray) -> None:
        self._dirty[idx] = True
        self._any_dirty = True
        self.version += 1

    def changed_since(self, draws: np.ndarray | None = None) -> int:
        """The latest version that changed any of `draws` (a bool mask; None: all): what
        a cache of their images (the shadow maps) compares."""
        self._update()
        last = self._since
        if last is not None and last[0] == self.version and last[1] is draws:
            return last[2]  # the same mask (the casters') and state: once per change
        versions = self.draw_versions if draws is None else self.draw_versions[draws]
        hit = int(versions.max(initial=0))
        self._since = (self.version, draws, hit)  # keeps the mask: its identity is the key
        return hit

    def _world_to_local(self, idx: np.ndarray, world: np.ndarray) -> np.ndarray:
        parents = self.tree.parents[idx]
        parent_world = np.broadcast_to(np.eye(4), world.shape).copy()
        has = parents >= 0
        if np.any(has):
            parent_world[has] = self.world()[parents[has]]
        return np.linalg.solve(parent_world, world)

    def grow(self, count: int, mesh_box: np.ndarray, names: Sequence[str],
             copies: NodeCopies | None = None, deformed: bool = False,
             skinned: bool = False) -> np.ndarray:
        """`count` new draws, each below a new root node of the tree named `names` (new
        instances of a mesh whose (2, 3) box is `mesh_box`: render/instances.py), hidden until
        placed; returns their tree nodes. The draw records and tree indices before stay.
        `copies`: below each new root, a copy of those nodes of the tree (a skinned mesh's
        skeleton: NodeCopies, which takes the copies' indices); `deformed`: the draws are
        posed by the deform step (`skinned`: by a skin, in world space)."""
        k = len(self.tree)
        nodes = np.arange(k, k + count)
        self._flush_pending()
        self.tree = grown_tree(self.tree, list(names))
        eye = np.tile(np.eye(4), (count, 1, 1))
        self._local = np.concatenate([self._local, eye])
        self._world = np.concatenate([self._world, eye])
        self.visible = np.concatenate([self.visible, np.zeros(count, bool)])
        self._shown = np.concatenate([self._shown, np.zeros(count, bool)])
        self._dirty = np.concatenate([self._dirty, np.zeros(count, bool)])
        draws = nodes
        if copies is not None:
            self._grow_copies(nodes, copies)
            if copies.draw_source is not None:  # the draws hang from the copy of that node
                draws = copies.nodes[-count:, int(np.flatnonzero(copies.sources == copies.draw_source)[0])]
        self.draw_tree = np.concatenate([self.draw_tree, draws])
        self.draw_local = np.concatenate([self.draw_local, eye])
        self._below = np.concatenate([self._below, np.zeros(count, bool)])
        boxes = np.broadcast_to(np.asarray(mesh_box, np.float64), (count, 2, 3))
        self.mesh_boxes = np.concatenate([self.mesh_boxes, boxes])
        self.rest = np.concatenate([self.rest, np.zeros((count, 4, 4))])
        self.skinned = np.concatenate([self.skinned, np.full(count, skinned)])
        self.draw_versions = np.concatenate([self.draw_versions, np.zeros(count, np.int64)])
        self._record_of = np.concatenate([self._record_of, -np.ones(count, np.int64)])
        if hasattr(self, "deformed"):
            self.deformed = np.concatenate([self.deformed, np.full(count, deformed)])
        self.table.grow(boxes)
        self._direct = self._is_direct()
        self._since = None
        self._shown_dirty = True
        self._mark(nodes)
        return nodes

    def _grow_copies(self, roots: np.ndarray, copies: NodeCopies) -> None:
        """Below each of `roots`, a copy of the nodes `copies.sources` (parents first), whose
        local transforms start as the file's; `copies` takes their indices (one row a root)."""
        src, n, s = copies.sources, len(roots), len(copies.sources)
        k = len(self.tree)
        at = -np.ones(k, np.int64)
        at[src] = np.arange(s)
        first = k + np.arange(n)[:, None] * s  # (n, 1): each root's copies, in source order
        parent = self.tree.parents[src]
        inside = parent >= 0
        parents = np.where(inside[None], first + at[np.maximum(parent, 0)][None], roots[:, None])
        names = [self.tree.names[i] for i in src] * n
        rest = np.tile(self.tree.local[src], (n, 1, 1))
        self.tree = copied_tree(self.tree, names, parents.ravel(), rest)
        self._local = np.concatenate([self._local, rest])
        self._world = np.concatenate([self._world, np.tile(np.eye(4), (n * s, 1, 1))])
        for name in ("visible", "_shown"):
            setattr(self, name, np.concatenate([getattr(self, name), np.ones(n * s, bool)]))
        self._dirty = np.concatenate([self._dirty, np.ones(n * s, bool)])
        copies.nodes = np.concatenate([copies.nodes, first + np.arange(s)[None]])
        copies.roots = np.concatenate([copies.roots, roots])
        copies.offsets = np.concatenate([copies.offsets, np.zeros(n)])
        self.copies.append(copies) if not any(c is copies for c in self.copies) else None

    def pose_copies(self) -> None:
        """The copied skeletons (`copies`: skinned and morphed instances) at the state's
        time plus each one's offset, under the animations set_time last played: one
        vectorised sample of all their times a group, the animated nodes' locals and the
        morph weights written to the copies."""
        if self.scene is None or self.time is None or not self.copies:
            return
        from vkpbr.scene.animation import sample

        chosen = self._chosen
        channels = [ch for i in (range(len(self.scene.animations)) if chosen is None else chosen)
                    for ch in self.scene.animations[i].channels]
        driven = {ch.node for ch in channels if ch.node is not None and ch.path != "weights"}
        for c in self.copies:
            if not len(c.roots):
                continue
            pose = sample(self.scene, self.time + c.offsets, chosen)
            cols = np.flatnonzero(np.isin(c.sources, list(driven)))
            if len(cols):
                self._local[c.nodes[:, cols]] = pose.local[:, c.sources[cols]]
            w = pose.weights.get(c.draw_source) if c.draw_source is not None else None
            touched = [c.nodes[:, cols].ravel(), c.roots]
            if w is not None:  # (the draws' nodes: the copies of draw_source)
                col = int(np.flatnonzero(c.sources == c.draw_source)[0])
                for node, row in zip(c.nodes[:, col].tolist(), w, strict=True):
                    self.weights[node] = np.asarray(row, np.float64)
                touched.append(c.nodes[:, col])
            self._changed(np.concatenate(touched))

    def _is_direct(self) -> bool:
        """Whether draw i is tree node i with nothing below it (one draw a root-level node:
        the frame's models are a view of the world matrices)."""
        return (len(self.draw_tree) == len(self.tree) and not self._below.any()
                and bool(np.array_equal(self.draw_tree, np.arange(len(self.tree)))))

    # --- the frame's update -----------------------------------------------------------------
    def attach_deform(self, layout: object, draws: np.ndarray) -> None:
        """The deformed records (render/deform.py's DeformLayout) and the draw of each:
        their models become the frames the deform step poses them in (a sphere around the
        posed vertices, which culling places: DeformLayout.frames)."""
        self.deform, self.deform_draws = layout, np.asarray(draws, np.int64)
        self._record_of = -np.ones(len(self.draw_tree), np.int64)
        self._record_of[self.deform_draws] = np.arange(len(self.deform_draws))
        rows = np.zeros(len(self.draw_tree), bool)
        rows[self.deform_draws] = True
        self._update_draws(rows, self.deform.frames(self._world, self.weights), rest=True)  # type: ignore[attr-defined]
        if self.version:  # (new instances: the draws posed before keep their nodes' poses,
            # which the rows above, on the models as loaded, had undone)
            self._changed(self.draw_tree[self.deform_draws])

    def _flush_pending(self) -> None:
        """The quaternion rows set_poses kept, as local matrices (in call order)."""
        for idx, rows, order in self._pending:
            self._local[as_slice(idx)] = pose_matrices(rows, order)
        self._pending.clear()

    def _update(self) -> None:
        """Bring the frame's arrays to this version: world matrices of the changed nodes'
        subtrees, then the rows of the draws below them (DrawTable.update). Once per
        version, whatever asks first (the frame slot's copy, the bounds, the shadow cache)."""
        if self._updated == self.version:
            return
        self._flush_pending()
        if self._any_dirty:
            touched = self._dirty
            for level in self.tree.levels()[1:]:  # the subtrees of what changed
                touched[level] |= touched[self.tree.parents[level]]
            self._update_world(touched)
            if self._shown_dirty:
                self._shown = self.visible.copy()
                for level in self.tree.levels()[1:]:
                    self._shown[level] &= self._shown[self.tree.parents[level]]
                self._shown_dirty = False
            rows = touched[self.draw_tree]
            frames = None
            if self.deform is not None:
                moved = self.deform.affected(touched)  # type: ignore[attr-defined]
                rows[self.deform_draws[moved]] = True
                if rows[self.deform_draws].any():
                    frames = self.deform.frames(self._world, self.weights)  # type: ignore[attr-defined]
            self._update_draws(rows, frames)
            touched[:] = False
            self._any_dirty = False
        self._updated = self.version

    def _update_world(self, touched: np.ndarray) -> None:
        if touched.all():  # (a tree of roots alone: its world is its local, no copy)
            levels = len(self.tree.levels())
            self._world = self._local if levels == 1 else self.tree.world(self._local)
            return
        for depth, level in enumerate(self.tree.levels()):
            lv = as_slice(level[touched[level]])
            if not isinstance(lv, np.ndarray) or len(lv):
                self._world[lv] = (self._local[lv] if depth == 0 else
                                   self._world[self.tree.parents[lv]] @ self._local[lv])

    def _update_draws(self, rows: np.ndarray, frames: np.ndarray | None, rest: bool = False) -> None:
        """Draws `rows` (bool) take their node's world matrix (with the instance matrix below
        it, a deformed draw's frame, zero when hidden); `rest`: at set-up, the deformed
        draws' frames on their loaded models, no version."""
        dd = np.flatnonzero(rows)
        if not len(dd):
            return
        sel: np.ndarray | slice = slice(None) if len(dd) == len(rows) else as_slice(dd)
        direct = not rest and self._direct and isinstance(sel, slice)  # draw i is node i
        nodes = sel if direct else self.draw_tree[sel]
        m = self.rest[sel].copy() if rest else self._world[nodes]
        below, skinned, hidden = self._below[sel], self.skinned[sel], ~self._shown[nodes]
        has = self._record_of[sel] >= 0 if frames is not None else None
        if direct and (skinned.any() or hidden.any() or (has is not None and has.any())):
            m = m.copy()  # (a view of the world matrices until something differs)
        if below.any() and not rest:
            m[below] = m[below] @ self.draw_local[sel][below]
        if skinned.any():
            m[skinned] = np.eye(4)
        if has is not None:
            m[has] = m[has] @ frames[self._record_of[sel][has]]
        if hidden.any():
            m[hidden] = 0.0
        self.table.update(sel, m)
        if not rest:
            self.draw_versions[sel] = self.version

    # --- what frames read ------------------------------------------------------------------
    def _cached(self, name: str, make: object) -> object:
        hit = self._cache.get(name)
        if hit is not None and hit[0] == self.version:
            return hit[1]
        value = make()  # type: ignore[operator]
        self._cache[name] = (self.version, value)
        return value

    def world(self) -> np.ndarray:
        """(K, 4, 4) float64 world matrices of the tree's nodes (read-only; valid until the
        next change)."""
        self._update()
        return _read_only(self._world)

    def shown(self) -> np.ndarray:
        """(K,) bool: the node and every ancestor visible."""
        self._update()
        return _read_only(self._shown)

    def draw_models(self) -> np.ndarray:
        """(D, 4, 4) float64 model matrices of the draws (zero for hidden ones; read-only,
        updated in place by the next frame: copy to keep)."""
        self._update()
        return _read_only(self.table.models)

    def draw_matrices(self) -> np.ndarray:
        """(D, 2, 4, 4) float32 Instances records: model and normal matrix, column-major."""
        self._update()
        return _read_only(self.table.records)

    def draw_centers(self) -> np.ndarray:
        """(D, 3) world centres of the draws' mesh boxes (the blended draws' order)."""
        self._update()
        return _read_only(self.table.centers)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World bounds (min, max) of the shown draws; zeros when nothing is shown."""
        self._update()
        return self._cached("bounds", self.table.bounds)  # type: ignore[return-value]


@dataclasses.dataclass
class NodeCopies:
    """Copies of some tree nodes below instance roots (a skinned or morphed mesh's node, its
    ancestors and its skeleton, one copy an instance): `sources` (S,) the copied nodes
    (parents first); per instance its root, (S,) copy indices (`nodes`, one row a root) and
    its time offset; `draw_source` the node whose copy each instance's draw hangs from and
    whose animated morph weights it takes."""

    sources: np.ndarray
    draw_source: int | None = None
    nodes: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0), np.int64))
    roots: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int64))
    offsets: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        self.nodes = np.zeros((0, len(self.sources)), np.int64)


def copied_tree(tree: NodeTree, names: list[str], parents: np.ndarray, local: np.ndarray
                ) -> NodeTree:
    """`tree` with new nodes after its own: `names`, `parents` (earlier indices) and `local`
    transforms, given as matrices and of no file node (animation reaches copies through
    SceneState.pose_copies, not through channels)."""
    n = len(names)
    return NodeTree(tree.names + names, np.concatenate([tree.parents, parents]),
                    np.concatenate([tree.local, local]),
                    np.concatenate([tree.translation, np.zeros((n, 3))]),
                    np.concatenate([tree.rotation, np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))]),
                    np.concatenate([tree.scale, np.ones((n, 3))]),
                    np.concatenate([tree.uses_matrix, np.ones(n, bool)]),
                    np.concatenate([tree.source, -np.ones(n, np.int64)]),
                    dict(tree.weights), dict(tree.skin))


def grown_tree(tree: NodeTree, names: list[str]) -> NodeTree:
    """`tree` with new roots named `names` after its nodes (identity, given as matrices:
    no animation drives them; no file node: source -1)."""
    n = len(names)
    return copied_tree(tree, names, -np.ones(n, np.int64), np.tile(np.eye(4), (n, 1, 1)))


def as_slice(idx: np.ndarray) -> np.ndarray | slice:
    """`idx` as a slice when it is a run of consecutive indices (copies instead of scatters:
    several times faster for thousands of rows), else itself."""
    n = len(idx)
    if n and int(idx[-1]) - int(idx[0]) == n - 1 and (n < 3 or bool(np.all(np.diff(idx) == 1))):
        return slice(int(idx[0]), int(idx[0]) + n)
    return idx


def _read_only(a: np.ndarray) -> np.ndarray:
    v = a.view()
    v.flags.writeable = False
    return v


def pose_matrices(rows: np.ndarray, order: str = "xyzw") -> np.ndarray:
    """(N, 4, 4) matrices of (N, 7) position + quaternion rows (`order` of the quaternion)."""
    out = np.empty((len(rows), 4, 4))
    for b in blocks(len(rows)):  # (cache-sized blocks: scene/draw_table.py)
        quaternion_matrices(rows[b, 3:], order, out[b, :3, :3])
        out[b, :3, 3] = rows[b, :3]
        out[b, 3] = (0.0, 0.0, 0.0, 1.0)
    return out


def _poses_of(poses: np.ndarray, n: int) -> np.ndarray:
    """`poses` as (n, 7) rows or (n, 4, 4) matrices (one pose may come without its axis)."""
    p = numbers(poses, "set_poses")
    if n == 1 and p.shape in ((4, 4), (7,)):
        p = p[None]
    if p.shape in ((n, 7), (n, 4, 4)):
        return p
    raise UsageError(f"set_poses: poses of shape {p.shape} for {n} node(s); give "
                     f"({n}, 4, 4) matrices or ({n}, 7) position + quaternion rows")


def numbers(value: object, what: str) -> np.ndarray:
    """`value` as a float64 array; a one-line UsageError for what NumPy cannot make one of
    (a string, a ragged list, None inside), where np.asarray raised a ValueError."""
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise UsageError(f"{what}: expected numbers, got {describe(value)}") from None


# Pose numbers past this are garbage, not poses (a simulator's blown-up state): as a camera's
# (scene/camera.py), and far from float64's overflow in the products of the frame's matrices.
POSE_LIMIT = 1e15


def _finite(p: np.ndarray) -> None:
    """Every number finite and within +-POSE_LIMIT. One dot product of the poses with
    themselves first (a BLAS pass: NaN, infinity or a number past the limit makes it exceed
    POSE_LIMIT^2, or NaN); the exact tests only then."""
    flat = p.reshape(-1)
    with np.errstate(over="ignore", invalid="ignore"):  # (overflow is what it looks for)
        if float(np.dot(flat, flat)) <= POSE_LIMIT * POSE_LIMIT:
            return
    if not np.isfinite(p).all():
        raise UsageError("set_poses: a pose holds NaN or infinity")
    if float(np.abs(p).max()) > POSE_LIMIT:
        raise UsageError(f"set_poses: a pose holds a number beyond +-{POSE_LIMIT:.0e} (a "
                         "simulation that blew up?); give positions within it")


def _check_rows(p: np.ndarray) -> None:
    """(N, 7) rows: rigid by construction, so only the numbers are checked."""
    _finite(p)
    q = p[:, 3:]
    if len(q) and np.einsum("ij,ij->i", q, q).min() < 1e-24:
        raise UsageError("set_poses: a quaternion of length 0 is no rotation")


# The parts of a row-major (4, 4) pose _check_matrices reads: its 3x3 part, then its last row.
_CHECKED_PARTS = np.array((0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 15))


def _check_matrices(p: np.ndarray) -> None:
    """(N, 4, 4): finite, affine (last row 0 0 0 1), not singular. The parts it reads are
    gathered once into rows of their own (one pass over the poses; the tests then run on
    contiguous rows: 10,000 poses 0.32 -> 0.18 ms on the 2-core machine, where each test on
    the strided parts of the (N, 4, 4) array had touched all of it)."""
    _finite(p)
    if not len(p):  # (no nodes: nothing to check, and no maximum of nothing)
        return
    c = p.reshape(len(p), 16).T[_CHECKED_PARTS]  # (13, N)
    if max(np.abs(c[9:12]).max(), np.abs(c[12] - 1.0).max()) > 1e-6:
        raise UsageError("set_poses: a matrix's last row must be 0 0 0 1 (an affine "
                         "transform; a projection is not a pose)")
    if np.abs(determinant_of_parts(*c[:9])).min() < 1e-12:
        raise UsageError("set_poses: a matrix is singular (a scale of 0 flattens the node; "
                         "hide it with set_visible instead)")


def _pointed_light(light: Light, member: str, value: np.ndarray) -> Light:
    """`light` with one animated property (KHR_lights_punctual's names, vkpbr's fields)."""
    if member == "color":
        return dataclasses.replace(light, color=tuple(float(v) for v in value[:3]))
    if member in ("intensity", "range"):
        return dataclasses.replace(light, **{member: max(float(value[0]), 0.0)})
    if member in ("inner_cone", "outer_cone") and light.kind == "spot":
        inner = float(value[0]) if member == "inner_cone" else light.inner_cone
        outer = float(value[0]) if member == "outer_cone" else light.outer_cone
        if 0.0 <= inner < outer <= np.pi / 2:  # else the file's (glTF requires it)
            return dataclasses.replace(light, inner_cone=inner, outer_cone=outer)
    return light


def _factor(field: str, value: object) -> tuple[float, ...]:
    """A material factor checked: its size and range (UsageError naming it)."""
    name = field.removesuffix("_factor")
    v = numbers(value, f"set_material: {name}").reshape(-1)
    sizes = {"base_color_factor": (3, 4), "emissive_factor": (3,)}.get(field, (1,))
    # (finite as the GPU's float32 holds them: 1e308 had become infinity there)
    if len(v) not in sizes or not np.all(np.abs(v) <= np.finfo(np.float32).max):
        raise UsageError(f"set_material: {name} must be {' or '.join(map(str, sizes))} finite "
                         f"number(s), got {shown(value, sequences=True)}")
    if field == "emissive_factor":
        if np.any(v < 0):
            raise UsageError(f"set_material: emissive must be >= 0, got {shown(value, sequences=True)}")
    elif np.any((v < 0) | (v > 1)):
        raise UsageError(f"set_material: {name} must be within [0, 1], got {shown(value, sequences=True)}")
    if field == "base_color_factor" and len(v) == 3:
        v = np.append(v, 1.0)
    return tuple(float(x) for x in v)
