"""A loop's batch step replayed: the last step's command buffer submitted again (issue 32).

A simulator renders the same cameras at the same size with the same options every step;
only the worlds' poses change, and those are data in buffers (the worlds kernel's inputs,
render/worlds.py), never recorded state. So once a frame slot of the ring has drawn a step,
the next step with the same plan that the ring hands that slot needs none of the frame's
set-up (lights, environment, shadow plan, scene-state copy, frame blocks, view records, post
and AO plans, the FrameSpec and its recorder lookup): the slot's buffers hold what it would
write again. What remains is the poses into the inputs (or the host-made world records into
the slot's region: world_expand="auto" on NumPy poses), the submission (with CUDA's
timeline values where the step is CUDA-ordered), the wait and the readback or torch
wrapping (BatchPath's own tail). A step's GPU timings are read only when asked for
(`StepStats`).

`Replays` keeps, per frame slot, the command buffer and how to finish the step, under a
`ReplayKey`: the plain values of the plan (route, size, linear, batch, the state's version,
the worlds' shape, the kernel's and the view buffers' generations) and the ids of the
objects it is made of (the parts, the cameras, the options, the world slots, the
world-of-view array, the world buffers: held by the key, so that their ids stay theirs).
A step may replay only where:

- nothing else drew since the last step of this key (the ring's frame count is the one
  that step left: another render, batch or step in between may have redrawn shared shadow
  maps, rebound sets or freed recordings), and the recording is still alive;
- it has no `lights` argument (a list can change in place), no depth, no per-world
  factors, dataset outputs, post steps or lenses (their buffers are written per call), and
  its views fit one submission. Host-made world records are written into the slot's region
  again, as the full path does; the worlds' own shadow maps are drawn by the recording
  itself, every step; ambient occlusion replays (its images are fitted when the target is
  made, its constants recorded: as the recorder's reuse of the commands has it);
- the recording it replays redrew no shadow map (a replay never redraws one; the state's
  maps are current when its version is unchanged).

Anything else takes BatchPath's full path, which records (or finds) the commands and
leaves them here for the slot's next step.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.render.frame_path import read_timings
from vkpbr.render.frames import FrameStats

__all__ = ["ReplayKey", "Replays", "StepStats", "replay_key"]


class ReplayKey:
    """What a step's recording and its slot's buffers depend on: `objects` (kept alive by
    the key, so that their ids, in `values`, stay theirs) and plain values; two keys are
    the same plan where their values are equal (one tuple comparison, in C)."""

    __slots__ = ("objects", "values")

    def __init__(self, objects: tuple, values: tuple) -> None:
        self.objects, self.values = objects, values

    def same(self, other: ReplayKey | None) -> bool:
        return other is not None and self.values == other.values


@dataclass
class _Entry:
    """A slot's last replayable step: its commands, their timestamps' names, and how its
    results come back (`finish(frame, out, order)`: the colour, the depth)."""

    cmd: Any
    stamp_names: tuple[str, ...]
    finish: Callable[[Any, Any, Any], tuple[Any, Any]]
    cuda_owner: Any  # what the host waits CUDA's last clone of (None: no CUDA)
    ordered: bool  # ordered against torch's stream on the GPU (render/cuda_order.py)


def replay_key(path: Any, route: str, views: Any, size: tuple[int, int], lights: Any,
               opts: Any, linear: bool, depth: bool, batch: int | str) -> ReplayKey | None:
    """The call's ReplayKey, or None where it cannot replay (its lights, depth or factors
    are written per call)."""
    call = path.world_call
    if lights is not None or depth or route not in ("compute", "layered", "cuda"):
        return None
    bv, parts = path.views, path.parts
    values = (route, int(size[0]), int(size[1]), bool(linear), batch, parts.gpu_state.state.version,
              -1 if bv is None else bv.generation, id(parts), id(views), id(opts))
    if call is None:
        return ReplayKey((parts, views, opts), values)
    gw, wb, index = call.gpu, path.world_buffers, call.world_of_view
    if call.factors is not None or not call.poses:
        return None
    if gw is None:  # records made on the host: written into the slot's region again
        return ReplayKey((parts, views, opts, index, wb), (
            *values, "host", len(call.records), id(index), id(wb)))  # type: ignore[arg-type]
    kernel = path.world_kernel
    # (the GpuWorlds' key is its push constants: worlds, slots, floats, order, visibility)
    return ReplayKey((parts, views, opts, gw.slots, index, wb), (
        *values, gw.key, gw.cuda, -1 if kernel is None else kernel.generation,
        id(gw.slots), id(index), id(wb)))


class Replays:
    """The replayable steps of one key, by frame slot (BatchPath owns one)."""

    def __init__(self) -> None:
        self.key: ReplayKey | None = None
        self.number = -1  # the ring's frame count after the key's last step
        self.entries: dict[int, _Entry] = {}
        self.replayed = 0  # steps replayed (tests read it: a replay that never happens is a bug)

    def entry(self, ring: Any, key: ReplayKey) -> _Entry | None:
        """The entry of the slot the ring hands out next, where it may replay `key`."""
        if ring.number != self.number or not key.same(self.key):
            self.entries.clear()  # (something else drew in between, or another plan)
            return None
        got = self.entries.get(ring.number % ring.count)
        if got is None or got.cmd.handle is None:  # (a freed recording: not replayable)
            return None
        return got

    def stepped(self, ring: Any, key: ReplayKey | None, frame: Any, cmd: Any,
                finish: Callable[[Any, Any, Any], tuple[Any, Any]] | None, cuda_owner: Any,
                ordered: bool) -> None:
        """A full step of `key` was submitted from `frame`'s slot: replayable there next
        time where `finish` is given (else the slot's entry is dropped)."""
        if key is None:
            self.clear()
            return
        if not key.same(self.key):
            self.entries.clear()
            self.key = key
        if finish is None:
            self.entries.pop(frame.index, None)
        else:
            self.entries[frame.index] = _Entry(cmd, frame.stamp_names, finish, cuda_owner,
                                               ordered)
        self.number = ring.number

    def clear(self) -> None:
        self.key, self.number = None, -1
        self.entries.clear()


def replay(path: Any, key: ReplayKey, out: np.ndarray | None) -> tuple[Any, Any] | None:
    """Submit the slot's recorded step again with this call's poses (None where the slot
    has no replayable step of `key`): BatchPath.run's fast path."""
    replays = path.replays
    ring = path.parts.ring
    got = replays.entry(ring, key)
    if got is None:
        return None
    path._t_start = time.perf_counter()
    order = path._order(True) if got.ordered else None
    path._ordered = order is not None
    frame = ring.begin()  # (waits for the slot's last submission)
    call = path.world_call
    if call is not None and call.gpu is not None:  # the poses into the kernel's inputs
        kernel = path.world_kernel  # (sized and bound already)
        kernel.order = order
        call.gpu.fill(kernel)
    elif call is not None:  # records made on the host: into the slot's region
        path.world_buffers.write(frame.index, path.parts.gpu_state.state.draw_matrices(),
                                 call.records)
    path._submissions = 0
    frame.stamp_names = got.stamp_names
    path._submit_cmd(frame, got.cmd, order, got.cuda_owner)
    replays.number = ring.number
    path._submitted(frame, order)
    replays.replayed += 1
    return got.finish(frame, out, order)


class StepStats(FrameStats):
    """A batch step's FrameStats whose GPU timings (`gpu_ms`, `pass_ms`) are read from its
    frame slot's timestamp queries when first asked for: a loop that does not read them
    pays no query and no dict a step. They can be read until the slot draws again (three
    steps later; NaN and {} after). Takes FrameStats' fields (dataclasses.replace and asdict
    work: the timings are then read)."""

    def __init__(self, cpu_ms: float = 0.0, wait_ms: float = 0.0, gpu_ms: float = math.nan,
                 readback_ms: float = 0.0, pass_ms: dict[str, float] | None = None,
                 driver_ms: float = 0.0) -> None:
        self.cpu_ms, self.wait_ms = cpu_ms, wait_ms
        self.readback_ms, self.driver_ms = readback_ms, driver_ms
        self._timings: tuple[float, dict[str, float]] | None = (gpu_ms, pass_ms or {})
        self._source: tuple | None = None  # (ring, frame, slot, the frame's number)

    @classmethod
    def of(cls, ring: Any, frame: Any, slot: Any, cpu_ms: float, wait_ms: float) -> StepStats:
        """The stats of `frame`'s finished submission (its timings read on first use)."""
        made = cls(cpu_ms, wait_ms)
        made._timings, made._source = None, (ring, frame, slot, frame.number)
        return made

    def with_cpu(self, cpu_ms: float) -> StepStats:
        """These stats with another `cpu_ms` (the timings still read on first use)."""
        made = StepStats(cpu_ms, self.wait_ms, readback_ms=self.readback_ms,
                         driver_ms=self.driver_ms)
        made._timings, made._source = self._timings, self._source
        return made

    def _read(self) -> tuple[float, dict[str, float]]:
        if self._timings is None:
            ring, frame, slot, number = self._source  # type: ignore[misc]
            if frame.number == number and frame.finished:
                got = read_timings(ring, frame, slot)
                self._timings = (got.gpu_ms, got.pass_ms)
            else:  # (the slot drew again since: its queries hold another step's)
                self._timings = (math.nan, {})
        return self._timings

    @property  # type: ignore[override]
    def gpu_ms(self) -> float:
        return self._read()[0]

    @gpu_ms.setter
    def gpu_ms(self, value: float) -> None:
        self._timings = (value, self._read()[1])

    @property  # type: ignore[override]
    def pass_ms(self) -> dict[str, float]:
        return self._read()[1]

    @pass_ms.setter
    def pass_ms(self, value: dict[str, float]) -> None:
        self._timings = (self._read()[0], value)

