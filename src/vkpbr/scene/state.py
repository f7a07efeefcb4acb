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

from collections.abc import Iterable, Sequence

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene.tree import NodeRef, NodeTree
from vkpbr.scene.types import Scene

__all__ = ["SceneState", "quaternion_matrices", "normal_matrices", "std140_pairs"]

QUATERNION_ORDERS = ("xyzw", "wxyz")
SPACES = ("local", "world")


def quaternion_matrices(q: np.ndarray, order: str = "xyzw") -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) quaternions in `order` (normalised first; a
    zero quaternion is refused by the caller)."""
    q = np.asarray(q, np.float64)
    x, y, z, w = (q.T if order == "xyzw" else q[:, [1, 2, 3, 0]].T)
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], axis=-2)


def normal_matrices(model: np.ndarray) -> np.ndarray:
    """(..., 4, 4) normal matrices (the inverse transpose of the 3x3 part) of model
    matrices; a singular one (a hidden draw's zero matrix) keeps its 3x3 part."""
    a = model[..., :3, :3]
    det = np.linalg.det(a)
    ok = np.abs(det) > 1e-30
    inv = np.zeros_like(a)
    if np.any(ok):
        inv[ok] = np.linalg.inv(a[ok])
    out = np.zeros_like(model)
    out[..., :3, :3] = np.where(ok[..., None, None], np.swapaxes(inv, -1, -2), a)
    out[..., 3, 3] = 1.0
    return out


def std140_pairs(model: np.ndarray) -> np.ndarray:
    """(D, 2, 4, 4) float32: each model matrix and its normal matrix as GLSL's column-major
    mat4 (Instances records: layouts.STORAGE)."""
    pairs = np.stack([model, normal_matrices(model)], axis=1)
    return np.ascontiguousarray(np.swapaxes(pairs, -1, -2), dtype=np.float32)


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
        self.time: float | None = None  # the time set_time last posed
        self.version = 0
        self.draw_versions = np.zeros(len(self.draw_tree), np.int64)  # when each last changed
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
        if not nodes and not morphed:
            return
        pose = sample(self.scene, float(time), chosen)
        idx = np.asarray(nodes, np.int64)
        self.local[idx] = pose.local[idx]
        for node in morphed:
            if node in pose.weights:
                self.weights[int(node)] = np.asarray(pose.weights[node], np.float64)
        self.time = float(time)
        self._changed(np.asarray(sorted(set(nodes) | {int(m) for m in morphed}), np.int64))

    def reset(self) -> None:
        """Back to the file's rest pose, everything shown."""
        self.local[:] = self.tree.local
        self.visible[:] = True
        self.weights.clear()
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
        if draws is None:
            return int(self.draw_versions.max(initial=0))
        return int(self.draw_versions[draws].max(initial=0))

    def _pose_matrices(self, poses: np.ndarray, n: int, quaternion: str) -> np.ndarray:
        p = np.asarray(poses, dtype=np.float64)
        if p.ndim == 2 and n == 1 and p.shape in ((4, 4), (1, 7)):
            p = p[None] if p.shape == (4, 4) else p
        if p.ndim == 1 and p.shape == (7,) and n == 1:
            p = p[None]
        if p.shape == (n, 4, 4):
            out = p
        elif p.shape == (n, 7):
            if quaternion not in QUATERNION_ORDERS:
                raise UsageError(f"quaternion {quaternion!r}: choose 'xyzw' or 'wxyz'")
            if np.any(np.linalg.norm(p[:, 3:], axis=1) < 1e-12):
                raise UsageError("set_poses: a quaternion of length 0 is no rotation")
            out = np.zeros((n, 4, 4))
            out[:, :3, :3] = quaternion_matrices(p[:, 3:], quaternion)
            out[:, :3, 3] = p[:, :3]
            out[:, 3, 3] = 1.0
        else:
            raise UsageError(f"set_poses: poses of shape {p.shape} for {n} node(s); give "
                             f"({n}, 4, 4) matrices or ({n}, 7) position + quaternion rows")
        if not np.all(np.isfinite(out)):
            raise UsageError("set_poses: a pose holds NaN or infinity")
        if not np.allclose(out[:, 3], [0.0, 0.0, 0.0, 1.0]):
            raise UsageError("set_poses: a matrix's last row must be 0 0 0 1 (an affine "
                             "transform; a projection is not a pose)")
        if np.any(np.abs(np.linalg.det(out[:, :3, :3])) < 1e-12):
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
            models = self.world()[self.draw_tree] @ self.draw_local
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
