"""The living scene: what changes between frames, as NumPy arrays (no GPU here).

A `SceneState` holds the node tree's local transforms (vkpbr.scene.tree) and which nodes are
shown, and turns them into what the GPU reads per draw: its model and normal matrices
(`draw_matrices`), the world bounds and the draws' centres (culling, the blended draws'
order, the shadow maps' fit). Every change bumps `version`; the renderer copies the state
into a frame slot when the slot's copy is older (render/scene_state.py), so a pose change is
one buffer write per frame and re-records nothing.

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
from vkpbr.scene.tree import NodeRef, NodeTree
from vkpbr.scene.types import Camera, Light, Scene

__all__ = ["SceneState", "quaternion_matrices", "normal_matrices", "std140_pairs"]

QUATERNION_ORDERS = ("xyzw", "wxyz")
_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])
SPACES = ("local", "world")


def quaternion_matrices(q: np.ndarray, order: str = "xyzw", out: np.ndarray | None = None
                        ) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) quaternions in `order` (normalised first; a
    zero quaternion is refused by the caller), into `out` when given (a (N, 3, 3) view)."""
    q = np.asarray(q, np.float64)
    x, y, z, w = np.ascontiguousarray(q.T if order == "xyzw" else q[:, [1, 2, 3, 0]].T)
    s = 2.0 / (x * x + y * y + z * z + w * w)  # normalises: 2 / |q|^2
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz, xx, xy, xz, yy, yz, zz = w * xs, w * ys, w * zs, x * xs, x * ys, x * zs, y * ys, y * zs, z * zs
    out = np.empty((len(q), 3, 3)) if out is None else out
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = 1.0 - (yy + zz), xy - wz, xz + wy
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = xy + wz, 1.0 - (xx + zz), yz - wx
    out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = xz - wy, yz + wx, 1.0 - (xx + yy)
    return out


def _cofactors(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cofactor matrices and determinants of (..., 3, 3) matrices, from the columns'
    cross products (inverse transpose = cofactors / determinant): a few vector operations
    for any number of matrices, where np.linalg.inv loops in LAPACK."""
    # Components as contiguous (...) arrays (elementwise products of strided views cost 10x).
    m = np.ascontiguousarray(np.moveaxis(a, (-2, -1), (0, 1)))  # m[row][column]
    cof = np.empty((3, 3, *a.shape[:-2]), a.dtype)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            cof[i, j] = m[i1, j1] * m[i2, j2] - m[i1, j2] * m[i2, j1]
    det = m[0, 0] * cof[0, 0] + m[0, 1] * cof[0, 1] + m[0, 2] * cof[0, 2]
    return np.moveaxis(cof, (0, 1), (-2, -1)), det


def determinants(a: np.ndarray) -> np.ndarray:
    """det of (..., 3, 3) matrices."""
    return _cofactors(a)[1]


def normal_matrices(model: np.ndarray) -> np.ndarray:
    """(..., 4, 4) normal matrices (the inverse transpose of the 3x3 part) of model
    matrices; a singular one (a hidden draw's zero matrix) keeps its 3x3 part."""
    a = model[..., :3, :3]
    cof, det = _cofactors(a)
    ok = np.abs(det) > 1e-30
    out = np.zeros_like(model)
    with np.errstate(divide="ignore", invalid="ignore"):
        out[..., :3, :3] = np.where(ok[..., None, None], cof / np.where(ok, det, 1.0)[..., None, None], a)
    out[..., 3, 3] = 1.0
    return out


def std140_pairs(model: np.ndarray) -> np.ndarray:
    """(D, 2, 4, 4) float32: each model matrix and its normal matrix as GLSL's column-major
    mat4 (Instances records: layouts.STORAGE)."""
    out = np.empty((len(model), 2, 4, 4), np.float32)
    out[:, 0] = np.swapaxes(model, -1, -2)
    out[:, 1] = np.swapaxes(normal_matrices(model), -1, -2)
    return out


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
        self._below = np.flatnonzero(np.any(self.draw_local != np.eye(4), axis=(1, 2)))
        self.mesh_boxes = np.asarray(mesh_boxes, np.float64).reshape(-1, 2, 3)
        self.rest = np.asarray(rest, np.float64).reshape(-1, 4, 4)
        # Skinned draws are posed in world space by their joints: their model stays the
        # identity (glTF ignores the skinned node's transform).
        self.skinned = (np.zeros(len(self.draw_tree), bool) if skinned is None
                        else np.asarray(skinned, bool))
        self.local = np.array(tree.local, np.float64, copy=True)
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

    def __len__(self) -> int:
        return len(self.tree)

    # --- changing it ----------------------------------------------------------------------
    def set_poses(self, nodes: NodeRef | Iterable[NodeRef] | np.ndarray, poses: np.ndarray,
                  space: str = "local", quaternion: str = "xyzw") -> None:
        """Set the transforms of `nodes` (indices, names, paths or patterns: NodeTree.indices)
        from (N, 4, 4) affine matrices or (N, 7) rows of position + unit quaternion
        (`quaternion` "xyzw" or "wxyz"), relative to each node's parent (`space="local"`) or
        in the world (`space="world"`)."""
        idx = self.tree.indices(nodes)
        matrices = self._pose_matrices(poses, len(idx), quaternion)
        if space not in SPACES:
            raise UsageError(f"space {space!r}: choose 'local' or 'world'")
        if space == "world":
            matrices = self._world_to_local(idx, matrices)
        self.local[idx] = matrices
        self._changed(idx)

    def set_pose(self, node: NodeRef, matrix: np.ndarray, space: str = "local") -> None:
        """Set one node's (4, 4) transform, or its (7,) position + quaternion x, y, z, w
        (`set_poses` for many)."""
        self.set_poses([node] if isinstance(node, (int, np.integer)) else self.tree.indices(node)[:1],
                       np.asarray(matrix, np.float64)[None], space)

    def set_visible(self, nodes: NodeRef | Iterable[NodeRef] | np.ndarray,
                    mask: bool | Sequence[bool] | np.ndarray = True) -> None:
        """Show (True) or hide (False) `nodes` and their subtrees: one flag or one per node."""
        idx = self.tree.indices(nodes)
        m = np.asarray(mask)
        if m.dtype != bool or m.ndim > 1 or (m.ndim == 1 and len(m) != len(idx)):
            raise UsageError(f"set_visible: the mask must be one bool or {len(idx)} of them "
                             f"(one per node), got {m.dtype} of shape {m.shape}")
        self.visible[idx] = m
        self._changed(idx)

    def set_weights(self, node: NodeRef, weights: Sequence[float] | np.ndarray) -> None:
        """Set the morph target weights of the mesh `node` shows (glTF `weights`)."""
        idx = self.tree.indices(node)
        w = np.asarray(weights, np.float64).reshape(-1)
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
        from vkpbr.scene.animation import animation_indices, sample

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
        self.local[idx] = pose.local[idx]
        for node in morphed:
            if node in pose.weights:
                self.weights[int(node)] = np.asarray(pose.weights[node], np.float64)
        self.time = float(time)
        self._changed(np.asarray(sorted(set(nodes) | {int(m) for m in morphed}), np.int64))

    def set_material(self, material: int | str, base_color: Sequence[float] | None = None,
                     metallic: float | None = None, roughness: float | None = None,
                     emissive: Sequence[float] | None = None) -> None:
        """Override a material's factors from the next frame on (randomised datasets; glTF
        animation pointers go through here too): `base_color` RGBA or RGB in [0, 1],
        `metallic` and `roughness` in [0, 1], `emissive` linear RGB >= 0. They multiply the
        material's textures, as glTF's factors do. `material`: index or name."""
        i = self._material_index(material)
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
        self.local[:] = self.tree.local
        self.visible[:] = True
        self.weights.clear()
        self.pointers.clear()
        if self.materials:
            self.materials.clear()
            self.material_version += 1
        self._changed(np.arange(len(self.tree)))

    def _changed(self, idx: np.ndarray) -> None:
        self.version += 1
        # The draws below the changed nodes (their subtrees): what the shadow cache asks.
        touched = np.zeros(len(self.tree), bool)
        touched[idx] = True
        for level in self.tree.levels()[1:]:
            touched[level] |= touched[self.tree.parents[level]]
        self.draw_versions[touched[self.draw_tree]] = self.version

    def changed_since(self, draws: np.ndarray | None = None) -> int:
        """The latest version that changed any of `draws` (a bool mask; None: all): what
        a cache of their images (the shadow maps) compares."""
        last = self._since
        if last is not None and last[0] == self.version and last[1] is draws:
            return last[2]  # the same mask (the casters') and state: once per change
        versions = self.draw_versions if draws is None else self.draw_versions[draws]
        hit = int(versions.max(initial=0))
        self._since = (self.version, draws, hit)  # keeps the mask: its identity is the key
        return hit

    def _pose_matrices(self, poses: np.ndarray, n: int, quaternion: str) -> np.ndarray:
        p = np.asarray(poses, dtype=np.float64)
        if p.ndim == 2 and n == 1 and p.shape in ((4, 4), (1, 7)):
            p = p[None] if p.shape == (4, 4) else p
        if p.ndim == 1 and p.shape == (7,) and n == 1:
            p = p[None]
        if p.shape == (n, 7):  # rigid by construction: only the numbers are checked
            if quaternion not in QUATERNION_ORDERS:
                raise UsageError(f"quaternion {quaternion!r}: choose 'xyzw' or 'wxyz'")
            if not np.isfinite(p).all():
                raise UsageError("set_poses: a pose holds NaN or infinity")
            if np.einsum("ij,ij->i", p[:, 3:], p[:, 3:]).min(initial=1.0) < 1e-24:
                raise UsageError("set_poses: a quaternion of length 0 is no rotation")
            out = np.empty((n, 4, 4))
            quaternion_matrices(p[:, 3:], quaternion, out[:, :3, :3])
            out[:, :3, 3] = p[:, :3]
            out[:, 3] = _LAST_ROW
            return out
        if p.shape == (n, 4, 4):
            out = p
        else:
            raise UsageError(f"set_poses: poses of shape {p.shape} for {n} node(s); give "
                             f"({n}, 4, 4) matrices or ({n}, 7) position + quaternion rows")
        if not np.isfinite(out).all():
            raise UsageError("set_poses: a pose holds NaN or infinity")
        if np.abs(out[:, 3] - _LAST_ROW).max(initial=0.0) > 1e-6:
            raise UsageError("set_poses: a matrix's last row must be 0 0 0 1 (an affine "
                             "transform; a projection is not a pose)")
        if np.abs(determinants(out[:, :3, :3])).min(initial=1.0) < 1e-12:
            raise UsageError("set_poses: a matrix is singular (a scale of 0 flattens the node; "
                             "hide it with set_visible instead)")
        return out

    def _world_to_local(self, idx: np.ndarray, world: np.ndarray) -> np.ndarray:
        parents = self.tree.parents[idx]
        parent_world = np.broadcast_to(np.eye(4), world.shape).copy()
        has = parents >= 0
        if np.any(has):
            parent_world[has] = self.world()[parents[has]]
        return np.linalg.solve(parent_world, world)

    # --- what frames read ------------------------------------------------------------------
    def _cached(self, name: str, make: object) -> object:
        hit = self._cache.get(name)
        if hit is not None and hit[0] == self.version:
            return hit[1]
        value = make()  # type: ignore[operator]
        self._cache[name] = (self.version, value)
        return value

    def world(self) -> np.ndarray:
        """(K, 4, 4) float64 world matrices of the tree's nodes."""
        return self._cached("world", lambda: self.tree.world(self.local))  # type: ignore[return-value]

    def shown(self) -> np.ndarray:
        """(K,) bool: the node and every ancestor visible."""
        def make() -> np.ndarray:
            out = self.visible.copy()
            for level in self.tree.levels()[1:]:
                out[level] &= out[self.tree.parents[level]]
            return out
        return self._cached("shown", make)  # type: ignore[return-value]

    def draw_models(self) -> np.ndarray:
        """(D, 4, 4) float64 model matrices of the draws (zero for hidden ones)."""
        def make() -> np.ndarray:
            if self.version == 0:
                return self.rest.copy()
            models = self.world()[self.draw_tree]
            if len(self._below):
                models[self._below] = models[self._below] @ self.draw_local[self._below]
            models[self.skinned] = np.eye(4)
            models[~self.shown()[self.draw_tree]] = 0.0
            return models
        return self._cached("models", make)  # type: ignore[return-value]

    def draw_matrices(self) -> np.ndarray:
        """(D, 2, 4, 4) float32 Instances records: model and normal matrix, column-major."""
        return self._cached("records", lambda: std140_pairs(self.draw_models()))  # type: ignore[return-value]

    def draw_centers(self) -> np.ndarray:
        """(D, 3) world centres of the draws' mesh boxes (the blended draws' order)."""
        def make() -> np.ndarray:
            m = self.draw_models()
            c = self.mesh_boxes.mean(axis=1)
            return np.einsum("dij,dj->di", m[:, :3, :3], c) + m[:, :3, 3]
        return self._cached("centers", make)  # type: ignore[return-value]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World bounds (min, max) of the shown draws; zeros when nothing is shown."""
        def make() -> tuple[np.ndarray, np.ndarray]:
            m = self.draw_models()
            shown = np.any(m[:, :3, :3] != 0.0, axis=(1, 2))
            if not np.any(shown):
                return np.zeros(3), np.zeros(3)
            lo, hi = self.mesh_boxes[shown, 0], self.mesh_boxes[shown, 1]
            centre, half = (lo + hi) / 2, (hi - lo) / 2
            ms = m[shown]
            c = np.einsum("dij,dj->di", ms[:, :3, :3], centre) + ms[:, :3, 3]
            r = np.einsum("dij,dj->di", np.abs(ms[:, :3, :3]), half)
            return (c - r).min(axis=0), (c + r).max(axis=0)
        return self._cached("bounds", make)  # type: ignore[return-value]


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
    v = np.asarray(value, np.float64).reshape(-1)
    sizes = {"base_color_factor": (3, 4), "emissive_factor": (3,)}.get(field, (1,))
    name = field.removesuffix("_factor")
    if len(v) not in sizes or not np.all(np.isfinite(v)):
        raise UsageError(f"set_material: {name} must be {' or '.join(map(str, sizes))} finite "
                         f"number(s), got {value!r}")
    if field == "emissive_factor":
        if np.any(v < 0):
            raise UsageError(f"set_material: emissive must be >= 0, got {value!r}")
    elif np.any((v < 0) | (v > 1)):
        raise UsageError(f"set_material: {name} must be within [0, 1], got {value!r}")
    if field == "base_color_factor" and len(v) == 3:
        v = np.append(v, 1.0)
    return tuple(float(x) for x in v)
