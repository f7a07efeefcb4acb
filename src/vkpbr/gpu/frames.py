"""The frame ring: frames in flight, defined once for every target.

Each `Frame` owns what one frame needs while the GPU works on it (vkguide's FrameData): a
fence, an image-available semaphore (used by swapchain targets), a row of timestamp queries,
and an index that render/ uses for its per-frame uniforms and that targets use for their
per-frame readback buffers. `FrameRing.begin` hands out the frames in turn, first waiting
for the frame's previous submission, so whatever a frame owns can be rewritten once it is
handed out. The fence is reset only just before a submit: a frame given up before its
submit (an out-of-date swapchain) leaves it signalled, and nothing can deadlock on it.

The hot path (wait, reset, submit, timestamps) calls the C entry points through `vulkan.lib`
with structs built once: the binding's wrappers cost 10-100 us a call (vulkan-python.md).
"""

from __future__ import annotations

import math
from typing import Any

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.vk import check_result

__all__ = ["FRAMES_IN_FLIGHT", "Frame", "FrameRing"]

FRAMES_IN_FLIGHT = 3  # the one definition: offscreen batches, the viewer, swapchains


class Frame:
    """One slot of the ring. `index` is stable (0..count-1); `number` counts submissions."""

    def __init__(self, device: Device, index: int, query_base: int, queries: int) -> None:
        vk = device.vk
        ffi = vk.ffi
        self.device, self.index = device, index
        self.query_base, self.queries = query_base, queries
        signalled = vk.VkFenceCreateInfo(flags=vk.VK_FENCE_CREATE_SIGNALED_BIT)
        self.fence = vk.vkCreateFence(device.handle, signalled, None)
        self.acquired = vk.vkCreateSemaphore(device.handle, vk.VkSemaphoreCreateInfo(), None)
        self.fences = ffi.new("VkFence[1]", [self.fence])
        self.number = -1  # the ring's frame number of the last submission from this slot
        self.finished = True  # its last submission is known to have finished (waited)
        self.stamped = False  # the last submission wrote this frame's timestamps
        self.stamp_names: tuple[str, ...] = ()  # what its timestamps 1.. follow (the steps)
        # Submit info built once; `submit` fills in the command buffer and semaphores.
        self._cmds = ffi.new("VkCommandBuffer[1]")
        self._wait = ffi.new("VkSemaphore[1]")
        self._signal = ffi.new("VkSemaphore[1]")
        self._stage = ffi.new("VkPipelineStageFlags[1]",
                              [vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT])
        self._submit = ffi.new("VkSubmitInfo*", {
            "sType": vk.VK_STRUCTURE_TYPE_SUBMIT_INFO, "commandBufferCount": 1,
            "pCommandBuffers": self._cmds, "pWaitSemaphores": self._wait,
            "pWaitDstStageMask": self._stage, "pSignalSemaphores": self._signal})
        # Timeline values (gpu/timeline.py: semaphores shared with CUDA), chained when given.
        self._values = ffi.new("uint64_t[2]")
        self._timeline = ffi.new("VkTimelineSemaphoreSubmitInfo*", {
            "sType": vk.VK_STRUCTURE_TYPE_TIMELINE_SEMAPHORE_SUBMIT_INFO,
            "pWaitSemaphoreValues": self._values, "pSignalSemaphoreValues": self._values + 1})
        self._stages = (vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                        vk.VK_PIPELINE_STAGE_ALL_COMMANDS_BIT)
        self._mode: tuple | None = None  # submit's (wait, signal, no values) last filled in

    def wait(self) -> None:
        """Block until this frame's last submission has finished on the GPU."""
        if self.finished:
            return  # waited already: no driver call (they cost microseconds each)
        self.device.wait_fences(self.fences, "a frame")
        self.finished = True

    def submit(self, cmd: Commands, wait: Any = None, signal: Any = None,
               values: tuple[int, int] | None = None) -> None:
        """Submit `cmd`, signalling this frame's fence; optionally waiting on `wait` (at the
        colour-output stage) and signalling `signal` (semaphores of a swapchain), or with
        `values` (wait value, signal value) two timeline semaphores (gpu/timeline.py: the
        wait before any command)."""
        lib = self.device.vk.lib
        result = lib.vkResetFences(self.device.handle, 1, self.fences)
        if result:  # (check_result only for an error: a call less a step)
            check_result(result, "vkResetFences")
        self._cmds[0] = cmd.handle
        mode = (wait, signal, values is None)
        if mode != self._mode:  # (a loop's steps submit alike: the struct as it was left)
            self._fill(wait, signal, values is not None)
            self._mode = mode
        if values is not None:  # (only the timeline values change step to step)
            self._values[0], self._values[1] = values
        self.finished = False
        result = lib.vkQueueSubmit(self.device.queue, 1, self._submit, self.fence)
        if result:
            check_result(result, "vkQueueSubmit")

    def _fill(self, wait: Any, signal: Any, timeline: bool) -> None:
        """The submit info's semaphores, stage and chain for `submit`'s arguments."""
        info = self._submit
        info.waitSemaphoreCount = 0 if wait is None else 1
        info.signalSemaphoreCount = 0 if signal is None else 1
        if wait is not None:
            self._wait[0] = wait
        if signal is not None:
            self._signal[0] = signal
        if not timeline:
            info.pNext = self.device.vk.ffi.NULL
            self._stage[0] = self._stages[0]
        else:
            t = self._timeline
            t.waitSemaphoreValueCount = info.waitSemaphoreCount
            t.signalSemaphoreValueCount = info.signalSemaphoreCount
            info.pNext = t
            self._stage[0] = self._stages[1]

    def destroy(self) -> None:
        vk, dev = self.device.vk, self.device.handle
        if self.fence is not None:
            vk.vkDestroyFence(dev, self.fence, None)
            vk.vkDestroySemaphore(dev, self.acquired, None)
            self.fence = self.acquired = None


class FrameRing:
    """`count` frames used in turn, and one timestamp query pool with `queries_per_frame`
    queries per frame (two for the frame's start and end, the rest for pass boundaries)."""

    def __init__(self, device: Device, count: int = FRAMES_IN_FLIGHT,
                 queries_per_frame: int = 2) -> None:
        vk = device.vk
        self.device = device
        self.count, self.queries_per_frame = count, queries_per_frame
        self.number = 0  # frames begun so far
        self.query_pool = None
        if device.timestamps:
            self.query_pool = vk.vkCreateQueryPool(device.handle, vk.VkQueryPoolCreateInfo(
                queryType=vk.VK_QUERY_TYPE_TIMESTAMP, queryCount=count * queries_per_frame), None)
        # One results array a frame: frames are read on several collector threads at once
        # (render/frame_path.py COLLECTORS), and the C call that fills it releases the GIL.
        self._stamps = [vk.ffi.new("uint64_t[]", queries_per_frame) for _ in range(count)]
        self._period_ms = float(device.limits.timestampPeriod) * 1e-6
        self.frames = [Frame(device, i, i * queries_per_frame, queries_per_frame)
                       for i in range(count)]
        device.track(self)

    def begin(self) -> Frame:
        """The next frame, once its previous submission has finished."""
        frame = self.frames[self.number % self.count]
        frame.wait()
        frame.number = self.number
        self.number += 1
        return frame

    def wait_all(self) -> None:
        for frame in self.frames:
            frame.wait()

    def restart(self) -> None:
        """Start over as a new ring would (every frame waited for first): frame numbers from
        0, no earlier submission's timestamps (a renderer's next scene keeps its ring)."""
        self.wait_all()
        self.number = 0
        for frame in self.frames:
            frame.number, frame.stamped, frame.stamp_names = -1, False, ()

    # --- timestamps -------------------------------------------------------------------------
    def stamp(self, cmd: Commands, frame: Frame, slot: int) -> None:
        """Record timestamp `slot` of `frame` (0 = start: also resets the frame's queries)."""
        if self.query_pool is None or slot >= frame.queries:
            return
        if slot == 0:
            cmd.reset_queries(self.query_pool, frame.query_base, frame.queries)
        cmd.timestamp(self.query_pool, frame.query_base + slot, after_all=slot != 0)

    def timings_ms(self, frame: Frame, slots: int) -> list[float]:
        """Milliseconds from timestamp 0 to each of timestamps 1..slots-1 of `frame`'s last
        submission (call after it finished); NaNs without timestamps."""
        if self.query_pool is None or not frame.stamped or slots < 2:
            return [math.nan] * max(slots - 1, 0)
        vk, stamps = self.device.vk, self._stamps[frame.index]
        result = vk.lib.vkGetQueryPoolResults(
            self.device.handle, self.query_pool, frame.query_base, slots, 8 * slots,
            stamps, 8, vk.VK_QUERY_RESULT_64_BIT)
        if result != vk.VK_SUCCESS:
            check_result(result, "vkGetQueryPoolResults")  # VK_NOT_READY raises as well
        t0 = stamps[0]
        return [(stamps[i] - t0) * self._period_ms for i in range(1, slots)]

    # --- lifetime ---------------------------------------------------------------------------
    def destroy(self) -> None:
        if self.frames is None:
            return
        self.device.wait_idle()
        for frame in self.frames:
            frame.destroy()
        self.frames = None  # type: ignore[assignment]
        if self.query_pool is not None:
            self.device.vk.vkDestroyQueryPool(self.device.handle, self.query_pool, None)
            self.query_pool = None
        self.device.untrack(self)
