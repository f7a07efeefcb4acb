"""render_many's stream (render/frame_path.py FramePath.stream): from its second frame on, each
frame is collected (waited for, copied into NumPy) on the device's collector thread while the
next is drawn. What a user must not see change: the frames, their order and their stats, the
abandoned generator's clean-up, errors in the middle of a stream; and a single `render()`
makes no thread. On lavapipe with the validation layer (synchronization validation too)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.render import frame_path
from vkpbr.scene.camera import Camera
from vkpbr.scene.default import default_scene

SIZE = (48, 36)


def cameras(n: int) -> list[Camera]:
    """`n` views around the default scene, each its own image."""
    out = []
    for i in range(n):
        a = 2 * np.pi * i / n
        out.append(Camera(eye=(3.0 * np.sin(a), 0.6 + 0.2 * i, 3.0 * np.cos(a)), target=(0.0, 0.2, 0.0)))
    return out


def collecting(r) -> list:  # noqa: ANN001
    """The collects of `r`'s streams not finished (the device's collector thread's work)."""
    return [f for f in r.device._background_work if not f.done()]


def collector(r) -> object:  # noqa: ANN001
    """`r`'s device's collector pool (None before a stream needed it)."""
    return r.device._background.get("collect")


@pytest.fixture(scope="module")
def scene():  # noqa: ANN201
    s = default_scene()
    return dataclasses.replace(s, nodes=[s.nodes[0], s.nodes[7], s.nodes[-3]])


@pytest.fixture(params=[1, 2, 3])
def collectors(request, monkeypatch) -> int:  # noqa: ANN001
    """The stream's collector threads: one (machines of fewer than 4 cores) or several
    collecting frames side by side (frame_path.COLLECTORS), whatever this machine's count."""
    monkeypatch.setattr(frame_path, "COLLECTORS", request.param)
    return request.param


def test_streamed_frames_are_each_cameras_render(make_renderer, scene, collectors: int) -> None:  # noqa: ANN001
    """Seven views through render_many (colour, depth and the dataset outputs), against
    render() of each: bit for bit, in order, each frame's own stats; with one collector
    thread and with several (the frames handed back in order however their collects end)."""
    r = make_renderer(scene)
    cams = cameras(7)
    alone = [r.render(c, size=SIZE, depth=True, outputs=["normal", "instance"]) for c in cams]
    streamed = []
    for got in r.render_many(cams, size=SIZE, depth=True, outputs=["normal", "instance"]):
        streamed.append(got)
        assert r.last_stats.gpu_ms == r.last_stats.gpu_ms  # (not NaN: its own timestamps)
    assert len(streamed) == len(cams)
    assert collector(r)._max_workers == collectors  # (the second frame on collected there)
    for i, (a, b) in enumerate(zip(alone, streamed, strict=True)):
        assert a.keys() == b.keys()
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"view {i}: {name}")
    assert not collecting(r)


def test_an_abandoned_stream_leaves_nothing_running(make_renderer, scene, collectors) -> None:  # noqa: ANN001
    """Two frames taken of six, the generator closed: none of its collects is left, and the
    next frames are right."""
    r = make_renderer(scene)
    cams = cameras(6)
    stream = r.render_many(cams, size=SIZE)
    first = [next(stream), next(stream)]
    assert collector(r) is not None  # (the second frame on: collected on the device's thread)
    stream.close()
    assert not collecting(r)
    np.testing.assert_array_equal(first[1], r.render(cams[1], size=SIZE))
    np.testing.assert_array_equal(next(iter(r.render_many(cams[4:], size=SIZE))),
                                  r.render(cams[4], size=SIZE))


def test_an_error_mid_stream_ends_it_cleanly(make_renderer, scene, collectors) -> None:  # noqa: ANN001
    """A bad third camera: the first two frames come, then its one-line error; nothing left
    running, and the renderer renders on."""
    r = make_renderer(scene)
    cams = cameras(3)
    got = []
    with pytest.raises(UsageError):
        for frame in r.render_many([cams[0], cams[1], "not a camera", cams[2]], size=SIZE):
            got.append(frame)
    assert len(got) <= 2
    assert not collecting(r)
    np.testing.assert_array_equal(r.render(cams[2], size=SIZE),
                                  list(r.render_many(cams, size=SIZE))[2])


def test_one_frame_makes_no_thread(make_renderer, scene) -> None:  # noqa: ANN001
    """render() (a stream of one frame) and a stream without readback hand nothing to a
    thread: only streams of two frames or more into NumPy use the device's collector."""
    r = make_renderer(scene)
    r.render(size=SIZE)
    for _ in r.render_many(cameras(4), size=SIZE, readback=False):
        pass
    assert collector(r) is None
    list(r.render_many(cameras(2), size=SIZE))
    assert collector(r) is not None


def test_a_renderer_closed_under_an_open_stream(make_renderer, scene, collectors) -> None:  # noqa: ANN001
    """A stream left open (frames queued on the collector) and its renderer closed: the
    close finishes the collect under way and drops the rest, and the stream, closed after,
    waits for nothing: no crash, no validation error (the fixture checks the layer's)."""
    r = make_renderer(scene)
    stream = r.render_many(cameras(6), size=SIZE)
    next(stream)
    r.close()
    assert r.device.handle is None
    stream.close()


def test_waiting_for_the_background_after_its_collects_were_dropped(make_renderer, scene) -> None:  # noqa: ANN001
    """A collect under way and one queued, the collector stopped (a scene's unmaking): the
    queued one is dropped, and waiting for the device's background returns."""
    import threading

    r = make_renderer(scene)
    release = threading.Event()
    r.device.in_background(lambda: release.wait(5), 1, "collect")
    queued = r.device.in_background(lambda: None, 1, "collect")
    threading.Timer(0.2, release.set).start()
    r.device.stop_background("collect")
    assert queued.cancelled()
    waited = threading.Thread(target=r.device.wait_background, daemon=True)
    waited.start()
    waited.join(5)
    assert not waited.is_alive(), "wait_background waited for a dropped collect"


def test_collectors_read_their_own_frames_timestamps(make_renderer, scene) -> None:  # noqa: ANN001
    """Several collector threads read timestamps at once (FrameRing.timings_ms: a C call
    that releases the GIL fills a results array): each frame's times must be its own. Three
    frames of different sizes drawn into the ring's three slots, then each read 3,000 times
    on its own thread: every read equals the frame's value read alone."""
    import threading

    r = make_renderer(scene)
    ring = r.parts.ring
    if ring.query_pool is None:
        pytest.skip(f"{r.device.info.name} has no timestamp queries")
    sizes = [(8, 8), (96, 72), (32, 24)]
    for size, camera in zip(sizes, cameras(3), strict=True):
        r.render(camera, size=size)  # (one slot each: the ring's frames in turn)
    frames = [f for f in ring.frames if f.stamped]
    alone = [ring.timings_ms(f, len(f.stamp_names) + 1) for f in frames]
    wrong: list[int] = []

    def read(i: int) -> None:
        for _ in range(3000):
            if ring.timings_ms(frames[i], len(frames[i].stamp_names) + 1) != alone[i]:
                wrong.append(i)

    threads = [threading.Thread(target=read, args=(i,)) for i in range(len(frames))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(frames) == ring.count and len({tuple(a) for a in alone}) > 1
    assert not wrong, f"{len(wrong)} reads got another frame's timestamps"


def test_an_open_stream_keeps_its_target_through_other_sizes(make_renderer, scene, monkeypatch) -> None:  # noqa: ANN001
    """Frames of other sizes rendered between a stream's frames: the renderer keeps targets
    of a few sizes (render/targets.py TARGETS_KEPT, here 1) and destroys the least recently
    used, but never one an open stream draws into; the stream's frames are still each
    camera's render."""
    from vkpbr.render import targets

    monkeypatch.setattr(targets, "TARGETS_KEPT", 1)
    r = make_renderer(scene)
    cams = cameras(4)
    stream = r.render_many(cams, size=SIZE)
    got = [next(stream)]
    for k, size in enumerate([(40, 30), (56, 40), (32, 32)]):
        r.render(cams[k], size=size)
        got.append(next(stream))
    assert len(r.targets._kept) == 2  # (the stream's and the last one's)
    for i, frame in enumerate(got):
        np.testing.assert_array_equal(frame, r.render(cams[i], size=SIZE), err_msg=f"view {i}")


def test_frames_rendered_inside_a_stream_wait_for_its_copies(make_renderer, scene, monkeypatch) -> None:  # noqa: ANN001
    """`render()` of the stream's own size between its frames takes the ring's next slot,
    whose frame a collector thread may still be copying out (here made slow): it waits for
    that copy before drawing into the slot, so the stream's frames stay each camera's
    render."""
    import time

    collect = frame_path.FramePath.collect

    def slow(self, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        if kwargs.get("split", True) is False or (len(args) > 6 and args[6] is False):
            time.sleep(0.25)  # (a collector thread's copy: the stream's second frame on)
        return collect(self, *args, **kwargs)

    r = make_renderer(scene)
    cams = cameras(6)
    want = [r.render(c, size=SIZE) for c in cams]
    monkeypatch.setattr(frame_path.FramePath, "collect", slow)
    got = []
    for i, frame in enumerate(r.render_many(cams, size=SIZE)):
        got.append(frame)
        r.render(cams[(i + 2) % len(cams)], size=SIZE)  # (into the slot of a frame being read)
    for i, frame in enumerate(got):
        np.testing.assert_array_equal(frame, want[i], err_msg=f"view {i}")
