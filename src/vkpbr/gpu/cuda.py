"""Vulkan memory seen by CUDA: frames handed to PyTorch on the same GPU without a host copy.

A buffer allocated exportable (gpu/buffer.py, VK_KHR_external_memory_fd) is exported as a
file descriptor and imported into CUDA as external memory, mapped as one device pointer
(`CudaImport`); `CudaImport.tensor` wraps it as a torch tensor through the CUDA Array
Interface (torch.as_tensor reads `__cuda_array_interface__` without copying).

The CUDA calls go through cuda-python (`cuda.bindings.runtime`, NVIDIA's own binding of the
CUDA runtime, the `cuda` extra): torch has no call that imports external memory, cupy would
be a second array library for one call, and hand-written ctypes structs of the runtime's
handle descriptors would be the renderer guessing CUDA's ABI. Everything here is optional:
`cuda_unavailable()` says in one line why it cannot run.
"""

from __future__ import annotations

import functools
from typing import Any

from vkpbr.errors import UsageError, VkpbrError

__all__ = ["CudaImport", "CudaTimeline", "cuda_unavailable", "cuda_device_for"]


@functools.cache  # (a step signals and waits through it: no import statement each call)
def _runtime() -> Any:
    try:
        from cuda.bindings import runtime  # cuda-python >= 12.6
    except ImportError:
        from cuda import cudart as runtime  # older cuda-python
    return runtime


def cuda_unavailable() -> str | None:
    """Why frames cannot be handed to torch on CUDA here, or None."""
    try:
        import torch
    except ImportError:
        return "PyTorch is not installed (pip install torch)"
    if not torch.cuda.is_available():
        return "torch.cuda.is_available() is False (no CUDA device or driver)"
    try:
        _runtime()
    except ImportError:
        return "cuda-python is not installed (pip install 'vkpbr[cuda]')"
    return None


def _check(result: Any, call: str) -> Any:
    """cuda-python returns (error, *values): raise on an error, return the values."""
    err, *values = result if isinstance(result, tuple) else (result,)
    if err != _runtime().cudaError_t.cudaSuccess:
        raise VkpbrError(f"CUDA {call} failed: {getattr(err, 'name', err)}")
    return values[0] if len(values) == 1 else values


def cuda_device_for(uuid: bytes, name: str) -> int:
    """The CUDA device index of the GPU whose UUID is `uuid` (the Vulkan device's)."""
    rt = _runtime()
    count = _check(rt.cudaGetDeviceCount(), "cudaGetDeviceCount")
    for i in range(count):
        props = _check(rt.cudaGetDeviceProperties(i), "cudaGetDeviceProperties")
        if bytes(props.uuid.bytes)[:16] == uuid[:16]:
            return i
    raise UsageError(f"device='cuda': the Vulkan device ({name}) is none of the {count} CUDA "
                     "devices; pick the NVIDIA GPU with Renderer(device=...)")


class _CudaArray:
    """A CUDA Array Interface (version 3) over `ptr`: what torch.as_tensor wraps."""

    def __init__(self, ptr: int, shape: tuple[int, ...], typestr: str, owner: Any) -> None:
        self.owner = owner  # keeps the import alive while a tensor views it
        self.__cuda_array_interface__ = {"shape": tuple(shape), "typestr": typestr,
                                         "data": (int(ptr), False), "version": 3,
                                         "strides": None, "stream": None}


class CudaImport:
    """`size` bytes of Vulkan memory exported as the file descriptor `fd` (ownership passes
    to CUDA), mapped into CUDA device `device` as one buffer."""

    def __init__(self, fd: int, size: int, device: int) -> None:
        rt = _runtime()
        self.device, self.size = device, int(size)
        _check(rt.cudaSetDevice(device), "cudaSetDevice")
        desc = rt.cudaExternalMemoryHandleDesc()
        desc.type = rt.cudaExternalMemoryHandleType.cudaExternalMemoryHandleTypeOpaqueFd
        desc.handle.fd = int(fd)
        desc.size = self.size
        self._ext = _check(rt.cudaImportExternalMemory(desc), "cudaImportExternalMemory")
        buf = rt.cudaExternalMemoryBufferDesc()
        buf.offset, buf.size, buf.flags = 0, self.size, 0
        self.ptr = int(_check(rt.cudaExternalMemoryGetMappedBuffer(self._ext, buf),
                              "cudaExternalMemoryGetMappedBuffer"))
        self._views: dict[tuple[tuple[int, ...], str], Any] = {}  # tensor()'s, by shape and type
        self.lent = False  # a tensor of it was handed to a caller (its owner closes it last)

    def tensor(self, shape: tuple[int, ...], dtype: str = "|u1") -> Any:
        """A torch tensor viewing the start of the buffer (no copy): valid until the memory
        is written again; callers clone it before handing it out. Made once per shape and
        type (a loop asks for the same each step; torch.as_tensor costs tens of us)."""
        key = (shape, dtype)
        view = self._views.get(key)
        if view is None:
            import torch

            view = torch.as_tensor(_CudaArray(self.ptr, shape, dtype, self),
                                   device=f"cuda:{self.device}")
            if len(self._views) > 8:
                self._views.clear()
            self._views[key] = view
        return view

    def close(self) -> None:
        if self._ext is None:
            return
        rt = _runtime()
        self._views.clear()
        _check(rt.cudaFree(self.ptr), "cudaFree")
        _check(rt.cudaDestroyExternalMemory(self._ext), "cudaDestroyExternalMemory")
        self._ext = None


def _stream(rt: Any, stream: int) -> Any:
    """A cudaStream_t of torch's `cuda_stream` handle (an int)."""
    return rt.cudaStream_t(stream) if hasattr(rt, "cudaStream_t") else stream


class CudaTimeline:
    """A Vulkan timeline semaphore (gpu/timeline.py SharedTimeline) exported as `fd`, imported
    into CUDA device `device`: a stream signals it to a value or waits for one."""

    def __init__(self, fd: int, device: int) -> None:
        rt = _runtime()
        _check(rt.cudaSetDevice(device), "cudaSetDevice")
        desc = rt.cudaExternalSemaphoreHandleDesc()
        desc.type = rt.cudaExternalSemaphoreHandleType.cudaExternalSemaphoreHandleTypeTimelineSemaphoreFd
        desc.handle.fd = int(fd)
        desc.flags = 0
        self._sem = _check(rt.cudaImportExternalSemaphore(desc), "cudaImportExternalSemaphore")
        self._sems = [self._sem]
        self._made: tuple[Any, Any, Any] | None = None  # (runtime, signal, wait parameters)
        self._stream: tuple[int, Any] | None = None  # (torch's handle, as a cudaStream_t)

    def signal(self, value: int, stream: int) -> None:
        """On `stream` (torch's cuda_stream handle): set the semaphore to `value` once the
        stream's work queued so far is done."""
        rt, params, handle = self._call(stream, signal=True)
        params.params.fence.value = int(value)
        _check(rt.cudaSignalExternalSemaphoresAsync(self._sems, [params], 1, handle),
               "cudaSignalExternalSemaphoresAsync")

    def wait(self, value: int, stream: int) -> None:
        """On `stream`: the work queued after this waits until the semaphore reaches `value`."""
        rt, params, handle = self._call(stream, signal=False)
        params.params.fence.value = int(value)
        _check(rt.cudaWaitExternalSemaphoresAsync(self._sems, [params], 1, handle),
               "cudaWaitExternalSemaphoresAsync")

    def _call(self, stream: int, signal: bool) -> tuple[Any, Any, Any]:
        """(the runtime, the signal or wait parameters, `stream` as a cudaStream_t): made
        once (a loop signals and waits every step on torch's same stream)."""
        if self._made is None:
            rt = _runtime()
            sig, wait = rt.cudaExternalSemaphoreSignalParams(), rt.cudaExternalSemaphoreWaitParams()
            sig.flags = wait.flags = 0
            self._made = (rt, sig, wait)
        rt, sig, wait = self._made
        if self._stream is None or self._stream[0] != stream:
            self._stream = (stream, _stream(rt, stream))
        return rt, sig if signal else wait, self._stream[1]

    def close(self) -> None:
        if self._sem is None:
            return
        _check(_runtime().cudaDestroyExternalSemaphore(self._sem), "cudaDestroyExternalSemaphore")
        self._sem = None
