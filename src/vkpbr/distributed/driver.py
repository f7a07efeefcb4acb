"""The driver: checks a job, connects to Ray, starts the renderer actors, hands them work items
and records each result in the manifests. Ray does the scheduling and the processes; the driver
only keeps every actor busy with one item and decides what a failure means.

- An item whose actor died (killed, out of memory, node lost) or that failed with an error of
  the machine (a device error) is given again, to another actor where one is free, up to
  `job.retries` more times; a dead actor is replaced (at most as many times as actors were
  started). An item whose input is bad (its scene does not load) fails the same way
  everywhere: it is recorded as failed at once.
- Every result is appended to the entry's manifest as it arrives, so a driver killed at any
  moment loses only the items in flight; a re-run skips what the manifests list as done.
- The files are written by the actors, atomically and under their final names, so a view
  rendered twice (its actor died after writing) is still one file.
- transforms.json (and COLMAP text) is written by the driver once an entry is complete.
"""

from __future__ import annotations

import collections
import contextlib
import itertools
import logging
import os
import time
import uuid
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from vkpbr.distributed.actor import encoders_for
from vkpbr.distributed.cluster import (
    ClusterError,
    RayRenderer,
    actor_plan,
    connect,
    import_ray,
    preflight,
)
from vkpbr.distributed.job import Job, SceneJob, WorkItem, job_from_doc, load_job, view_times
from vkpbr.distributed.manifest import (
    Manifest,
    abandon_frames_folder,
    open_frames_folder,
    remove_leftovers,
    start_frames_folder,
)
from vkpbr.distributed.processes import (
    DEPTH,
    ActorLost,
    ProcessActor,
    default_processes,
    wait_one,
)
from vkpbr.errors import UsageError

__all__ = ["render", "JobResult", "Failure", "ClusterError", "check_job", "import_ray",
           "IN_PROCESS", "PROCESSES"]

log = logging.getLogger(__name__)

IN_PROCESS = "in-process"  # render(address=...): no Ray, one renderer in this process
PROCESSES = "processes"  # render(address=..., actors=N): no Ray, N renderer processes here


@dataclass(frozen=True)
class Failure:
    """An item that failed for good: its entry, views, a label for messages and the error."""

    entry: int
    views: tuple[int, ...]
    label: str
    error: str
    attempts: int


@dataclass
class JobResult:
    """What a run did. `ok`: nothing failed. `summary()`: the lines the CLI prints."""

    views: int = 0  # in the whole job
    rendered: int = 0  # by this run
    skipped: int = 0  # done by an earlier run
    failures: list[Failure] = field(default_factory=list)
    actors: int = 0
    actor_kind: str = "actor"  # what rendered: "actor" (Ray's, or this process), "process"
    actors_lost: int = 0
    retries: int = 0  # items given again after a failure or a lost actor
    seconds: float = 0.0
    render_seconds: float = 0.0  # from the first item handed out to the last result
    incomplete: list[str] = field(default_factory=list)  # out folders without transforms.json

    @property
    def ok(self) -> bool:
        return not self.failures

    @property
    def failed_views(self) -> int:
        return sum(len(f.views) for f in self.failures)

    def summary(self, limit: int = 20) -> list[str]:
        if not self.actors:
            return [f"{self.views} views: all {self.skipped} done before, nothing to render"]
        rate = self.rendered / self.render_seconds if self.render_seconds > 0 else 0.0
        lines = [f"{self.views} views: {self.rendered} rendered, {self.skipped} done before, "
                 f"{self.failed_views} failed; {self.seconds:.1f} s ({rate:.1f} views/s on "
                 f"{self.actors} {_plural(self.actor_kind, self.actors)})"
                 + (f"; {self.actors_lost} actor(s) lost" if self.actors_lost else "")
                 + (f", {self.retries} item(s) retried" if self.retries else "")]
        for f in self.failures[:limit]:
            lines.append(f"failed: {f.label}: {f.error}")
        if len(self.failures) > limit:
            lines.append(f"... and {len(self.failures) - limit} more failed items (see the manifests)")
        return lines


def _plural(noun: str, n: int) -> str:
    return noun if n == 1 else noun + ("es" if noun.endswith("s") else "s")


def _as_job(job: Job | dict | list | str | os.PathLike[str]) -> Job:
    if isinstance(job, Job):
        return job
    if isinstance(job, (dict, list)):
        return job_from_doc(job)
    return load_job(job)


def check_job(job: Job) -> list[Manifest]:
    """Everything that can fail before an actor starts, without creating anything: each out
    folder is writable or can be made, each output format can be written (OpenEXR for
    .exr), and each folder is new or this job's (its manifest, read and checked). Returns
    the manifests, one per entry."""
    return [open_frames_folder(scene) for scene in job.scenes]


@dataclass
class _Task:
    item: WorkItem
    attempts: int = 0
    avoid: set[int] = field(default_factory=set)  # actor numbers it failed on
    last_error: str = ""
    key: tuple = ()  # its scene (settings.scene_key()), for the hand-out's choices

    def __post_init__(self) -> None:
        self.key = self.item.settings.scene_key()


# How far down the waiting tasks the driver looks for an actor's scene (_PICK) or the next
# scene to load ahead (_AHEAD): a job's items are in entry order, so a scene's items are
# together near the front; the bounds keep a hand-out cheap in jobs of millions of items.
_PICK, _AHEAD = 64, 256


def _pick(pending: collections.deque[_Task], actor: int, keys: tuple[tuple | None, ...]) -> int:
    """The waiting task for `actor`: one of the scene it has (then the one it loaded ahead),
    so that scenes are not loaded twice; else the first it has not failed; else the first."""
    first = None
    for key in (k for k in keys if k is not None):
        for k, task in enumerate(itertools.islice(pending, _PICK)):
            if actor in task.avoid:
                continue
            first = k if first is None else first
            if task.key == key:
                return k
    if first is None:
        first = next((k for k, t in enumerate(pending) if actor not in t.avoid), 0)
    return first


def _next_scene(pending: collections.deque[_Task], actor: int, scenes: dict[int, tuple],
                ahead: dict[int, tuple]) -> Any:
    """The settings of the first waiting scene no actor has or loads ahead (the scene
    `actor` should load while it renders; recorded in `ahead`), or None."""
    taken = {*scenes.values(), *(v for a, v in ahead.items() if a != actor)}
    for task in itertools.islice(pending, _AHEAD):
        if task.key not in taken:
            ahead[actor] = task.key
            return task.item.settings
    ahead.pop(actor, None)
    return None


def _scenes_after(items: list[WorkItem]) -> list[Any]:
    """For each item, the settings of the first later item of another scene (None: none)."""
    out: list[Any] = [None] * len(items)
    for n in range(len(items) - 2, -1, -1):
        same = items[n + 1].settings.scene_key() == items[n].settings.scene_key()
        out[n] = out[n + 1] if same else items[n + 1].settings
    return out


def _finish_entry(scene: SceneJob, manifest: Manifest) -> bool:
    """Write transforms.json (and COLMAP text) of a complete entry; False when incomplete."""
    from vkpbr.scene.camera_files import write_colmap, write_transforms

    s = scene.settings
    cameras = manifest.cameras(len(scene.poses))
    if cameras is None:
        return False
    names = [scene.transforms_name(i) for i in range(len(cameras))]
    write_transforms(Path(s.out) / "transforms.json", cameras, s.size, names,
                     times=view_times(scene.poses, s))  # (each frame's "time", as render writes)
    if scene.colmap:
        write_colmap(Path(s.out), cameras, s.size, names)
    return True


def render(job: Job | dict | list | str | os.PathLike[str], address: str | None = None, *,
           actors: int | None = None, num_cpus: float | None = None,
           num_gpus: float | None = None, progress: bool | None = None,
           local_cpus: int | None = None, devices: Sequence[str | int] | None = None,
           on_result: Callable[[WorkItem, dict], None] | None = None) -> JobResult:
    """Render a job on Ray; returns a JobResult (`.ok` False when items failed).

    Parameters
    ----------
    job : a Job, a job document (dict or list, as in a job file) or a job file's path.
    address : a Ray cluster ("HOST:PORT", "ray://HOST:PORT", "auto"); None starts a local
        Ray instance (with `local_cpus` CPUs; None: all). An initialised Ray is used as is.
        "in-process" (IN_PROCESS): no Ray; one renderer in this process renders the items in
        order, loading the next scene on a thread meanwhile (the same files and manifests).
        "processes" (PROCESSES): no Ray; `actors` renderer processes on this machine's
        default device, each with its own GIL (distributed/processes.py; a many-scene job's
        scene changes run side by side).
    actors : how many renderer actors (None: one per GPU, else one per CPU of the cluster;
        with "processes", 3 for every 8 cores, 1 to 8; never more than the job's items).
    devices : with "processes", the Vulkan devices (indices or name parts, as `--device`)
        the processes open in turn (process k the k-th modulo their count); None: the
        default device. Ray places its actors on GPUs itself.
    num_cpus, num_gpus : Ray resources of each actor (None: 1 GPU and 1 CPU where the cluster
        has GPUs, else 1 CPU); num_gpus=0.5 puts two actors on each GPU.
    progress : a tqdm bar on stderr (views/s, ETA, failures); None: when stderr is a terminal.
    on_result : called in the driver with each item and its actor's result (tests, logging).

    Raises
    ------
    UsageError : a bad job (before Ray is touched), no ray installed, an out folder that is not
        writable, a manifest of another job.
    ClusterError : the cluster cannot be reached or has no room for one actor.
    """
    t0 = time.perf_counter()
    job = _as_job(job)
    manifests = check_job(job)
    here = address == IN_PROCESS
    ray = None if address in (IN_PROCESS, PROCESSES) else import_ray()
    if ray is None and (num_cpus is not None or num_gpus is not None):
        raise UsageError(f"num_cpus and num_gpus are Ray's resources; {address!r} takes none")
    if devices is not None and address != PROCESSES:
        raise UsageError("devices: for renderer processes (address 'processes'); Ray places "
                         "its actors on GPUs itself")
    if devices is not None and (not devices or any(str(d).strip() == "" for d in devices)):
        raise UsageError(f"devices: expected device indices or names, got {list(devices)!r}")
    if address not in (None, "local", IN_PROCESS, PROCESSES):
        preflight(address)  # unreachable: one line now, even when nothing is left to render
    result = JobResult(views=job.views)
    try:
        done = [m.done_views() for m in manifests]
        result.skipped = sum(len(d) for d in done)
        items = job.items(done)
        if items:
            started = False if ray is None else connect(ray, address, local_cpus)
            made: list[tuple[SceneJob, Manifest, bool]] = []
            try:  # the folders are made last, right before the actors write into them
                busy = {item.entry for item in items}
                for e in sorted(busy):
                    made.append((job.scenes[e], manifests[e],
                                 start_frames_folder(job.scenes[e], manifests[e])))
                if here:
                    _run_here(job, items, manifests, result, progress, on_result)
                else:
                    pool_of = (_ProcessActors(actors, len(items), devices) if ray is None else
                               _RayActors(ray, actors, num_cpus, num_gpus))
                    _run(pool_of, job, items, manifests, result, progress, on_result)
            except BaseException:
                for scene, manifest, created in made:
                    abandon_frames_folder(scene, manifest, created)
                raise
            finally:
                if started:
                    ray.shutdown()
        for scene, manifest in zip(job.scenes, manifests, strict=True):
            remove_leftovers(scene)
            if not _finish_entry(scene, manifest):
                result.incomplete.append(str(scene.settings.out))
    finally:
        for m in manifests:
            m.close()
    result.seconds = time.perf_counter() - t0
    return result


def _record(item: WorkItem, res: dict, attempts: int, manifests: list[Manifest],
            result: JobResult) -> None:
    """A finished item's views and files into its entry's manifest."""
    manifests[item.entry].done(item.frames, res["files"], res["cameras"], sizes=res.get("sizes"),
                               attempts=attempts, pid=res.get("pid"),
                               seconds=round(float(res.get("seconds", 0.0)), 4))
    result.rendered += len(item.frames)


def _run_here(job: Job, items: list[WorkItem], manifests: list[Manifest], result: JobResult,
              progress: bool | None, on_result: Callable[[WorkItem, dict], None] | None) -> None:
    """The items in order by one RendererActor in this process, each told the next item's
    scene when it differs (loaded on its thread meanwhile); an item that fails with an
    error of the machine is tried again up to `job.retries` times."""
    from tqdm import tqdm

    from vkpbr.distributed.actor import RendererActor

    actor = RendererActor()
    result.actors = 1
    bar = tqdm(total=sum(len(i.frames) for i in items), unit="view", dynamic_ncols=True,
               disable=None if progress is None else not progress, desc="vkpbr")
    t0 = time.perf_counter()
    try:
        aheads = _scenes_after(items)
        for n, (item, ahead) in enumerate(zip(items, aheads, strict=True)):
            # the next item is of another scene: the renderer changes to it during this
            # item's encoding (an item tried again finds its scene already there), and the
            # scene after that starts loading then
            switch = n + 1 < len(items) and items[n + 1].settings is ahead
            later = aheads[n + 1] if switch else None
            for attempt in range(1, job.retries + 2):
                res = actor.render(item, ahead, switch, later)
                if on_result is not None:
                    on_result(item, res)
                if res.get("ok") or not res.get("retry") or attempt > job.retries:
                    break
                result.retries += 1
            if res.get("ok"):
                _record(item, res, attempt, manifests, result)
            else:
                manifests[item.entry].failed(item.frames, str(res.get("error")), attempt)
                result.failures.append(Failure(item.entry, item.frames, item.label(),
                                               str(res.get("error")), attempt))
            bar.update(len(item.frames))
    finally:
        bar.close()
        result.render_seconds = time.perf_counter() - t0
        actor.close()


class _RayActors:
    """Ray's renderer actors, for _run's loop."""

    def __init__(self, ray: Any, actors: int | None, num_cpus: float | None,
                 num_gpus: float | None) -> None:
        self.ray = ray
        self.count, resources = actor_plan(ray, actors, num_cpus, num_gpus)
        self._cls = ray.remote(max_restarts=0, max_task_retries=0, **resources)(RayRenderer)
        self._run_id = uuid.uuid4().hex[:8]
        self.kind, self.depth = "actor", 1

    def start(self, n: int) -> Any:
        return self._cls.options(name=f"vkpbr-renderer-{self._run_id}-{n}").remote()

    @staticmethod
    def call(handle: Any, item: WorkItem, ahead: Any) -> Any:
        return handle.render.remote(item, ahead)

    def wait_one(self, calls: list[Any]) -> Any:
        return self.ray.wait(calls, num_returns=1)[0][0]

    def get(self, call: Any) -> dict:
        """The call's result; ActorLost when its actor died (killed, crashed, node lost)."""
        from ray.exceptions import RayActorError, RayError

        try:
            return self.ray.get(call)
        except RayActorError as exc:
            why = (str(exc).strip().splitlines() or [""])[0][:160]
            raise ActorLost(f"its renderer actor died ({type(exc).__name__}: {why})") from None
        except RayError as exc:  # the call itself failed (an object lost, ...)
            return {"ok": False, "error": str(exc).strip().splitlines()[0], "retry": True}

    def end(self, handle: Any, now: bool = False) -> None:
        with contextlib.suppress(Exception):  # already gone
            self.ray.kill(handle)


class _ProcessActors:
    """Renderer processes of this machine (distributed/processes.py), for _run's loop."""

    def __init__(self, actors: int | None, items: int,
                 devices: Sequence[str | int] | None = None) -> None:
        if actors is not None and actors < 1:
            raise UsageError(f"processes: expected at least 1, got {actors}")
        # (never more than there are items: a process more would only start and end)
        self.count = default_processes(items) if actors is None else min(actors, items)
        self._devices = list(devices or [])
        self._encoders = encoders_for(self.count)
        self.kind, self.depth = "process", DEPTH

    def start(self, n: int) -> ProcessActor:
        device = self._devices[n % len(self._devices)] if self._devices else None
        return ProcessActor(self._encoders, device=device, name=f"vkpbr-renderer-{n}")

    @staticmethod
    def call(handle: ProcessActor, item: WorkItem, ahead: Any) -> Future:
        return handle.render(item, ahead)

    @staticmethod
    def wait_one(calls: list[Future]) -> Future:
        return wait_one(calls)

    @staticmethod
    def get(call: Future) -> dict:
        return call.result()  # (ActorLost when the process ended first)

    @staticmethod
    def end(handle: ProcessActor, now: bool = False) -> None:
        """Its work finished (`now`: killed, as a stopped job's: the files are atomic)."""
        if now:
            handle.kill()
        else:
            handle.close()


def _run(pool_of: _RayActors | _ProcessActors, job: Job, items: list[WorkItem],
         manifests: list[Manifest], result: JobResult, progress: bool | None,
         on_result: Callable[[WorkItem, dict], None] | None) -> None:
    """The items handed to `pool_of`'s actors, `pool_of.depth` items each at a time (an
    actor's own scene first, then the one it loads ahead); a lost actor is replaced and its
    items tried again."""
    from tqdm import tqdm

    n = pool_of.count
    pool: dict[int, Any] = {}  # actor number -> handle
    made = 0

    def start_actor() -> None:
        nonlocal made
        pool[made] = pool_of.start(made)
        made += 1

    for _ in range(n):
        start_actor()
    result.actors, result.actor_kind = n, pool_of.kind
    replacements = n
    idle = collections.deque(a for a in pool for _ in range(pool_of.depth))  # free slots
    pending = collections.deque(_Task(item) for item in items)
    in_flight: dict[Any, tuple[int, _Task]] = {}
    bar = tqdm(total=sum(len(i.frames) for i in items), unit="view", dynamic_ncols=True,
               disable=None if progress is None else not progress, desc="vkpbr")
    t_first: float | None = None

    scenes: dict[int, tuple] = {}  # actor -> the scene of its last item (its renderer's)
    ahead: dict[int, tuple] = {}  # actor -> the scene it was told to load ahead

    def give_out() -> None:
        nonlocal t_first
        while idle and pending:
            actor = idle.popleft()
            if actor not in pool:  # a slot of a lost actor
                continue
            k = _pick(pending, actor, (scenes.get(actor), ahead.get(actor)))
            task = pending[k]
            del pending[k]
            task.attempts += 1
            scenes[actor] = task.key
            hint = _next_scene(pending, actor, scenes, ahead)
            in_flight[pool_of.call(pool[actor], task.item, hint)] = (actor, task)
            t_first = time.perf_counter() if t_first is None else t_first

    def fail(task: _Task, error: str, retry: bool, actor: int) -> None:
        task.avoid.add(actor)
        task.last_error = error
        if retry and task.attempts <= job.retries:
            result.retries += 1
            pending.appendleft(task)
            log.info("%s: %s; trying again (attempt %d)", task.item.label(), error,
                     task.attempts + 1)
            return
        item = task.item
        manifests[item.entry].failed(item.frames, error, task.attempts)
        result.failures.append(Failure(item.entry, item.frames, item.label(), error, task.attempts))
        bar.update(len(item.frames))
        bar.set_postfix(failed=result.failed_views, refresh=False)

    try:
        give_out()
        while in_flight:
            ready = pool_of.wait_one(list(in_flight))
            actor, task = in_flight.pop(ready)
            try:
                res = pool_of.get(ready)
            except ActorLost as exc:
                # The actor is gone (killed, crashed, its node lost): replace it (once, for
                # all its items in flight), retry the item.
                if actor in pool:
                    result.actors_lost += 1
                    pool_of.end(pool.pop(actor))
                    scenes.pop(actor, None)
                    ahead.pop(actor, None)
                    if replacements > 0:
                        replacements -= 1
                        start_actor()
                        idle.extend([made - 1] * pool_of.depth)
                fail(task, str(exc), True, actor)
                if not pool:  # nothing left to render on
                    while pending:
                        fail(pending.popleft(), "no renderer actor left", False, actor)
                give_out()
                continue
            if on_result is not None:
                on_result(task.item, res)
            if res.get("ok"):
                _record(task.item, res, task.attempts, manifests, result)
                bar.update(len(task.item.frames))
            else:
                fail(task, str(res.get("error")), bool(res.get("retry")), actor)
            idle.append(actor)
            give_out()
    except BaseException:  # (stopped: its actors at once, their items in flight lost)
        for handle in pool.values():
            pool_of.end(handle, now=True)
        pool.clear()
        raise
    finally:
        bar.close()
        result.render_seconds = time.perf_counter() - (t_first or time.perf_counter())
        for handle in pool.values():
            pool_of.end(handle)
