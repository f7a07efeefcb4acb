"""A swapchain stand-in without a window, for running the viewer's frame loop headless.

`vkpbr view --offscreen` draws into three sRGB images of a fixed size that are never shown:
on a GPU server with no display this measures the viewer's own loop (input replay, camera,
uniforms, HUD, command-buffer choice, submit) and its frame rate, with the same frame-slot
synchronisation as the real swapchain (gpu/swapchain.py) minus the semaphores that only the
presentation engine needs.
"""

from __future__ import annotations

from typing import Any

from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image
from vkpbr.gpu.swapchain import Swapchain
from vkpbr.gpu.vk import check_result

__all__ = ["OffscreenSwapchain"]

_IMAGES = 3


class OffscreenSwapchain(Swapchain):
    """Swapchain interface (acquire, submit_and_present, record_*) over offscreen images."""

    def __init__(self, device: Device, size: tuple[int, int]) -> None:
        vk = device.vk
        self._init_state(device, None, vsync=False)
        self.color_format, self.color_format_name = vk.VK_FORMAT_R8G8B8A8_SRGB, "R8G8B8A8_SRGB"
        self.present_mode_name = "offscreen"
        self.can_copy = True
        self._create_sync()
        # Nothing to wait for before drawing and nobody to signal after: no semaphores.
        self._submit.waitSemaphoreCount = 0
        self._submit.signalSemaphoreCount = 0
        self.recreate(size)

    def surface_size(self, window_size: tuple[int, int]) -> tuple[int, int]:
        return window_size

    def recreate(self, window_size: tuple[int, int]) -> bool:
        vk, device = self.device.vk, self.device
        device.wait_idle()
        self._destroy_swapchain()
        if 0 in window_size:
            return False
        w, h = window_size
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        colors = [self._own(Image(device, w, h, self.color_format, usage, name="offscreen frame"))
                  for _ in range(_IMAGES)]
        self.images = [c.handle for c in colors]
        self.handle, self.extent = "offscreen", (w, h)  # not None: "a swapchain exists"
        self._create_image_resources()
        self.generation += 1
        return True

    def _destroy_swapchain(self) -> None:
        self.handle = None  # no VkSwapchainKHR to destroy; the images are in _owned
        super()._destroy_swapchain()

    def acquire(self) -> int | None:
        """The next image in turn, once the frames that last used its slot and it are done."""
        self.wait_frame(self.slot)
        return self._claim(self.frame % len(self.images))

    def submit_and_present(self, cmd: Any, index: int) -> bool:
        lib, slot = self.device.vk.lib, self.slot
        check_result(lib.vkResetFences(self.device.handle, 1, self._fence_ptrs[slot]),
                     "vkResetFences")
        self._cmds[0] = cmd
        check_result(lib.vkQueueSubmit(self.device.queue, 1, self._submit, self._fences[slot]),
                     "vkQueueSubmit")
        self.frame += 1
        return True

    def record_end(self, cmd: Any, index: int) -> None:
        # No presentation engine to hand the image to; the next frame starts from UNDEFINED.
        self.device.vk.vkCmdEndRendering(cmd)
