"""Timeline semaphores shared with CUDA: a batch ordered against torch's stream on the GPU.

A batch of worlds whose poses and frames are torch tensors (render/batch_path.py) needs two
orderings and no host wait: the batch starts after CUDA has written its inputs, and CUDA reads
the frames (and writes the next inputs) after the batch ends. `SharedTimeline` is a Vulkan
timeline semaphore exported as a file descriptor (VK_KHR_external_semaphore_fd, opaque fd);
gpu/cuda.py `CudaTimeline` imports it into CUDA, whose stream signals and waits on its values
(cudaSignalExternalSemaphoresAsync / cudaWaitExternalSemaphoresAsync) as a Vulkan submission
does (Frame.submit(values=...)).
"""

from __future__ import annotations

from vkpbr.gpu.device import Device

__all__ = ["SharedTimeline"]


class SharedTimeline:
    """A timeline semaphore (initial value 0) whose payload CUDA can import."""

    def __init__(self, device: Device, exportable: bool = True) -> None:
        vk = device.vk
        self.device = device
        self._type = vk.VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT
        export = vk.VkExportSemaphoreCreateInfo(handleTypes=self._type) if exportable else None
        kind = vk.VkSemaphoreTypeCreateInfo(pNext=export,
                                            semaphoreType=vk.VK_SEMAPHORE_TYPE_TIMELINE,
                                            initialValue=0)
        self.handle = vk.vkCreateSemaphore(device.handle, vk.VkSemaphoreCreateInfo(pNext=kind), None)

    def value(self) -> int:
        """The semaphore's current value (vkGetSemaphoreCounterValue)."""
        return int(self.device.vk.vkGetSemaphoreCounterValue(self.device.handle, self.handle))

    def signal(self, value: int) -> None:
        """Set the value from the host (vkSignalSemaphore)."""
        vk = self.device.vk
        vk.vkSignalSemaphore(self.device.handle, vk.VkSemaphoreSignalInfo(
            semaphore=self.handle, value=value))

    def export_fd(self) -> int:
        """A new file descriptor of the semaphore (CUDA's import takes ownership)."""
        vk = self.device.vk
        get_fd = vk.vkGetDeviceProcAddr(self.device.handle, "vkGetSemaphoreFdKHR")
        return int(get_fd(self.device.handle, vk.VkSemaphoreGetFdInfoKHR(
            semaphore=self.handle, handleType=self._type)))

    def destroy(self) -> None:
        if self.handle is not None:
            self.device.vk.vkDestroySemaphore(self.device.handle, self.handle, None)
            self.handle = None
