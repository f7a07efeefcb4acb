"""Logical device, graphics queue, command pool, memory types, and child-object lifetime.

`Device` owns every object created through the gpu layer: children register themselves and
`close()` destroys them in reverse creation order, then the device, then the instance (the
order Sascha Willems' renderheadless and vkguide's deletion queue use). Nothing is freed from
`__del__`: GC order is arbitrary and the device must outlive its children.
"""

from __future__ import annotations

import contextlib
import functools
import os
import threading
import time
import weakref
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from typing import Any, Protocol

from vkpbr.errors import GpuTimeoutError, UsageError, VkpbrError
from vkpbr.gpu.instance import Instance, PhysicalDeviceInfo
from vkpbr.gpu.kept import KeptHandles
from vkpbr.gpu.memory import MemoryRecycler, kept_limit
from vkpbr.gpu.vk import live_objects, live_objects_by_kind, load

# live_objects / live_objects_by_kind (counted in gpu/vk.py) are re-exported for leak tests.
__all__ = ["Device", "DeviceRequest", "Destroyable", "DeviceObject", "anisotropy_usable",
           "live_objects", "live_objects_by_kind"]


def anisotropy_usable(info: PhysicalDeviceInfo, supported: bool) -> bool:
    """Whether samplers may use anisotropic filtering on this device.

    Off on llvmpipe (lavapipe): its anisotropic sampling path (Mesa 22.3.6, Debian 12) can
    loop without end on a tiny triangle at a sphere's silhouette, hanging the queue; found with
    the default scene at 160x120 (tests/gpu/test_views.py::test_llvmpipe_tiny_triangle_does_not_hang).
    Trilinear filtering is used there instead; VKPBR_LLVMPIPE_ANISOTROPY=1 turns it back on
    for a Mesa without the bug.
    """
    if not supported:
        return False
    if info.kind == "cpu" and info.name.startswith("llvmpipe"):
        return os.environ.get("VKPBR_LLVMPIPE_ANISOTROPY", "0") == "1"
    return True



# How long one submission may take before vkpbr reports a hung GPU instead of waiting forever.
GPU_TIMEOUT_ENV = "VKPBR_GPU_TIMEOUT_S"
GPU_TIMEOUT_DEFAULT_S = 120.0
VK_TIMEOUT = 2  # VkResult: the wait timed out


def gpu_timeout_ns() -> int:
    """$VKPBR_GPU_TIMEOUT_S (seconds, default 120) in nanoseconds: the longest wait for one
    submission (a frame, an upload). A GPU that never finishes is an error, not a hang."""
    return _timeout_ns(os.environ.get(GPU_TIMEOUT_ENV, ""))


@functools.lru_cache(maxsize=8)
def _timeout_ns(text: str) -> int:
    """gpu_timeout_ns of the variable's text (parsed once a value: every fence wait asks)."""
    try:
        seconds = float(text) if text else GPU_TIMEOUT_DEFAULT_S
    except ValueError:
        seconds = GPU_TIMEOUT_DEFAULT_S
    if not 0 < seconds < 1e9:
        seconds = GPU_TIMEOUT_DEFAULT_S
    return int(seconds * 1e9)


# Device features the compute path needs (Device.compute_path: all present, then enabled).
COMPUTE_PATH_FEATURES = ("geometryShader", "shaderStorageImageWriteWithoutFormat",
                         "subgroupOperations")


def before_later_commands(vk: Any, cmd: Any, stages: int, writes: int) -> None:
    """A barrier at the end of a submission made outside the frame graph (an upload): the
    writes of `stages` before any later command's reads and writes (a frame's first use of
    a resource does not wait for copies: gpu/graph.py)."""
    vk.vkCmdPipelineBarrier2(cmd, vk.VkDependencyInfo(
        memoryBarrierCount=1, pMemoryBarriers=[vk.VkMemoryBarrier2(
            srcStageMask=stages, srcAccessMask=writes,
            dstStageMask=vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
            dstAccessMask=vk.VK_ACCESS_2_MEMORY_READ_BIT | vk.VK_ACCESS_2_MEMORY_WRITE_BIT)]))


class Destroyable(Protocol):
    def destroy(self) -> None: ...


class DeviceLock:
    """`Device.lock`: a re-entrant lock that, once the device is closed (or in a forked
    child), raises instead (a frame recorded on a destroyed device aborted the process in the
    driver; one on a parent's device hung the child)."""

    def __init__(self, device: Device) -> None:
        self._lock = threading.RLock()
        self._device = device

    def __enter__(self) -> DeviceLock:
        self._lock.acquire()
        if self._device.handle is None:
            self._lock.release()
            if self._device.forked:
                raise UsageError("this renderer was made before this process was forked (a "
                                 "torch DataLoader worker, multiprocessing's fork): make the "
                                 "Renderer in the process that renders with it")
            raise UsageError("this renderer is closed: make a new Renderer")
        return self

    def __exit__(self, *exc: object) -> None:
        self._lock.release()


class DeviceObject:
    """Base of the wrappers that own one handle of a Device, released by `_destroy_fn`.

    `destroy()` is idempotent: it clears the handle before releasing it. A wrapper whose
    handle the device keeps (`_kept_handle`, gpu/kept.py) only lets go of it.
    """

    _destroy_fn = ""  # the vkDestroy* function name
    device: Device
    handle: Any = None
    _shared = False  # the handle is the device's kept one (gpu/kept.py): not destroyed here

    def _kept_handle(self, key: Any, make: Any) -> Any:
        """`make()`'s handle, or on a device that keeps handles (Device.kept) the one kept
        for `key` (this class's definition of it), made by `make()` the first time."""
        kept = self.device.kept
        if kept is None:
            return make()
        self._shared = True
        return kept.get((type(self).__name__, key), self._destroy_fn, make)

    def destroy(self) -> None:
        if self.handle is None:
            return
        handle, self.handle = self.handle, None
        if not self._shared:
            getattr(self.device.vk, self._destroy_fn)(self.device.handle, handle, None)
        self.device.untrack(self)


@dataclass(frozen=True)
class DeviceRequest:
    """A device selector plus the extensions a caller needs (a window: the surface
    extensions on the instance, VK_KHR_swapchain on the device). Anything that takes a
    device selector and hands it to `Device` (e.g. `Renderer(device=...)`) accepts one."""

    selector: str | int | None = None
    instance_extensions: tuple[str, ...] = ()
    extensions: tuple[str, ...] = ()


# The devices of this process, forgotten in a forked child (`_forked_child`).
_DEVICES: weakref.WeakSet[Device] = weakref.WeakSet()


def _forked_child() -> None:
    """In a forked child the parent's devices cannot be used (the driver's threads and locks
    stayed in the parent: a frame on one hung): their handles are forgotten, so each use
    says so (DeviceLock, the binding's wrapper) and closing destroys nothing of the parent's.
    A device made in the child works."""
    for device in list(_DEVICES):
        device.forked, device.handle, device.instance = True, None, None
        device._background = {}


os.register_at_fork(after_in_child=_forked_child)


class Device:
    """A VkDevice with one graphics queue. Use as a context manager or call `close()`.

    `device` is a name substring, an index, None (the best device) or a `DeviceRequest`;
    `instance_extensions` and `extensions` are required extensions (missing ones raise).
    """

    def __init__(
        self,
        device: str | int | DeviceRequest | None = None,
        validation: bool = False,
        sync_validation: bool = False,
        instance_extensions: tuple[str, ...] = (),
        extensions: tuple[str, ...] = (),
    ) -> None:
        if isinstance(device, DeviceRequest):
            instance_extensions = (*instance_extensions, *device.instance_extensions)
            extensions = (*extensions, *device.extensions)
            device = device.selector
        self._required_extensions = tuple(dict.fromkeys(extensions))
        t0 = time.perf_counter()
        load()  # the binding's import, the first time (timed apart from the instance)
        t1 = time.perf_counter()
        self.instance = Instance(validation=validation, sync_validation=sync_validation,
                                 extensions=tuple(dict.fromkeys(instance_extensions)))
        # Seconds of its making (benchmarks/bench_load.py): the binding's import, the
        # instance (the loader and its drivers), the physical device's choice and queries,
        # the logical device and pool.
        self.timings = {"binding": t1 - t0, "instance": time.perf_counter() - t1}
        self.vk = vk = self.instance.vk
        self._children: list[Destroyable] = []
        # Children made under `keeping()`: the device's for its life (not a scene's).
        self._kept_children: list[Destroyable] = []
        # (per thread: the frame graph makes a recording's kernels, the device's and a
        # scene's, on several threads at once)
        self._keeping = threading.local()
        self.handle = None
        # Its VkPipelineCache (gpu/pipeline_cache.py): set by the caller with a file to keep
        # it in, else made in memory by the first pipeline build.
        self.pipeline_cache: Any = None
        # Immutable handles shared by their definition for the device's life (gpu/kept.py;
        # a Renderer's device sets one); None: every wrapper makes and destroys its own.
        self.kept: KeptHandles | None = None
        # Freed memory kept for the next buffer or image of its type and size (gpu/memory.py)
        self.memory = MemoryRecycler(self)
        # Unsignalled fences for one-time submissions (`take_fence`): NVIDIA takes ~0.5 ms to
        # create one and as long to destroy it (H200, run h: 20 a scene change's uploads).
        self._fences: list[Any] = []
        self._fences_lock = threading.Lock()
        # One thread's frames, batches and scene changes at a time (the renderer takes it):
        # the queue, the command pool, the frame ring and the kept targets are shared, and
        # Vulkan leaves the first two to the caller to synchronise. Re-entrant: a frame drawn
        # inside a stream of the same thread is the supported way to interleave.
        self.lock = DeviceLock(self)
        self.forked = False  # (a forked child's copy of a parent's device: _forked_child)
        _DEVICES.add(self)
        # Work on the device's own threads (`in_background`: kernels compiled ahead), which
        # `close` waits for: none may still be in a Vulkan call when the device goes.
        self._background: dict[str, ThreadPoolExecutor] = {}
        self._background_work: list[Future] = []
        try:
            t0 = time.perf_counter()
            self.info: PhysicalDeviceInfo = self.instance.choose_device(device)
            self.physical = self.info.handle
            self.properties = vk.vkGetPhysicalDeviceProperties(self.physical)
            self.limits = self.properties.limits
            self.memory_properties = vk.vkGetPhysicalDeviceMemoryProperties(self.physical)
            self.memory.limit = kept_limit(self._device_local_bytes())
            self.queue_family = self._graphics_queue_family()
            t1 = time.perf_counter()
            self._create_device()
            self.queue = vk.vkGetDeviceQueue(self.handle, self.queue_family, 0)
            self.command_pool = vk.vkCreateCommandPool(
                self.handle,
                vk.VkCommandPoolCreateInfo(
                    flags=vk.VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
                    queueFamilyIndex=self.queue_family,
                ),
                None,
            )
            self.timings.update(choice=t1 - t0, device=time.perf_counter() - t1)
        except BaseException:
            self.close()
            raise

    # --- creation ---------------------------------------------------------------------------
    def _graphics_queue_family(self) -> int:
        vk = self.vk
        families = vk.vkGetPhysicalDeviceQueueFamilyProperties(self.physical)
        for i, fam in enumerate(families):
            if fam.queueFlags & vk.VK_QUEUE_GRAPHICS_BIT:
                return i
        raise VkpbrError(f"{self.info.name}: no graphics queue")

    def _create_device(self) -> None:
        vk = self.vk
        supported = self._query_features()
        self.anisotropy = anisotropy_usable(self.info, bool(supported["samplerAnisotropy"]))
        self.timestamps = bool(self.limits.timestampComputeAndGraphics)
        # Shadow maps: one layered draw fills a point light's six cube faces (or a light's
        # cascades): the vertex shader writes gl_Layer (shaderOutputLayer) from its instance
        # and base instance (shaderDrawParameters); cube-array images hold point lights' maps.
        self.layered_shadows = bool(supported["shaderOutputLayer"]
                                    and supported["shaderDrawParameters"])
        self.image_cube_array = bool(supported["imageCubeArray"])
        # Batched views (render/batch.py): layered rendering as the shadows', and indirect
        # draws whose firstInstance starts each draw's list of visible views.
        self.batch_views = bool(self.layered_shadows and supported["drawIndirectFirstInstance"])
        on = {True: vk.VK_TRUE, False: vk.VK_FALSE}
        # maintenance4 (required of Vulkan 1.3): glslc's vulkan1.3 compute shaders declare
        # their work-group size with LocalSizeId, which needs it.
        f13 = vk.VkPhysicalDeviceVulkan13Features(
            dynamicRendering=vk.VK_TRUE, synchronization2=vk.VK_TRUE, maintenance4=vk.VK_TRUE
        )
        # The compute rasteriser (render/compute_path.py): 64-bit integers and their atomics
        # on storage buffers, besides the compute path's features.
        self.compute_raster = bool(all(supported[k] for k in COMPUTE_PATH_FEATURES)
                                   and supported["shaderInt64"]
                                   and supported["shaderBufferInt64Atomics"])
        # Timeline semaphores shared with CUDA (gpu/timeline.py: batches whose inputs and
        # frames live in torch tensors), where the driver exports them.
        self.timeline_semaphores = bool(supported["timelineSemaphore"])
        # A compute batch's blended draws (render/batch_path.py): each view drawn into its
        # tile of the atlas, clipped to it by the vertex shader's clip distances.
        self.atlas_blend = bool(self.compute_raster and supported["shaderClipDistance"])
        f12 = vk.VkPhysicalDeviceVulkan12Features(
            pNext=f13, shaderOutputLayer=on[self.layered_shadows],
            shaderBufferInt64Atomics=on[self.compute_raster],
            timelineSemaphore=on[self.timeline_semaphores])
        f11 = vk.VkPhysicalDeviceVulkan11Features(
            pNext=f12, shaderDrawParameters=on[self.layered_shadows])
        # The compute path (render/compute_path.py) needs the primitive index in fragment
        # shaders (geometryShader), storage writes without a declared format, and subgroup
        # ballot, vote and shuffle in compute shaders.
        self.compute_path = all(supported[k] for k in COMPUTE_PATH_FEATURES)
        # BC7 textures (KHR_texture_basisu's KTX2 transcoded to blocks: a quarter of RGBA8's
        # memory): the feature and linear filtering of both colour spaces.
        self.bc7_textures = bool(supported["textureCompressionBC"]) and all(
            self.format_supports(getattr(vk, f"VK_FORMAT_BC7_{space}_BLOCK"),
                                 "SAMPLED_IMAGE_FILTER_LINEAR") for space in ("SRGB", "UNORM"))
        # Only what vkpbr uses: dynamic rendering, synchronization2, maintenance4, anisotropic
        # filtering, layered rendering and cube-map arrays (shadows), the compute path's, BC7,
        # clip distances (the compute batch's blended draws).
        core = vk.VkPhysicalDeviceFeatures(
            samplerAnisotropy=vk.VK_TRUE if self.anisotropy else vk.VK_FALSE,
            imageCubeArray=on[self.image_cube_array], geometryShader=on[self.compute_path],
            drawIndirectFirstInstance=on[self.batch_views],
            shaderStorageImageWriteWithoutFormat=on[self.compute_path],
            shaderInt64=on[self.compute_raster], textureCompressionBC=on[self.bc7_textures],
            shaderClipDistance=on[self.atlas_blend])
        available = {
            e.extensionName
            for e in vk.vkEnumerateDeviceExtensionProperties(self.physical, None)
        }
        # The driver's statistics of compiled pipelines (registers, instructions: a compute
        # kernel's occupancy; ComputePipeline.statistics), where it reports them. Diagnostics
        # only: nothing changes unless a pipeline is made with capture_statistics.
        self.pipeline_statistics = "VK_KHR_pipeline_executable_properties" in available
        chain = f11
        if self.pipeline_statistics:
            chain = vk.VkPhysicalDevicePipelineExecutablePropertiesFeaturesKHR(
                pNext=f11, pipelineExecutableInfo=vk.VK_TRUE)
        features = vk.VkPhysicalDeviceFeatures2(pNext=chain, features=core)
        missing = [e for e in self._required_extensions if e not in available]
        if missing:
            raise VkpbrError(f"{self.info.name}: device extension(s) {', '.join(missing)} missing")
        self.extensions: list[str] = list(self._required_extensions)
        # Frames handed to CUDA without a host copy (Renderer.render_batch(device="cuda")):
        # memory exported as a file descriptor, where the driver has it.
        self._has_memory_budget = "VK_EXT_memory_budget" in available
        self.external_memory_fd = "VK_KHR_external_memory_fd" in available
        if self.external_memory_fd and "VK_KHR_external_memory_fd" not in self.extensions:
            self.extensions.append("VK_KHR_external_memory_fd")
        self.external_semaphore_fd = (self.timeline_semaphores
                                      and "VK_KHR_external_semaphore_fd" in available)
        if self.external_semaphore_fd and "VK_KHR_external_semaphore_fd" not in self.extensions:
            self.extensions.append("VK_KHR_external_semaphore_fd")
        if self.pipeline_statistics and "VK_KHR_pipeline_executable_properties" not in self.extensions:
            self.extensions.append("VK_KHR_pipeline_executable_properties")
        # Keep the queue info alive until vkCreateDevice returns: the binding copies structs
        # into arrays, and the copy's pQueuePriorities points into the original's memory.
        queue_info = vk.VkDeviceQueueCreateInfo(
            queueFamilyIndex=self.queue_family, pQueuePriorities=[1.0]
        )
        info = vk.VkDeviceCreateInfo(
            pNext=features,
            pQueueCreateInfos=[queue_info],
            ppEnabledExtensionNames=self.extensions,
        )
        self.handle = vk.vkCreateDevice(self.physical, info, None)

    def _query_features(self) -> dict[str, int]:
        vk = self.vk
        f13 = vk.VkPhysicalDeviceVulkan13Features()
        f12 = vk.VkPhysicalDeviceVulkan12Features(pNext=f13)
        f11 = vk.VkPhysicalDeviceVulkan11Features(pNext=f12)
        f2 = vk.VkPhysicalDeviceFeatures2(
            sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, pNext=f11
        )
        vk.vkGetPhysicalDeviceFeatures2(self.physical, f2)
        if not (f13.dynamicRendering and f13.synchronization2):
            raise VkpbrError(
                f"{self.info.name}: Vulkan 1.3 dynamic rendering and synchronization2 are "
                "required (update the driver; Mesa >= 22 lavapipe has them)"
            )
        sub = vk.VkPhysicalDeviceSubgroupProperties(
            sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES)
        vk.vkGetPhysicalDeviceProperties2(self.physical, vk.VkPhysicalDeviceProperties2(
            sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, pNext=sub))
        ops = (vk.VK_SUBGROUP_FEATURE_BASIC_BIT | vk.VK_SUBGROUP_FEATURE_VOTE_BIT
               | vk.VK_SUBGROUP_FEATURE_BALLOT_BIT | vk.VK_SUBGROUP_FEATURE_SHUFFLE_BIT)
        core = f2.features
        return {"samplerAnisotropy": core.samplerAnisotropy,
                "imageCubeArray": core.imageCubeArray,
                "drawIndirectFirstInstance": core.drawIndirectFirstInstance,
                "shaderOutputLayer": f12.shaderOutputLayer,
                "shaderDrawParameters": f11.shaderDrawParameters,
                "geometryShader": core.geometryShader,
                "shaderInt64": core.shaderInt64,
                "shaderClipDistance": core.shaderClipDistance,
                "textureCompressionBC": core.textureCompressionBC,
                "shaderBufferInt64Atomics": f12.shaderBufferInt64Atomics,
                "timelineSemaphore": f12.timelineSemaphore,
                "shaderStorageImageWriteWithoutFormat": core.shaderStorageImageWriteWithoutFormat,
                "subgroupOperations": int((sub.supportedOperations & ops) == ops and bool(
                    sub.supportedStages & vk.VK_SHADER_STAGE_COMPUTE_BIT))}

    # --- helpers ----------------------------------------------------------------------------
    def uuid(self) -> bytes:
        """The physical device's UUID (VkPhysicalDeviceIDProperties.deviceUUID): CUDA names
        the same GPU by the same 16 bytes."""
        vk = self.vk
        ids = vk.VkPhysicalDeviceIDProperties(sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES)
        vk.vkGetPhysicalDeviceProperties2(self.physical, vk.VkPhysicalDeviceProperties2(
            sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, pNext=ids))
        return bytes(ids.deviceUUID)

    def _device_local_bytes(self) -> int:
        """The largest device-local heap's size."""
        mp = self.memory_properties
        return max((int(mp.memoryHeaps[i].size) for i in range(mp.memoryHeapCount)
                    if mp.memoryHeaps[i].flags & self.vk.VK_MEMORY_HEAP_DEVICE_LOCAL_BIT),
                   default=0)

    def memory_available(self) -> tuple[int, int]:
        """(device-local, host-visible) bytes free to allocate: the heaps' budgets less their
        use where the driver reports them (VK_EXT_memory_budget: NVIDIA does), else the
        heaps' sizes (lavapipe). Each is the largest heap of its kind."""
        vk = self.vk
        mp = self.memory_properties
        free = [int(mp.memoryHeaps[i].size) for i in range(mp.memoryHeapCount)]
        if self._has_memory_budget:
            budget = vk.VkPhysicalDeviceMemoryBudgetPropertiesEXT(
                sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MEMORY_BUDGET_PROPERTIES_EXT)
            vk.vkGetPhysicalDeviceMemoryProperties2(self.physical, vk.VkPhysicalDeviceMemoryProperties2(
                sType=vk.VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MEMORY_PROPERTIES_2, pNext=budget))
            free = [max(0, int(budget.heapBudget[i]) - int(budget.heapUsage[i]))
                    for i in range(mp.memoryHeapCount)]
        local = [free[i] for i in range(mp.memoryHeapCount)
                 if mp.memoryHeaps[i].flags & vk.VK_MEMORY_HEAP_DEVICE_LOCAL_BIT]
        host = [free[mp.memoryTypes[t].heapIndex] for t in range(mp.memoryTypeCount)
                if mp.memoryTypes[t].propertyFlags & vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT]
        return max(local, default=1 << 30), max(host, default=1 << 30)

    def format_supports(self, format: int, feature: str) -> bool:
        """Whether optimal-tiling images of `format` support `feature`, a
        VkFormatFeatureFlagBits name without its prefix and suffix ("SAMPLED_IMAGE_FILTER_LINEAR")."""
        vk = self.vk
        props = vk.vkGetPhysicalDeviceFormatProperties(self.physical, format)
        bit = getattr(vk, f"VK_FORMAT_FEATURE_{feature}_BIT")
        return bool(props.optimalTilingFeatures & bit)

    def memory_type(self, type_bits: int, required: int, preferred: int = 0) -> int:
        """Index of a memory type allowed by `type_bits` with `required` (and ideally
        `preferred`) property flags."""
        mp = self.memory_properties
        candidates = [
            i
            for i in range(mp.memoryTypeCount)
            if type_bits & (1 << i)
            and (mp.memoryTypes[i].propertyFlags & required) == required
        ]
        if not candidates:
            raise VkpbrError(f"{self.info.name}: no memory type with flags {required:#x}")
        for i in candidates:
            if (mp.memoryTypes[i].propertyFlags & preferred) == preferred:
                return i
        return candidates[0]

    def allocate_command_buffer(self) -> Any:
        vk = self.vk
        return vk.vkAllocateCommandBuffers(
            self.handle,
            vk.VkCommandBufferAllocateInfo(
                commandPool=self.command_pool,
                level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                commandBufferCount=1,
            ),
        )[0]

    def free_command_buffer(self, cmd: Any) -> None:
        if self.handle is not None:
            self.vk.vkFreeCommandBuffers(self.handle, self.command_pool, 1, [cmd])

    @contextlib.contextmanager
    def one_time_commands(self) -> Iterator[Any]:
        """Record commands, then submit them and wait (uploads, mip generation)."""
        vk = self.vk
        cmd = self.allocate_command_buffer()
        try:
            vk.vkBeginCommandBuffer(
                cmd,
                vk.VkCommandBufferBeginInfo(
                    flags=vk.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT
                ),
            )
            yield cmd
            before_later_commands(vk, cmd, vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                                  vk.VK_ACCESS_2_MEMORY_WRITE_BIT)
            vk.vkEndCommandBuffer(cmd)
            fence = self.take_fence()
            try:
                vk.vkQueueSubmit(
                    self.queue, 1, [vk.VkSubmitInfo(pCommandBuffers=[cmd])], fence
                )
                self.wait_fences(vk.ffi.new("VkFence[1]", [fence]), "an upload")
            except BaseException:
                vk.vkDestroyFence(self.handle, fence, None)  # (not known to be unsignalled)
                raise
            self.give_fence(fence)
        finally:
            self.free_command_buffer(cmd)

    def take_fence(self) -> Any:
        """An unsignalled fence for one submission: a kept one, else a new one; hand it back
        with `give_fence` once it signalled and was waited for."""
        with self._fences_lock:
            if self._fences:
                return self._fences.pop()
        return self.vk.vkCreateFence(self.handle, self.vk.VkFenceCreateInfo(), None)

    def give_fence(self, fence: Any) -> None:
        """A fence from `take_fence`, signalled and waited for: reset and kept for the next."""
        self.vk.vkResetFences(self.handle, 1, [fence])
        with self._fences_lock:
            self._fences.append(fence)

    def wait_fences(self, fences: Any, what: str) -> None:
        """Wait for a cffi `VkFence[1]` array; GpuTimeoutError after gpu_timeout_ns()."""
        timeout = gpu_timeout_ns()
        result = self.vk.lib.vkWaitForFences(self.handle, 1, fences, 1, timeout)
        if result == VK_TIMEOUT:
            raise GpuTimeoutError("vkWaitForFences", "VK_TIMEOUT", (
                f"{self.info.name} did not finish {what} in {timeout / 1e9:g} s: the device "
                f"looks hung (set {GPU_TIMEOUT_ENV} to wait longer for very large frames)"))
        if result != 0:  # (VK_SUCCESS: no call; check_result names any other)
            from vkpbr.gpu.vk import check_result

            check_result(result, "vkWaitForFences")

    def wait_idle(self) -> None:
        if self.handle is not None:
            self.vk.vkDeviceWaitIdle(self.handle)

    # --- lifetime ---------------------------------------------------------------------------
    def track(self, child: Destroyable) -> None:
        (self._kept_children if self.keeps_here() else self._children).append(child)

    def untrack(self, child: Destroyable) -> None:
        for children in (self._children, self._kept_children):
            with contextlib.suppress(ValueError):
                children.remove(child)
                return

    @contextlib.contextmanager
    def keeping(self) -> Iterator[None]:
        """Children made inside, on this thread, are the device's for its life: outside the
        `live_children` count, so `destroy_children` (a scene's unmaking) leaves them;
        `close` destroys them after the others. The caller makes nothing of a scene inside;
        other threads' children stay theirs."""
        local = self._keeping
        local.depth = getattr(local, "depth", 0) + 1
        try:
            yield
        finally:
            local.depth -= 1

    def keeps_here(self) -> bool:
        """Whether this thread is inside `keeping()`."""
        return getattr(self._keeping, "depth", 0) > 0

    @property
    def live_children(self) -> int:
        return len(self._children)

    def destroy_children(self, since: int) -> None:
        """Destroy the children made after the first `since` (`live_children` then), newest
        first, as `close` does: what one scene's parts made (Renderer.set_scene). The caller
        waits for the device first."""
        while len(self._children) > since:
            self._children.pop().destroy()

    def bytes_allocated(self) -> tuple[int, int]:
        """(device-local, host-visible) bytes of the live buffers and images this device made,
        as their memory requirements asked (benchmarks report a batch's footprint with it)."""
        local = host = 0
        for child in self._children + self._kept_children:
            size = getattr(child, "allocation_size", None) or getattr(child, "bytes", 0)
            if getattr(child, "host_visible", False):
                host += int(size)
            else:
                local += int(size)
        return local, host

    def check_validation(self) -> None:
        self.instance.check()

    def in_background(self, work: Callable[[], Any], threads: int, group: str = "ahead") -> Future:
        """`work()` on one of the device's `threads` threads of `group` (made with the
        group's first call; kernels compiled ahead, render/kernels_ahead.py); `close` waits
        for it (and drops what has not begun)."""
        if group not in self._background:
            self._background[group] = ThreadPoolExecutor(threads, f"vkpbr-{group}")
        future = self._background[group].submit(work)
        self._background_work = [f for f in self._background_work if not f.done()] + [future]
        return future

    def stop_background(self, group: str) -> None:
        """`group`'s work under way finished, the rest dropped (its futures cancelled), its
        threads ended (the next `in_background` of the group makes them again)."""
        pool = self._background.pop(group, None)
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)

    def wait_background(self) -> None:
        """Until the work given to `in_background` so far is done (or dropped: a future
        `stop_background` cancelled is never "notified", and `wait` would wait for it)."""
        wait([f for f in self._background_work if not f.done()])

    def close(self) -> None:
        """Destroy every child (reverse order), the device, then the instance. Idempotent."""
        for pool in getattr(self, "_background", {}).values():
            pool.shutdown(wait=True, cancel_futures=True)
        self._background = {}
        vk = self.vk if hasattr(self, "vk") else None
        if self.handle is not None and vk is not None:
            with contextlib.suppress(Exception):
                vk.vkDeviceWaitIdle(self.handle)
            for children in (self._children, self._kept_children):
                while children:
                    children.pop().destroy()
            self.memory.clear()
            while self._fences:
                vk.vkDestroyFence(self.handle, self._fences.pop(), None)
            if getattr(self, "kept", None) is not None:
                self.kept.destroy(vk, self.handle)
            if getattr(self, "command_pool", None) is not None:
                vk.vkDestroyCommandPool(self.handle, self.command_pool, None)
                self.command_pool = None
            handle, self.handle = self.handle, None
            vk.vkDestroyDevice(handle, None)
        if getattr(self, "instance", None) is not None:
            self.instance.destroy()

    def __enter__(self) -> Device:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
