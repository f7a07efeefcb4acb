"""A batch ordered against torch's current stream on the GPU, with no host wait for CUDA.

`render_batch(worlds=<CUDA tensor>, device="cuda")` (docs/batch.md "Worlds") takes a
simulator's poses and gives frames back as torch tensors. `CudaOrder` orders each step on the
GPU with two timeline semaphores shared by Vulkan and CUDA (gpu/timeline.py, gpu/cuda.py):

    torch's stream:  wait done >= n-1 | copy the poses into the inputs | signal inputs = n
    Vulkan:          wait inputs >= n | the batch (worlds kernel first) | signal done = n
    torch's stream:  wait done >= n   | clone the frames into the tensor returned

so the copy never overwrites inputs the previous batch still reads, the batch never reads
inputs before they are written, the clone never reads frames before they are drawn, and the
next batch never draws over frames before the clone read them (it waits for inputs n + 1,
signalled after the clone). Python returns once the batch is submitted; the next call first
waits for this batch's fence (the host's own buffers of the batch are then free to rewrite).
A loop's next step on the same stream skips its first wait (done >= n, queued already by
the clone's wait: stream order): two CUDA semaphore calls a step, not three. With
batch_step(frames="view") there is no clone: what torch queues reading the frames before the
next call is ordered before its inputs' signal, so before the next batch draws.
"""

from __future__ import annotations

from vkpbr.gpu.device import Device
from vkpbr.gpu.timeline import SharedTimeline

__all__ = ["CudaOrder", "current_stream"]


def current_stream() -> int:
    """torch's current CUDA stream's handle on its current device. torch.cuda.current_stream()
    makes a Stream object through several Python calls (~10 us a step on the H200's host);
    torch._C._cuda_getCurrentRawStream, what Triton's launcher calls, gives the same handle
    in one (the public way where a torch lacks it)."""
    import torch

    raw = getattr(torch._C, "_cuda_getCurrentRawStream", None)
    if raw is None:
        return int(torch.cuda.current_stream().cuda_stream)
    return int(raw(torch._C._cuda_getDevice()))


class CudaOrder:
    """The two shared timelines of a renderer's CUDA-ordered batches and the step counter."""

    def __init__(self, device: Device) -> None:
        from vkpbr.gpu.cuda import CudaTimeline, cuda_device_for

        self.device = device
        self.inputs, self.done = SharedTimeline(device), SharedTimeline(device)
        index = cuda_device_for(device.uuid(), device.info.name)
        self._cuda_inputs = CudaTimeline(self.inputs.export_fd(), index)
        self._cuda_done = CudaTimeline(self.done.export_fd(), index)
        self.value = 0  # the last value signalled on either
        self._fresh = False  # inputs signalled for the next submission
        self._step_stream: int | None = None  # torch's stream of the step under way
        # (value, stream) the last frames_ready queued a wait for on `done`: the next step's
        # before_inputs on that stream, at that value, needs no second wait (stream order)
        self._ready_at: tuple[int, int] | None = None

    def _stream(self) -> int:
        """torch's current stream's handle, asked once a step (before_inputs: the step's
        calls are on the stream current then; current_stream() costs microseconds)."""
        if self._step_stream is None:
            self._step_stream = current_stream()
        return self._step_stream

    def before_inputs(self) -> None:
        """Queue on torch's stream: wait until the last batch is done (its inputs read)."""
        self._step_stream = None  # (a new step: the stream asked again)
        stream = self._stream()
        if self._ready_at != (self.value, stream):  # (else queued already: frames_ready)
            self._cuda_done.wait(self.value, stream)
        self._ready_at = None

    def inputs_written(self) -> None:
        """Queue on torch's stream: signal the next value once what is queued is done."""
        self.value += 1
        self._cuda_inputs.signal(self.value, self._stream())
        self._fresh = True

    def submit_values(self) -> tuple[int, int]:
        """(wait, signal) values of the next submission (a fresh value where the call's
        earlier submission used the last one)."""
        if not self._fresh:
            self.inputs_written()
        self._fresh = False
        return self.value, self.value

    def frames_ready(self) -> None:
        """Queue on torch's stream: wait until the submitted batch is done (before the
        frames' clone); the step's end (the next asks for the stream again)."""
        stream = self._stream()
        self._cuda_done.wait(self.value, stream)
        self._ready_at = (self.value, stream)
        self._step_stream = None

    def destroy(self) -> None:
        import torch

        self.device.wait_idle()
        torch.cuda.current_stream().synchronize()  # (its waits on `done` have returned)
        for c in (self._cuda_inputs, self._cuda_done):
            c.close()
        self.inputs.destroy()
        self.done.destroy()

    @classmethod
    def available(cls, device: Device) -> bool:
        return bool(getattr(device, "external_semaphore_fd", False))
