"""Time every call into the Vulkan binding by function name, in this process (bench_load.py
--time-vk-calls runs each renderer process with it): which driver calls a process waits in,
and how that changes with several processes on one GPU.

    import vk_call_timer; vk_call_timer.install(folder)   # before vkpbr imports the binding

At exit the process writes `folder/<pid>.json`: {name: [calls, seconds]}. Calls made
through `vulkan.lib` directly are not seen: the frame's hot path (gpu/frames.py: submit,
fences, timestamps) and, since session 22, the commands a recording makes most
(gpu/commands.py: binds, pushes, dispatches, draws, fills, barriers).
"""

from __future__ import annotations

import atexit
import json
import os
import threading
import time
from pathlib import Path

_TIMES: dict[str, list[float]] = {}
_LOCK = threading.Lock()


def install(folder: str) -> None:
    """Wrap the binding's vk* functions (module attributes, as vkpbr reads them)."""
    import vulkan

    for name in dir(vulkan):
        fn = getattr(vulkan, name)
        if name.startswith("vk") and callable(fn) and not isinstance(fn, type):
            setattr(vulkan, name, _timed(name, fn))
    atexit.register(_write, Path(folder))


def _timed(name: str, fn):  # noqa: ANN001, ANN202
    def call(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        t = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            dt = time.perf_counter() - t
            with _LOCK:
                row = _TIMES.setdefault(name, [0, 0.0])
                row[0] += 1
                row[1] += dt
    return call


def _write(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{os.getpid()}.json").write_text(json.dumps(_TIMES))


def summary(folder: Path, items: int, top: int = 20) -> list[str]:
    """The calls that took longest over the processes' files in `folder`, per item."""
    total: dict[str, list[float]] = {}
    files = sorted(folder.glob("*.json"))
    for f in files:
        for name, (calls, seconds) in json.loads(f.read_text()).items():
            row = total.setdefault(name, [0, 0.0])
            row[0] += calls
            row[1] += seconds
    rows = sorted(total.items(), key=lambda kv: -kv[1][1])
    out = [f"{len(files)} processes; Vulkan calls an item ({items} items): "
           f"{sum(r[0] for _, r in rows) / items:.0f} calls, "
           f"{1000 * sum(r[1] for _, r in rows) / items:.1f} ms",
           "| call | calls an item | ms an item | us a call |", "|---|---:|---:|---:|"]
    for name, (calls, seconds) in rows[:top]:
        out.append(f"| {name} | {calls / items:.1f} | {1000 * seconds / items:.2f} | "
                   f"{1e6 * seconds / max(calls, 1):.1f} |")
    return out
