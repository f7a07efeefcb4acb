"""The actor's encoding gate (distributed/actor.py EncodeGate): at most its limit inside at
once, the limit asked again while callers wait (an actor lets 2 files encode while a scene
loads ahead, all its encoders otherwise)."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

from vkpbr.distributed.actor import EncodeGate


def _run(gate: EncodeGate, tasks: int, workers: int, seconds: float = 0.01) -> list[int]:
    """Each task notes how many were inside with it; returns those counts."""
    inside, seen, lock = [0], [], threading.Lock()

    def task() -> None:
        with gate:
            with lock:
                inside[0] += 1
                seen.append(inside[0])
            time.sleep(seconds)
            with lock:
                inside[0] -= 1

    with ThreadPoolExecutor(workers) as pool:
        for f in [pool.submit(task) for _ in range(tasks)]:
            f.result()
    return seen


def test_at_most_the_limit_inside() -> None:
    seen = _run(EncodeGate(lambda: 3), tasks=24, workers=8)
    assert max(seen) == 3 and len(seen) == 24


def test_a_risen_limit_lets_waiting_callers_in() -> None:
    limit = [1]
    gate = EncodeGate(lambda: limit[0])
    threading.Timer(0.05, lambda: limit.__setitem__(0, 6)).start()  # as a load ahead ends
    seen = _run(gate, tasks=40, workers=8)
    assert seen[:3] == [1, 1, 1] and max(seen) == 6
