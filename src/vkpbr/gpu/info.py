"""What `vkpbr info` reports: every Vulkan device and the features vkpbr relies on."""

from __future__ import annotations

from typing import Any

from vkpbr.gpu.device import anisotropy_usable
from vkpbr.gpu.instance import Instance, PhysicalDeviceInfo

__all__ = ["device_report"]


def _features(vk: Any, info: PhysicalDeviceInfo) -> dict[str, Any]:
    handle = info.handle
    f13 = vk.VkPhysicalDeviceVulkan13Features()
    f12 = vk.VkPhysicalDeviceVulkan12Features(pNext=f13)
    f11 = vk.VkPhysicalDeviceVulkan11Features(pNext=f12)
    f2 = vk.VkPhysicalDeviceFeatures2(sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, pNext=f11)
    vk.vkGetPhysicalDeviceFeatures2(handle, f2)
    props = vk.vkGetPhysicalDeviceProperties(handle)
    limits = props.limits
    heaps = vk.vkGetPhysicalDeviceMemoryProperties(handle)
    extensions = {e.extensionName for e in vk.vkEnumerateDeviceExtensionProperties(handle, None)}
    device_local = sum(
        heaps.memoryHeaps[i].size
        for i in range(heaps.memoryHeapCount)
        if heaps.memoryHeaps[i].flags & vk.VK_MEMORY_HEAP_DEVICE_LOCAL_BIT
    )
    return {
        "dynamicRendering": bool(f13.dynamicRendering),
        "synchronization2": bool(f13.synchronization2),
        "samplerAnisotropy": bool(f2.features.samplerAnisotropy),
        # What vkpbr's samplers use (off on llvmpipe: gpu/device.py anisotropy_usable).
        "anisotropyUsed": anisotropy_usable(info, bool(f2.features.samplerAnisotropy)),
        "maxSamplerAnisotropy": float(limits.maxSamplerAnisotropy),
        "timestamps": bool(limits.timestampComputeAndGraphics),
        "timestampPeriod_ns": float(limits.timestampPeriod),
        "maxImageDimension2D": int(limits.maxImageDimension2D),
        "msaa4x": bool(limits.framebufferColorSampleCounts & vk.VK_SAMPLE_COUNT_4_BIT),
        "maxPushConstantsSize": int(limits.maxPushConstantsSize),
        "deviceLocalMemory_MiB": int(device_local >> 20),
        # Renderer.render_batch: layered rendering and instanced indirect draws (else it
        # renders view by view), up to maxFramebufferLayers views a chunk; device="cuda"
        # needs the memory export.
        "batchedViews": bool(f12.shaderOutputLayer and f11.shaderDrawParameters
                             and f2.features.drawIndirectFirstInstance),
        "maxFramebufferLayers": int(limits.maxFramebufferLayers),
        "externalMemoryFd": "VK_KHR_external_memory_fd" in extensions,
        "memoryBudget": "VK_EXT_memory_budget" in extensions,
        # KTX2 (KHR_texture_basisu) with its mips is uploaded as BC7 where this holds (and
        # both BC7 formats filter linearly: gpu/device.py bc7_textures), else as RGBA8.
        "textureCompressionBC": bool(f2.features.textureCompressionBC),
    }


def device_report() -> dict[str, Any]:
    instance = Instance(validation=False)
    try:
        devices = instance.physical_devices()
        chosen = instance.choose_device(None).index if devices else -1
        return {
            "devices": [
                {
                    "index": d.index,
                    "name": d.name,
                    "kind": d.kind,
                    "api_version": d.api_version,
                    "vendor_id": d.vendor_id,
                    "device_id": d.device_id,
                    "driver_version": d.driver_version,
                    "chosen": d.index == chosen,
                    "features": _features(instance.vk, d),
                }
                for d in devices
            ]
        }
    finally:
        instance.destroy()
