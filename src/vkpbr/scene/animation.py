"""Sampling glTF animations into poses, vectorised over times (NumPy, no GPU).

`sample(scene, time, animation)` evaluates every channel of the chosen animations at one
time or at B times at once (1,000 instances each at its own time: one call, no Python loop
over times or keyframes; the loop is over channels) and returns a `Pose`: the tree's local
TRS, local matrices, morph weights and KHR_animation_pointer values, each with the times'
shape in front. `Pose.world(tree)` gives world matrices; `joint_matrices(world, skin)` a
skin's joint matrices. The rules (glTF 2.0 spec 3.11 and Appendix C) and fallbacks are in
docs/animation.md:

- STEP holds a keyframe's value until the next one; LINEAR interpolates (rotations by
  spherical linear interpolation, the shorter way round); CUBICSPLINE is the cubic Hermite
  spline with the file's tangents scaled by the keyframe interval. Rotations are normalised.
- Times before the first keyframe take the first value, after the last the last.
- Nodes no channel animates keep the file's TRS; a node given as a matrix keeps its matrix.
- Morph weights: the node's `weights`, else its mesh's, replaced by what animation gives.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene.draw_table import blocks
from vkpbr.scene.tree import NodeTree
from vkpbr.scene.tree import quaternion_matrices as rotation_matrices
from vkpbr.scene.types import Animation, AnimationSampler, Scene, Skin

__all__ = ["Pose", "sample", "sample_sampler", "joint_matrices", "trs_matrices",
           "quaternion_matrices", "animation_indices", "animation_time"]


@dataclass
class Pose:
    """The tree's state at one or more times; `...` is the shape of the times given
    (() for one float, (B,) for B times).

    translation (..., K, 3), rotation (..., K, 4) unit quaternions x, y, z, w, scale
        (..., K, 3): every tree node's TRS (the file's where nothing animates it; identity
        for nodes given as a matrix).
    local : (..., K, 4, 4) float64 local matrices, T * R * S, or the node's matrix.
    weights : {tree node: (..., T)} morph weights of every node showing a morphed mesh.
    pointers : {KHR_animation_pointer string: (..., C)} the sampled values of the pointer
        channels (C = 1 for a scalar property), node properties included.
    """

    translation: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    local: np.ndarray
    weights: dict[int, np.ndarray] = field(default_factory=dict)
    pointers: dict[str, np.ndarray] = field(default_factory=dict)

    def world(self, tree: NodeTree) -> np.ndarray:
        """(..., K, 4, 4) world matrices of this pose (one batched product per tree level)."""
        return tree.world(self.local)

    def at(self, index: int | tuple[int, ...]) -> Pose:
        """The pose of one of the times (index into the leading axes)."""
        return Pose(self.translation[index], self.rotation[index], self.scale[index],
                    self.local[index], {k: v[index] for k, v in self.weights.items()},
                    {k: v[index] for k, v in self.pointers.items()})


def animation_indices(scene: Scene, animation: int | str | Sequence[int | str] | None) -> list[int]:
    """Indices into scene.animations: None = all, an index, a name, or a list of them.
    UsageError naming the animations when one matches nothing."""
    n = len(scene.animations)
    if animation is None:
        return list(range(n))
    one = isinstance(animation, (int, np.integer, str)) or not isinstance(animation, Iterable)
    refs = [animation] if one else list(animation)
    out = []
    for ref in refs:
        if isinstance(ref, (int, np.integer)) and not isinstance(ref, bool):
            if not 0 <= int(ref) < n:
                raise UsageError(f"animation {int(ref)} is out of range: the scene has {n} "
                                 f"animation{'s' * (n != 1)}")
            out.append(int(ref))
            continue
        names = [a.name for a in scene.animations]
        if ref not in names:
            shown = ", ".join(repr(x) for x in names[:8]) or "none"
            raise UsageError(f"no animation is named {ref!r} (the scene has: {shown})")
        out.append(names.index(ref))
    return out


def animation_time(time: object) -> float:
    """One animation time in seconds (`set_time`'s, `render`'s `time`, one of `times`): a
    finite number (NumPy's and 0-d arrays too); a one-line UsageError for anything else."""
    try:
        if isinstance(time, (str, bytes)):
            raise TypeError
        t = float(time)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise UsageError("animation time: expected a number of seconds, got "
                         f"{type(time).__name__}") from None
    if not math.isfinite(t):
        raise UsageError(f"animation time must be finite, got {t}")
    return t


def sample(scene: Scene, time: float | np.ndarray,
           animation: int | str | Sequence[int | str] | None = None) -> Pose:
    """The pose of `scene` at `time` (seconds: a float or an array of B times) under the
    chosen animations (None: all of them, applied in order; a later channel on the same
    property wins). UsageError for a non-finite time or an unknown animation."""
    t = np.asarray(time, dtype=np.float64)
    if not np.isfinite(t).all():
        raise UsageError(f"animation time must be finite, got {time!r}")
    lead = t.shape
    flat = t.reshape(-1)
    tree = scene.node_tree()
    k = len(tree)
    b = len(flat)
    trs = {"translation": np.broadcast_to(tree.translation, (b, k, 3)).copy(),
           "rotation": np.broadcast_to(tree.rotation, (b, k, 4)).copy(),
           "scale": np.broadcast_to(tree.scale, (b, k, 3)).copy()}
    weights = _rest_weights(scene, tree, b)
    pointers: dict[str, np.ndarray] = {}
    chosen = [scene.animations[i] for i in animation_indices(scene, animation)]
    spans: dict[int, tuple] = {}
    for anim in chosen:  # mesh weights first: a node's own weights override them
        for ch in anim.channels:
            if ch.kind == "mesh":
                value = _value(anim, ch.sampler, flat, False, spans)
                pointers[str(ch.pointer)] = value
                for row in ch.targets:
                    if row not in tree.weights and row in weights:
                        weights[row] = value
    grouped = _sample_groups(chosen, flat, spans, trs)
    for anim in chosen:
        for ch in anim.channels:
            if ch.kind == "mesh" or id(ch) in grouped:
                continue
            value = _value(anim, ch.sampler, flat, ch.path == "rotation", spans)
            if ch.pointer is not None:
                pointers[ch.pointer] = value
            if ch.node is None:
                continue
            if ch.path == "weights":
                if ch.node in weights:
                    weights[ch.node] = value
            else:
                trs[ch.path][:, ch.node] = value
    local = trs_matrices(trs["translation"], trs["rotation"], trs["scale"])
    local[:, tree.uses_matrix] = tree.local[tree.uses_matrix]
    return Pose(trs["translation"].reshape(*lead, k, 3), trs["rotation"].reshape(*lead, k, 4),
                trs["scale"].reshape(*lead, k, 3), local.reshape(*lead, k, 4, 4),
                {r: w.reshape(*lead, -1) for r, w in weights.items()},
                {p: v.reshape(*lead, -1) for p, v in pointers.items()})


def _sample_groups(chosen: list[Animation], times: np.ndarray, spans: dict, trs: dict[str, np.ndarray]
                   ) -> set[int]:
    """The LINEAR translation, rotation and scale channels sampled together, a group per
    path (a skeleton's 19 rotations in one interpolation over (19, B) rows, not 19 of B):
    written into `trs`; returns the id() of each channel done. None when two channels
    drive the same property (then the later must win: channel by channel)."""
    groups: dict[str, list[tuple[AnimationSampler, int, int]]] = {}
    constant: list[tuple[str, int, np.ndarray, int]] = []
    seen: set[tuple[int, str]] = set()
    for anim in chosen:
        for ch in anim.channels:
            if ch.kind == "mesh" or ch.node is None:
                continue
            if (ch.node, ch.path) in seen:
                return set()
            seen.add((ch.node, ch.path))
            s = anim.samplers[ch.sampler]
            if (ch.pointer is None and ch.path in trs and s.interpolation == "LINEAR"
                    and len(s.input) >= 2):
                if ch.path != "rotation" and _constant(s):  # (exporters key every bone's
                    constant.append((ch.path, ch.node, s.output[0], id(ch)))  # translation)
                else:
                    groups.setdefault(ch.path, []).append((s, ch.node, id(ch)))
    done: set[int] = set()
    for path, node, value, key in constant:  # a + u (a - a) is a, bit for bit
        trs[path][:, node] = value
        done.add(key)
    for path, members in groups.items():
        if len(members) < 2:
            continue
        value = _sample_linear([m[0] for m in members], times, path == "rotation", spans)
        trs[path][:, [m[1] for m in members]] = value
        done.update(m[2] for m in members)
    return done


def _sample_linear(samplers: list[AnimationSampler], times: np.ndarray, rotation: bool,
                   spans: dict) -> np.ndarray:
    """(B, G, C) values of G LINEAR samplers at (B,) times: one gather and one
    interpolation over all of them (sample_sampler's rules), in the (time, sampler) order
    the caller writes them in. What depends on the keyframes alone (the concatenated
    values, each rotation interval's arc) is made once per group of samplers (`_group`)."""
    found = [_span(s.input, times, spans) for s in samplers]
    base, table = _group(samplers, rotation)
    first = found[0]
    if all(f is first for f in found):  # one time accessor for the group (exporters' habit)
        idx = first[0][:, None] + base
        u = np.broadcast_to(first[2], (len(times), len(samplers)))[..., None]
    else:
        idx = np.stack([f[0] for f in found], axis=1) + base
        u = np.stack([f[2][:, 0] for f in found], axis=1)[..., None]
    if not rotation:
        a, d = table[0][idx], table[1][idx]  # start and (end - start) of each interval
        return a + u * d
    a, b, angle, inv = (t[idx] for t in table)
    small = inv == 0.0
    wa = np.where(small, 1.0 - u, np.sin((1.0 - u) * angle) * inv)
    wb = np.where(small, u, np.sin(u * angle) * inv)
    return _normalised(wa * a + wb * b)


_GROUPS: dict[tuple, tuple] = {}  # (sampler ids, rotation) -> (samplers, base, table)


def _group(samplers: list[AnimationSampler], rotation: bool) -> tuple[np.ndarray, tuple]:
    """(G,) each sampler's first keyframe in the concatenation and the concatenated tables:
    (start, end - start) of every interval, or for rotations _arcs' (start, end, angle,
    1 / sine). Cached while the same samplers (and outputs) live: a crowd samples the same
    group every frame."""
    key = (tuple(id(s) for s in samplers), rotation)
    hit = _GROUPS.get(key)
    if hit is not None and all(a is b and a.output is o for a, b, o in
                               zip(samplers, hit[0], hit[3], strict=True)):
        return hit[1], hit[2]
    base = np.cumsum([0] + [len(s.input) for s in samplers[:-1]]).astype(np.int64)
    if rotation:
        parts = [_arcs(s) for s in samplers]
        table = tuple(np.concatenate([p[k] for p in parts]) for k in range(4))
    else:
        values = np.concatenate([np.asarray(s.output, np.float64) for s in samplers])
        nxt = np.concatenate([np.concatenate([s.output[1:], s.output[-1:]]) for s in samplers])
        table = (values, np.asarray(nxt, np.float64) - values)
    if len(_GROUPS) > 256:  # (files come and go: keep the cache small)
        _GROUPS.clear()
    _GROUPS[key] = (list(samplers), base, table, [s.output for s in samplers])
    return base, table


def _constant(s: AnimationSampler) -> bool:
    """Whether every keyframe of a LINEAR sampler holds the same value (kept on the sampler,
    as _arcs)."""
    cached = getattr(s, "_constant", None)
    if cached is not None and cached[0] is s.output:
        return cached[1]
    out = np.asarray(s.output)
    same = bool(np.all(np.isfinite(out)) and np.array_equal(out, np.broadcast_to(out[:1], out.shape)))
    s._constant = (s.output, same)  # type: ignore[attr-defined]
    return same


def _arcs(s: AnimationSampler) -> tuple[np.ndarray, ...]:
    """Per keyframe k of a rotation sampler, the arc to keyframe k + 1 as _slerp takes it:
    (K, 4) unit start, (K, 4) unit end on the shorter side, (K, 1) angle, (K, 1) 1 / sine
    (0 where the angle is tiny: linear there). Kept on the sampler (its keyframes do not
    change once loaded)."""
    cached = getattr(s, "_arcs", None)
    if cached is not None and cached[0] is s.output:
        return cached[1]
    q = _normalised(np.asarray(s.output, np.float64))
    a, b = q, np.concatenate([q[1:], q[-1:]])
    d = np.einsum("bi,bi->b", a, b)[:, None]
    b = np.where(d < 0, -b, b)
    angle = np.arccos(np.minimum(np.abs(d), 1.0))
    sin_angle = np.sin(angle)
    inv = np.where(sin_angle < 1e-6, 0.0, 1.0 / np.where(sin_angle < 1e-6, 1.0, sin_angle))
    arcs = (a, b, angle, inv)
    s._arcs = (s.output, arcs)  # type: ignore[attr-defined]
    return arcs


def _rest_weights(scene: Scene, tree: NodeTree, b: int) -> dict[int, np.ndarray]:
    """(b, T) morph weights of each tree node showing a morphed mesh: node's, else mesh's."""
    out: dict[int, np.ndarray] = {}
    for node in scene.nodes:
        mesh_weights = scene.meshes[node.mesh].morph_weights
        if mesh_weights is None or node.tree in out:
            continue
        w = tree.weights.get(node.tree, mesh_weights)
        out[node.tree] = np.broadcast_to(np.asarray(w, np.float64), (b, len(w))).copy()
    return out


def _value(anim: Animation, sampler: int, times: np.ndarray, rotation: bool,
           spans: dict[int, tuple]) -> np.ndarray:
    return sample_sampler(anim.samplers[sampler], times, rotation, spans)


def _span(inp: np.ndarray, times: np.ndarray, spans: dict[int, tuple] | None) -> tuple:
    """(i, dt, s) of `times` in keyframe times `inp`: the interval t_i <= t < t_i+1, its
    length and the clamped fraction s in [0, 1], shared by the samplers with the same input
    array in one sample() call (exporters write one time accessor for many channels:
    CesiumMan's 57 channels use 19)."""
    # By content where small (exporters often write equal time arrays, one per channel).
    key = inp.tobytes() if len(inp) <= 4096 else id(inp)
    if spans is not None and key in spans:
        return spans[key][1]
    i = np.clip(np.searchsorted(inp, times, side="right") - 1, 0, len(inp) - 2)
    dt = inp[i + 1] - inp[i]
    s = np.clip((times - inp[i]) / dt, 0.0, 1.0)[:, None]  # clamps times outside the range
    if spans is not None:
        spans[key] = (inp, (i, dt[:, None], s))  # inp kept alive: its id stays its own
    return i, dt[:, None], s


def sample_sampler(s: AnimationSampler, times: np.ndarray, rotation: bool = False,
                   spans: dict[int, tuple] | None = None) -> np.ndarray:
    """(B, C) values of sampler `s` at (B,) `times`; `rotation`: quaternions, interpolated
    by slerp (LINEAR) and normalised. `spans`: a cache of keyframe intervals by input array,
    for many samplers at the same times."""
    inp, out = s.input, s.output
    cubic = s.interpolation == "CUBICSPLINE"
    values = out[:, 1] if cubic else out  # (k, C) keyframe values
    if len(inp) == 1:
        v = np.broadcast_to(values[0], (len(times), values.shape[-1])).copy()
    elif s.interpolation == "STEP":
        v = values[np.clip(np.searchsorted(inp, times, side="right") - 1, 0, len(inp) - 1)]
    else:
        i, dt, u = _span(inp, times, spans)
        if cubic:
            u2, u3 = u * u, u * u * u
            v = ((2 * u3 - 3 * u2 + 1) * values[i] + (u3 - 2 * u2 + u) * dt * out[i, 2]
                 + (-2 * u3 + 3 * u2) * values[i + 1] + (u3 - u2) * dt * out[i + 1, 0])
        elif rotation:
            v = _slerp(values[i], values[i + 1], u)
        else:
            v = values[i] + u * (values[i + 1] - values[i])
    return _normalised(v) if rotation else v


def _slerp(a: np.ndarray, b: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation of (B, 4) quaternions (glTF Appendix C): the shorter
    arc (b negated when a . b < 0), linear interpolation where the angle is tiny. The
    keyframes are normalised first (as the Sample Viewer does): files store them to float32
    or 8/16-bit precision, and AnimatedTriangle's (0, 0, 0.707, 0.707) is 1.5e-4 short."""
    a, b = _normalised(a), _normalised(b)
    d = np.einsum("bi,bi->b", a, b)[:, None]
    b = np.where(d < 0, -b, b)
    d = np.abs(d)
    angle = np.arccos(np.minimum(d, 1.0))
    sin_angle = np.sin(angle)
    small = sin_angle < 1e-6
    safe = np.where(small, 1.0, sin_angle)
    wa = np.where(small, 1.0 - u, np.sin((1.0 - u) * angle) / safe)
    wb = np.where(small, u, np.sin(u * angle) / safe)
    return wa * a + wb * b


def _normalised(q: np.ndarray) -> np.ndarray:
    """Unit quaternions; a zero one becomes the identity."""
    n = np.sqrt(np.einsum("...i,...i->...", q, q))[..., None]
    zero = n < 1e-12
    if zero.any():
        return np.where(zero, np.float64([0, 0, 0, 1]), q / np.where(zero, 1.0, n))
    return q / n


def quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices of (..., 4) quaternions x, y, z, w (normalised first)."""
    q = _normalised(np.asarray(q, np.float64))
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty((*q.shape[:-1], 3, 3))
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    out[..., 0, 0] = 1 - 2 * (yy + zz)
    out[..., 0, 1] = 2 * (xy - wz)
    out[..., 0, 2] = 2 * (xz + wy)
    out[..., 1, 0] = 2 * (xy + wz)
    out[..., 1, 1] = 1 - 2 * (xx + zz)
    out[..., 1, 2] = 2 * (yz - wx)
    out[..., 2, 0] = 2 * (xz - wy)
    out[..., 2, 1] = 2 * (yz + wx)
    out[..., 2, 2] = 1 - 2 * (xx + yy)
    return out


def trs_matrices(t: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(..., 4, 4) float64 T * R * S of (..., 3) translations, (..., 4) quaternions and (..., 3)
    scales (the glTF node transform)."""
    t = np.asarray(t, np.float64)
    lead = t.shape[:-1]
    t3 = t.reshape(-1, 3)
    q = np.asarray(r, np.float64).reshape(-1, 4)  # (rotation_matrices normalises)
    s3 = np.broadcast_to(np.asarray(s, np.float64), (*lead, 3)).reshape(-1, 3)
    out = np.zeros((len(t3), 4, 4))
    for b in blocks(len(t3)):  # cache-sized blocks, contiguous components (scene/state.py)
        rotation_matrices(q[b], out=out[b, :3, :3], scale=s3[b])
        out[b, :3, 3] = t3[b]
    out[:, 3, 3] = 1.0
    return out.reshape(*lead, 4, 4)


def joint_matrices(world: np.ndarray, skin: Skin) -> np.ndarray:
    """(..., J, 4, 4) joint matrices: world[joints] @ inverse_bind. They take a skinned
    vertex from the mesh's bind space to world space; the skinned mesh's own node transform
    is not applied (glTF 3.7.3: only the joints' transforms count)."""
    return np.asarray(world)[..., skin.joints, :, :] @ skin.inverse_bind
