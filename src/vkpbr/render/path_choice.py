"""`--pipeline auto` on a GPU: the frame path that measured fastest on this device.

The first auto frame on a GPU (per device, driver and vkpbr version) times the candidates,
forward, the compute path with the raster units and the compute path with the compute
rasteriser (where the device has 64-bit atomics), on the renderer's own scene at the frame's
size (at most 1920x1080), streams of frames each by GPU timestamps, and keeps the fastest: in
`<cache_dir>/frame-paths.json` when the renderer has a cache directory (the CLI's:
$VKPBR_CACHE_DIR, else ~/.cache/vkpbr), else for the process. Later renderers on that device
read it instead of measuring (a new driver or new shaders measure again). CPUs (lavapipe) take the forward path without measuring: the
compute path is the slower there and the measurement would cost seconds. A device without
timestamps, or a cache file that cannot be read, falls back to the rule the H200 measured
(compute path + compute rasteriser on GPUs: BENCHMARKS.md). $VKPBR_FRAME_PATHS=rule never
measures (reproducible runs); =measure measures on CPUs too.
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
import os
import statistics
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vkpbr.atomic import atomic_writer
from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import read_json
from vkpbr.render import layouts as L

# The renderer is passed in, not imported (it imports this module): `Renderer` below is any
# object with its device, scene, render, last_stats and default_camera.
Renderer = Any

__all__ = ["CACHE_FILE", "RULE_CPU", "RULE_GPU", "PathChoice", "device_key", "frame_paths_mode", "is_auto", "measure",
           "recorded", "resolve"]

log = logging.getLogger(__name__)

CACHE_FILE = "frame-paths.json"
# Frames per candidate and round: WARM_UP before the first round (pipelines, caches, clocks),
# TIMED per round, the rounds interleaving the candidates so that a GPU's clocks ramping up
# or down between them favour none (the H200's first record, 3 warm-up frames then 8 frames
# of one candidate after another, measured the two compute paths 0.2% apart where they
# differ by a third in a steady stream of frames: BENCHMARKS.md, the fourth run).
WARM_UP, TIMED, ROUNDS = 10, 20, 2
MAX_SIZE = (1920, 1080)
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
RULE_CPU = PathChoice(compute=False, compute_raster=False)


def device_key(renderer: Renderer) -> str:
    """The device, its driver and vkpbr's shaders: a new driver or new shaders measure again."""
    info = renderer.device.info
    return _key(info.name, info.vendor_id, info.device_id, info.driver_version)


def _key(name: str, vendor_id: int, device_id: int, driver_version: int) -> str:
    return f"{name} [{vendor_id:04x}:{device_id:04x}] driver {driver_version} shaders {_shaders_digest()}"


def recorded(cache_dir: str | Path, device: dict) -> dict | None:
    """The record for one of `vkpbr info`'s devices (its report's dict) in `cache_dir`."""
    key = _key(device["name"], device["vendor_id"], device["device_id"], device["driver_version"])
    return _valid(_read(Path(cache_dir) / CACHE_FILE).get(key))


@functools.cache
def _shaders_digest() -> str:
    """sha1 of the SPIR-V vkpbr runs (src/vkpbr/shaders/spv), first 12 hex digits."""
    digest = hashlib.sha1()
    for path in sorted((Path(__file__).resolve().parent.parent / "shaders" / "spv").glob("*.spv")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def _candidates(renderer: Renderer) -> list[PathChoice]:
    out = [PathChoice(False, False, True), PathChoice(True, False, True)]
    if renderer.device.compute_raster:
        out.append(PathChoice(True, True, True))
    return out


def measure(renderer: Renderer, size: tuple[int, int]) -> dict[str, Any]:
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


def resolve(renderer: Renderer, size: tuple[int, int], cache_dir: str | Path | None) -> PathChoice:
    """The recorded choice for this device, else measure now (and record it)."""
    key = device_key(renderer)
    path = Path(cache_dir) / CACHE_FILE if cache_dir is not None else None
    records = _read(path) if path is not None else _in_process
    record = _valid(records.get(key))
    choice = _from_label(record["choice"], True) if record is not None else None
    if choice is not None and (not choice.compute_raster or renderer.device.compute_raster):
        return choice
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
