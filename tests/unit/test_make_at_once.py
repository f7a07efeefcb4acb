"""gpu/compute.py `make_at_once`: a signal's exception in the calling thread (Ctrl-C, the
CLI's SIGTERM raising `Terminated`) propagates only after the makers under way have ended:
a renderer closed next must not destroy its device under a thread still compiling (on the
H200 a SIGTERM during a cold first frame's compiles had ended `vkpbr render` in SIGSEGV)."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from vkpbr.gpu import compute


def test_an_interrupt_waits_for_the_makers_under_way(monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setattr(compute, "KERNEL_THREADS", 2)
    # (Python's own Ctrl-C handler, as in a terminal: a run started in the background of a
    # script inherits SIGINT ignored, and then nothing would be raised)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    began, ended = threading.Event(), threading.Event()

    def slow() -> str:
        began.set()
        time.sleep(0.5)
        ended.set()
        return "slow"

    def interrupt() -> None:
        began.wait(5)
        time.sleep(0.1)  # (the caller is waiting for the makers by now)
        os.kill(os.getpid(), signal.SIGINT)  # (Python runs the handler in the main thread)

    threading.Thread(target=interrupt, daemon=True).start()
    try:
        with pytest.raises(KeyboardInterrupt):
            compute.make_at_once([slow, lambda: "quick"])
    finally:
        signal.signal(signal.SIGINT, previous)
    assert ended.is_set(), "the interrupt propagated while a maker was still running"


def test_results_come_in_the_makers_order(monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setattr(compute, "KERNEL_THREADS", 3)
    makers = [lambda i=i: (time.sleep(0.01 * (5 - i)), i)[1] for i in range(5)]
    assert compute.make_at_once(makers) == list(range(5))


@pytest.mark.parametrize("given,want", [("1", 1), ("12", 12), (" 3 ", 3), ("0", None),
                                        ("-2", None), ("abc", None), ("2.5", None), ("", None)])
def test_kernel_threads_from_the_environment(monkeypatch, given: str, want: int | None) -> None:  # noqa: ANN001
    """VKPBR_KERNEL_THREADS as a benchmark sets it; anything but a positive whole number
    leaves the default (2 to 8 by the cores), never an error at import."""
    monkeypatch.setenv("VKPBR_KERNEL_THREADS", given)
    default = max(2, min(8, os.cpu_count() or 1))
    assert compute._kernel_threads() == (default if want is None else want)


def test_makers_that_make_at_once_themselves_finish(monkeypatch) -> None:  # noqa: ANN001
    """Makers on every kept thread, each making at once again (an environment's kernels
    made inside a step's maker): they make in their own threads, nothing waits for ever."""
    monkeypatch.setattr(compute, "KERNEL_THREADS", 2)
    inner = [lambda i=i: i for i in range(3)]
    outer = [lambda: compute.make_at_once(inner) for _ in range(4)]
    done: list = []
    t = threading.Thread(target=lambda: done.append(compute.make_at_once(outer)), daemon=True)
    t.start()
    t.join(10)
    assert done == [[[0, 1, 2]] * 4]
