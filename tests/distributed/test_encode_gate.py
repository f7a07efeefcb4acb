"""The actor's encoding gate (distributed/actor.py EncodeGate): at most its limit inside at
once, the limit asked again while callers wait (an actor lets 2 files encode while a scene
loads ahead, all its encoders otherwise)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from vkpbr.distributed.actor import EncodeGate


def _run(gate: EncodeGate, tasks: int, workers: int, seconds: float = 0.05,
         done: Callable[[int], None] = lambda n: None) -> list[int]:
    """Each task notes how many were inside with it (then calls `done` with how many have
    finished); returns those counts in the order they entered."""
    inside, finished, seen, lock = [0], [0], [], threading.Lock()

    def task() -> None:
        with gate:
            with lock:
                inside[0] += 1
                seen.append(inside[0])
            time.sleep(seconds)  # (long enough for every waiting worker to look again)
            with lock:
                inside[0] -= 1
                finished[0] += 1
                done(finished[0])

    with ThreadPoolExecutor(workers) as pool:
        for f in [pool.submit(task) for _ in range(tasks)]:
            f.result()
    return seen


def test_at_most_the_limit_inside() -> None:
    seen = _run(EncodeGate(lambda: 3), tasks=24, workers=8)
    assert max(seen) == 3 and len(seen) == 24


def test_a_risen_limit_lets_waiting_callers_in() -> None:
    """The limit rises (as a load ahead ends) once 3 tasks have finished one at a time:
    the waiting workers, polling, come in up to the new limit."""
    limit = [1]
    gate = EncodeGate(lambda: limit[0])

    def rise(finished: int) -> None:
        if finished == 3:
            limit[0] = 6

    seen = _run(gate, tasks=40, workers=8, done=rise)
    assert seen[:3] == [1, 1, 1] and max(seen) == 6
