"""Window surface, swapchain with per-image depth, and the per-frame synchronisation.

Two frames in flight, in the shape of vulkan-tutorial's "Frames in flight" chapter and
vkguide's FrameData: each frame slot owns an image-available semaphore and a fence; each
swapchain image owns a render-finished semaphore (a present may still wait on it after the
slot comes round again) and remembers the fence of the frame that last drew into it, which
is waited before the image's per-image resources (uniforms, command buffers) are reused.

The hot path (acquire, submit, present, fences) calls the C entry points through
`vulkan.lib` / raw function pointers with pre-built structs: the binding's wrappers cost
10-100 us per call, and they raise on VK_SUBOPTIMAL_KHR, which is a success code that still
hands out an image (vulkan-python.md, trap 10). Out-of-date and suboptimal swapchains are
reported to the caller, which calls `recreate`; a zero-sized (minimised) window has no
swapchain at all until it has a size again.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from vkpbr.errors import VkpbrError
from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image, ImageView, pipeline_barrier
from vkpbr.gpu.vk import check_result, translate_errors

__all__ = ["Surface", "Swapchain", "FRAMES_IN_FLIGHT"]

FRAMES_IN_FLIGHT = 2
_NO_TIMEOUT = 2**64 - 1
_SRGB_FORMATS = ("VK_FORMAT_B8G8R8A8_SRGB", "VK_FORMAT_R8G8B8A8_SRGB")


class Surface:
    """A VkSurfaceKHR made by `create(instance_handle)` (e.g. a GLFW call), owned by `device`
    so it is destroyed before the instance."""

    def __init__(self, device: Device, create: Callable[[Any], Any]) -> None:
        self.device = device
        self.handle = create(device.instance.handle)
        device.track(self)
        vk = device.vk
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
    """Swapchain images (sRGB, for the same bytes as the headless renderer) with a D32 depth
    image each, and the frame-slot synchronisation objects.

    Attributes `color_format`, `depth_format` and `samples` let `Renderer.build_pipelines`
    and `Renderer.record_draws` treat it like a render target. `generation` increases on each
    recreation so that callers know their per-image command buffers are stale.
    """

    def __init__(self, device: Device, surface: Surface, size: tuple[int, int],
                 vsync: bool = True) -> None:
        vk = device.vk
        self._init_state(device, surface, vsync)
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
        self._choose_format_and_mode()
        self._create_sync()
        self.recreate(size)

    # --- creation ---------------------------------------------------------------------------
    def _init_state(self, device: Device, surface: Surface | None, vsync: bool) -> None:
        self.device, self.surface, self.vsync = device, surface, vsync
        self.handle: Any = None
        self.samples = 1
        self.depth_format = device.vk.VK_FORMAT_D32_SFLOAT
        self.generation = 0
        self.needs_recreate = False
        self.can_copy = False
        self.frame = 0  # frames submitted so far; the slot is frame % FRAMES_IN_FLIGHT
        self.extent = (0, 0)
        self.images: list[Any] = []
        self._owned: list[Any] = []  # views, depth images: per swapchain generation
        self._render_done: list[Any] = []
        self._image_fence: list[Any] = []

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

    def _create_sync(self) -> None:
        vk, dev = self.device.vk, self.device.handle
        ffi = vk.ffi
        signalled = vk.VkFenceCreateInfo(flags=vk.VK_FENCE_CREATE_SIGNALED_BIT)
        self._acquired = [vk.vkCreateSemaphore(dev, vk.VkSemaphoreCreateInfo(), None)
                          for _ in range(FRAMES_IN_FLIGHT)]
        self._fences = [vk.vkCreateFence(dev, signalled, None) for _ in range(FRAMES_IN_FLIGHT)]
        self._fence_ptrs = [ffi.new("VkFence[1]", [f]) for f in self._fences]
        self._index = ffi.new("uint32_t*")
        # Submit and present infos are built once; a frame only updates their arrays.
        self._wait_sem = ffi.new("VkSemaphore[1]")
        self._wait_stage = ffi.new("VkPipelineStageFlags[1]",
                                   [vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT])
        self._signal_sem = ffi.new("VkSemaphore[1]")
        self._cmds = ffi.new("VkCommandBuffer[1]")
        self._submit = ffi.new("VkSubmitInfo*", {
            "sType": vk.VK_STRUCTURE_TYPE_SUBMIT_INFO, "waitSemaphoreCount": 1,
            "pWaitSemaphores": self._wait_sem, "pWaitDstStageMask": self._wait_stage,
            "commandBufferCount": 1, "pCommandBuffers": self._cmds,
            "signalSemaphoreCount": 1, "pSignalSemaphores": self._signal_sem})
        self._swapchains = ffi.new("VkSwapchainKHR[1]")
        self._present_info = ffi.new("VkPresentInfoKHR*", {
            "sType": vk.VK_STRUCTURE_TYPE_PRESENT_INFO_KHR, "waitSemaphoreCount": 1,
            "pWaitSemaphores": self._signal_sem, "swapchainCount": 1,
            "pSwapchains": self._swapchains, "pImageIndices": self._index})

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
        with translate_errors("vkCreateSwapchainKHR"):
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
                                    vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                                    name="window depth"))
            self.depth_images.append(depth)
            self.depth_views.append(self._own(ImageView(depth, aspect="depth")))
            self._render_done.append(vk.vkCreateSemaphore(dev, vk.VkSemaphoreCreateInfo(), None))
            self._image_fence.append(None)

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
        self._render_done, self._image_fence, self.images = [], [], []
        if self.handle is not None:
            handle, self.handle = self.handle, None
            self._destroy_fn(dev, handle, None)

    # --- per frame --------------------------------------------------------------------------
    @property
    def slot(self) -> int:
        return self.frame % FRAMES_IN_FLIGHT

    def acquire(self) -> int | None:
        """Wait for this slot's previous frame, then acquire an image: its index, or None when
        the swapchain is out of date (recreate, then try again). Suboptimal images are used
        and `needs_recreate` is set, so the caller recreates after presenting."""
        vk = self.device.vk
        self.wait_frame(self.slot)
        result = self._acquire(self.device.handle, self.handle, _NO_TIMEOUT,
                               self._acquired[self.slot], vk.ffi.NULL, self._index)
        if result == vk.VK_ERROR_OUT_OF_DATE_KHR:
            return None
        self.needs_recreate = result == vk.VK_SUBOPTIMAL_KHR
        if result not in (vk.VK_SUCCESS, vk.VK_SUBOPTIMAL_KHR):
            check_result(result, "vkAcquireNextImageKHR")
        return self._claim(int(self._index[0]))

    def _claim(self, index: int) -> int:
        """Make image `index` this slot's: first wait for a frame of the other slot that may
        still be drawing into it."""
        prev, mine = self._image_fence[index], self._fence_ptrs[self.slot]
        if prev is not None and prev is not mine:
            check_result(self.device.vk.lib.vkWaitForFences(
                self.device.handle, 1, prev, 1, _NO_TIMEOUT), "vkWaitForFences")
        self._image_fence[index] = mine
        return index

    def submit_and_present(self, cmd: Any, index: int) -> bool:
        """Submit `cmd` for image `index` (waiting for the acquire, signalling the slot's
        fence) and present it; False when the swapchain must be recreated."""
        vk, lib = self.device.vk, self.device.vk.lib
        slot = self.slot
        check_result(lib.vkResetFences(self.device.handle, 1, self._fence_ptrs[slot]),
                     "vkResetFences")
        self._wait_sem[0] = self._acquired[slot]
        self._signal_sem[0] = self._render_done[index]
        self._cmds[0] = cmd
        check_result(lib.vkQueueSubmit(self.device.queue, 1, self._submit, self._fences[slot]),
                     "vkQueueSubmit")
        self._index[0] = index
        result = self._present(self.device.queue, self._present_info)
        self.frame += 1
        if result in (vk.VK_ERROR_OUT_OF_DATE_KHR, vk.VK_SUBOPTIMAL_KHR):
            return False
        check_result(result, "vkQueuePresentKHR")
        return not self.needs_recreate

    def wait_frame(self, slot: int) -> None:
        """Block until the frame last submitted in `slot` has finished on the GPU."""
        check_result(self.device.vk.lib.vkWaitForFences(
            self.device.handle, 1, self._fence_ptrs[slot], 1, _NO_TIMEOUT), "vkWaitForFences")

    # --- recording --------------------------------------------------------------------------
    def _barrier(self, image: Any, aspect: int, old: int, new: int, src: tuple, dst: tuple) -> Any:
        vk = self.device.vk
        return vk.VkImageMemoryBarrier2(
            srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
            oldLayout=old, newLayout=new, srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED, image=image,
            subresourceRange=vk.VkImageSubresourceRange(
                aspectMask=aspect, baseMipLevel=0, levelCount=1, baseArrayLayer=0, layerCount=1))

    def record_begin(self, cmd: Any, index: int, clear: tuple[float, float, float, float] | None,
                     transition: bool = True) -> None:
        """Begin dynamic rendering on image `index` and its depth (cleared to `clear`, or
        loaded when None); with `transition`, first move both out of UNDEFINED."""
        vk = self.device.vk
        color_att_l = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL
        depth_l = vk.VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL
        if transition:
            # The acquire semaphore is waited at COLOR_ATTACHMENT_OUTPUT: chain on that stage.
            out = vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT
            tests = (vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT
                     | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT)
            dw = vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
            pipeline_barrier(vk, cmd, [
                self._barrier(self.images[index], vk.VK_IMAGE_ASPECT_COLOR_BIT,
                              vk.VK_IMAGE_LAYOUT_UNDEFINED, color_att_l, (out, 0),
                              (out, vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT)),
                self._barrier(self.depth_images[index].handle, vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                              vk.VK_IMAGE_LAYOUT_UNDEFINED, depth_l, (tests, dw),
                              (tests, dw | vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT)),
            ])
        load = vk.VK_ATTACHMENT_LOAD_OP_LOAD if clear is None else vk.VK_ATTACHMENT_LOAD_OP_CLEAR
        color = vk.VkRenderingAttachmentInfo(
            imageView=self.views[index], imageLayout=color_att_l, loadOp=load,
            storeOp=vk.VK_ATTACHMENT_STORE_OP_STORE,
            clearValue=vk.VkClearValue(color=vk.VkClearColorValue(float32=list(clear or (0,) * 4))))
        depth = vk.VkRenderingAttachmentInfo(
            imageView=self.depth_views[index].handle, imageLayout=depth_l, loadOp=load,
            storeOp=vk.VK_ATTACHMENT_STORE_OP_STORE,
            clearValue=vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=1.0)))
        area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(*self.extent))
        vk.vkCmdBeginRendering(cmd, vk.VkRenderingInfo(
            renderArea=area, layerCount=1, pColorAttachments=[color], pDepthAttachment=depth))
        vk.vkCmdSetViewport(cmd, 0, 1, [vk.VkViewport(
            x=0, y=0, width=self.extent[0], height=self.extent[1], minDepth=0.0, maxDepth=1.0)])
        vk.vkCmdSetScissor(cmd, 0, 1, [area])

    def record_copy(self, cmd: Any, index: int, buffer: Buffer) -> None:
        """Between two renderings: copy image `index` into a host-visible `buffer` (tightly
        packed texels in the swapchain's format) and make it an attachment again."""
        vk = self.device.vk
        att = (vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
               vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT)
        xfer = (vk.VK_PIPELINE_STAGE_2_COPY_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
        img, aspect = self.images[index], vk.VK_IMAGE_ASPECT_COLOR_BIT
        att_l, src_l = vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        pipeline_barrier(vk, cmd, [self._barrier(img, aspect, att_l, src_l, att, xfer)])
        w, h = self.extent
        vk.vkCmdCopyImageToBuffer(cmd, img, src_l, buffer.handle, 1, [vk.VkBufferImageCopy(
            bufferOffset=0, imageSubresource=vk.VkImageSubresourceLayers(
                aspectMask=aspect, mipLevel=0, baseArrayLayer=0, layerCount=1),
            imageExtent=vk.VkExtent3D(width=w, height=h, depth=1))])
        host = vk.VkBufferMemoryBarrier2(
            srcStageMask=vk.VK_PIPELINE_STAGE_2_COPY_BIT, srcAccessMask=vk.VK_ACCESS_2_TRANSFER_WRITE_BIT,
            dstStageMask=vk.VK_PIPELINE_STAGE_2_HOST_BIT, dstAccessMask=vk.VK_ACCESS_2_HOST_READ_BIT,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED, dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            buffer=buffer.handle, offset=0, size=buffer.size)
        pipeline_barrier(vk, cmd, [self._barrier(img, aspect, src_l, att_l, xfer, att)], [host])

    def record_end(self, cmd: Any, index: int) -> None:
        """End rendering and hand image `index` to the presentation engine."""
        vk = self.device.vk
        vk.vkCmdEndRendering(cmd)
        pipeline_barrier(vk, cmd, [self._barrier(
            self.images[index], vk.VK_IMAGE_ASPECT_COLOR_BIT,
            vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, vk.VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
            (vk.VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
             vk.VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT),
            (vk.VK_PIPELINE_STAGE_2_NONE, vk.VK_ACCESS_2_NONE))])

    # --- lifetime ---------------------------------------------------------------------------
    def destroy(self) -> None:
        """Wait for the GPU, then destroy the swapchain and the sync objects (idempotent)."""
        if getattr(self, "_fences", None) is None:
            return
        vk, dev = self.device.vk, self.device.handle
        self.device.wait_idle()
        self._destroy_swapchain()
        for sem in self._acquired:
            vk.vkDestroySemaphore(dev, sem, None)
        for fence in self._fences:
            vk.vkDestroyFence(dev, fence, None)
        self._fences = None
