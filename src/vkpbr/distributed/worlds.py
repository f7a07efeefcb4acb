"""Per-view world state of a job entry: the `"worlds"` key (docs/distributed.md, "Worlds").

A randomised dataset renders each view of one scene in its own state: some nodes at poses of
their own and some hidden. An entry names those nodes once and gives the state per world in
.npy files beside the job file (or inline):

    "worlds": {"nodes": ["cube", "arm/*"],     # names, paths, patterns or indices (world_slots)
               "poses": "worlds.npy",          # (W, N, 7) position + quaternion, or (W, N, 4, 4)
               "quaternion": "xyzw",           # the rows' order: "xyzw" (default) or "wxyz"
               "visible": "visible.npy",       # optional (W, N) bools
               "materials": {"names": ["floor"],           # optional material factor overrides
                             "base_color": "colors.npy",   # (W, M, 3 or 4) in [0, 1]
                             "metallic": ..., "roughness": ...,  # (W, M) in [0, 1]
                             "emissive": ...},             # (W, M, 3) >= 0
               "world_of_view": "index.npy"}   # optional (V,) integers; omitted: W = V, view v
                                               # sees world v

"poses" (with "nodes") or "materials" or both; each array's first axis is the W worlds.

Everything is checked when the job is read, before any actor starts: the arrays' headers
(shape, dtype) before their data, the shapes against the entry's V views and the N nodes,
NaN and infinities, zero quaternions, indices in range; files are read with
allow_pickle=False, only regular files, only inside the job file's folder (unless the entry
says `allow_outside_paths`). A pattern's node count is only known once the scene is loaded:
the actor checks it then (an item of a bad input fails at once, without retries).

A work item carries only its views' worlds (`ItemWorlds`), and each view has a digest of its
world (the nodes, the quaternion order, its pose rows and visibility): the manifest records it
with the view, so a view whose world changed is rendered again and the others resume.
"""

from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import UsageError

__all__ = ["JobWorlds", "ItemWorlds", "job_worlds"]

_KEYS = frozenset({"nodes", "poses", "quaternion", "visible", "world_of_view", "materials"})
# Material factors a world may override: (values per material, low, high) as set_material
# takes them (vkpbr.scene.state).
_FACTORS = {"base_color": ((3, 4), 0.0, 1.0), "metallic": ((), 0.0, 1.0),
            "roughness": ((), 0.0, 1.0), "emissive": ((3,), 0.0, np.inf)}
_MAX_BYTES = 4 << 30  # one array the driver holds in memory: 4 GiB (33 million 4x4 poses)
_GLOB = frozenset("*?[")


@dataclass(frozen=True, eq=False)
class Materials:
    """Material factor overrides of W worlds: M materials (`names`: names or indices) and
    per factor a (W, M) or (W, M, k) float64 array (`factors`, the names of _FACTORS)."""

    names: tuple[str | int, ...]
    factors: dict[str, np.ndarray]

    @property
    def count(self) -> int:
        """W: the worlds the factors give."""
        return len(next(iter(self.factors.values())))

    def rows(self, used: np.ndarray) -> Materials:
        return Materials(self.names, {k: v[used] for k, v in self.factors.items()})



@dataclass(frozen=True, eq=False)
class ItemWorlds:
    """The worlds of one work item's views: `poses` (K, N, 7) or (K, N, 4, 4) float64 of the
    K distinct worlds it sees (None: no poses), `visible` (K, N) bool or None, `materials`
    their material overrides or None, and `index` (views,) the row each of its views sees."""

    nodes: tuple[str | int, ...]
    quaternion: str
    poses: np.ndarray | None
    visible: np.ndarray | None
    index: np.ndarray
    materials: Materials | None = None


@dataclass(frozen=True, eq=False)
class JobWorlds:
    """An entry's checked worlds: W worlds of N nodes, and the world each of V views sees."""

    nodes: tuple[str | int, ...]
    quaternion: str
    poses: np.ndarray | None  # (W, N, 7) or (W, N, 4, 4) float64
    visible: np.ndarray | None  # (W, N) bool
    world_of_view: np.ndarray  # (V,) int64
    materials: Materials | None = None

    def item(self, views: tuple[int, ...]) -> ItemWorlds:
        """The worlds `views` see, as few as there are distinct ones (what an item ships)."""
        used, index = np.unique(self.world_of_view[list(views)], return_inverse=True)
        return ItemWorlds(self.nodes, self.quaternion,
                          None if self.poses is None else self.poses[used],
                          None if self.visible is None else self.visible[used],
                          index.astype(np.int64),
                          None if self.materials is None else self.materials.rows(used))

    def _parts(self, w: int) -> list[np.ndarray]:
        """World `w`'s arrays, in a fixed order."""
        parts = [a[w] for a in (self.poses, self.visible) if a is not None]
        if self.materials is not None:
            parts += [self.materials.factors[k][w] for k in sorted(self.materials.factors)]
        return parts

    @cached_property
    def _world_digests(self) -> list[str]:
        """A digest of each world's state: what its views' files depend on."""
        rows = self.poses is not None and self.poses.ndim == 3
        mats = self.materials
        head = repr((self.nodes, self.quaternion if rows else "matrices",
                     self.visible is not None, mats.names if mats else None,
                     sorted(mats.factors) if mats else None))
        out = []
        for w in range(self._count):
            h = hashlib.blake2b(head.encode(), digest_size=16)
            for part in self._parts(w):
                h.update(np.ascontiguousarray(part).tobytes())
            out.append(h.hexdigest())
        return out

    @property
    def _count(self) -> int:
        return len(self.poses) if self.poses is not None else self.materials.count  # type: ignore[union-attr]

    def digest(self, view: int) -> str:
        """The digest of view `view`'s world (recorded with the view in the manifest)."""
        return self._world_digests[int(self.world_of_view[view])]


def _type(value: object) -> str:
    from vkpbr.scene.poses import _json_type

    return _json_type(value)


def _nodes(value: object, where: str, key: str = "nodes",
           what: str = "node names, paths, patterns or indices") -> tuple[str | int, ...]:
    """A list of names or indices (a single one is a list of one)."""
    if isinstance(value, (str, int)) and not isinstance(value, bool):
        value = [value]
    if not isinstance(value, list) or not value:
        raise UsageError(f"{where}: {key}: expected a list of {what}, got "
                         f"{'an empty list' if value == [] else _type(value)}")
    for v in value:
        if not ((isinstance(v, str) and v.strip())
                or (isinstance(v, int) and not isinstance(v, bool) and v >= 0)):
            raise UsageError(f"{where}: {key}: expected a list of {what}, got {_type(v)} "
                             f"{str(v)[:40]!r} in it")
    if len(set(value)) != len(value):
        raise UsageError(f"{where}: {key}: {str(value)[:80]} names one twice")
    return tuple(value)


def _inside(path: Path, base: Path, shown: str, where: str) -> None:
    """UsageError unless `path` (symlinks resolved) lies in `base`'s folder tree."""
    real, root = os.path.realpath(path), os.path.realpath(base)
    if os.path.commonpath([real, root]) != root:
        raise UsageError(f"{where}: {shown} is outside the job file's folder ({base}); keep it "
                         'beside the job, or give the entry "allow_outside_paths": true')


def _read_npy(value: str, key: str, where: str, base: Path, outside: bool) -> np.ndarray:
    """The array of the .npy file `value` (relative to `base`): a regular file inside the
    job's folder, its header (shape, dtype, size) checked before its data is read, no
    pickles. One-line UsageErrors name the entry, the key and the file."""
    from vkpbr.user_paths import check_path, os_reason

    what = f"{where}: {key} {value}"
    check_path(value, f"{where}: {key}")
    p = Path(os.path.expanduser(value))
    p = check_path(p if p.is_absolute() else base / p, f"{where}: {key}")
    if not outside:
        _inside(p, base, f"{key} {value}", where)
    try:
        if not stat.S_ISREG(os.stat(p).st_mode):  # a FIFO, /dev/zero, a folder: not opened
            raise UsageError(f"{what}: not a regular file")
        # Non-blocking, and checked again: a file swapped for a FIFO meanwhile cannot block.
        with os.fdopen(os.open(p, os.O_RDONLY | os.O_NONBLOCK), "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                raise UsageError(f"{what}: not a regular file")
            shape, dtype = _header(f, what)
            need = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
            if need > _MAX_BYTES:
                raise UsageError(f"{what}: {need / 2**30:.1f} GiB, more than the "
                                 f"{_MAX_BYTES >> 30} GiB an entry's array may have")
            if os.fstat(f.fileno()).st_size - f.tell() < need:
                raise UsageError(f"{what}: the file is cut short ({shape} of {dtype} need "
                                 f"{need:,} bytes of data)")
            f.seek(0)
            return np.load(f, allow_pickle=False)
    except FileNotFoundError:
        raise UsageError(f"{what}: no such file") from None
    except OSError as exc:
        raise UsageError(f"{what}: cannot read it: {os_reason(exc)}") from None
    except (ValueError, EOFError) as exc:
        raise UsageError(f"{what}: not a readable .npy file ({str(exc).splitlines()[0]})") from None


def _header(f: Any, what: str) -> tuple[tuple[int, ...], np.dtype]:
    """The .npy header's shape and dtype (numpy.lib.format), without reading the data."""
    fmt = np.lib.format
    try:
        version = fmt.read_magic(f)
        read = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
        shape, _fortran, dtype = read(f)
    except (ValueError, EOFError, SyntaxError, TypeError) as exc:
        raise UsageError(f"{what}: not a .npy file ({str(exc).splitlines()[0]})") from None
    if dtype.hasobject or dtype.fields is not None:
        raise UsageError(f"{what}: an array of {dtype}: give plain numbers")
    return tuple(int(s) for s in shape), dtype


def _array(value: object, key: str, where: str, base: Path, outside: bool) -> np.ndarray:
    """A .npy file's array, or the array of an inline JSON list."""
    if isinstance(value, str):
        return _read_npy(value, key, where, base, outside)
    if isinstance(value, list):
        try:
            return np.asarray(value)
        except ValueError:
            raise UsageError(f"{where}: {key}: an inline array of rows of different lengths") from None
    raise UsageError(f"{where}: {key}: expected a .npy file or an inline array, got {_type(value)}")


def _poses(value: object, nodes: tuple[str | int, ...], quaternion: str, where: str, base: Path,
           outside: bool) -> np.ndarray:
    a = _array(value, "poses", where, base, outside)
    name = value if isinstance(value, str) else "(inline)"
    if a.dtype.kind not in "fiu" or a.dtype == bool:
        raise UsageError(f"{where}: poses {name}: an array of {a.dtype}; give numbers")
    if not ((a.ndim == 3 and a.shape[2] == 7) or (a.ndim == 4 and a.shape[2:] == (4, 4))):
        raise UsageError(f"{where}: poses {name}: shape {a.shape}; give (worlds, nodes, 7) "
                         "position + quaternion rows or (worlds, nodes, 4, 4) world matrices")
    if a.shape[0] == 0 or a.shape[1] == 0:
        raise UsageError(f"{where}: poses {name}: shape {a.shape} holds no worlds")
    plain = all(isinstance(n, int) or not (_GLOB & set(n)) for n in nodes)
    if plain and a.shape[1] != len(nodes):  # a pattern's count is the actor's to check
        raise UsageError(f"{where}: poses {name}: {a.shape[1]} node(s) a world, but nodes "
                         f"names {len(nodes)}")
    from vkpbr.scene.worlds import WorldPoses

    a = a.astype(np.float64)
    bad = ~np.isfinite(a.reshape(len(a), -1)).all(axis=1)
    if bad.any():
        raise UsageError(f"{where}: poses {name}: world {int(np.argmax(bad))} holds NaN or infinity")
    try:
        WorldPoses.of(a, a.shape[1], quaternion)  # zero quaternions, affine matrices
    except UsageError as exc:
        raise UsageError(f"{where}: poses {name}: {str(exc).removeprefix('worlds: ')}") from None
    return a


def _visible(value: object, shape: tuple[int, int], where: str, base: Path,
             outside: bool) -> np.ndarray:
    a = _array(value, "visible", where, base, outside)
    name = value if isinstance(value, str) else "(inline)"
    if a.dtype != bool and not (a.dtype.kind in "iu" and np.isin(a, (0, 1)).all()):
        raise UsageError(f"{where}: visible {name}: an array of {a.dtype}; give bools (or 0 and 1)")
    if a.shape != shape:
        raise UsageError(f"{where}: visible {name}: shape {a.shape}, expected {shape} "
                         "(worlds, nodes) as the poses")
    return a.astype(bool)


def _world_of_view(value: object, views: int, worlds: int, where: str, base: Path,
                   outside: bool) -> np.ndarray:
    if value is None:
        if worlds != views:
            raise UsageError(f"{where}: {worlds} world(s) for {views} view(s); give one "
                             'world per view, or "world_of_view" (the world each view sees)')
        return np.arange(views, dtype=np.int64)
    a = _array(value, "world_of_view", where, base, outside)
    name = value if isinstance(value, str) else "(inline)"
    if a.dtype.kind not in "iu" or a.dtype == bool or a.shape != (views,):
        raise UsageError(f"{where}: world_of_view {name}: expected ({views},) integers (one "
                         f"per view), got shape {a.shape} of {a.dtype}")
    a = a.astype(np.int64)
    out = (a < 0) | (a >= worlds)
    if out.any():
        v = int(np.argmax(out))
        raise UsageError(f"{where}: world_of_view {name}: view {v} sees world {int(a[v])}, out "
                         f"of range (0..{worlds - 1})")
    return a


def _materials(value: object, where: str, base: Path, outside: bool) -> Materials:
    """The "materials" object: names and per-world factor arrays, each checked (shape, range,
    NaN); the names are the actor's to find in the scene."""
    where = f"{where}: materials"
    if not isinstance(value, Mapping):
        raise UsageError(f"{where}: expected an object with names and factors, got {_type(value)}")
    unknown = sorted(set(value) - {"names", *_FACTORS})
    if unknown:
        raise UsageError(f"{where}: unknown key {unknown[0]!r} (known: names, "
                         f"{', '.join(_FACTORS)})")
    if "names" not in value:
        raise UsageError(f'{where}: missing "names" (the materials each world overrides)')
    names = _nodes(value["names"], where, "names", "material names or indices")
    factors = {}
    for key, (sizes, lo, hi) in _FACTORS.items():
        if key not in value:
            continue
        a = _array(value[key], key, where, base, outside)
        shown = value[key] if isinstance(value[key], str) else "(inline)"
        tails = [(len(names), k) for k in sizes] if sizes else [(len(names),)]
        if a.dtype.kind not in "fiu" or a.dtype == bool or a.ndim < 2 or a.shape[1:] not in tails:
            want = " or ".join(f"(worlds, {', '.join(map(str, t))})" for t in tails)
            raise UsageError(f"{where}: {key} {shown}: shape {a.shape} of {a.dtype}; give {want}")
        a = a.astype(np.float64)
        bad = ~((a >= lo) & (a <= hi)).reshape(len(a), -1).all(axis=1)  # NaN fails both
        if bad.any():
            rng = f">= {lo:g}" if hi == np.inf else f"within [{lo:g}, {hi:g}]"
            raise UsageError(f"{where}: {key} {shown}: world {int(np.argmax(bad))} holds a value "
                             f"not {rng} (or NaN)")
        factors[key] = a
    if not factors:
        raise UsageError(f"{where}: no factor given ({', '.join(_FACTORS)})")
    counts = {len(a) for a in factors.values()}
    if len(counts) > 1 or 0 in counts:
        raise UsageError(f"{where}: the factors give {sorted(counts)} worlds; give each the same")
    return Materials(names, factors)


def job_worlds(value: object, views: int, where: str, base: Path, outside: bool) -> JobWorlds:
    """An entry's checked `"worlds"` (see the module docstring) for its `views` views;
    `where` starts every message ("job.json: entry 2: worlds"), `base`: the job file's
    folder, `outside`: the entry's allow_outside_paths."""
    if not isinstance(value, Mapping):
        raise UsageError(f"{where}: expected an object with nodes and poses, got {_type(value)}")
    unknown = sorted(set(value) - _KEYS)
    if unknown:
        raise UsageError(f"{where}: unknown key {unknown[0]!r} (known: {', '.join(sorted(_KEYS))})")
    if "poses" not in value and value.get("materials") is None:
        raise UsageError(f'{where}: missing "poses" (or "materials")')
    if ("nodes" in value) != ("poses" in value):
        missing = "poses" if "nodes" in value else "nodes"
        raise UsageError(f'{where}: missing "{missing}" ("nodes" names what "poses" moves)')
    quaternion = value.get("quaternion", "xyzw")
    if quaternion not in ("xyzw", "wxyz"):
        raise UsageError(f'{where}: quaternion: expected "xyzw" or "wxyz", got {quaternion!r}')
    nodes, poses, visible = (), None, None
    if "poses" in value:
        nodes = _nodes(value["nodes"], where)
        poses = _poses(value["poses"], nodes, quaternion, where, base, outside)
        if value.get("visible") is not None:
            visible = _visible(value["visible"], poses.shape[:2], where, base, outside)
    elif value.get("visible") is not None:
        raise UsageError(f'{where}: visible needs "nodes" and "poses"')
    materials = None
    if value.get("materials") is not None:
        materials = _materials(value["materials"], where, base, outside)
    worlds = len(poses) if poses is not None else materials.count
    if materials is not None and materials.count != worlds:
        raise UsageError(f"{where}: materials give {materials.count} worlds, poses {worlds}; "
                         "give each the same")
    index = _world_of_view(value.get("world_of_view"), views, worlds, where, base, outside)
    return JobWorlds(nodes, quaternion, poses, visible, index, materials)
