"""The handles a device keeps (gpu/kept.py) and the children it keeps (Device.keeping), on a
bare device with the validation layer: one handle per definition, wrappers that let go of it
without destroying it, children outside a scene's count, and nothing left after close."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.compute import ComputePipeline, make_at_once
from vkpbr.gpu.descriptors import BindingSpec, DescriptorSetLayout
from vkpbr.gpu.device import Device, live_objects
from vkpbr.gpu.kept import KeptHandles
from vkpbr.gpu.pipeline_cache import pipeline_cache
from vkpbr.render.codegen import SPV_DIR

ROWS = [BindingSpec(0, "storage", ("compute",), "a"), BindingSpec(1, "storage", ("compute",))]


def _kernel(dev: Device, name: str = "dst", push: int = 16) -> ComputePipeline:
    """The BRDF table's kernel (its one binding: a storage image) with `push` bytes."""
    layout = DescriptorSetLayout(dev, [BindingSpec(1, "storage_image", ("compute",), name)])
    return ComputePipeline(dev, SPV_DIR / "env_brdf_lut.comp.spv", [layout], push_bytes=push)


def test_one_handle_per_definition_until_close() -> None:
    start = live_objects()
    dev = Device(validation=True)
    try:
        dev.kept = KeptHandles()
        assert pipeline_cache(dev).handle  # (made by the first build otherwise, its file opened
        # on a thread: waited for here, so it is not counted below)
        mark, base = dev.live_children, live_objects()
        first = _kernel(dev)
        made = live_objects() - base  # set layout, pipeline layout, pipeline (the module: gone)
        assert made == 3
        dev.destroy_children(mark)  # a scene's end: the wrappers let go, the handles stay
        assert first.handle is None and live_objects() - base == made
        again = _kernel(dev, "renamed")
        assert live_objects() - base == made and len(dev.kept) == made
        assert dev.kept.hits == 3  # (a binding's name is no part of the definition)
        other = _kernel(dev, push=32)  # another pipeline layout: its own, and its pipeline
        assert live_objects() - base == made + 2 and other.handle != again.handle
        dev.check_validation()
    finally:
        dev.close()
    assert live_objects() == start


def test_kept_children_outlive_a_scene_and_not_the_device() -> None:
    start = live_objects()
    dev = Device(validation=True)
    try:
        mark = dev.live_children
        with dev.keeping():
            kept = Buffer(dev, 64, "storage", name="kept")
        scene = Buffer(dev, 64, "storage", name="a scene's")
        assert dev.live_children == mark + 1
        dev.destroy_children(mark)
        assert scene.handle is None and kept.handle is not None
        plain = [DescriptorSetLayout(dev, ROWS) for _ in range(2)]  # no KeptHandles: two
        assert plain[0].handle != plain[1].handle
    finally:
        dev.close()
    assert kept.handle is None and live_objects() == start


def test_one_definition_made_on_many_threads_at_once_is_built_once() -> None:
    """The frame graph makes a recording's kernels on threads (gpu/graph.build_kernels); two
    steps of one kernel ask for one definition at once: one build, one handle, both
    wrappers share it."""
    dev = Device(validation=True)
    try:
        dev.kept = KeptHandles()
        stats = pipeline_cache(dev).stats
        layout = DescriptorSetLayout(dev, [BindingSpec(1, "storage_image", ("compute",), "dst")])
        kernels = make_at_once([lambda: ComputePipeline(
            dev, SPV_DIR / "env_brdf_lut.comp.spv", [layout], push_bytes=16)] * 8)
        assert len({k.handle for k in kernels}) == 1 and stats.built == 1
        assert dev.kept.hits == 14  # (the other seven makers: a pipeline layout and a pipeline)
        dev.check_validation()
    finally:
        dev.close()


def test_a_failed_maker_leaves_the_key_to_the_next_caller() -> None:
    kept, started, calls = KeptHandles(), threading.Event(), []

    def failing() -> object:
        started.set()
        time.sleep(0.05)  # (the second caller is waiting for this key meanwhile)
        raise RuntimeError("driver says no")

    def waiting() -> object:
        started.wait()
        return kept.get("key", "vkDestroyPipeline", lambda: calls.append(1) or "handle")

    with ThreadPoolExecutor(2) as pool:
        first = pool.submit(kept.get, "key", "vkDestroyPipeline", failing)
        second = pool.submit(waiting)
        with pytest.raises(RuntimeError, match="driver says no"):
            first.result()
        assert second.result() == "handle" and calls == [1]


def test_keeping_is_this_threads_only() -> None:
    """A kernel made on another thread while this one keeps is a scene's child (the device's
    own kernels and a scene's are made on threads at once)."""
    dev = Device(validation=True)
    try:
        mark = dev.live_children
        with dev.keeping():
            assert dev.keeps_here()
            with ThreadPoolExecutor(1) as pool:
                other = pool.submit(Buffer, dev, 64, "storage", name="a scene's").result()
            kept = Buffer(dev, 64, "storage", name="kept")
        assert not dev.keeps_here() and dev.live_children == mark + 1
        dev.destroy_children(mark)
        assert other.handle is None and kept.handle is not None
        dev.check_validation()
    finally:
        dev.close()
