"""Worlds: many states of one scene, each its own poses of a few named nodes (NumPy, no GPU).

A batch of worlds (Renderer.render_batch(worlds=...), docs/batch.md "Worlds") shares the
scene's geometry, materials and the renderer's state, and differs in the world poses of N
chosen nodes (`WorldSlots`: picked once by name, path, pattern or index) and, optionally,
which of them are shown. Each of those nodes carries its subtree: every draw hangs from its
nearest chosen ancestor-or-self (its anchor) by the transform it has in the renderer's state,

    model[w, d] = pose[w, anchor(d)] @ relative[d],   relative[d] = inverse(world(anchor)) @ model(d),

and draws with no chosen ancestor keep the state's model in every world. A draw directly on a
chosen node (relative[d] the identity, the usual case: one rigid body a node) takes the pose
itself, so a world of root-level nodes equals `set_poses(..., space="world")` of that world
bit for bit. This module is that formula in NumPy (the mirror of render/shaders/worlds.comp,
which evaluates it on the GPU for poses that live there) and the checks of what users give.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene.state import QUATERNION_ORDERS, SceneState, quaternion_matrices, std140_pairs
from vkpbr.scene.tree import NodeRef

__all__ = ["WorldSlots", "WorldPoses", "WorldMaterials", "WorldLights", "WorldEnvironment",
           "world_models", "world_records", "world_blocks"]

_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])


@dataclass(frozen=True)
class WorldSlots:
    """The N nodes whose poses each world gives (`nodes`: tree indices, in the order the
    worlds' arrays list them) and what follows from the state at `version`: each draw's
    anchor (index into `nodes`, -1 for none) and its transform below it."""

    nodes: np.ndarray  # (N,) tree indices
    names: tuple[str, ...]  # their paths, for messages
    anchor: np.ndarray  # (D,) int64
    relative: np.ndarray  # (D, 4, 4) float64: model = pose @ relative (state model if no anchor)
    identity: np.ndarray  # (D,) bool: relative is exactly the identity (model = pose)
    covers: np.ndarray  # (N, D) bool: slot n is the draw's node or an ancestor (hides it)
    version: int  # the state version these were made at
    frame: np.ndarray  # (N, 4, 4) each slot's parent's world matrix in the state (local poses)
    nested: bool  # a slot has another slot above it

    @classmethod
    def of(cls, state: SceneState, nodes: NodeRef | Iterable[NodeRef] | np.ndarray) -> WorldSlots:
        """The slots of `nodes` (NodeTree.indices: names, paths, patterns, indices) in `state`."""
        idx = state.tree.indices(nodes)
        if len(idx) == 0:
            raise UsageError("world_slots: no nodes given; name the nodes each world poses")
        if len(np.unique(idx)) != len(idx):
            raise UsageError("world_slots: a node is named twice")
        paths = state.tree.paths()
        return cls._made(state, idx, tuple(paths[i] for i in idx))

    @classmethod
    def _made(cls, state: SceneState, idx: np.ndarray, names: tuple[str, ...]) -> WorldSlots:
        tree = state.tree
        slot_of = np.full(len(tree), -1, np.int64)
        slot_of[idx] = np.arange(len(idx))
        anchor_of = slot_of.copy()  # nearest chosen ancestor-or-self, level by level
        for level in tree.levels()[1:]:
            own = anchor_of[level]
            anchor_of[level] = np.where(own >= 0, own, anchor_of[tree.parents[level]])
        anchor = anchor_of[state.draw_tree]
        below = np.zeros((len(idx), len(tree)), bool)  # each slot's subtree
        below[np.arange(len(idx)), idx] = True
        for level in tree.levels()[1:]:
            below[:, level] |= below[:, tree.parents[level]]
        models = state.draw_models()
        world = state.world()
        relative = models.copy()
        has = anchor >= 0
        if np.any(has):
            relative[has] = np.linalg.solve(world[idx[anchor[has]]], models[has])
        identity = has & (state.draw_tree == idx[np.maximum(anchor, 0)]) & ~state.skinned
        identity &= np.all(state.draw_local == np.eye(4), axis=(1, 2))
        relative[identity] = np.eye(4)
        # Skinned draws are posed by their joints (world space): their model stays as is.
        relative[has & state.skinned] = models[has & state.skinned]
        anchor = np.where(state.skinned, -1, anchor)
        parents = tree.parents[idx]
        frame = np.tile(np.eye(4), (len(idx), 1, 1))
        frame[parents >= 0] = state.world()[parents[parents >= 0]]
        nested = bool(np.any(below[:, idx].sum(axis=0) > 1))
        return cls(idx, names, anchor, relative, identity, below[:, state.draw_tree], state.version,
                   frame, nested)

    def refreshed(self, state: SceneState) -> WorldSlots:
        """These slots against the state now (the renderer's set_poses moved what they hang
        from): remade when its version changed."""
        return self if state.version == self.version else self._made(state, self.nodes, self.names)

    def __len__(self) -> int:
        return len(self.nodes)


@dataclass(frozen=True)
class WorldPoses:
    """W worlds' poses of N slots as (W, N, 4, 4) float64 world matrices, and which slots
    each world shows ((W, N) bool, or None: all)."""

    given: np.ndarray  # (W, N, 4, 4) matrices, or (W, N, 7) rows (position + quaternion)
    visible: np.ndarray | None
    wxyz: bool = False  # the rows' quaternion order
    local: bool = False  # relative to each node's parent as the state places it (else world)

    @property
    def count(self) -> int:
        return len(self.given)

    @property
    def rows(self) -> np.ndarray | None:
        """The (W, N, 7) rows as given, or None for matrices."""
        return self.given if self.given.ndim == 3 else None

    @cached_property
    def matrices(self) -> np.ndarray:
        """(W, N, 4, 4) float64 world matrices (made from the rows on first use: the GPU
        expands rows itself)."""
        given = np.asarray(self.given, np.float64)  # (float32 poses are kept as given)
        if given.ndim == 4:
            return given
        return _rows_to_matrices(given, "wxyz" if self.wxyz else "xyzw")

    @classmethod
    def of(cls, poses: Any, slots: int, quaternion: str = "xyzw", visible: Any = None,
           space: str = "world") -> WorldPoses:
        """Checked poses: (W, N, 4, 4) affine world matrices or (W, N, 7) position + unit
        quaternion rows (`quaternion` "xyzw" as SAPIEN/scipy, or "wxyz" as MuJoCo/Isaac);
        `visible` (W, N) of bools. One-line UsageErrors name what is wrong. A NumPy array
        of the layout checked last (shape, dtype, slots, quaternion order, space; no
        visibility) has only its values checked: a loop's steps give the same each time."""
        layout = None
        if type(poses) is np.ndarray and visible is None and poses.dtype in _KEPT:
            layout = (poses.shape, poses.dtype, slots, quaternion, space)
            if layout == _LAYOUT[0]:
                p = poses[:, None] if poses.ndim == 2 else poses
                (_row_values if p.ndim == 3 else _checked_matrices)(p)
                return cls(p, None, quaternion == "wxyz", space == "local")
        made = cls._of(poses, slots, quaternion, visible, space)
        if layout is not None:
            _LAYOUT[0] = layout
        return made

    @classmethod
    def _of(cls, poses: Any, slots: int, quaternion: str, visible: Any, space: str
            ) -> WorldPoses:
        p = _array("worlds", poses, keep=True)
        if p.ndim == 2 and p.shape[-1] == 7 and slots == 1:
            p = p[:, None]
        if p.ndim == 3 and p.shape[1:] == (slots, 7):
            given = _checked_rows(p, quaternion)
        elif p.ndim == 4 and p.shape[1:] == (slots, 4, 4):
            given = _checked_matrices(p)
        else:
            raise UsageError(f"worlds: poses of shape {tuple(p.shape)} for {slots} slot node(s); "
                             f"give (W, {slots}, 4, 4) world matrices or (W, {slots}, 7) "
                             "position + quaternion rows")
        if len(given) == 0:
            raise UsageError("worlds: no worlds given (W = 0)")
        shown = None
        if visible is not None:
            v = _array("visible", visible)
            if v.shape != given.shape[:2]:
                raise UsageError(f"visible: shape {tuple(v.shape)}, expected "
                                 f"{given.shape[:2]} (worlds, slot nodes)")
            shown = v.astype(bool)
        return cls(given, shown, quaternion == "wxyz", check_space(space))


def check_space(space: str) -> bool:
    """True for "local" (poses relative to each node's parent as the renderer's state places
    it: a simulator's frame below a fixed root), False for "world"; UsageError otherwise."""
    if space not in ("world", "local"):
        raise UsageError(f"space {space!r}: choose 'world' or 'local'")
    return space == "local"


_KEPT = (np.dtype(np.float32), np.dtype(np.float64))  # poses read as given
# WorldPoses.of's last checked layout of a NumPy array (shape, dtype, slots, quaternion,
# space): a loop's next steps check only their values
_LAYOUT: list[tuple | None] = [None]


def _array(what: str, value: Any, keep: bool = False) -> np.ndarray:
    """`value` as a float64 NumPy array, or bool (a CPU torch tensor or anything
    array-like); `keep`: float32 kept as given too (the poses: no copy a step, read within
    the call)."""
    if hasattr(value, "detach") and hasattr(value, "device"):  # torch, not imported here
        if str(value.device) != "cpu":
            raise UsageError(f"{what}: a tensor on {value.device} reaches this path only "
                             "through the GPU route (render_batch(device='cuda'))")
        value = value.detach().numpy()
    try:
        a = np.asarray(value)
        if a.dtype == bool or a.dtype == np.float64 or (keep and a.dtype == np.float32):
            return a  # (float32 poses: WorldPoses.matrices converts them where needed)
        return a.astype(np.float64)
    except (TypeError, ValueError) as exc:
        raise UsageError(f"{what}: not an array of numbers ({exc})") from None


def _checked_rows(p: np.ndarray, quaternion: str) -> np.ndarray:
    if quaternion not in QUATERNION_ORDERS:
        raise UsageError(f"quaternion {quaternion!r}: choose 'xyzw' or 'wxyz'")
    return _row_values(p)


def _row_values(p: np.ndarray) -> np.ndarray:
    """`p`'s values checked (W, N, 7): finite, no quaternion of length 0."""
    _check_finite(p)
    q = p[..., 3:]  # (a view: no copy of the quaternions, read strided)
    if np.minimum.reduce(_square_norms(q, q), axis=None, initial=1.0) < 1e-24:
        raise UsageError("worlds: a quaternion of length 0 is no rotation")
    return p


def _check_finite(p: np.ndarray) -> None:
    """UsageError where `p` holds NaN or infinity (np.isfinite's bool temporary: measured
    faster than a sum's propagation on float32, whose pairwise sum is slow)."""
    if not np.logical_and.reduce(np.isfinite(p), axis=None):
        raise UsageError("worlds: a pose holds NaN or infinity")


# (..., 4) x (..., 4) -> (...) dot products: NumPy 2's vecdot ufunc (one C call), else einsum
_square_norms = getattr(np, "vecdot", None) or (lambda a, b: np.einsum("...i,...i->...", a, b))


def _rows_to_matrices(p: np.ndarray, quaternion: str) -> np.ndarray:
    w, n = p.shape[:2]
    q = p[..., 3:].reshape(-1, 4)
    out = np.empty((w * n, 4, 4))
    quaternion_matrices(q, quaternion, out[:, :3, :3])
    out[:, :3, 3] = p[..., :3].reshape(-1, 3)
    out[:, 3] = _LAST_ROW
    return out.reshape(w, n, 4, 4)


def _checked_matrices(p: np.ndarray) -> np.ndarray:
    _check_finite(p)
    if np.abs(p[..., 3, :] - _LAST_ROW).max(initial=0.0) > 1e-6:
        raise UsageError("worlds: a matrix's last row must be 0 0 0 1 (an affine transform)")
    return p


def world_models(state: SceneState, slots: WorldSlots, poses: WorldPoses) -> np.ndarray:
    """(W, D, 4, 4) float64 model matrices of every draw in every world (zero where hidden:
    hidden in the state, or its anchor hidden in that world)."""
    base = state.draw_models()
    w, d = poses.count, len(base)
    out = np.broadcast_to(base, (w, d, 4, 4)).copy()
    has = slots.anchor >= 0
    exact = slots.identity
    moved = has & ~exact
    pose = poses.matrices
    if poses.local:
        if slots.nested:
            raise UsageError("worlds: space='local' with a chosen node below another chosen "
                             "node; give world poses (space='world')")
        pose = slots.frame[None] @ pose
    if np.any(exact):
        out[:, exact] = pose[:, slots.anchor[exact]]
    if np.any(moved):
        out[:, moved] = pose[:, slots.anchor[moved]] @ slots.relative[moved]
    hidden = ~np.any(base[:, :3, :3] != 0.0, axis=(1, 2))  # hidden in the state: in all
    if poses.visible is not None:  # a hidden node hides its subtree, as set_visible does
        off = (~poses.visible).astype(np.int64) @ slots.covers.astype(np.int64) > 0
        out[off] = 0.0
    out[:, hidden] = 0.0
    return out


def world_records(state: SceneState, slots: WorldSlots, poses: WorldPoses) -> np.ndarray:
    """(W * D, 2, 4, 4) float32 Instances records of every world's draws, world after world
    (what a batch of worlds' views read from their world's instance_base)."""
    models = world_models(state, slots, poses)
    return std140_pairs(models.reshape(-1, 4, 4))


# Per-world material factors: the glTF factors a dataset randomises (what set_material sets).
FACTOR_CHANNELS = {"base_color": (3, 4), "metallic": (1,), "roughness": (1,), "emissive": (3,)}


@dataclass(frozen=True)
class WorldMaterials:
    """W worlds' factors of K named materials: `materials` (K,) indices into the scene's,
    `values` {field: (W, K, channels) float64} for the fields given (base_color RGBA,
    metallic, roughness, emissive), checked as set_material checks one."""

    materials: np.ndarray
    values: dict[str, np.ndarray]

    @property
    def count(self) -> int:
        return len(next(iter(self.values.values())))

    @staticmethod
    def indices(state: SceneState, materials: Iterable[int | str]) -> np.ndarray:
        """(K,) indices of the named materials (names or indices; UsageError for others)."""
        return np.array([state._material_index(m) for m in materials], np.int64)

    @classmethod
    def of(cls, state: SceneState, materials: Iterable[int | str], given: Any) -> WorldMaterials:
        idx = cls.indices(state, materials)
        if len(idx) == 0:
            raise UsageError("world_materials: name the materials first: "
                             "renderer.world_slots(nodes, materials=['paint', ...])")
        if not isinstance(given, dict) or not given:
            raise UsageError("world_materials: a dict of base_color, metallic, roughness, "
                             "emissive arrays, each (W, K[, channels])")
        values: dict[str, np.ndarray] = {}
        for field, value in given.items():
            if field not in FACTOR_CHANNELS:
                raise UsageError(f"world_materials: unknown factor {field!r} (choose "
                                 f"{', '.join(FACTOR_CHANNELS)})")
            values[field] = _factor_array(field, _array(f"world_materials[{field!r}]", value),
                                          len(idx))
        counts = {len(v) for v in values.values()}
        if len(counts) != 1 or 0 in counts:
            raise UsageError(f"world_materials: every factor needs the same number of worlds "
                             f"(got {sorted(counts)})")
        return cls(idx, values)


def _factor_array(field: str, v: np.ndarray, k: int) -> np.ndarray:
    sizes = FACTOR_CHANNELS[field]
    if sizes == (1,) and v.ndim == 2:
        v = v[..., None]
    if v.ndim != 3 or v.shape[1] != k or v.shape[2] not in sizes:
        shapes = " or ".join(f"(W, {k}{'' if c == 1 else f', {c}'})" for c in sizes)
        raise UsageError(f"world_materials[{field!r}]: shape {tuple(v.shape)}, expected {shapes}")
    if not np.isfinite(v).all():
        raise UsageError(f"world_materials[{field!r}]: NaN or infinity")
    if field == "emissive":
        if (v < 0).any():
            raise UsageError("world_materials['emissive']: must be >= 0")
    elif ((v < 0) | (v > 1)).any():
        raise UsageError(f"world_materials[{field!r}]: must be within [0, 1]")
    if field == "base_color" and v.shape[2] == 3:
        v = np.concatenate([v, np.ones(v.shape[:2] + (1,))], axis=2)
    return v


@dataclass(frozen=True)
class WorldLights:
    """W worlds' intensity (W, L) and/or colour (W, L, 3) of the frame's L lights, in the
    order the frame lists them (the call's `lights`, else the scene's or the preset's)."""

    values: dict[str, np.ndarray]

    @property
    def count(self) -> int:
        return len(next(iter(self.values.values())))

    @classmethod
    def of(cls, given: Any, lights: int) -> WorldLights:
        if not isinstance(given, dict) or not given or set(given) - {"intensity", "color"}:
            raise UsageError("world_lights: a dict of 'intensity' (W, L) and/or 'color' "
                             f"(W, L, 3) arrays for the frame's {lights} light(s)")
        values = {}
        for field, value in given.items():
            v = _array(f"world_lights[{field!r}]", value)
            want = (lights,) if field == "intensity" else (lights, 3)
            if v.ndim != 1 + len(want) or v.shape[1:] != want or len(v) == 0:
                raise UsageError(f"world_lights[{field!r}]: shape {tuple(v.shape)}, expected "
                                 f"(W, {', '.join(map(str, want))}) for the frame's {lights} light(s)")
            if not np.isfinite(v).all() or (v < 0).any():
                raise UsageError(f"world_lights[{field!r}]: must be finite and >= 0")
            values[field] = v
        if len({len(v) for v in values.values()}) != 1:
            raise UsageError("world_lights: intensity and color need the same number of worlds")
        return cls(values)


@dataclass(frozen=True)
class WorldEnvironment:
    """W worlds' environment intensity and/or rotation about +Y in degrees, (W,) each."""

    values: dict[str, np.ndarray]

    @property
    def count(self) -> int:
        return len(next(iter(self.values.values())))

    @classmethod
    def of(cls, given: Any) -> WorldEnvironment:
        if not isinstance(given, dict) or not given or set(given) - {"intensity", "rotation"}:
            raise UsageError("world_environment: a dict of 'intensity' and/or 'rotation' "
                             "(degrees about +Y), each (W,)")
        values = {}
        for field, value in given.items():
            v = _array(f"world_environment[{field!r}]", value)
            if v.ndim != 1 or len(v) == 0 or not np.isfinite(v).all():
                raise UsageError(f"world_environment[{field!r}]: (W,) finite numbers, got "
                                 f"shape {tuple(v.shape)}")
            if field == "intensity" and (v < 0).any():
                raise UsageError("world_environment['intensity']: must be >= 0")
            values[field] = v
        if len({len(v) for v in values.values()}) != 1:
            raise UsageError("world_environment: intensity and rotation need the same number of worlds")
        return cls(values)


def world_blocks(worlds: int, materials: np.ndarray, wm: WorldMaterials | None,
                 lights: np.ndarray, wl: WorldLights | None, environment: tuple[float, float],
                 we: WorldEnvironment | None) -> np.ndarray:
    """(W, S, 4) float32 WorldFactors blocks (shaders/worlds.glsl): a header (uint bits:
    where the lights and the environment start, whether each is given), every material's
    three factor rows (`materials` (M, 3, 4): base colour; emissive, metallic; roughness; the
    named ones replaced), each light's colour x intensity (`lights` (L, 4): colour, intensity)
    and the environment's (intensity, cos, sin) of its rotation (`environment`: intensity,
    radians)."""
    m, n = len(materials), len(lights)
    size = 1 + 3 * m + n + 1
    out = np.zeros((worlds, size, 4), np.float32)
    head = out[:, 0].view(np.uint32)
    head[:, 0], head[:, 1] = 1 + 3 * m, 1 + 3 * m + n
    head[:, 2], head[:, 3] = wl is not None, we is not None
    mats = np.broadcast_to(materials, (worlds, m, 3, 4)).copy()
    if wm is not None:
        rows = {"base_color": (0, slice(0, 4)), "emissive": (1, slice(0, 3)),
                "metallic": (1, slice(3, 4)), "roughness": (2, slice(0, 1))}
        for field, value in wm.values.items():
            row, cols = rows[field]
            mats[:, wm.materials, row, cols] = value
    out[:, 1:1 + 3 * m] = mats.reshape(worlds, 3 * m, 4)
    if n:
        color = np.broadcast_to(lights[:, :3], (worlds, n, 3))
        intensity = np.broadcast_to(lights[:, 3], (worlds, n))
        if wl is not None:
            color = wl.values.get("color", color)
            intensity = wl.values.get("intensity", intensity)
        out[:, 1 + 3 * m:1 + 3 * m + n, :3] = color * intensity[..., None]
    env_i = np.full(worlds, environment[0])
    env_r = np.full(worlds, environment[1])
    if we is not None:
        env_i = we.values.get("intensity", env_i)
        env_r = np.radians(we.values["rotation"]) if "rotation" in we.values else env_r
    out[:, -1, 0], out[:, -1, 1], out[:, -1, 2] = env_i, np.cos(env_r), np.sin(env_r)
    return out
