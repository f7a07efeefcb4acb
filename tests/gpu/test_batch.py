"""Batch rendering (issue 6): frames in flight give exactly the single-frame images."""

from __future__ import annotations

import dataclasses

import numpy as np


def orbit(camera, n: int):  # noqa: ANN001, ANN201
    eye = np.asarray(camera.eye, float)
    target = np.asarray(camera.target, float)
    out = []
    for i in range(n):
        a = np.radians(12.0 * i)
        d = eye - target
        rotated = (d[0] * np.cos(a) + d[2] * np.sin(a), d[1], -d[0] * np.sin(a) + d[2] * np.cos(a))
        out.append(dataclasses.replace(camera, eye=tuple(target + rotated)))
    return out


def test_render_many_equals_single_renders(make_renderer) -> None:
    r = make_renderer()
    cameras = orbit(r.default_camera(), 7)  # more frames than slots: every slot is reused
    batch = list(r.render_many(cameras, size=(80, 60)))
    singles = [r.render(c, size=(80, 60)) for c in cameras]
    assert len(batch) == len(cameras)
    for i, (a, b) in enumerate(zip(batch, singles, strict=True)):
        assert np.array_equal(a, b), f"frame {i} differs"
    assert not np.array_equal(batch[0], batch[3])  # the cameras really differ


def test_render_many_depth_linear_and_options(make_renderer) -> None:
    r = make_renderer()
    cameras = orbit(r.default_camera(), 4)
    out = list(r.render_many(cameras, size=(64, 48), linear=True, depth=True, view="f"))
    for (color, depth), cam in zip(out, cameras, strict=True):
        c1, d1 = r.render(cam, size=(64, 48), linear=True, depth=True, view="f")
        assert color.dtype == np.float32 and np.array_equal(color, c1)
        assert np.array_equal(depth, d1)


def test_abandoned_batch_leaves_renderer_usable(make_renderer) -> None:
    r = make_renderer()
    cameras = orbit(r.default_camera(), 6)
    frames = r.render_many(cameras, size=(48, 32))
    first = next(frames)
    frames.close()  # frames 2-3 were still queued on the GPU
    assert np.array_equal(first, r.render(cameras[0], size=(48, 32)))
    assert len(list(r.render_many(cameras, size=(48, 32)))) == 6
