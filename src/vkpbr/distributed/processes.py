"""Renderer actors as processes of this machine, without Ray (`render(job, address=PROCESSES)`,
`vkpbr batch --processes N`).

One process renders a many-scene job at the rate its GIL allows: the thread that renders,
the thread that loads the next scene and the encoders all take turns in it, and a scene
change is ~150 ms of Python (docs/batch.md, "Many scenes"). Several processes on one GPU
each have their own GIL, device and scene; the driver hands them items as it hands Ray's
actors theirs (distributed/driver.py), so the files, manifests, retries and resumption are
the same.

A worker is `python -c WORKER` (app/render_worker.py) fed pickled requests on its stdin; it
answers on its own copy of the stdout it was given, and points its stdout at its stderr, so
that anything printed there (by Python or a Vulkan layer) cannot corrupt the answers. Not
multiprocessing's workers: its "spawn" imports the parent's `__main__` in every worker,
which runs a user's script again where it lacks a main guard, and "fork" would copy a
process that may hold a Vulkan device and threads. A worker ends when its stdin closes, so
one whose driver was killed ends too. Its diagnostics go to the driver's stderr, one line
each, at the driver's vkpbr log level.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import pickle
import signal
import subprocess
import sys
import threading
from concurrent.futures import FIRST_COMPLETED, Future, wait
from typing import IO

from vkpbr.distributed.job import RenderSettings, WorkItem

__all__ = ["ProcessActor", "ActorLost", "default_processes", "DEPTH", "WORKER"]

log = logging.getLogger(__name__)

# A worker's program (app/render_worker.py: a process's main, with the CLI's one-line
# diagnostics); -c, not -m: the package imports that module before runpy would
WORKER = "from vkpbr.app.render_worker import serve; serve()"
CLOSE_TIMEOUT_S = 30.0  # a worker asked to end that has not ended by then is killed
DEPTH = 2  # requests in flight a worker: the next one known while this one renders


class ActorLost(Exception):
    """A renderer process ended (killed, crashed, out of memory) with work in flight."""


def default_processes(items: int) -> int:
    """Renderer processes for a job of `items` work items: 3 for every 8 cores (each keeps a
    thread rendering, one loading and two encoding busy), 1 to 8, at most one an item. H200
    with 16 cores, 100 scenes x 16 views (benchmarks/results/h200-2026-12-04s19.md, run b):
    3, 4, 5, 6 processes 220, 251, 278, 291 views/s; one in this process 120."""
    return max(1, min(8, (os.cpu_count() or 2) * 3 // 8, items))


# --- the driver's side ---------------------------------------------------------------------
class ProcessActor:
    """One renderer process on `device` (None: the default): `render(item, ahead)` sends it
    an item and returns a Future of its result (ActorLost when the process ends first); a
    thread reads the answers."""

    def __init__(self, encoders: int, device: str | int | None = None,
                 name: str = "vkpbr-renderer") -> None:
        # (this process's import path, so that the worker finds the same vkpbr)
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
        level = logging.getLogger("vkpbr").getEffectiveLevel()
        argv = [sys.executable, "-c", WORKER, str(encoders), str(level),
                "" if device is None else str(device)]
        self.process = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        env=env)
        self._waiting: collections.deque[Future] = collections.deque()
        self._lock = threading.Lock()  # (the waiting futures, the requests, `_ended`)
        self._ended: str | None = None  # why no answer will come any more
        self._reader = threading.Thread(target=self._read, name=f"{name}-answers", daemon=True)
        self._reader.start()

    def render(self, item: WorkItem, ahead: RenderSettings | None) -> Future:
        """Send `item` (and the scene to load ahead); its result comes in the Future."""
        future: Future = Future()
        stdin: IO[bytes] | None = self.process.stdin
        with self._lock:
            if self._ended is not None:  # (its reader has finished: fail it here)
                future.set_exception(ActorLost(self._ended))
                return future
            self._waiting.append(future)
            try:
                assert stdin is not None
                pickle.dump((item, ahead), stdin, pickle.HIGHEST_PROTOCOL)
                stdin.flush()
            except (OSError, ValueError):  # the process is gone: the reader fails the future
                pass
        return future

    def _read(self) -> None:
        out = self.process.stdout
        assert out is not None
        while True:
            try:
                res = pickle.load(out)
            except EOFError:  # the process ended
                break
            except Exception:  # noqa: BLE001 - a torn or unreadable answer: end the process
                self.process.kill()  # (its futures fail below: no answer can be trusted)
                break
            with self._lock:
                future = self._waiting.popleft() if self._waiting else None
            if future is not None:
                future.set_result(res)
        code = self.process.wait()
        with self._lock:
            self._ended = f"its renderer process ended ({_status(code)})"
            lost, self._waiting = list(self._waiting), collections.deque()
        for future in lost:
            future.set_exception(ActorLost(self._ended))

    def kill(self) -> None:
        self.process.kill()
        self._reader.join(CLOSE_TIMEOUT_S)

    def close(self) -> None:
        """Ask the worker to end (its stdin closed), killed after CLOSE_TIMEOUT_S."""
        with contextlib.suppress(OSError, ValueError), self._lock:
            if self.process.stdin is not None:
                self.process.stdin.close()
        try:
            self.process.wait(CLOSE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
        self._reader.join(CLOSE_TIMEOUT_S)


def _status(code: int) -> str:
    """A process's end as words: "exit status 1", "killed by SIGKILL"."""
    if code < 0:
        with contextlib.suppress(ValueError):
            return f"killed by {signal.Signals(-code).name}"
    return f"exit status {code}"


def wait_one(futures: list[Future]) -> Future:
    """The first of `futures` to finish."""
    done, _ = wait(futures, return_when=FIRST_COMPLETED)
    return next(iter(done))
