"""`--pipeline auto` on a GPU: the frame path that measured fastest on this device.

Auto's measurement times the candidates, forward, the compute path with the raster units and
the compute path with the compute rasteriser (where the device has 64-bit atomics), on the
renderer's own scene at the frame's size (at most 1920x1080), streams of frames each by GPU
timestamps, and keeps the fastest: in `<cache_dir>/frame-paths.json` when the renderer has a
cache directory (the CLI's: $VKPBR_CACHE_DIR, else ~/.cache/vkpbr), else for the process.
Renderers on that device read the record (a new driver or new shaders measure again).

When it measures (`when`): not on the first frame. The measurement costs about 150 frames
and the other paths' pipelines (1.24 s of the H200's 2.21 s from Sponza's file to its first
frame), more than a short run renders in all, so a GPU with nothing recorded takes the rule
(the compute path + compute rasteriser: what the H200 measured fastest, BENCHMARKS.md) and
measures at the first auto frame MEASURE_AFTER_S after its first one: a process that renders
that long (the viewer, a job, a benchmark) pays the measurement once for every later process,
at most a tenth of its time; a one-shot `vkpbr render` never does. Frames of one renderer
may so change path once, mid-run (the paths agree within 1/255: docs/compute-path.md).
CPUs (lavapipe) take the compute path with the raster units without measuring (the
measurement would cost seconds there): since session 26, when lavapipe measured it 1.6-2x the
forward path (the chart at 1280x720 245 ms a frame against 401, Sponza at 640x360 202 against
400; the compute rasteriser the slower of the two there at 640x480). A device without timestamps, or a cache file
that cannot be read, falls back to the rule. $VKPBR_FRAME_PATHS=rule never measures
(reproducible runs: one path from the first frame to the last); =measure measures at the
first auto frame, on CPUs too.

`FramePaths` is the renderer's side of it: which path a frame of a target takes (and whether
it has the depth pre-pass), and `choose`, which the caller layer runs before auto frames
(Renderer.render_many, the viewer; never `draw` itself): the measurement renders its own
frames through the `FrameStream` it is given.
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
import os
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from vkpbr.atomic import atomic_writer
from vkpbr.errors import JsonError, OutOfDeviceMemoryError, UsageError
from vkpbr.gpu.device import COMPUTE_PATH_FEATURES, Device
from vkpbr.gpu.target import FrameTarget
from vkpbr.json_input import read_json
from vkpbr.render import layouts as L
from vkpbr.render.frames import FrameStats
from vkpbr.render.options import RenderOptions
from vkpbr.scene.types import Camera, Scene

__all__ = ["CACHE_FILE", "MEASURE_AFTER_S", "RULE_CPU", "RULE_GPU", "FramePaths", "FrameStream",
           "PathChoice", "device_key", "shaders_digest", "frame_paths_mode", "is_auto", "measure",
           "recorded", "resolve", "when"]

log = logging.getLogger(__name__)

CACHE_FILE = "frame-paths.json"
# Frames per candidate and round: WARM_UP before the first round (pipelines, caches, clocks),
# TIMED per round, the rounds interleaving the candidates so that a GPU's clocks ramping up
# or down between them favour none (the H200's first record, 3 warm-up frames then 8 frames
# of one candidate after another, measured the two compute paths 0.2% apart where they
# differ by a third in a steady stream of frames: BENCHMARKS.md, the fourth run).
WARM_UP, TIMED, ROUNDS = 10, 20, 2
MAX_SIZE = (1920, 1080)
# Seconds of auto frames on the rule before a GPU with nothing recorded measures (`when`): the
# measurement's ~1 s is then at most a tenth of the process's rendering time.
MEASURE_AFTER_S = 10.0
_in_process: dict[str, dict] = {}  # device key -> record, for renderers without a cache dir


@dataclass(frozen=True)
class PathChoice:
    """What auto resolves to: the compute path or not, and its rasteriser."""

    compute: bool
    compute_raster: bool
    measured: bool = False  # False: the rule (no timestamps, or a CPU)

    @property
    def label(self) -> str:
        return "forward" if not self.compute else f"compute/{'compute' if self.compute_raster else 'hardware'}"


RULE_GPU = PathChoice(compute=True, compute_raster=True)
# CPUs: the compute path with the raster units (lavapipe, session 26: 1.6-2x the forward
# path; its compute rasteriser the slower at 640x480: DamagedHelmet 12.7 frames/s against
# 15.4, Sponza 2.7 against 4.1).
RULE_CPU = PathChoice(compute=True, compute_raster=False)


class FrameStream(Protocol):
    """What the measurement renders through (a Renderer is one): streams of frames of its
    scene from its default camera, each frame's timings in `last_stats`."""

    device: Device
    scene: Scene
    last_stats: FrameStats

    def default_camera(self) -> Camera: ...

    def render_many(self, cameras: Any, *args: Any, **kwargs: Any) -> Any: ...


def device_key(renderer: FrameStream) -> str:
    """The device, its driver and vkpbr's shaders: a new driver or new shaders measure again."""
    info = renderer.device.info
    return _key(info.name, info.vendor_id, info.device_id, info.driver_version)


def _key(name: str, vendor_id: int, device_id: int, driver_version: int) -> str:
    return f"{name} [{vendor_id:04x}:{device_id:04x}] driver {driver_version} shaders {shaders_digest()}"


def recorded(cache_dir: str | Path, device: dict) -> dict | None:
    """The record for one of `vkpbr info`'s devices (its report's dict) in `cache_dir`."""
    key = _key(device["name"], device["vendor_id"], device["device_id"], device["driver_version"])
    return _valid(_read(Path(cache_dir) / CACHE_FILE).get(key))


@functools.cache
def shaders_digest() -> str:
    """sha1 of the SPIR-V vkpbr runs (src/vkpbr/shaders/spv), first 12 hex digits."""
    digest = hashlib.sha1()
    for path in sorted((Path(__file__).resolve().parent.parent / "shaders" / "spv").glob("*.spv")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def _candidates(renderer: FrameStream) -> list[PathChoice]:
    out = [PathChoice(False, False, True), PathChoice(True, False, True)]
    if renderer.device.compute_raster:
        out.append(PathChoice(True, True, True))
    return out


def measure(renderer: FrameStream, size: tuple[int, int]) -> dict[str, Any]:
    """Time every candidate on `renderer`'s scene at `size` (its default camera and lights)
    in a stream of frames, as an application draws them (render_many: frames queued back to
    back, no readback), ROUNDS times interleaved: the record `resolve` keeps ({"choice":
    label, "gpu_ms": {label: the best round's median ms}, ...})."""
    w, h = min(size[0], MAX_SIZE[0]), min(size[1], MAX_SIZE[1])
    camera = renderer.default_camera()
    rounds: dict[str, list[float]] = {c.label: [] for c in _candidates(renderer)}
    for k in range(ROUNDS):
        for c in _candidates(renderer):
            opts = {"pipeline": "compute" if c.compute else "forward",
                    "raster": "compute" if c.compute_raster else "hardware"}
            skip = WARM_UP if k == 0 else 2  # the other candidates' frames ran in between
            gpu = []
            for i, _ in enumerate(renderer.render_many([camera] * (skip + TIMED), size=(w, h),
                                                       readback=False, **opts)):
                if i >= skip:
                    gpu.append(renderer.last_stats.gpu_ms)
            rounds[c.label].append(statistics.median(gpu))
    times = {label: min(ms) for label, ms in rounds.items()}
    finite = {k: v for k, v in times.items() if v == v and v > 0}  # NaN: no timestamps
    choice = min(finite, key=finite.get) if finite else RULE_GPU.label
    return {"choice": choice, "gpu_ms": times, "size": [w, h], "scene": renderer.scene.name,
            "frames": TIMED, "rounds": ROUNDS}


def _from_label(label: Any, measured: bool) -> PathChoice | None:
    for c in (PathChoice(False, False), PathChoice(True, False), PathChoice(True, True)):
        if c.label == label:
            return PathChoice(c.compute, c.compute_raster, measured)
    return None


def _valid(record: Any) -> dict | None:
    """`record` when it is one `measure` wrote (a hand-edited or foreign one may not be)."""
    if not isinstance(record, dict) or _from_label(record.get("choice"), True) is None:
        return None
    times, size = record.get("gpu_ms"), record.get("size")
    if not (isinstance(times, dict) and all(isinstance(v, (int, float)) for v in times.values())
            and isinstance(size, list) and len(size) == 2 and all(isinstance(n, int) for n in size)):
        return None
    return record


def _read(path: Path) -> dict[str, dict]:
    try:
        data = read_json(path)
    except FileNotFoundError:
        return {}
    except (OSError, JsonError) as exc:
        log.warning("%s: unreadable (%s); ignored (the next auto frame measures again)", path, exc)
        return {}
    return data if isinstance(data, dict) else {}


def resolve(renderer: FrameStream, size: tuple[int, int], cache_dir: str | Path | None,
            measure_now: bool = True) -> PathChoice | None:
    """The recorded choice for this device, else measure now (and record it); None when
    nothing is recorded and not `measure_now`."""
    key = device_key(renderer)
    path = Path(cache_dir) / CACHE_FILE if cache_dir is not None else None
    records = _read(path) if path is not None else _in_process
    record = _valid(records.get(key))
    choice = _from_label(record["choice"], True) if record is not None else None
    if choice is not None and (not choice.compute_raster or renderer.device.compute_raster):
        return choice
    if not measure_now:
        return None
    record = measure(renderer, size)
    log.info("frame paths measured on %s at %dx%d: %s -> %s", renderer.device.info.name,
             *record["size"], ", ".join(f"{k} {v:.3f} ms" for k, v in record["gpu_ms"].items()),
             record["choice"])
    records = {**(_read(path) if path is not None else _in_process), key: record}
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_writer(path) as f:
                f.write(json.dumps(records, indent=1, sort_keys=True).encode())
        except OSError as exc:  # a read-only cache: measured again next time, no error
            log.warning("%s: not written (%s)", path, exc.strerror or exc)
    else:
        _in_process.update(records)
    return _from_label(record["choice"], True) or RULE_GPU


MODES = ("auto", "measure", "rule")


def frame_paths_mode() -> str:
    """$VKPBR_FRAME_PATHS: "auto" (default: measure on GPUs), "measure" (CPUs too) or "rule"
    (never measure: the same choice on every machine of a kind, for reproducible runs)."""
    mode = os.environ.get("VKPBR_FRAME_PATHS", "auto").strip().lower() or "auto"
    if mode not in MODES:
        raise UsageError(f"VKPBR_FRAME_PATHS={mode!r}: use one of {', '.join(MODES)}")
    return mode


def is_auto(options: Any) -> bool:
    """Whether `options` leave the frame path or its rasteriser to auto."""
    return options.pipeline == L.PipelinePath.AUTO or options.raster == L.RasterPath.AUTO


class FramePaths:
    """Which frame path frames take on `device`: the fragment path or the compute path (and
    its rasteriser), with or without the depth pre-pass; auto's choice once `choose` has
    made it (until then, and where it cannot, the rule: RULE_GPU's on GPUs, RULE_CPU's on
    CPUs). `triangles`: the scene's; `blended`: whether it has blended draws (which the
    compute batch draws into its atlas with clip distances); `depth_prepass` and `cache_dir` as the Renderer's."""

    def __init__(self, device: Device, msaa: int, triangles: int, blended: bool,
                 depth_prepass: bool | None, cache_dir: str | os.PathLike[str] | None) -> None:
        self.device, self.msaa, self.triangles, self.blended = device, msaa, triangles, blended
        self.depth_prepass, self.cache_dir = depth_prepass, cache_dir
        self.choice: PathChoice | None = None  # what auto measured (or read back)
        self._since: float | None = None  # when auto frames began on the rule, nothing recorded

    def prepass_for(self, target: FrameTarget) -> bool:
        """Whether frames of `target` run the depth pre-pass (see Renderer's `depth_prepass`)."""
        if self.depth_prepass is not None:
            return bool(self.depth_prepass)
        w, h = target.extent
        return self.device.info.kind != "cpu" and self.triangles <= w * h

    def compute_unavailable(self, target: FrameTarget) -> str | None:
        """Why frames of `target` cannot take the compute path, or None when they can."""
        if not self.device.compute_path:
            return "the device lacks " + ", ".join(COMPUTE_PATH_FEATURES)
        if not getattr(target, "compute", False):
            return "it needs a single-sample offscreen target (not MSAA, not a window)"
        w, h = target.extent
        limit = int(self.device.limits.maxStorageBufferRange)
        if 4 * w * h > limit:  # the pixel list: 4 bytes a pixel in one storage binding
            return f"{w}x{h} exceeds its pixel list's limit here ({limit // 4:,} pixels)"
        return None

    def uses_compute(self, target: FrameTarget, options: RenderOptions) -> bool:
        """Whether frames of `target` with `options` take the compute path (UsageError when
        it is asked for and cannot: say why and what to use)."""
        if options.pipeline == L.PipelinePath.COMPUTE:
            why = self.compute_unavailable(target)
            if why is not None:
                raise UsageError(f"--pipeline compute is not available here: {why}; use "
                                 "--pipeline forward or auto")
            return True
        if options.pipeline == L.PipelinePath.FORWARD:
            return False
        # auto: on GPUs, what measured fastest on the device (until it is measured, the
        # compute path where the target allows it: the H200 measured it 1.5-3.9x faster at
        # 128x128 to 1920x1080); on CPUs the compute path too (lavapipe: 1.6-2x, session 26).
        if self.choice is not None:  # measured (or read back) for this device
            return self.choice.compute and self.compute_unavailable(target) is None
        return self.compute_unavailable(target) is None

    def uses_compute_raster(self, options: RenderOptions, target: FrameTarget) -> bool:
        """Whether the compute path's visibility buffer comes from the compute rasteriser
        (UsageError when it is asked for and the device or the target's size cannot; auto
        takes it on GPUs where it can, the raster units otherwise)."""
        if options.raster == L.RasterPath.HARDWARE:
            return False
        w, h = target.extent
        limit = int(self.device.limits.maxStorageBufferRange)
        if options.raster == L.RasterPath.AUTO:
            wanted = (self.choice.compute_raster if self.choice is not None
                      else self.device.info.kind != "cpu")
            return wanted and bool(self.device.compute_raster) and 8 * w * h <= limit
        if not self.device.compute_raster:
            raise UsageError("--raster compute is not available here: the device lacks 64-bit "
                             "storage-buffer atomics (shaderInt64, shaderBufferInt64Atomics); "
                             "use --raster hardware")
        if 8 * w * h > limit:  # 8 bytes a pixel in one storage binding
            raise UsageError(f"--raster compute is not available for {w}x{h} here: at most "
                             f"{limit // 8:,} pixels; use --raster hardware")
        return True

    def compute_batch_unavailable(self) -> str | None:
        """Why `render_batch(pipeline="compute")` cannot take the compute batch (its views
        are then rendered one by one on the compute path), or None."""
        if not self.device.compute_raster:
            return "the device lacks 64-bit storage-buffer atomics"
        if self.msaa > 1:
            return "MSAA"
        if self.blended and not self.device.atlas_blend:
            return "the scene has blended materials and the device lacks clip distances"
        return None

    def takes_compute_batch(self, options: RenderOptions) -> bool:
        """Whether render_batch takes the compute batch: pipeline "compute" or "auto", where
        `compute_batch_unavailable` is None (else the fragment path's layered batch). On CPUs
        too since session 26, as `render`'s auto takes the compute path there: lavapipe
        measured it as fast as the layered batch at 64x48 and 1.2-5x at 128x128 and more
        (4-6x with dataset outputs, for which the layered batch draws every view again)."""
        return options.pipeline != L.PipelinePath.FORWARD and not self.compute_batch_unavailable()

    def choose(self, target: FrameTarget, options: RenderOptions, stream: FrameStream) -> None:
        """Before auto frames of `target` where it can take the compute path: the rule, the
        recorded choice for the device, or the candidates measured now through `stream`
        (frames of explicit options, which do not come back here), as `when` says. Run by
        the caller layer before it draws: never from inside a frame."""
        if not is_auto(options) or (self.choice is not None and self._since is None):
            return  # explicit options, or decided for good
        mode = frame_paths_mode()  # VKPBR_FRAME_PATHS: auto, measure (CPUs too) or rule
        cpu, now = self.device.info.kind == "cpu", time.perf_counter()
        what = when(mode, cpu, None if self._since is None else now - self._since)
        if what == "wait":
            return
        if what == "rule":  # decided once, not per frame
            self.choice = RULE_CPU if cpu else RULE_GPU
            return
        if self.compute_unavailable(target) is not None:  # a window: decided by a later target
            return
        since, self._since = self._since, None  # (no auto frames come back here meanwhile)
        self.choice = RULE_GPU  # while measuring, and if measuring fails
        try:
            got = resolve(stream, target.extent, self.cache_dir, measure_now=what == "measure")
        except (OutOfDeviceMemoryError, UsageError) as exc:  # a candidate cannot run here
            log.warning("frame paths not measured (%s); auto takes %s", exc, RULE_GPU.label)
            return
        if got is None:  # nothing recorded: the rule, measured MEASURE_AFTER_S from now
            self._since = now if since is None else since
        else:
            self.choice = got


def when(mode: str, cpu: bool, waited_s: float | None) -> str:
    """What `FramePaths.choose` does before an auto frame (the module docstring says why):
    "rule" (the rule for good), "read" (the record, else the rule while MEASURE_AFTER_S
    pass), "wait" (on the rule, still waiting: nothing read), "measure" (the record, else
    measure now). `mode`: frame_paths_mode(); `cpu`: the device is one; `waited_s`: seconds
    since the renderer's first auto frame on the rule (None: nothing read yet)."""
    if mode == "rule" or (cpu and mode != "measure"):
        return "rule"
    if mode == "measure" or (waited_s is not None and waited_s >= MEASURE_AFTER_S):
        return "measure"
    return "read" if waited_s is None else "wait"
