"""One Renderer shared by several threads (a web server's handlers, a data loader's workers):
its frames, streams, batches and scene changes take the device one thread at a time
(gpu/device.py Device.lock), so every result is what the same call returns alone. Before,
two threads recorded into the device's one command pool and submitted to its one queue at
once: the validation layer's threading checks failed (a crash or wrong frames without it).
On lavapipe with the validation layer, whose threading checks see any overlap."""

from __future__ import annotations

import threading

import numpy as np
from test_batch import SIZE
from test_stream import cameras


def run_threads(work, count: int) -> list:  # noqa: ANN001
    """`work(k)` on `count` threads at once; what each raised (none expected)."""
    errors: list = []
    start = threading.Barrier(count)

    def one(k: int) -> None:
        try:
            start.wait()
            work(k)
        except Exception as exc:  # (reported, not lost in the thread)
            errors.append((k, repr(exc)[:300]))

    threads = [threading.Thread(target=one, args=(k,)) for k in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return errors


def test_threads_share_a_renderer(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer()
    cams = cameras(4)
    single = [r.render(c, size=SIZE) for c in cams]
    batch = r.render_batch(cams, SIZE)
    streamed = list(r.render_many(cams, size=(40, 30)))
    wrong: list = []

    def work(k: int) -> None:
        for i in range(4):
            if k == 0 and not np.array_equal(r.render(cams[i], size=SIZE), single[i]):
                wrong.append(("render", i))
            if k == 1 and not np.array_equal(r.render_batch(cams, SIZE), batch):
                wrong.append(("render_batch", i))
            if k == 2:
                got = list(r.render_many(cams, size=(40, 30)))
                if not all(np.array_equal(a, b) for a, b in zip(got, streamed, strict=True)):
                    wrong.append(("render_many", i))

    assert run_threads(work, 3) == []
    assert wrong == []
    assert r.device.instance.errors == []
