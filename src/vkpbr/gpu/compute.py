"""Compute pipelines: a SPIR-V compute shader, its own descriptor set layout(s) and push
constants, and the barriers between dispatches (style.md: Vulkan vocabulary stays in gpu/).

    layout = DescriptorSetLayout(device, [BindingSpec(0, "samplerCube", ("compute",)),
                                          BindingSpec(1, "storage_image", ("compute",))])
    pipe = ComputePipeline(device, SPV_DIR / "prefilter.comp.spv", [layout], push_bytes=16)
    cmd.bind_pipeline(pipe); cmd.bind_set(0, ds); cmd.push(consts)
    cmd.dispatch(*groups((w, h, 6), (8, 8, 1)))
    cmd.image_barrier(image, "general", "shader_read", "compute", "compute")

`Commands.bind_pipeline` binds either kind of pipeline at its own bind point (`bind_point`).
"""

from __future__ import annotations

import os
import struct
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from pathlib import Path
from typing import Any, TypeVar

from vkpbr.errors import VkpbrError
from vkpbr.gpu.descriptors import DescriptorSetLayout
from vkpbr.gpu.device import Device, DeviceObject
from vkpbr.gpu.kept import address
from vkpbr.gpu.pipeline import PipelineLayout, ShaderModule, shader_key
from vkpbr.gpu.pipeline_cache import Feedback
from vkpbr.gpu.vk import check_result

__all__ = ["ComputePipeline", "groups", "make_at_once", "LAYOUTS", "STAGES"]

# Image layouts and pipeline stages in words, for Commands.image_barrier.
LAYOUTS = {
    "undefined": "VK_IMAGE_LAYOUT_UNDEFINED",
    "general": "VK_IMAGE_LAYOUT_GENERAL",
    "shader_read": "VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL",
    "transfer_src": "VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL",
    "transfer_dst": "VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL",
    "color_attachment": "VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL",
}
# stage -> (stage flag, the accesses a barrier waits for / makes visible there)
STAGES = {
    "none": ("VK_PIPELINE_STAGE_2_NONE", ("VK_ACCESS_2_NONE",)),
    "compute": ("VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT",
                ("VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT", "VK_ACCESS_2_SHADER_STORAGE_READ_BIT",
                 "VK_ACCESS_2_SHADER_SAMPLED_READ_BIT")),
    "fragment": ("VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT",
                 ("VK_ACCESS_2_SHADER_SAMPLED_READ_BIT", "VK_ACCESS_2_SHADER_STORAGE_READ_BIT")),
    # Sampled by a frame's shaders: the fragment path's and the compute path's.
    "sampled": ("VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT|VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT",
                 ("VK_ACCESS_2_SHADER_SAMPLED_READ_BIT", "VK_ACCESS_2_SHADER_STORAGE_READ_BIT")),
    "transfer": ("VK_PIPELINE_STAGE_2_TRANSFER_BIT",
                 ("VK_ACCESS_2_TRANSFER_READ_BIT", "VK_ACCESS_2_TRANSFER_WRITE_BIT")),
    # Drawn into as a colour attachment.
    "color": ("VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT",
              ("VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT", "VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT")),
}


def groups(size: Sequence[int], local: Sequence[int]) -> tuple[int, int, int]:
    """Work groups covering `size` (x, y, z) with `local`-sized groups (rounded up)."""
    g = [-(-int(s) // int(t)) for s, t in zip(size, local, strict=True)]
    return g[0], g[1], g[2]


def _kernel_threads() -> int:
    """Threads that compile a recording's kernels at once: VKPBR_KERNEL_THREADS where it is
    a positive whole number (benchmarks; 1: one after another), else 2 to 8 by the cores."""
    given = os.environ.get("VKPBR_KERNEL_THREADS", "").strip()
    if given.isdigit() and int(given) > 0:
        return int(given)
    return max(2, min(8, os.cpu_count() or 1))


KERNEL_THREADS = _kernel_threads()
T = TypeVar("T")


def make_at_once(makers: Sequence[Callable[[], T]]) -> list[T]:
    """Each of `makers`' results, made on up to KERNEL_THREADS threads at once: pipeline
    builds, whose compiles then overlap (the binding lets go of the GIL in its calls, and
    the device's pipeline cache is internally synchronised). A maker's error is raised.
    The threads are the process's, kept (`_kernel_pool`): most calls find every kernel made
    already (a recording of a new shadow redraw, a new blend order), and a pool made and
    joined each time had cost such a recording ~8 ms of thread starts on the H200's host
    (benchmarks/profile_record.py; benchmarks/results/h200-2026-12-04s22.md, run e)."""
    if len(makers) < 2 or KERNEL_THREADS < 2 or _on_kernel_thread():
        # (a maker that makes at once itself makes in its own thread: the kept pool's
        # threads all waiting for work queued behind them would wait for ever)
        return [make() for make in makers]
    futures = [_kernel_pool(KERNEL_THREADS).submit(make) for make in makers]
    try:
        return [f.result() for f in futures]
    finally:
        # Also when a signal's exception (Ctrl-C, the CLI's SIGTERM) interrupts the wait: the
        # builds under way end before it propagates, or the device could be closed under a
        # thread still in vkCreateComputePipelines (a segfault at exit on the H200); those
        # not begun are dropped.
        for f in futures:
            f.cancel()
        wait(futures)


_kernel_pools: dict[int, ThreadPoolExecutor] = {}  # by size (benchmarks and tests set it)
_kernel_pools_lock = threading.Lock()


def _kernel_pool(threads: int) -> ThreadPoolExecutor:
    """The process's kept pool of `threads` kernel threads (made on first use)."""
    with _kernel_pools_lock:
        pool = _kernel_pools.get(threads)
        if pool is None:
            pool = _kernel_pools[threads] = ThreadPoolExecutor(threads, "vkpbr-kernels")
        return pool


def _on_kernel_thread() -> bool:
    return threading.current_thread().name.startswith("vkpbr-kernels")


def _forget_kernel_pools() -> None:
    """A forked child has none of its parent's threads: it makes its own."""
    global _kernel_pools_lock
    _kernel_pools.clear()
    _kernel_pools_lock = threading.Lock()


os.register_at_fork(after_in_child=_forget_kernel_pools)


class ComputePipeline(DeviceObject):
    """One compute shader with its layout; `layout` (a PipelineLayout) is owned here."""

    _destroy_fn = "vkDestroyPipeline"
    bind_point = "compute"

    def __init__(self, device: Device, spirv: Path, set_layouts: Sequence[DescriptorSetLayout],
                 push_bytes: int = 0, capture_statistics: bool = False,
                 specialization: Sequence[int] = ()) -> None:
        """`capture_statistics`: keep the driver's statistics of the compiled kernel for
        `statistics()` (a device with `pipeline_statistics` only). `specialization`: the
        values of the shader's specialization constants 0, 1, ... (32-bit each: uint, int
        as its two's complement, bool as 0 or 1); the driver compiles the kernel for them."""
        vk = device.vk
        self.push_bytes = push_bytes
        if capture_statistics and not device.pipeline_statistics:
            raise VkpbrError(f"{device.info.name}: the driver reports no pipeline statistics "
                             "(VK_KHR_pipeline_executable_properties)")
        self.device = device
        self.layout = PipelineLayout(device, list(set_layouts), push_bytes, stages=("compute",))
        key = (shader_key(Path(spirv)), address(self.layout.handle, vk.ffi),
               tuple(int(v) & 0xFFFFFFFF for v in specialization))
        build = lambda: self._build(Path(spirv), specialization, capture_statistics)  # noqa: E731
        # (a kernel whose statistics are read is its own: the flag changes the build)
        self.handle = build() if capture_statistics else self._kept_handle(key, build)
        device.track(self)

    def _build(self, spirv: Path, specialization: Sequence[int], capture_statistics: bool) -> Any:
        """The pipeline's handle, with its shader module made for the call only."""
        vk, device = self.device.vk, self.device
        module = ShaderModule(device, spirv)
        try:
            # Keep the stage struct referenced until the call returns: the binding copies it
            # into the create info, and the copy's pName points into the original's memory.
            spec = None
            if specialization:
                data = struct.pack(f"<{len(specialization)}I",
                                   *(int(v) & 0xFFFFFFFF for v in specialization))
                spec = vk.VkSpecializationInfo(
                    pMapEntries=[vk.VkSpecializationMapEntry(constantID=i, offset=4 * i, size=4)
                                 for i in range(len(specialization))],
                    dataSize=len(data), pData=vk.ffi.from_buffer(data))
            stage = vk.VkPipelineShaderStageCreateInfo(
                stage=vk.VK_SHADER_STAGE_COMPUTE_BIT, module=module.handle, pName="main",
                pSpecializationInfo=spec)
            flags = vk.VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR if capture_statistics else 0
            feedback = Feedback(device)  # the build goes through the device's pipeline cache
            info = vk.VkComputePipelineCreateInfo(pNext=feedback.info, flags=flags, stage=stage,
                                                  layout=self.layout.handle)
            return feedback.build("compute", info, spirv.name)
        finally:
            module.destroy()

    def statistics(self) -> dict[str, float | int | bool]:
        """The driver's statistics of this kernel (made with `capture_statistics`), by the
        names it gives them (NVIDIA's: registers, shared memory, instructions, ...); those
        of several executables (rare for compute) prefixed with the executable's name."""
        vk = self.device.vk
        ffi, dev = vk.ffi, self.device.handle

        def listed(name: str, info: Any, ctype: str, stype: int) -> Any:
            # Raw calls: the binding's wrappers leave the outputs' sType unset.
            call = ffi.cast(f"PFN_{name}", vk.lib.vkGetDeviceProcAddr(dev, name.encode()))
            count = ffi.new("uint32_t*")
            check_result(call(dev, info, count, ffi.NULL), name)
            items = ffi.new(f"{ctype}[]", count[0])
            for item in items:
                item.sType = stype
            check_result(call(dev, info, count, items), name)
            return items

        pipeline = ffi.new("VkPipelineInfoKHR*", {"sType": vk.VK_STRUCTURE_TYPE_PIPELINE_INFO_KHR,
                                                  "pipeline": self.handle})
        executables = listed("vkGetPipelineExecutablePropertiesKHR", pipeline,
                             "VkPipelineExecutablePropertiesKHR",
                             vk.VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_PROPERTIES_KHR)
        read = {vk.VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_BOOL32_KHR: lambda v: bool(v.b32),
                vk.VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_INT64_KHR: lambda v: int(v.i64),
                vk.VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_UINT64_KHR: lambda v: int(v.u64),
                vk.VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_FLOAT64_KHR: lambda v: float(v.f64)}
        out: dict[str, float | int | bool] = {}
        for index, props in enumerate(executables):
            prefix = "" if len(executables) == 1 else f"{ffi.string(props.name).decode()}: "
            info = ffi.new("VkPipelineExecutableInfoKHR*", {
                "sType": vk.VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_INFO_KHR,
                "pipeline": self.handle, "executableIndex": index})
            for st in listed("vkGetPipelineExecutableStatisticsKHR", info,
                             "VkPipelineExecutableStatisticKHR",
                             vk.VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_STATISTIC_KHR):
                out[prefix + ffi.string(st.name).decode()] = read[st.format](st.value)
        return out

    def destroy(self) -> None:
        super().destroy()
        self.layout.destroy()


def stage_access(vk: Any, stage: str) -> tuple[int, int]:
    flag_names, accesses = STAGES[stage]
    flags = 0
    for a in accesses:
        flags |= getattr(vk, a)
    stages = 0
    for name in flag_names.split("|"):
        stages |= getattr(vk, name)
    return stages, flags
