"""render_many's stream (render/frame_path.py FramePath.stream): from its second frame on, each
frame is collected (waited for, copied into NumPy) on a thread of the stream's own while the
next is drawn. What a user must not see change: the frames, their order and their stats, the
abandoned generator's clean-up, errors in the middle of a stream; and a single `render()`
makes no thread. On lavapipe with the validation layer (synchronization validation too)."""

from __future__ import annotations

import dataclasses
import threading

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


MADE: list[frame_path.ThreadPoolExecutor] = []  # the streams' collectors, as each test made them


@pytest.fixture(autouse=True)
def made(monkeypatch: pytest.MonkeyPatch) -> list:
    """The collectors the streams of the test make (frame_path's ThreadPoolExecutor, counted)."""
    MADE.clear()

    class Counted(frame_path.ThreadPoolExecutor):
        def __init__(self, *args, **kwargs) -> None:  # noqa: ANN002, ANN003
            MADE.append(self)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(frame_path, "ThreadPoolExecutor", Counted)
    return MADE


def collectors() -> list[threading.Thread]:
    """The test's collectors' threads still running."""
    return [t for ex in MADE for t in list(ex._threads) if t.is_alive()]


@pytest.fixture(scope="module")
def scene():  # noqa: ANN201
    s = default_scene()
    return dataclasses.replace(s, nodes=[s.nodes[0], s.nodes[7], s.nodes[-3]])


def test_streamed_frames_are_each_cameras_render(make_renderer, scene) -> None:  # noqa: ANN001
    """Seven views through render_many (colour, depth and the dataset outputs), against
    render() of each: bit for bit, in order, each frame's own stats."""
    r = make_renderer(scene)
    cams = cameras(7)
    alone = [r.render(c, size=SIZE, depth=True, outputs=["normal", "instance"]) for c in cams]
    streamed = []
    for got in r.render_many(cams, size=SIZE, depth=True, outputs=["normal", "instance"]):
        streamed.append(got)
        assert r.last_stats.gpu_ms == r.last_stats.gpu_ms  # (not NaN: its own timestamps)
    assert len(streamed) == len(cams)
    for i, (a, b) in enumerate(zip(alone, streamed, strict=True)):
        assert a.keys() == b.keys()
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"view {i}: {name}")
    assert not collectors()


def test_an_abandoned_stream_leaves_nothing_running(make_renderer, scene) -> None:  # noqa: ANN001
    """Two frames taken of six, the generator closed: its collector is gone, and the next
    frames are right."""
    r = make_renderer(scene)
    cams = cameras(6)
    stream = r.render_many(cams, size=SIZE)
    first = [next(stream), next(stream)]
    assert collectors()  # (the second frame on: collected on the stream's thread)
    stream.close()
    assert not collectors()
    np.testing.assert_array_equal(first[1], r.render(cams[1], size=SIZE))
    np.testing.assert_array_equal(next(iter(r.render_many(cams[4:], size=SIZE))),
                                  r.render(cams[4], size=SIZE))


def test_an_error_mid_stream_ends_it_cleanly(make_renderer, scene) -> None:  # noqa: ANN001
    """A bad third camera: the first two frames come, then its one-line error; nothing left
    running, and the renderer renders on."""
    r = make_renderer(scene)
    cams = cameras(3)
    got = []
    with pytest.raises(UsageError):
        for frame in r.render_many([cams[0], cams[1], "not a camera", cams[2]], size=SIZE):
            got.append(frame)
    assert len(got) <= 2
    assert not collectors()
    np.testing.assert_array_equal(r.render(cams[2], size=SIZE),
                                  list(r.render_many(cams, size=SIZE))[2])


def test_one_frame_makes_no_thread(make_renderer, scene, made) -> None:  # noqa: ANN001
    """render() (a stream of one frame) and a stream without readback hand nothing to a
    thread: only streams of two frames or more into NumPy make one."""
    r = make_renderer(scene)
    r.render(size=SIZE)
    for _ in r.render_many(cameras(4), size=SIZE, readback=False):
        pass
    assert made == []
    list(r.render_many(cameras(2), size=SIZE))
    assert len(made) == 1
