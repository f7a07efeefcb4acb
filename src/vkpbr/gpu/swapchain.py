"""Window surface and swapchain: a frame target (gpu/target.py) that presents.

Frames in flight come from the frame ring (gpu/frames.py), as for offscreen targets: each
frame brings a fence and an image-available semaphore. Each swapchain image owns a depth
image and a render-finished semaphore (a present may still wait on it after the frame slot
comes round again), and remembers the frame that last drew into it, which `acquire` waits
for before the image is drawn into again (vulkan-tutorial's "images in flight").

The hot path (acquire, submit, present) calls the C entry points through `vulkan.lib` / raw
function pointers with pre-built structs: the binding's wrappers cost 10-100 us per call, and
they raise on VK_SUBOPTIMAL_KHR, which is a success code that still hands out an image
(vulkan-python.md, trap 10). Out-of-date and suboptimal swapchains are reported to the
caller, which calls `recreate`; a zero-sized (minimised) window has no swapchain at all until
it has a size again.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from vkpbr.errors import VkpbrError
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.frames import Frame
from vkpbr.gpu.graph import ImageResource, Step
from vkpbr.gpu.image import Image, ImageView
from vkpbr.gpu.rendering import Attachments, barriers, copy_image_to_buffer, host_read_barrier
from vkpbr.gpu.target import COPY_COLOR
from vkpbr.gpu.vk import check_result

__all__ = ["Surface", "Swapchain"]

_NO_TIMEOUT = 2**64 - 1
_SRGB_FORMATS = ("VK_FORMAT_B8G8R8A8_SRGB", "VK_FORMAT_R8G8B8A8_SRGB")


class Surface:
    """A VkSurfaceKHR made by `create(instance_handle, out)`, a window system's call that
    writes the surface into the VkSurfaceKHR* `out` and returns a VkResult (GLFW's
    `glfw.create_window_surface(instance, window, None, out)`). Owned by `device`, so it is
    destroyed before the instance."""

    def __init__(self, device: Device, create: Callable[[Any, Any], int]) -> None:
        vk = device.vk
        self.device = device
        out = vk.ffi.new("VkSurfaceKHR*")
        check_result(create(device.instance.handle, out), "glfwCreateWindowSurface")
        self.handle = out[0]
        device.track(self)
        supported = vk.vkGetInstanceProcAddr(
            device.instance.handle, "vkGetPhysicalDeviceSurfaceSupportKHR")(
                device.physical, device.queue_family, self.handle)
        if not supported:
            self.destroy()
            raise VkpbrError(f"{device.info.name}: its graphics queue cannot present to a window")

    def destroy(self) -> None:
        if self.handle is None:
            return
        handle, self.handle = self.handle, None
        inst = self.device.instance.handle
        self.device.vk.vkGetInstanceProcAddr(inst, "vkDestroySurfaceKHR")(inst, handle, None)
        self.device.untrack(self)


class Swapchain:
    """Swapchain images (sRGB, for the same bytes as the offscreen target) with a D32 depth
    image each. A FrameTarget: `generation` increases on each recreation."""

    samples = 1

    stores_depth = False  # nothing reads a window's depth after its frame
    depth_sampled = True  # ambient occlusion reads it within the frame (render/ao.py)

    def __init__(self, device: Device, surface: Surface, size: tuple[int, int],
                 vsync: bool = True, clear_color: tuple[float, float, float, float] = (0, 0, 0, 1)
                 ) -> None:
        vk = device.vk
        self.device, self.surface, self.vsync = device, surface, vsync
        self.clear_color = clear_color
        self.handle: Any = None
        self.depth_format = vk.VK_FORMAT_D32_SFLOAT
        self.generation = 0
        self.needs_recreate = False
        self.extent = (0, 0)
        self.images: list[Any] = []
        self._owned: list[Any] = []  # views, depth images: per swapchain generation
        self._render_done: list[Any] = []
        self._image_frame: list[Frame | None] = []
        self._screenshots: dict[int, Buffer] = {}
        inst, dev = device.instance.handle, device.handle
        get_i = vk.vkGetInstanceProcAddr
        self._caps_fn = get_i(inst, "vkGetPhysicalDeviceSurfaceCapabilitiesKHR")
        self._formats_fn = get_i(inst, "vkGetPhysicalDeviceSurfaceFormatsKHR")
        self._modes_fn = get_i(inst, "vkGetPhysicalDeviceSurfacePresentModesKHR")
        self._create_fn = vk.vkGetDeviceProcAddr(dev, "vkCreateSwapchainKHR")
        self._destroy_fn = vk.vkGetDeviceProcAddr(dev, "vkDestroySwapchainKHR")
        self._images_fn = vk.vkGetDeviceProcAddr(dev, "vkGetSwapchainImagesKHR")
        ffi, lib = vk.ffi, vk.lib
        self._acquire = ffi.cast("PFN_vkAcquireNextImageKHR",
                                 lib.vkGetDeviceProcAddr(dev, b"vkAcquireNextImageKHR"))
        self._present = ffi.cast("PFN_vkQueuePresentKHR",
                                 lib.vkGetDeviceProcAddr(dev, b"vkQueuePresentKHR"))
        self._index = ffi.new("uint32_t*")
        self._swapchains = ffi.new("VkSwapchainKHR[1]")
        self._present_wait = ffi.new("VkSemaphore[1]")
        self._present_info = ffi.new("VkPresentInfoKHR*", {
            "sType": vk.VK_STRUCTURE_TYPE_PRESENT_INFO_KHR, "waitSemaphoreCount": 1,
            "pWaitSemaphores": self._present_wait, "swapchainCount": 1,
            "pSwapchains": self._swapchains, "pImageIndices": self._index})
        self._choose_format_and_mode()
        device.track(self)
        self.recreate(size)

    # --- creation ---------------------------------------------------------------------------
    def _choose_format_and_mode(self) -> None:
        vk = self.device.vk
        formats = {(f.format, f.colorSpace) for f in self._formats_fn(self.device.physical,
                                                                       self.surface.handle)}
        for name in _SRGB_FORMATS:
            if (getattr(vk, name), vk.VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) in formats:
                self.color_format = getattr(vk, name)
                self.color_format_name = name[len("VK_FORMAT_"):]
                break
        else:
            raise VkpbrError("the window offers no B8G8R8A8_SRGB or R8G8B8A8_SRGB swapchain format")
        modes = set(self._modes_fn(self.device.physical, self.surface.handle))
        order = ["FIFO"] if self.vsync else ["MAILBOX", "IMMEDIATE", "FIFO"]
        for name in order:
            if getattr(vk, f"VK_PRESENT_MODE_{name}_KHR") in modes:
                self.present_mode, self.present_mode_name = (
                    getattr(vk, f"VK_PRESENT_MODE_{name}_KHR"), name.lower())
                break

    def surface_size(self, window_size: tuple[int, int]) -> tuple[int, int]:
        """The extent a swapchain would have now: (0, 0) while the window is minimised."""
        caps = self._caps_fn(self.device.physical, self.surface.handle)
        cur = caps.currentExtent
        if cur.width != 0xFFFFFFFF:
            return int(cur.width), int(cur.height)
        w = min(max(window_size[0], caps.minImageExtent.width), caps.maxImageExtent.width)
        h = min(max(window_size[1], caps.minImageExtent.height), caps.maxImageExtent.height)
        return int(w), int(h)

    def recreate(self, window_size: tuple[int, int]) -> bool:
        """(Re)create the swapchain for the window's size; False (and no swapchain) when the
        surface is zero-sized, i.e. minimised. Waits for the device to go idle."""
        vk, device = self.device.vk, self.device
        device.wait_idle()
        extent = self.surface_size(window_size)
        if 0 in extent or 0 in window_size:
            self._destroy_swapchain()
            return False
        caps = self._caps_fn(device.physical, self.surface.handle)
        count = max(caps.minImageCount + 1, 3)
        if caps.maxImageCount:
            count = min(count, caps.maxImageCount)
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT
        self.can_copy = bool(caps.supportedUsageFlags & vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT)
        if self.can_copy:
            usage |= vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        alpha = vk.VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
        if not caps.supportedCompositeAlpha & alpha:
            alpha = caps.supportedCompositeAlpha & -caps.supportedCompositeAlpha
        info = vk.VkSwapchainCreateInfoKHR(
            surface=self.surface.handle, minImageCount=count, imageFormat=self.color_format,
            imageColorSpace=vk.VK_COLOR_SPACE_SRGB_NONLINEAR_KHR,
            imageExtent=vk.VkExtent2D(*extent), imageArrayLayers=1, imageUsage=usage,
            imageSharingMode=vk.VK_SHARING_MODE_EXCLUSIVE, preTransform=caps.currentTransform,
            compositeAlpha=alpha, presentMode=self.present_mode, clipped=vk.VK_TRUE,
            oldSwapchain=self.handle)
        new = self._create_fn(device.handle, info, None)
        self._destroy_swapchain()
        self.handle, self.extent = new, extent
        self._swapchains[0] = new
        self.images = list(self._images_fn(device.handle, new))
        self._create_image_resources()
        self.generation += 1
        return True

    def _create_image_resources(self) -> None:
        vk, dev = self.device.vk, self.device.handle
        w, h = self.extent
        self.views, self.depth_images, self.depth_views = [], [], []
        for img in self.images:
            view = vk.vkCreateImageView(dev, vk.VkImageViewCreateInfo(
                image=img, viewType=vk.VK_IMAGE_VIEW_TYPE_2D, format=self.color_format,
                components=vk.VkComponentMapping(),
                subresourceRange=vk.VkImageSubresourceRange(
                    aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0, levelCount=1,
                    baseArrayLayer=0, layerCount=1)), None)
            self.views.append(view)
            depth = self._own(Image(self.device, w, h, self.depth_format,
                                    vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                                    | vk.VK_IMAGE_USAGE_SAMPLED_BIT, name="window depth"))
            self.depth_images.append(depth)
            self.depth_views.append(self._own(ImageView(depth, aspect="depth")))
            self._render_done.append(vk.vkCreateSemaphore(dev, vk.VkSemaphoreCreateInfo(), None))
            self._image_frame.append(None)

    def _own(self, obj: Any) -> Any:
        self._owned.append(obj)
        return obj

    def _destroy_swapchain(self) -> None:
        vk, dev = self.device.vk, self.device.handle
        for view in getattr(self, "views", []):
            vk.vkDestroyImageView(dev, view, None)
        self.views = []
        while self._owned:
            self._owned.pop().destroy()
        for sem in self._render_done:
            vk.vkDestroySemaphore(dev, sem, None)
        self._render_done, self._image_frame, self.images = [], [], []
        self._screenshots.clear()
        if self.handle is not None:
            handle, self.handle = self.handle, None
            self._destroy_fn(dev, handle, None)

    # --- the frame-target protocol -----------------------------------------------------------
    def acquire(self, frame: Frame) -> int | None:
        """Acquire an image for `frame` (signalling its `acquired` semaphore): its index, or
        None when the swapchain is out of date (recreate, then try again). Suboptimal images
        are used and `needs_recreate` is set, so `submit` asks for a recreation."""
        vk = self.device.vk
        result = self._acquire(self.device.handle, self.handle, _NO_TIMEOUT, frame.acquired,
                               vk.ffi.NULL, self._index)
        if result == vk.VK_ERROR_OUT_OF_DATE_KHR:
            return None
        self.needs_recreate = result == vk.VK_SUBOPTIMAL_KHR
        if result not in (vk.VK_SUCCESS, vk.VK_SUBOPTIMAL_KHR):
            check_result(result, "vkAcquireNextImageKHR")
        index = int(self._index[0])
        # Another frame may still be drawing into this image: wait for it.
        previous = self._image_frame[index]
        if previous is not None and previous is not frame:
            previous.wait()
        self._image_frame[index] = frame
        return index

    def attachments(self, image: int) -> Attachments:
        return Attachments(self.views[image], self.depth_views[image].handle, self.extent)

    def resources(self, image: int, frame_index: int) -> dict[str, ImageResource]:
        """Image `image` and its depth as graph resources ("color", "depth"). The acquire semaphore is waited at
        COLOR_ATTACHMENT_OUTPUT; a frame's first use of an image waits for all earlier
        commands (`copied`: a screenshot's copy; gpu/graph.py), which chains on it."""
        return {"color": ImageResource(self.images[image], view=self.views[image], copied=True),
                "depth": ImageResource(self.depth_images[image].handle, depth=True,
                                       view=self.depth_views[image].handle)}

    def finish_steps(self, image: int, frame_index: int, copy: tuple[str, ...],
                     prefix: str = "", sources: Any = None) -> list[Step]:
        """The colour copied into the frame's screenshot buffer when `copy` names it, then
        the image handed to the presentation engine. `prefix`: its resources' names' in the
        frame (`sources`, where the frame drew its depth, has nothing to copy here)."""
        steps = []
        if COPY_COLOR in copy:
            if not self.can_copy:
                raise VkpbrError("this window's swapchain images cannot be copied (no TRANSFER_SRC)")
            buffer = self.screenshot_buffer(frame_index)

            def record(cmd: Commands) -> None:  # the buffer is the frame slot's own
                copy_image_to_buffer(cmd, self.images[image], False, buffer, self.extent)
                barriers(cmd, [], [host_read_barrier(cmd.vk, buffer)])

            steps.append(Step("copy", record, ((prefix + "color", "transfer_src"),)))
        return [*steps, Step("present", uses=((prefix + "color", "present"),), timed=False)]

    def submit(self, frame: Frame, cmd: Commands, image: int) -> bool:
        """Submit `cmd` (waiting for the acquire, signalling the image's render-finished
        semaphore and the frame's fence) and present; False when it must be recreated."""
        vk = self.device.vk
        done = self._render_done[image]
        frame.submit(cmd, wait=frame.acquired, signal=done)
        self._index[0] = image
        self._present_wait[0] = done
        result = self._present(self.device.queue, self._present_info)
        if result in (vk.VK_ERROR_OUT_OF_DATE_KHR, vk.VK_SUBOPTIMAL_KHR):
            return False
        check_result(result, "vkQueuePresentKHR")
        return not self.needs_recreate

    # --- screenshots ------------------------------------------------------------------------
    def screenshot_buffer(self, frame_index: int) -> Buffer:
        """Frame `frame_index`'s host-visible copy of a presented image (made on first use,
        for this swapchain generation)."""
        buf = self._screenshots.get(frame_index)
        if buf is None:
            w, h = self.extent
            buf = self._screenshots[frame_index] = self._own(Buffer(
                self.device, w * h * 4, self.device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                host_visible=True, name="screenshot"))
        return buf

    def read_color(self, frame_index: int) -> np.ndarray:
        """(H, W, 4) uint8 RGBA of the frame's screenshot copy (after its fence was waited)."""
        w, h = self.extent
        px = self.screenshot_buffer(frame_index).array(np.uint8, w * h * 4).reshape(h, w, 4)
        if self.color_format_name.startswith("B8G8R8A8"):
            return px[:, :, [2, 1, 0, 3]].copy()
        return px.copy()

    # --- lifetime ---------------------------------------------------------------------------
    def destroy(self) -> None:
        """Wait for the GPU, then destroy the swapchain and its per-image objects (idempotent)."""
        if self.device is None:
            return
        self.device.wait_idle()
        self._destroy_swapchain()
        self.device.untrack(self)
        self.device = None  # type: ignore[assignment]
