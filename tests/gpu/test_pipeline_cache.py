"""The pipeline cache kept in the cache folder (gpu/pipeline_cache.py; issue 32, must-have 7).

What is asserted: a Renderer with a cache folder writes its device's VkPipelineCache there,
atomically, with vkpbr's header; the next Renderer hands the same bytes back to the driver
(`loaded_bytes`), and where the driver keeps compiled pipelines in it, the second Renderer's
builds are its hits (the cache does not grow, and every build the driver reports on is a
hit). A file that is cut short, altered, of other shaders or not vkpbr's is ignored with one
warning line naming it, and the pipelines are compiled afresh. Nothing here times anything:
counts and sizes only.
"""

from __future__ import annotations

import logging
import struct
from pathlib import Path

import numpy as np
import pytest

from vkpbr.gpu.compute import ComputePipeline
from vkpbr.gpu.descriptors import BindingSpec, DescriptorSetLayout
from vkpbr.gpu.device import Device
from vkpbr.gpu.pipeline_cache import FILE_PREFIX, MAGIC, PipelineCache
from vkpbr.render.codegen import SPV_DIR

VK_HEADER_BYTES = 32  # VkPipelineCacheHeaderVersionOne


def _build_one(device: Device) -> None:
    """One compute pipeline built through the device's cache (the smallest real build)."""
    layout = DescriptorSetLayout(device, [BindingSpec(i, "storage", ("compute",))
                                          for i in range(5)])  # batch_cull.comp's bindings
    ComputePipeline(device, SPV_DIR / "batch_cull.comp.spv", [layout], push_bytes=12)


def _cache(tmp_path: Path, salt: str = "shaders-a") -> tuple[Device, PipelineCache]:
    device = Device(validation=True)
    device.pipeline_cache = PipelineCache(device, tmp_path, salt)
    assert device.pipeline_cache.handle is not None  # (its file opens on a thread: waited for,
    return device, device.pipeline_cache              # as the first pipeline's build waits)


def _saved(tmp_path: Path, salt: str = "shaders-a") -> Path:
    """A cache file of this device and `salt`, written by a device that built a pipeline."""
    device, cache = _cache(tmp_path, salt)
    try:
        _build_one(device)
    finally:
        device.close()  # saves
    assert cache.path is not None and cache.path.is_file()
    return cache.path


def test_renderers_write_and_read_the_cache(make_renderer, tmp_path: Path) -> None:  # noqa: ANN001
    first = make_renderer(cache_dir=tmp_path)
    first.render(size=(32, 32))
    built = first.device.pipeline_cache.stats.built
    first.close()
    files = sorted(tmp_path.glob(f"{FILE_PREFIX}*.bin"))
    assert len(files) == 1 and built > 0
    raw = files[0].read_bytes()
    magic, _key, _digest, size = struct.unpack_from("<8s32s32sQ", raw)
    payload = raw[80:]
    assert magic == MAGIC and size == len(payload) >= VK_HEADER_BYTES
    header_size, version = struct.unpack_from("<II", payload)
    assert (header_size, version) == (VK_HEADER_BYTES, 1)

    second = make_renderer(cache_dir=tmp_path)
    cache = second.device.pipeline_cache
    assert cache.loaded_bytes == len(payload)  # the driver got the file's data back
    second.render(size=(32, 32))
    assert cache.stats.built == built  # the same pipelines, asked of the cache
    grown = len(cache.data())
    if len(payload) == VK_HEADER_BYTES:
        pytest.skip(f"{second.device.info.name} keeps no pipelines in its cache (its data is "
                    "the 32-byte header): hits are checked on drivers that keep them (the GPU)")
    assert grown == len(payload), "the second renderer compiled pipelines the file did not hold"
    if cache.stats.hits:  # where the driver reports hits (creation feedback), all are hits
        assert cache.stats.hits == cache.stats.built


def test_saved_file_is_reloaded(tmp_path: Path) -> None:
    path = _saved(tmp_path)
    device, cache = _cache(tmp_path)
    try:
        assert cache.path == path
        assert cache.loaded_bytes == len(path.read_bytes()) - 80 >= VK_HEADER_BYTES
    finally:
        device.close()


def _truncated(raw: bytes) -> bytes:
    return raw[: len(raw) - 7]


def _flipped(raw: bytes) -> bytes:
    body = bytearray(raw)
    body[-1] ^= 0xFF
    return bytes(body)


def _not_ours(raw: bytes) -> bytes:
    return b"\x00" * len(raw)


@pytest.mark.parametrize(("damage", "why"), [(_truncated, "corrupt"), (_flipped, "corrupt"),
                                              (_not_ours, "not a vkpbr pipeline cache"),
                                              (lambda raw: raw[:10], "too short")])
def test_damaged_file_is_ignored_with_a_note(tmp_path: Path, caplog: pytest.LogCaptureFixture,
                                             damage, why: str) -> None:  # noqa: ANN001
    path = _saved(tmp_path)
    path.write_bytes(damage(path.read_bytes()))
    with caplog.at_level(logging.WARNING, logger="vkpbr.gpu.pipeline_cache"):
        device, cache = _cache(tmp_path)
    try:
        notes = [r.getMessage() for r in caplog.records]
        assert len(notes) == 1 and str(path) in notes[0] and why in notes[0], notes
        assert "\n" not in notes[0]
        assert cache.loaded_bytes == 0
        _build_one(device)  # compiled afresh
    finally:
        device.close()
    assert path.read_bytes()[:8] == MAGIC  # written again, whole
    device, cache = _cache(tmp_path)
    try:
        assert cache.loaded_bytes > 0
    finally:
        device.close()


def test_foreign_file_is_ignored_and_stale_files_removed(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    old = _saved(tmp_path, "shaders-a")
    device, cache = _cache(tmp_path, "shaders-b")  # new shaders: a file of their own
    try:
        assert cache.path != old and cache.loaded_bytes == 0
        assert cache.path is not None
        cache.path.write_bytes(old.read_bytes())  # another key under this name
        with caplog.at_level(logging.WARNING, logger="vkpbr.gpu.pipeline_cache"):
            other = PipelineCache(device, tmp_path, "shaders-b")
        assert other.loaded_bytes == 0
        assert any("another device, driver or set of shaders" in r.getMessage()
                   for r in caplog.records)
        other.destroy()
        cache.path.unlink()
        _build_one(device)
    finally:
        device.close()
    assert not old.exists()  # the same device's file of the old shaders is gone
    assert [p.name for p in tmp_path.glob(f"{FILE_PREFIX}*.bin")] == [cache.path.name]


def test_unwritable_folder_is_a_warning(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    blocker = tmp_path / "file"
    blocker.write_bytes(b"")
    device, cache = _cache(blocker / "sub")  # its parent is a file: cannot be made
    with caplog.at_level(logging.WARNING, logger="vkpbr.gpu.pipeline_cache"):
        try:
            _build_one(device)
        finally:
            device.close()
    assert any("not written" in r.getMessage() for r in caplog.records)
    assert np.all([not p.name.startswith(FILE_PREFIX) for p in tmp_path.iterdir()])


def test_device_closed_while_its_cache_file_opens(tmp_path: Path) -> None:
    """The cache's file opens on a thread: a device closed before anything asked for the
    cache waits for it, destroys it, and leaves the file as it was (nothing was built)."""
    path = _saved(tmp_path)
    before = path.read_bytes()
    for _ in range(3):
        device = Device(validation=True)
        device.pipeline_cache = PipelineCache(device, tmp_path, "shaders-a")
        device.close()  # validation: no leaked VkPipelineCache, no call after the device's end
    assert path.read_bytes() == before


def _build_other(device: Device) -> None:
    """Another compute pipeline than `_build_one`'s (the BRDF table's kernel)."""
    layout = DescriptorSetLayout(device, [BindingSpec(1, "storage_image", ("compute",))])
    ComputePipeline(device, SPV_DIR / "env_brdf_lut.comp.spv", [layout], push_bytes=16)


def test_caches_sharing_a_folder_merge_what_each_saved(tmp_path: Path) -> None:
    """Two devices (a job's renderer processes) read the same file, build different
    pipelines and save in turn: the second merges the first's saved data (under the lock
    file) instead of writing over it, so a third finds both pipelines there."""
    first, a = _cache(tmp_path)
    second, b = _cache(tmp_path)
    try:
        _build_one(first)
        _build_other(second)
        assert a.save() and a.path is not None
        one_alone = a.path.read_bytes()
        assert b.save()
        both = b.path.read_bytes()
        first.check_validation()
        second.check_validation()
    finally:
        first.close()
        second.close()
    third, c = _cache(tmp_path)
    try:
        assert c.loaded_bytes == len(both) - 80
        if len(one_alone) - 80 == VK_HEADER_BYTES:
            pytest.skip(f"{third.info.name} keeps no pipelines in its cache (its data is the "
                        "32-byte header): the merge's content is checked where it does (the GPU)")
        assert len(both) > len(one_alone)
        _build_one(third)
        _build_other(third)
        assert c.stats.built == 2 and len(c.data()) == len(both) - 80  # (nothing new compiled)
        if c.stats.hits:  # where the driver reports hits, both were
            assert c.stats.hits == 2
    finally:
        third.close()


def test_a_save_within_its_interval_waits_for_the_next(tmp_path: Path) -> None:
    """A job saves after every item at most every SAVE_EVERY seconds (each save merges the
    file back in): a save of new pipelines within the interval writes nothing, and the next
    one without it (close's) writes them."""
    device, cache = _cache(tmp_path)
    try:
        _build_one(device)
        assert cache.save(min_interval=3600.0)  # (nothing written before: not within it)
        if len(cache.data()) == VK_HEADER_BYTES:
            pytest.skip(f"{device.info.name} keeps no pipelines in its cache (its data is the "
                        "32-byte header): new data to hold back is checked where it does")
        written = cache.path.read_bytes()
        _build_other(device)
        assert not cache.save(min_interval=3600.0) and cache.path.read_bytes() == written
        assert cache.save() and len(cache.path.read_bytes()) > len(written)
        device.check_validation()
    finally:
        device.close()
