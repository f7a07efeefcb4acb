"""A device's VkPipelineCache, kept in a file of the cache folder between processes.

Every pipeline the gpu layer builds (gpu/pipeline.py, gpu/compute.py) goes through its
device's `PipelineCache` (`Feedback.build`): a second pipeline of the same shaders and state
is the driver's cache hit, in this process and, once the file is saved, in the next. The
file's name carries a digest of what makes its data usable (the device's UUID and pipeline
cache UUID, vendor and device ids, the driver version and the caller's `salt`: the SPIR-V's
digest), so another GPU, driver or set of shaders starts a file of its own; saving removes
the same device's files of other shaders. Its contents are checked before the driver sees
them (vkpbr's header: magic, that digest, the payload's length and SHA-256; then Vulkan's own
header against the device): a corrupt, truncated or foreign file is ignored with one warning
line and the pipelines are compiled afresh, never a crash. Writes are atomic
(vkpbr.atomic), so processes sharing the folder (Ray's actors, a job's renderer processes)
never read half a file, and a save merges what others saved since (under a lock file), so
the file holds every process's pipelines.

`stats` counts the builds, the driver's reported cache hits (VK_PIPELINE_CREATION_FEEDBACK:
drivers that do not report them leave `hits` 0) and the seconds spent building (summed over
the threads that build at once: FrameRecorder.build_pipelines).
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import struct
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from vkpbr.atomic import atomic_writer
from vkpbr.gpu.device import Device, DeviceObject
from vkpbr.gpu.vk import check_result

__all__ = ["PipelineCache", "PipelineStats", "Feedback", "pipeline_cache", "MAGIC", "FILE_PREFIX"]

log = logging.getLogger(__name__)
_STATS_LOCK = threading.Lock()

MAGIC = b"VKPBRPC1"
FILE_PREFIX = "pipelines-"
# vkpbr's header: magic, the key's SHA-256, the payload's SHA-256, the payload's length.
_HEADER = struct.Struct("<8s32s32sQ")
# Vulkan's VkPipelineCacheHeaderVersionOne: size, version, vendor, device, cache UUID.
_VK_HEADER = struct.Struct("<IIII16s")


@dataclass
class PipelineStats:
    """What a device's pipeline builds cost: how many, how many the driver reported as cache
    hits, and the seconds spent in vkCreate*Pipelines."""

    built: int = 0
    hits: int = 0
    seconds: float = 0.0
    # (what was built, when it began on perf_counter's clock, its seconds, the driver's hit,
    # the thread that built it)
    builds: list[tuple[str, float, float, bool, str]] = field(default_factory=list)


class PipelineCache(DeviceObject):
    """`device`'s VkPipelineCache; loaded from `folder` (None: in memory only) when a valid
    file of this device and `salt` is there. `save()` writes it back when it grew."""

    _destroy_fn = "vkDestroyPipelineCache"

    def __init__(self, device: Device, folder: str | Path | None = None, salt: str = "") -> None:
        self.device = device
        self.stats = PipelineStats()
        props = device.properties
        self._vk_header = (int(props.vendorID), int(props.deviceID),
                           bytes(props.pipelineCacheUUID))
        self._key = hashlib.sha256(repr((device.uuid(), *self._vk_header,
                                         int(props.driverVersion), salt)).encode()).digest()
        self._device_digest = hashlib.sha256(repr((device.uuid(), *self._vk_header)).encode()
                                             ).hexdigest()[:12]
        self.path = (Path(folder) / f"{FILE_PREFIX}{self._device_digest}-{self._key.hex()[:12]}.bin"
                     if folder is not None else None)
        self._handle: Any = None
        self._loaded_bytes = 0
        self._saved = b""
        self._built_at_save = 0
        self._written_at = -float("inf")  # (time.monotonic of the last write)
        self._failure: BaseException | None = None
        device.track(self)
        # A file of many pipelines takes the NVIDIA driver a quarter of a second to read
        # back (H200: 0.24 s of Sponza's warm start), and nothing needs it before the first
        # pipeline is built: open it on a thread (the file's read, its checksum and
        # vkCreatePipelineCache all let go of the GIL) while the scene uploads; `handle`
        # waits for it. Without a file, at once.
        self._opening: threading.Thread | None = None
        if self.path is not None and self.path.is_file():
            self._opening = threading.Thread(target=self._open, name="vkpbr-pipeline-cache",
                                             daemon=True)
            self._opening.start()
        else:
            self._open()

    def _open(self) -> None:
        try:
            initial = self._read() if self.path is not None else b""
            vk = self.device.vk
            blob = vk.ffi.from_buffer(initial) if initial else vk.ffi.NULL
            self._handle = vk.vkCreatePipelineCache(self.device.handle, vk.VkPipelineCacheCreateInfo(
                initialDataSize=len(initial), pInitialData=blob), None)
            self._loaded_bytes = len(initial)
            self._saved = initial
        except BaseException as exc:  # noqa: BLE001 - raised where the handle is asked for
            self._failure = exc

    def _wait_opened(self) -> None:
        opening = self._opening
        if opening is not None:
            opening.join()
            self._opening = None
        if self._failure is not None:
            failure, self._failure = self._failure, None
            raise failure

    @property
    def handle(self) -> Any:  # type: ignore[override]
        """The VkPipelineCache (waits for its file's opening)."""
        self._wait_opened()
        return self._handle

    @handle.setter
    def handle(self, value: Any) -> None:
        self._handle = value

    @property
    def loaded_bytes(self) -> int:
        """The driver's data given back to it from the file (0: none)."""
        self._wait_opened()
        return self._loaded_bytes

    # --- the file -------------------------------------------------------------------------
    def _read(self) -> bytes:
        """The file's payload when it is whole and this device's, else b"" (with a note)."""
        assert self.path is not None
        try:
            raw = self.path.read_bytes()
        except FileNotFoundError:
            return b""
        except OSError as exc:
            return self._ignored(exc.strerror or str(exc))
        if len(raw) < _HEADER.size:
            return self._ignored("too short")
        magic, key, digest, size = _HEADER.unpack_from(raw)
        payload = raw[_HEADER.size:]
        if magic != MAGIC:
            return self._ignored("not a vkpbr pipeline cache")
        if key != self._key:
            return self._ignored("made for another device, driver or set of shaders")
        if size != len(payload) or hashlib.sha256(payload).digest() != digest:
            return self._ignored("corrupt (its length or checksum does not match)")
        if len(payload) < _VK_HEADER.size:
            return self._ignored("no Vulkan header")
        _, version, vendor, dev, uuid = _VK_HEADER.unpack_from(payload)
        if version != 1 or (vendor, dev, uuid) != self._vk_header:
            return self._ignored("its Vulkan header names another device")
        return payload

    def _ignored(self, why: str) -> bytes:
        log.warning("%s: pipeline cache ignored (%s); pipelines are compiled afresh", self.path, why)
        return b""

    def data(self) -> bytes:
        """The driver's serialised cache now (vkGetPipelineCacheData)."""
        vk = self.device.vk
        ffi, dev = vk.ffi, self.device.handle
        size = ffi.new("size_t*")
        check_result(vk.lib.vkGetPipelineCacheData(dev, self.handle, size, ffi.NULL),
                     "vkGetPipelineCacheData")
        buf = ffi.new("char[]", max(1, size[0]))
        check_result(vk.lib.vkGetPipelineCacheData(dev, self.handle, size, buf),
                     "vkGetPipelineCacheData")
        return ffi.buffer(buf, size[0])[:]

    def save(self, min_interval: float = 0.0) -> bool:
        """Write the cache to its file (atomically) when pipelines were built since it was
        loaded or last saved and the driver's data holds something the file did not; True
        when written. What another process wrote to the file since this one read it is
        merged in first (vkMergePipelineCaches, under a lock file): processes sharing the
        folder (a job's renderer processes, each building its scenes' variants) all keep
        theirs, where the last writer's alone had been kept. `min_interval`: not within that
        many seconds of the last write (a job saves after every item; the merge reads the
        whole file back). A folder that cannot be written is a warning: the next process
        compiles again."""
        if self.path is None or self.handle is None or self.stats.built == self._built_at_save:
            return False
        if min_interval and time.monotonic() - self._written_at < min_interval:
            return False  # (the builds stay counted as unsaved: a later save writes them)
        self._built_at_save = self.stats.built
        payload = self.data()
        if payload == self._saved:  # (cache hits: nothing the file lacks)
            return False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with _locked(self.path.parent / f"{FILE_PREFIX}{self._device_digest}.lock"):
                if self._merge_file():
                    payload = self.data()
                head = _HEADER.pack(MAGIC, self._key, hashlib.sha256(payload).digest(), len(payload))
                with atomic_writer(self.path) as f:
                    f.write(head + payload)
        except OSError as exc:
            log.warning("%s: pipeline cache not written (%s)", self.path, exc.strerror or exc)
            return False
        self._saved = payload
        self._written_at = time.monotonic()
        self._remove_stale()
        return True

    def _merge_file(self) -> bool:
        """Merge into this cache the file's data where another process wrote it since this
        one read or wrote it (a damaged file is ignored, with `_read`'s note); True when
        merged."""
        if self.path is None or not self.path.is_file():
            return False
        theirs = self._read()
        if not theirs or theirs == self._saved:
            return False
        vk, dev = self.device.vk, self.device.handle
        other = vk.vkCreatePipelineCache(dev, vk.VkPipelineCacheCreateInfo(
            initialDataSize=len(theirs), pInitialData=vk.ffi.from_buffer(theirs)), None)
        try:
            vk.vkMergePipelineCaches(dev, self.handle, 1, [other])
        finally:
            vk.vkDestroyPipelineCache(dev, other, None)
        return True

    def _remove_stale(self) -> None:
        """This device's files of other shaders or drivers: never read again."""
        assert self.path is not None
        for old in self.path.parent.glob(f"{FILE_PREFIX}{self._device_digest}-*.bin"):
            if old != self.path:
                old.unlink(missing_ok=True)

    def destroy(self) -> None:
        """Save (when it grew), then destroy the VkPipelineCache (one that failed to open
        has nothing to destroy: its error was for the pipelines that needed it)."""
        try:
            self._wait_opened()
        except Exception:  # noqa: BLE001
            self.device.untrack(self)
            return
        if self.handle is not None:
            self.save()
        super().destroy()


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """An exclusive lock on the file `path` (made if missing) while inside: where fcntl is
    missing (Windows), none."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - POSIX only
        yield
        return
    with open(path, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def pipeline_cache(device: Device) -> PipelineCache:
    """The device's cache: the one `Device.pipeline_cache` holds, made in memory at first use."""
    cache = getattr(device, "pipeline_cache", None)
    if cache is None or cache.handle is None:
        cache = PipelineCache(device)
        device.pipeline_cache = cache
    return cache


class Feedback:
    """A VkPipelineCreationFeedbackCreateInfo to chain into a pipeline's create info, and the
    timed build through the device's cache (`build`)."""

    def __init__(self, device: Device, next_struct: Any = None) -> None:
        vk = device.vk
        self.device = device
        self.result = vk.ffi.new("VkPipelineCreationFeedback*")
        self.info = vk.VkPipelineCreationFeedbackCreateInfo(
            pNext=next_struct, pPipelineCreationFeedback=self.result,
            pipelineStageCreationFeedbackCount=0, pPipelineStageCreationFeedbacks=None)

    def build(self, kind: str, info: Any, name: str = "") -> Any:
        """One pipeline of `info` (whose pNext chain holds `self.info`), `kind` "graphics" or
        "compute", through the device's pipeline cache; `name` (its shaders) for the stats."""
        vk, device = self.device.vk, self.device
        cache = pipeline_cache(device)
        create = vk.vkCreateGraphicsPipelines if kind == "graphics" else vk.vkCreateComputePipelines
        t0 = time.perf_counter()
        handle = create(device.handle, cache.handle, 1, [info], None)[0]
        seconds = time.perf_counter() - t0
        flags = int(self.result.flags)
        hit = bool(flags & vk.VK_PIPELINE_CREATION_FEEDBACK_VALID_BIT and (
            flags & vk.VK_PIPELINE_CREATION_FEEDBACK_APPLICATION_PIPELINE_CACHE_HIT_BIT))
        with _STATS_LOCK:  # builds may run on several threads (FrameRecorder.build_pipelines)
            cache.stats.seconds += seconds
            cache.stats.built += 1
            cache.stats.hits += hit
            cache.stats.builds.append((name or kind, t0, seconds, hit,
                                       threading.current_thread().name))
        return handle
