"""What a loop's render_batch calls share, made once (issue 32: a step's Python cost).

A simulator renders the same cameras at the same size with the same options every step;
only the poses change. `BatchCache` (one a Renderer) keeps what such a call makes of its
arguments besides the poses, under a key of cheap parts (object identities and version
counters: no array is hashed or compared):

- `Prepared`: the cameras as a CameraBatch, the options, the route and outputs
  (render/batch_route.py), by (frame parts, cameras, size, options and overrides, linear,
  depth, outputs, device). The cameras are cached only as a CameraBatch (its arrays are
  read-only: it cannot change); (B, 4, 4) arrays and lists are converted every call. The
  parts are replaced when the scene is: a new scene clears the cache.
- `WorldShape` (CUDA poses) and the world of each view: the checks of a batch of worlds'
  poses that do not read their values (the slot count, shape, dtype, quaternion order,
  space, world_of_view), by (prepared, slots and the state version they were made at, shape,
  dtype, quaternion, space, world_of_view). `world_of_view` is cached when it is None (view
  b sees world b) or a read-only NumPy array; a writable one is checked every call (it could
  change in place).
- The CUDA device index of the renderer's GPU (found by UUID once: the Vulkan query and
  cudaGetDeviceProperties took every call before).

The recorded commands, the view records and the worlds' buffers are the batch path's and
already reused (render/batch_path.py): the poses are data in buffers, not recorded state.
`BatchStep` (Renderer.batch_step, render/batch_call.py) is the explicit form: the arguments
given once, the poses each call, the same cache.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.render.batch_route import batch_route, check_out
from vkpbr.render.options import RenderOptions
from vkpbr.scene._checks import frame_size
from vkpbr.scene.camera_batch import CameraBatch, as_camera_batch

__all__ = ["BatchCache", "Prepared", "WorldShape", "batch_cache"]

KEPT = 8  # prepared calls kept (least recently used dropped): a loop uses one or two


@dataclass(frozen=True)
class Prepared:
    """A call's arguments but the worlds, checked: the views, the options, the route and the
    dataset outputs asked for."""

    views: CameraBatch
    opts: RenderOptions
    route: str
    wanted: tuple[str, ...]
    holds: tuple  # the objects the key names by identity (kept alive: ids stay theirs)


@dataclass(frozen=True)
class WorldShape:
    """What a batch of worlds' poses of one shape give, their values aside: the slots, the
    floats a pose (7 or 16), quaternion order, space, and the world of each view."""

    slots: Any  # vkpbr.scene.worlds.WorldSlots
    floats: int
    wxyz: bool
    local: bool
    index: np.ndarray  # (B,) int64


class BatchCache:
    """A renderer's prepared calls (`prepared`), its worlds' shapes (`world_shape`) and the
    CUDA index of its GPU (`cuda_index`)."""

    def __init__(self) -> None:
        self._prepared: OrderedDict[tuple, Prepared] = OrderedDict()
        self._worlds: OrderedDict[tuple, tuple[tuple, Any]] = OrderedDict()  # (holds, made)
        self._cuda: tuple[Any, int] | None = None  # (device, its CUDA index)
        self._parts: Any = None  # the frame parts the entries were made with
        self.hits = self.misses = 0  # (tests read them: a cache that is never hit is a bug)
        self.version = 0  # bumped when cleared: a BatchStep's kept Prepared is then made again

    def prepared(self, r: Any, cameras: Any, size: tuple[int, int],
                 options: RenderOptions | None, overrides: dict[str, Any], linear: bool,
                 depth: bool, outputs: Iterable[str] | None, device: str,
                 out: np.ndarray | None, make_options: Callable[..., RenderOptions]) -> Prepared:
        """The call's Prepared: cached where its key can be made of identities and plain
        values, else made now (and not kept)."""
        frame_size(size, int(r.device.limits.maxImageDimension2D))  # (before the key: int(8.5))
        if self._parts is not r.parts:  # a new scene: nothing made for the old one holds
            self.clear()
            self._parts = r.parts
        key = _prepared_key(r, cameras, size, options, overrides, linear, depth, outputs, device)
        got = None if key is None else self._prepared.get(key)
        if got is not None:
            self.hits += 1
            self._prepared.move_to_end(key)  # type: ignore[arg-type]
            if out is not None:  # (the key leaves `out` out: checked each call)
                check_out(out, (len(got.views), size[1], size[0], 4),
                          np.float32 if linear else np.uint8, device)
            return got
        self.misses += 1
        views = as_camera_batch(cameras, r.default_camera())
        opts = make_options(options, overrides)
        route, wanted = batch_route(r.parts, views, size, opts, linear, depth, outputs, device, out)
        made = Prepared(views, opts, route, wanted, (r.parts, cameras, options))
        if key is not None:
            self._prepared[key] = made
            while len(self._prepared) > KEPT:
                self._prepared.popitem(last=False)
        return made

    def world_shape(self, prepared: Prepared, slots: Any, shape: tuple[int, ...], dtype: Any,
                    quaternion: str, space: str, world_of_view: Any,
                    make: Callable[[], WorldShape]) -> WorldShape:
        """The WorldShape of poses of `shape` and `dtype` (`make` checks and makes it), cached
        where `world_of_view` cannot change (None or a read-only NumPy array)."""
        key = ("shape", id(prepared), id(slots), slots.version, shape, str(dtype), quaternion,
               space, id(world_of_view))
        return self._memo(key, (prepared, slots, world_of_view), world_of_view, make)

    def world_index(self, prepared: Prepared, worlds: int, world_of_view: Any,
                    make: Callable[[], np.ndarray]) -> np.ndarray:
        """(B,) int64 the world each of `prepared`'s views sees (`make` checks and makes it),
        cached as `world_shape` is."""
        key = ("index", id(prepared), worlds, id(world_of_view))
        return self._memo(key, (prepared, world_of_view), world_of_view, make)

    def _memo(self, key: tuple, holds: tuple, world_of_view: Any, make: Callable[[], Any]) -> Any:
        """`make()`, kept under `key` (which names `holds` by identity: they are kept alive
        with it) unless `world_of_view` could change in place."""
        fixed = world_of_view is None or (isinstance(world_of_view, np.ndarray)
                                          and not world_of_view.flags.writeable)
        if not fixed:
            return make()
        got = self._worlds.get(key)
        if got is not None:
            self.hits += 1
            self._worlds.move_to_end(key)
            return got[1]
        self.misses += 1
        made = make()
        if isinstance(made, np.ndarray):
            made.flags.writeable = False  # (shared by the calls that hit the cache)
        self._worlds[key] = (holds, made)
        while len(self._worlds) > KEPT:
            self._worlds.popitem(last=False)
        return made

    def cuda_index(self, device: Any) -> int:
        """The CUDA device index of Vulkan `device` (by UUID, found once; a UsageError where
        CUDA is unavailable)."""
        if self._cuda is None or self._cuda[0] is not device:
            from vkpbr.errors import UsageError
            from vkpbr.gpu.cuda import cuda_device_for, cuda_unavailable

            why = cuda_unavailable()
            if why is not None:
                raise UsageError(f"worlds on CUDA: {why}")
            self._cuda = (device, cuda_device_for(device.uuid(), device.info.name))
        return self._cuda[1]

    def keeps(self, prepared: Prepared) -> bool:
        """Whether `prepared` is one of the kept calls (its key was one of identities)."""
        return any(v is prepared for v in self._prepared.values())

    def clear(self) -> None:
        self.version += 1
        self._prepared.clear()
        self._worlds.clear()


def batch_cache(renderer: Any) -> BatchCache:
    """The renderer's BatchCache (made on first use; the renderer keeps it)."""
    cache = getattr(renderer, "_batch_cache", None)
    if cache is None:
        cache = renderer._batch_cache = BatchCache()
    return cache


def _prepared_key(r: Any, cameras: Any, size: Any, options: RenderOptions | None,
                  overrides: dict[str, Any], linear: bool, depth: bool,
                  outputs: Iterable[str] | None, device: str) -> tuple | None:
    """The cheap key of a call's Prepared, or None where it cannot be made of identities and
    plain values (cameras not a CameraBatch, outputs an iterator, an unhashable override)."""
    if not isinstance(cameras, CameraBatch):
        return None
    if outputs is not None and not isinstance(outputs, (tuple, str)):
        return None
    try:
        size_key = (int(size[0]), int(size[1]))
        key = (id(r.parts), id(cameras), size_key, id(options), tuple(overrides.items()), bool(linear), bool(depth), outputs, device)
        hash(key)
    except (TypeError, ValueError, IndexError):
        return None
    return key
