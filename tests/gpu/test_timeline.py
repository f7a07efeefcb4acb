"""Timeline semaphores on a frame's submission (gpu/timeline.py, Frame.submit(values=...)):
what a batch shared with CUDA does, here with the host in CUDA's place. A submission waiting
for value 1 does not run before the host signals 1, then signals its own value; under
synchronization validation. (Exporting to CUDA needs VK_KHR_external_semaphore_fd and an
NVIDIA GPU: tests/gpu/test_worlds_cuda.py.)"""

from __future__ import annotations

import time

import pytest

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.timeline import SharedTimeline


def test_a_submission_waits_for_and_signals_timeline_values(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer()
    if not r.device.timeline_semaphores:
        pytest.skip(f"{r.device.info.name} has no timeline semaphores")
    inputs, done = SharedTimeline(r.device, exportable=False), SharedTimeline(r.device, exportable=False)
    try:
        frame = r.ring.begin()
        cmd = Commands(r.device).begin()
        cmd.end()
        frame.submit(cmd, wait=inputs.handle, signal=done.handle, values=(1, 7))
        time.sleep(0.2)
        assert done.value() == 0, "the submission ran before its wait value was signalled"
        inputs.signal(1)
        frame.wait()
        # (lavapipe under load published the value once after the submission's fence, which
        # the spec orders after it: one fresh-clone suite run in seven; polled briefly here)
        deadline = time.monotonic() + 2.0
        while done.value() != 7 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert done.value() == 7
        frame.submit(cmd, values=None)  # and plain again: no timeline chained
        frame.wait()
        cmd.free()
    finally:
        r.device.wait_idle()
        inputs.destroy()
        done.destroy()
