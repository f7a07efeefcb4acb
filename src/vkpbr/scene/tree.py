"""The scene's node hierarchy: names, parents and local transforms, kept as arrays.

A loaded Scene's `nodes` are what is drawn (one Node per mesh primitive instance, each with
its world matrix at load time); the `NodeTree` is the file's hierarchy those hang from
(glTF nodes: a Node's `tree` is the index of the tree node it belongs to). The living-scene
state (vkpbr.scene.state) changes the tree's local transforms and recomputes world matrices
with `world`: one batched matrix product per depth level, never a Python loop over nodes.
Loaders without a hierarchy (OBJ, baked files, the default scene) get `NodeTree.flat`: one
root per Node.

Names: a node is found by its name or by its path from the root ("truck/wheel_front");
`find` takes shell-style patterns ("wheel*", "arm/*").
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from vkpbr.errors import UsageError

__all__ = ["NodeTree", "NodeRef", "quaternion_matrices"]

NodeRef = int | str  # a tree node: its index, name or path


def quaternion_matrices(q: np.ndarray, order: str = "xyzw", out: np.ndarray | None = None,
                        scale: np.ndarray | None = None) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) quaternions in `order` (normalised by the
    formula; a zero quaternion gives the identity), into `out` when given (a (N, 3, 3) view);
    with `scale` ((N, 3)), R * diag(scale)."""
    q = np.asarray(q, np.float64)
    x, y, z, w = np.ascontiguousarray(q.T if order == "xyzw" else q[:, [1, 2, 3, 0]].T)
    n2 = x * x + y * y + z * z + w * w
    s = 2.0 / np.where(n2 > 1e-24, n2, np.inf)  # normalises: 2 / |q|^2 (0: the identity)
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz, xx, xy, xz, yy, yz, zz = w * xs, w * ys, w * zs, x * xs, x * ys, x * zs, y * ys, y * zs, z * zs
    # Built as (3, 3, N) contiguous rows, then one transposing copy (9 strided writes cost more).
    m = np.empty((3, 3, len(q)))
    m[0, 0], m[0, 1], m[0, 2] = 1.0 - (yy + zz), xy - wz, xz + wy
    m[1, 0], m[1, 1], m[1, 2] = xy + wz, 1.0 - (xx + zz), yz - wx
    m[2, 0], m[2, 1], m[2, 2] = xz - wy, yz + wx, 1.0 - (xx + yy)
    if scale is not None:  # R * S: column j times scale j
        m *= np.ascontiguousarray(np.asarray(scale, np.float64).T)[None]
    out = np.empty((len(q), 3, 3)) if out is None else out
    out[...] = m.transpose(2, 0, 1)
    return out


@dataclass
class NodeTree:
    """K nodes in parent-before-child order (a parent's index is below its children's).

    names : each node's name (glTF `name`, else "node <i>" with the file's index).
    parents : (K,) int64, -1 for a root.
    local : (K, 4, 4) float64 local transforms of the rest pose (the file's).
    translation, rotation, scale : (K, 3), (K, 4) quaternion x, y, z, w, (K, 3): the file's
        TRS (identity where the node gives a matrix: `uses_matrix`); what animation samples
        replace (glTF animates TRS, never a matrix).
    uses_matrix : (K,) bool, the node gives `matrix` rather than TRS.
    source : (K,) int64, the node's index in the file (glTF `nodes`; animations target it).
    weights : {tree node: (T,) float64} morph weights the node gives (glTF `weights`).
    skin : {tree node: index into Scene.skins} nodes whose mesh is skinned (glTF `skin`).
    """

    names: list[str]
    parents: np.ndarray
    local: np.ndarray
    translation: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    uses_matrix: np.ndarray
    source: np.ndarray
    weights: dict[int, np.ndarray] = field(default_factory=dict)
    skin: dict[int, int] = field(default_factory=dict)
    _levels: list[np.ndarray] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        k = len(self.names)
        self.parents = np.asarray(self.parents, np.int64).reshape(k)
        if np.any(self.parents >= np.arange(k)):
            raise ValueError("NodeTree: every parent must come before its children")

    def __len__(self) -> int:
        return len(self.names)

    @classmethod
    def flat(cls, matrices: Sequence[np.ndarray], names: Sequence[str]) -> NodeTree:
        """One root per matrix (scenes without a hierarchy): node i's local = its matrix."""
        k = len(names)
        local = np.asarray(np.reshape(matrices, (k, 4, 4)), np.float64) if k else np.zeros((0, 4, 4))
        ident = _identity_trs(k)
        return cls(list(names), -np.ones(k, np.int64), local, *ident, np.ones(k, bool),
                   np.arange(k, dtype=np.int64))

    # --- world transforms ---------------------------------------------------------------
    def levels(self) -> list[np.ndarray]:
        """Node indices by depth: roots first; each level's parents are in earlier ones."""
        if self._levels is None:
            depth = np.zeros(len(self), np.int64)
            for i in np.flatnonzero(self.parents >= 0):  # parents first: one pass at load
                depth[i] = depth[self.parents[i]] + 1
            self._levels = [np.flatnonzero(depth == d) for d in range(int(depth.max(initial=0)) + 1)]
        return self._levels

    def world(self, local: np.ndarray | None = None) -> np.ndarray:
        """(..., K, 4, 4) world matrices of `local` (default: the rest pose's), with any
        leading batch axes (worlds): one batched product per depth level."""
        local = self.local if local is None else local
        levels = self.levels()
        # Roots copied; every deeper level is written by its product (no copy of it first).
        world = np.empty(np.shape(local), np.float64)
        world[..., levels[0], :, :] = local[..., levels[0], :, :]
        for level in levels[1:]:
            world[..., level, :, :] = world[..., self.parents[level], :, :] @ local[..., level, :, :]
        return world

    # --- names --------------------------------------------------------------------------
    def paths(self) -> list[str]:
        """Each node's path from its root, names joined by "/"."""
        out: list[str] = []
        for i, name in enumerate(self.names):
            p = int(self.parents[i])
            out.append(name if p < 0 else f"{out[p]}/{name}")
        return out

    def find(self, pattern: str) -> np.ndarray:
        """Indices of the nodes whose name or path matches the shell-style `pattern`
        ("wheel*", "truck/*", "node 3"), in tree order; empty when none does."""
        paths = self.paths()
        hits = [i for i, (n, p) in enumerate(zip(self.names, paths, strict=True))
                if fnmatch.fnmatchcase(n, pattern) or fnmatch.fnmatchcase(p, pattern)]
        return np.asarray(hits, np.int64)

    def indices(self, nodes: NodeRef | Iterable[NodeRef] | np.ndarray) -> np.ndarray:
        """(N,) int64 tree indices of `nodes`: an index, a name, a path, a pattern, or a
        sequence of them. Raises UsageError naming what matches nothing or is out of range."""
        if isinstance(nodes, (int, np.integer, str)):
            nodes = [nodes]
        elif not isinstance(nodes, Iterable):
            raise UsageError(f"nodes: expected an index, a name, a path, a pattern or a list of "
                             f"them, got {type(nodes).__name__}")
        arr = np.asarray(nodes) if not isinstance(nodes, np.ndarray) else nodes
        if arr.dtype.kind in "iu":
            if arr.dtype.kind == "u" and arr.size and int(arr.max()) >= len(self):
                raise self._out_of_range(int(arr.max()))  # (before int64 wraps 2**63 negative)
            idx = arr.astype(np.int64, copy=False).ravel()
            if len(idx) and (idx.min() < 0 or idx.max() >= len(self)):  # two reductions
                bad = idx[(idx < 0) | (idx >= len(self))]
                raise self._out_of_range(int(bad[0]))
            return idx
        out: list[np.ndarray] = []
        for ref in list(arr.ravel() if isinstance(nodes, np.ndarray) else nodes):
            if isinstance(ref, (int, np.integer)):  # (past int64: NumPy made objects of them)
                if not 0 <= ref < len(self):
                    raise self._out_of_range(int(ref))
                out.append(np.array([ref], np.int64))
                continue
            hit = self.find(str(ref))
            if not len(hit):
                raise UsageError(f"no node is named {str(ref)!r} (Scene.tree.names lists them; "
                                 "patterns such as 'wheel*' match names and paths)")
            out.append(hit)
        return np.concatenate(out) if out else np.zeros(0, np.int64)

    def _out_of_range(self, i: int) -> UsageError:
        shown = i if abs(i) < 10**20 else f"{'-' if i < 0 else ''}1e20 or more"
        return UsageError(f"node index {shown} is out of range: the scene has {len(self)} "
                          f"nodes (0..{len(self) - 1})")


def _identity_trs(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rot = np.zeros((k, 4))
    rot[:, 3] = 1.0
    return np.zeros((k, 3)), rot, np.ones((k, 3))
