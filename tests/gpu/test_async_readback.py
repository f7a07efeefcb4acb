"""Frames read back on the device's copy engine (gpu/target.py "async readback"): where the
device has a transfer-only queue family, a frame's pixels reach the host through a device-
local twin and the transfer queue; what the user gets must be what the graphics queue's own
copy gives (VKPBR_ASYNC_READBACK=0), byte for byte, for render(), render_many (frames in
flight) and a batch into NumPy, with depth and the dataset outputs, validation on."""

from __future__ import annotations

import numpy as np
import pytest

from vkpbr.gpu.device import Device
from vkpbr.scene.types import Camera


def _has_copy_engine() -> bool:
    with Device() as dev:
        return dev.transfer_queue is not None


pytestmark = pytest.mark.skipif(not _has_copy_engine(),
                                reason="this device has no transfer-only queue family (lavapipe "
                                       "has one family): its frames read back on the graphics queue")

CAMERAS = [Camera(eye=(2.5 * np.cos(a), 1.2, 2.5 * np.sin(a)), target=(0.0, 0.3, 0.0))
           for a in np.linspace(0.0, 2.0, 5)]


def _frames(renderer) -> list:  # noqa: ANN001
    size = (96, 64)
    one = [renderer.render(c, size=size, depth=True) for c in CAMERAS[:2]]
    many = list(renderer.render_many(CAMERAS, size=size, outputs=["depth", "normals", "ids"]))
    batch = renderer.render_batch(CAMERAS, (48, 32))
    return [*one, *many, batch]


def _equal(a, b) -> None:  # noqa: ANN001
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            _equal(a[k], b[k])
    elif isinstance(a, tuple):
        for x, y in zip(a, b, strict=True):
            _equal(x, y)
    else:
        np.testing.assert_array_equal(a, b)


def test_frames_through_the_copy_engine_equal_the_graphics_queues(make_renderer, monkeypatch) -> None:  # noqa: ANN001
    on = make_renderer()
    assert on.device.transfer_queue is not None
    got = _frames(on)
    monkeypatch.setenv("VKPBR_ASYNC_READBACK", "0")
    off = make_renderer()
    assert off.device.transfer_queue is None
    want = _frames(off)
    assert len(got) == len(want)
    for a, b in zip(got, want, strict=True):
        _equal(a, b)
    assert np.ptp(want[0][0]) > 0, "the frames are blank (test is moot)"
