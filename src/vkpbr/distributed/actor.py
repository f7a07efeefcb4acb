"""The renderer actor: one per GPU (or per CPU worker on lavapipe). It keeps one Renderer for
the scene it last rendered (loaded through the bake cache), renders a work item's views and
writes their files atomically. It never writes the manifest: it returns what it wrote, and
the driver records it.

`RendererActor` is a plain class; the driver makes it a Ray actor (`ray.remote(...)`), so this
module imports without Ray, and tests and benchmarks can run it in-process.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

try:
    import resource  # (Unix: an item's thread's user and system time, for benchmarks)
except ImportError:  # pragma: no cover - Windows
    resource = None  # type: ignore[assignment]

from vkpbr.distributed.job import RenderSettings, WorkItem, view_times
from vkpbr.distributed.manifest import camera_record
from vkpbr.distributed.worlds import ItemWorlds
from vkpbr.errors import SceneError, UsageError, VkpbrError
from vkpbr.io import Kind, write_output

__all__ = ["RendererActor", "render_views", "load_renderer", "load_scene_for", "predecode",
           "encoders_for"]

log = logging.getLogger(__name__)

def encoders_for(processes: int) -> int:
    """Encoding threads of each of `processes` renderer processes on this machine: the cores
    shared out between them, 2 to 8 each."""
    return max(2, min(8, (os.cpu_count() or 2) // max(1, processes)))


# Threads that encode an actor's files (PNG, EXR): half the cores, 2 to 8; while the next
# scene loads (a bake or a decode, on the loading thread), at most LOADING_ENCODERS of them
# encode at once. H200 (benchmarks/results/h200-2026-12-04s18.md, runs d-f): 8 encoders
# render one scene's views 2x faster than 2 (a 256x256 PNG is ~5 ms of a core), but they
# took the GIL from a job's loading thread: 8 made a many-scene job with a cold bake cache
# 20-40% slower than 2.
ENCODERS = encoders_for(2)
LOADING_ENCODERS = 2
# Python's GIL switch interval while an actor renders an item (the default is 5 ms). The
# item's thread makes thousands of short Vulkan calls a scene change, the loading thread
# thousands of small reads, and each gives up the GIL: with the encoding threads busy, each
# waited up to the interval to get it back. H200, 50 scenes x 16 views of the 18 sample
# models (benchmarks/results/h200-2026-12-04s18.md, run e): with 8 encoders, the cold job
# 33.9 -> 54.0 views/s and the warm one 87.5 -> 95.8 at 1 ms.
SWITCH_INTERVAL = 0.001
# An item keeps the pipelines it compiled in the cache folder (Ray kills actors without
# close), at most this often: each save of new pipelines merges the file's (every process's)
# back in first, a read and a merge of a few MB (gpu/pipeline_cache.py); close saves the rest.
SAVE_EVERY = 5.0


# What RendererActor.render asks about the next item once its views are rendered: (its
# settings, the scene to load after it) when it is known and of another scene, else None
Upcoming = Callable[[], "tuple[RenderSettings, RenderSettings | None] | None"]


@contextlib.contextmanager
def quick_switches() -> Iterator[None]:
    """Python's thread switch interval at most SWITCH_INTERVAL inside, as it was after."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(min(before, SWITCH_INTERVAL))
    try:
        yield
    finally:
        sys.setswitchinterval(before)


def render_views(renderer: Any, cameras: list[Any], lights: Any, settings: RenderSettings,
                 worlds: ItemWorlds | None = None, where: str = "worlds",
                 times: list[float] | None = None) -> Iterator[dict[str, np.ndarray]]:
    """The one render call of a work item: its views in order, each a dict of arrays
    ("color" and the dataset outputs), through the batch path (`Renderer.render_batch`);
    with `worlds`, each view in its own world (`world_views`; `where` starts its messages);
    with `times`, each view at its time of `settings.animation` (render_many's `times=`, as
    `vkpbr render --cameras` renders a poses file's "time"s).

    Yields per view: "color" (H, W, 4) uint8 sRGB, or float32 linear with `settings.linear`;
    each dataset output as `Renderer.render(outputs=...)` returns it.
    """
    if worlds is not None:
        yield from world_views(renderer, cameras, lights, settings, worlds, where)
        return
    names = settings.outputs
    # The batch path, as `vkpbr render --cameras` takes it (a view renders the same in any
    # batch, so items of any size give the single-process frames).
    frames = renderer.render_many(cameras, lights, settings.size, settings.render_options(),
                                  linear=settings.linear,
                                  outputs=("color", *names) if names else None,
                                  batch=settings.batch or None, times=times,
                                  animation=settings.animation if times is not None else None)
    for frame in frames:
        yield frame if names else {"color": frame}


def load_scene_for(settings: RenderSettings) -> Any:
    """`settings.scene` loaded as `vkpbr render [--cache]` loads it (None: the built-in chart)."""
    if settings.scene is None:
        return None
    from vkpbr.config import default_cache_dir
    from vkpbr.scene.loader import load_scene

    path, root = Path(settings.scene), None
    if settings.cache and path.suffix.lower() != ".vkpbr":
        from vkpbr.bake.bake import cached_bake

        root = path.parent  # the bake's external textures lie beside the source
        path = cached_bake(path, settings.cache_dir or default_cache_dir(),
                           allow_outside_paths=settings.allow_outside_paths)
    kwargs: dict[str, Any] = {"strict": True} if settings.strict else {}
    return load_scene(path, allow_outside_paths=settings.allow_outside_paths, root=root, **kwargs)


def predecode(scene: Any, max_size: int) -> Any:
    """`scene` with its images decoded to RGBA8 as the renderer's upload decodes them
    (render/gpu_scene.py: the same decoder and size limit), so that the upload, on the
    thread that drives the GPU, only copies: the actor runs this one scene ahead, on its
    prefetch thread. Scenes with KTX2 images are left as they are (their BC7 levels are the
    device's choice, made on upload)."""
    import dataclasses

    from vkpbr.bake.ahead import may_hold_ktx2
    from vkpbr.scene.textures import decode_images

    images = getattr(scene, "images", None)
    if not images or may_hold_ktx2(scene):
        return scene
    pixels = decode_images(scene, max_size=max_size)
    if any(p is None for p in pixels):  # missing or undecodable: the upload reports them
        return scene
    decoded = [img if img.pixels is not None else dataclasses.replace(img, pixels=px)
               for img, px in zip(images, pixels, strict=True)]
    return dataclasses.replace(scene, images=decoded)


def world_views(renderer: Any, cameras: list[Any], lights: Any, settings: RenderSettings,
                worlds: ItemWorlds, where: str = "worlds") -> Iterator[dict[str, np.ndarray]]:
    """`render_views` of views that each see their own world: view i equals the scene
    rendered with world `worlds.index[i]` set on it (set_poses(space="world"), set_visible,
    set_material), as a batch of worlds renders it (docs/batch.md). Two routes give them:

    - a batch of worlds, `render_batch(worlds=..., world_materials=...)`, `settings.batch`
      views at a time, where shadows are off (a batch of worlds gives each world one
      scene-wide map a light, not the cascades a frame fits to its camera: docs/batch.md);
    - else each world set on the renderer's state in turn and its views rendered as plain
      views are (a batch, or frame by frame with batch 0), so each world casts its own
      shadows; the state is put back afterwards.
    """
    from vkpbr.render.batch_route import per_view

    placed = _world_slots(renderer, worlds, where)
    options, names = settings.render_options(), settings.outputs
    wanted = ("color", *names) if names else None
    batch = settings.batch if renderer.device.batch_views else 0
    if options.shadows or not batch:
        yield from _world_by_world(renderer, cameras, lights, settings, placed, worlds.index)
        return
    factors = None if worlds.materials is None else worlds.materials.factors
    for lo in range(0, len(cameras), batch):
        chunk = cameras[lo:lo + batch]
        got = renderer.render_batch(chunk, settings.size, lights, options, settings.linear,
                                    outputs=wanted, worlds=worlds.poses,
                                    world_of_view=worlds.index[lo:lo + batch],
                                    quaternion=worlds.quaternion, world_visible=worlds.visible,
                                    world_materials=factors)
        for frame in per_view(got, len(chunk), False):
            yield frame if names else {"color": frame}


def _world_slots(renderer: Any, worlds: ItemWorlds, where: str) -> tuple[Any, Any, Any]:
    """The renderer's slots of `worlds.nodes` (world_slots, for its batches of worlds), the
    checked poses and material factors (None where not given). A node or material the
    scene lacks, or patterns that match another count of nodes than the poses give, is one
    line."""
    from vkpbr.scene.worlds import WorldMaterials, WorldPoses

    names = None if worlds.materials is None else list(worlds.materials.names)
    mats = None
    if names is not None:
        try:
            mats = WorldMaterials.of(renderer.state, names, worlds.materials.factors)  # type: ignore[union-attr]
        except UsageError as exc:
            raise UsageError(f"{where}: materials: {exc}") from None
    nodes = None if worlds.poses is None else list(worlds.nodes)
    try:
        slots = renderer.world_slots(nodes, materials=names)
    except UsageError as exc:
        raise UsageError(f"{where}: nodes: {exc}") from None
    if worlds.poses is None:
        return None, None, mats
    n = worlds.poses.shape[1]
    if len(slots) != n:
        shown = ", ".join(slots.names[:6]) + (" ..." if len(slots) > 6 else "")
        raise UsageError(f"{where}: nodes {nodes} are {len(slots)} node(s) of the scene "
                         f"({shown}), but the poses give {n} a world")
    return slots, WorldPoses.of(worlds.poses, n, worlds.quaternion, worlds.visible), mats


def _world_by_world(renderer: Any, cameras: list[Any], lights: Any, settings: RenderSettings,
                    placed: tuple[Any, Any, Any], index: np.ndarray
                    ) -> Iterator[dict[str, np.ndarray]]:
    """Each world set on the renderer's state (`placed`: its slots, poses and materials, each
    or None), its views rendered as plain views (shadow maps of that world), the state put
    back; the frames in the views' order."""
    from vkpbr.render.batch_call import apply_materials, apply_saved, apply_world

    names, state = settings.outputs, renderer.state
    slots, poses, materials = placed
    frames: dict[int, dict[str, np.ndarray]] = {}
    restore = apply_saved(state)  # poses, visibility and material overrides
    try:
        for w in dict.fromkeys(index.tolist()):  # the worlds in the order views first see them
            views = np.flatnonzero(index == w)
            if poses is not None:
                apply_world(state, slots, poses, w)
            if materials is not None:
                apply_materials(state, materials, w)
            got = renderer.render_many([cameras[v] for v in views], lights, settings.size,
                                       settings.render_options(), linear=settings.linear,
                                       outputs=("color", *names) if names else None,
                                       batch=settings.batch or None)
            for v, frame in zip(views, got, strict=True):
                frames[int(v)] = frame if names else {"color": frame}
    finally:
        restore()
    for v in range(len(cameras)):
        yield frames.pop(v)


def load_renderer(settings: RenderSettings, device: str | int | None = None,
                  scene: Any = None) -> Any:
    """A Renderer for `settings.scene` (or the `scene` given, loaded from it already),
    loaded as `vkpbr render [--cache]` loads it."""
    from vkpbr.config import default_cache_dir
    from vkpbr.render.renderer import Renderer

    if scene is None:
        scene = load_scene_for(settings)
    return Renderer(scene, device=device, msaa=settings.msaa, cache_dir=default_cache_dir(),
                    semantics=settings.semantic_source())


def _thread_cpu() -> tuple[float, float]:
    """This thread's (user, system) CPU seconds; where the system has no per-thread
    accounting (not Linux), all of its CPU time as user time."""
    who = getattr(resource, "RUSAGE_THREAD", None) if resource is not None else None
    if who is None:
        return time.thread_time(), 0.0
    got = resource.getrusage(who)
    return got.ru_utime, got.ru_stime


def _cpu_since(before: tuple[float, float]) -> dict[str, float]:
    """{"cpu": user + system, "cpu system": system} of this thread since `before`."""
    user, system = _thread_cpu()
    return {"cpu": user - before[0] + system - before[1], "cpu system": system - before[1]}


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


class EncodeGate:
    """At most `limit()` callers inside at once (asked again as they wait: it may change)."""

    def __init__(self, limit: Callable[[], int]) -> None:
        self._limit = limit
        self._inside = 0
        self._cond = threading.Condition()

    def __enter__(self) -> None:
        with self._cond:
            while self._inside >= self._limit():
                self._cond.wait(0.002)  # (the limit rises when a load ends: no one notifies)
            self._inside += 1

    def __exit__(self, *exc: object) -> None:
        with self._cond:
            self._inside -= 1
            self._cond.notify()


class RendererActor:
    """Renders work items with one Renderer, which changes scene (`Renderer.set_scene`: the
    device and its pipeline cache are kept) when an item's scene is not the last one's, and
    is made anew only when the renderer's own settings (msaa, semantics) change. The scene
    the driver says comes next (`render(item, ahead=...)`) is loaded on a thread of its own
    while this item renders: parsed or read from the bake cache, its textures decoded; at
    most one scene ahead (docs/batch.md, "Many scenes").

    device : the Vulkan device (name substring or index) the Renderer opens; None: the default.
    encoders : threads that encode its files (None: ENCODERS).
    """

    def __init__(self, device: str | int | None = None, encoders: int | None = None) -> None:
        self.device = device
        encoders = encoders or ENCODERS
        self._key: tuple | None = None  # the scene the renderer draws
        self._renderer: Any = None
        self._renderer_args: tuple | None = None  # (msaa, semantics) it was made with
        self._bad_scenes: dict[tuple, VkpbrError] = {}  # scene key -> why it cannot load
        # Encoding overlaps the next views' rendering, and on a machine of many cores it is
        # the slowest part of a small view's life (a 256x256 PNG: ~5 ms of a core)
        self._pool = ThreadPoolExecutor(encoders, thread_name_prefix="vkpbr-encode")
        self._gate = EncodeGate(lambda: min(LOADING_ENCODERS, encoders) if self._loading()
                                else encoders)
        self._loader = ThreadPoolExecutor(1, thread_name_prefix="vkpbr-next-scene")
        self._ahead: tuple[tuple, Future] | None = None  # (scene key, its load)
        # scenes loaded on the thread / when needed; changed to during an item's encoding
        self.loads = {"ahead": 0, "now": 0, "early": 0}

    def _loading(self) -> bool:
        """Whether a scene is loading ahead now."""
        ahead = self._ahead
        return ahead is not None and not ahead[1].done()

    def _write(self, path: Path, array: np.ndarray, kind: Kind, option: str = "--out") -> None:
        """One file written (`vkpbr.io.write_output`) through the encoding gate."""
        with self._gate:
            write_output(path, array, kind, option)

    def info(self) -> dict[str, object]:
        return {"pid": os.getpid(), "host": socket.gethostname(), "device": self.device}

    def prefetch(self, settings: RenderSettings) -> None:
        """Start loading `settings`' scene on the prefetch thread (not the current one, a
        known bad one or the one already ahead). One scene ahead at most: a load not yet
        started is replaced; one under way is left to finish and this hint dropped."""
        key = settings.scene_key()
        if key == self._key or key in self._bad_scenes:
            return
        ahead = self._ahead  # a finished load of another scene is dropped, one under way kept
        if ahead is not None and (ahead[0] == key or not (ahead[1].done() or ahead[1].cancel())):
            return
        size = (int(self._renderer.device.limits.maxImageDimension2D)
                if self._renderer is not None else None)
        self._ahead = (key, self._loader.submit(self._load, settings, size))

    @staticmethod
    def _load(settings: RenderSettings, max_size: int | None) -> Any:
        scene = load_scene_for(settings)
        return predecode(scene, max_size) if max_size and scene is not None else scene

    def _scene(self, settings: RenderSettings, key: tuple) -> Any:
        """`settings`' scene: the one loaded ahead when it is that one, else loaded now."""
        ahead, self._ahead = self._ahead, None
        if ahead is not None and ahead[0] == key:
            self.loads["ahead"] += 1
            return ahead[1].result()  # (its load's error, as loading now would raise it)
        if ahead is not None:
            ahead[1].cancel()
        self.loads["now"] += 1
        return load_scene_for(settings)

    def _renderer_for(self, settings: RenderSettings) -> Any:
        key = settings.scene_key()
        if key in self._bad_scenes:
            raise self._bad_scenes[key]  # as it was first raised (its one line names the file)
        if key == self._key:
            return self._renderer
        same = self._renderer is not None and self._renderer_args == (settings.msaa,
                                                                      settings.semantics)
        try:
            scene = self._scene(settings, key)
            self._key = None  # (the renderer's scene is about to change)
            if same:
                self._renderer.set_scene(scene)
            else:
                self.close()
                self._renderer = load_renderer(settings, self.device, scene)
                self._renderer_args = (settings.msaa, settings.semantics)
        except (SceneError, UsageError) as exc:
            self._bad_scenes[key] = exc
            raise
        finally:
            if self._renderer is not None and self._renderer.device.handle is None:
                self._renderer = None  # closed by a failed set_scene
        self._key = key
        return self._renderer

    def render(self, item: WorkItem, ahead: RenderSettings | None = None,
               switch: bool = False, later: RenderSettings | None = None,
               upcoming: Upcoming | None = None) -> dict[str, object]:
        """Render and write `item`'s views; `ahead`: the settings of the scene expected next,
        loaded on the prefetch thread meanwhile; `switch`: the next item is of that scene, so
        the renderer changes to it while this item's files are encoded (the swap and the
        encoding overlap; a scene that fails to load then is this actor's known bad scene,
        reported by the next item), and `later`'s scene (the one after it) starts loading
        then, a whole item ahead of its use; `upcoming` (without `switch`): asked once the
        views are rendered for (the next item's settings, the scene after it) when the next
        item is known by then and of another scene, which is then changed to as with `switch`
        (a renderer process's next request: distributed/processes.py). Returns {"ok": True,
        "views", "files", "cameras", "seconds", "pid", ...}, or {"ok": False, "error": one
        line, "retry": bool}: an error in the input (a scene that does not load, a bad
        option) fails the same way everywhere and is not retried."""
        t0 = time.perf_counter()
        try:
            with quick_switches():
                return self._render(item, t0, ahead, switch, later, upcoming)
        except (SceneError, UsageError) as exc:
            if ahead is not None:  # this scene failed: the next one still loads meanwhile
                self.prefetch(ahead)
            return {"ok": False, "error": _one_line(exc), "retry": False, "pid": os.getpid(),
                    "loads": dict(self.loads)}  # (a scene that failed to load counts too)
        except Exception as exc:  # noqa: BLE001 - reported to the driver, which retries elsewhere
            log.exception("work item %s failed", item.label())
            self.close()  # a device error may leave the Renderer unusable: start afresh
            return {"ok": False, "error": _one_line(exc), "retry": True, "pid": os.getpid()}

    def _render(self, item: WorkItem, t0: float, ahead: RenderSettings | None,
                switch: bool = False, later: RenderSettings | None = None,
                upcoming: Upcoming | None = None) -> dict[str, object]:
        from vkpbr.io import check_id_count, output_kind, output_path

        settings = item.settings
        cpu0 = _thread_cpu()
        renderer = self._renderer_for(settings)
        t_load = time.perf_counter()
        if ahead is not None:  # after this scene's load: the two do not contend
            self.prefetch(ahead)
        times = view_times(item.poses, settings)
        if renderer.state.time is not None:  # an earlier item played the animation: the rest
            renderer.reset_pose()             # pose, as a fresh renderer draws it
        base = renderer.default_camera()
        cameras = [pose.camera(base) for pose in item.poses]
        options = settings.render_options()
        lights = renderer.frame_lights(options)
        out = Path(settings.out)
        for name in settings.outputs:
            if output_kind(name) == "ids":
                check_id_count(renderer.max_id, output_path(out / "frame.png", name),
                               f"{item.label()}: outputs")
        files: list[str] = []
        writes = []
        frames = render_views(renderer, cameras, lights, settings, item.worlds,
                              f"{item.where}: worlds", times)
        for k, (_view, frame) in enumerate(zip(item.frames, frames, strict=True)):
            names = item.files_of(k)
            (out / names[0]).parent.mkdir(parents=True, exist_ok=True)  # a file_path's folder
            writes.append(self._pool.submit(self._write, out / names[0], frame["color"], "color"))
            for name, file in zip(settings.outputs, names[1:], strict=True):
                writes.append(self._pool.submit(self._write, out / file, frame[name],
                                                output_kind(name), "outputs"))
            files += names
        t_views = time.perf_counter()
        if switch and ahead is not None:
            self._change_early(ahead, later)
        elif upcoming is not None and (following := upcoming()) is not None:
            self._change_early(*following)
        t_switch = time.perf_counter()
        for w in writes:
            w.result()
        t_written = time.perf_counter()
        cache = getattr(renderer.device, "pipeline_cache", None)
        if cache is not None:  # Ray kills actors without close(): keep new pipelines now
            cache.save(min_interval=SAVE_EVERY)  # (and at close, whatever is left)
        sizes = [(out / f).stat().st_size for f in files]
        return {"ok": True, "views": list(item.frames), "files": files, "sizes": sizes,
                "cameras": [camera_record(c) for c in cameras], "pid": os.getpid(),
                "device": renderer.device.info.name,
                "load_s": t_load - t0, "seconds": time.perf_counter() - t0,
                "loads": dict(self.loads),
                # where the item's wall time went, and its thread's CPU time (benchmarks)
                "phases": {"scene": t_load - t0, "views": t_views - t_load,
                           "next scene": t_switch - t_views, "files": t_written - t_switch,
                           **_cpu_since(cpu0)}}

    def _change_early(self, ahead: RenderSettings, later: RenderSettings | None) -> None:
        """The next item's scene (`ahead`) set now, and `later`'s load started."""
        self._switch_to(ahead)
        if later is not None:
            self.prefetch(later)

    def _switch_to(self, settings: RenderSettings) -> None:
        """Change the renderer's scene to `settings`' now (its load ahead waited for), when
        the renderer is kept for it (`set_scene`: the same msaa and semantics). A scene that
        fails to load is recorded as bad (`_renderer_for`) for the next item to report; any
        other failure leaves the next item to make its renderer afresh and try again."""
        same = self._renderer is not None and self._renderer_args == (settings.msaa,
                                                                      settings.semantics)
        if not same or settings.scene_key() in self._bad_scenes:
            return
        try:
            self._renderer_for(settings)
            self.loads["early"] += 1
        except (SceneError, UsageError):
            pass  # kept in _bad_scenes: the next item's one line
        except Exception:  # noqa: BLE001 - this item's views are done: the next one retries
            log.warning("changing to the next scene (%s) failed; it is tried again for its item",
                        settings.scene, exc_info=True)
            self.close()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        self._renderer, self._key = None, None
