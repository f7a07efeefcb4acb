# gpu/graph.py's barrier derivation, checked against the Vulkan specification's rules for
# synchronisation (no device needed: the barriers are the structs the tracker would record).
# - A frame's first use of a resource waits for every earlier command and makes every write
#   available (a recording replays after any other), and discards the contents (UNDEFINED);
#   every earlier command but copies where the resource is not `copied` (no copy touches it
#   last in any recording, or the recording that did closes with a barrier after the copy).
# - Write after write or read: a dependency from the earlier stages (an execution dependency
#   only, access 0, after reads alone).
# - Read after write: the write made visible to the reader's stage and access, once.
# - A new layout is a barrier even between reads.
# - Attachment uses inside one rendering need none (rasterisation order).

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import pytest
import vulkan as vk

from vkpbr.gpu.graph import BufferResource, ImageResource, Step, Tracker, build_kernels


@dataclass
class FakeBuffer:  # a gpu.buffer.Buffer's two fields the tracker reads
    handle: object
    size: int


def tracker() -> Tracker:
    return Tracker(vk, {"img": ImageResource(vk.ffi.NULL), "buf": BufferResource(FakeBuffer(vk.ffi.NULL, 64)),
                        "depth": ImageResource(vk.ffi.NULL, depth=True)})


def barrier(t: Tracker) -> tuple:
    """The one queued barrier as (src stage, src access, dst stage, dst access, old, new)."""
    assert len(t.images) + len(t.buffers) == 1, (t.images, t.buffers)
    b = (t.images or t.buffers)[0]
    layouts = (b.oldLayout, b.newLayout) if t.images else (None, None)
    t.images, t.buffers = [], []
    return (b.srcStageMask, b.srcAccessMask, b.dstStageMask, b.dstAccessMask, *layouts)


COMPUTE = vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
READ, WRITE = vk.VK_ACCESS_2_SHADER_STORAGE_READ_BIT, vk.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT
GENERAL = vk.VK_IMAGE_LAYOUT_GENERAL


NOT_COPIES = (vk.VK_PIPELINE_STAGE_2_ALL_GRAPHICS_BIT | COMPUTE | vk.VK_PIPELINE_STAGE_2_CLEAR_BIT
              | vk.VK_PIPELINE_STAGE_2_BLIT_BIT | vk.VK_PIPELINE_STAGE_2_RESOLVE_BIT)


def test_first_use_waits_for_everything_but_copies_and_discards() -> None:
    t = tracker()
    t.use("img", "storage")
    assert barrier(t) == (NOT_COPIES, vk.VK_ACCESS_2_MEMORY_WRITE_BIT,
                          COMPUTE, READ | WRITE, vk.VK_IMAGE_LAYOUT_UNDEFINED, GENERAL)
    assert not NOT_COPIES & (vk.VK_PIPELINE_STAGE_2_COPY_BIT | vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT)


def test_first_use_of_a_copied_resource_waits_for_everything() -> None:
    t = Tracker(vk, {"out": ImageResource(vk.ffi.NULL, copied=True),
                     "readback": BufferResource(FakeBuffer(vk.ffi.NULL, 64), copied=True)})
    t.use("out", "storage")
    assert barrier(t)[:2] == (vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, vk.VK_ACCESS_2_MEMORY_WRITE_BIT)
    t.use("readback", "transfer_dst")
    assert barrier(t)[:2] == (vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, vk.VK_ACCESS_2_MEMORY_WRITE_BIT)


@dataclass
class FakeCommands:  # what Tracker.flush hands gpu.rendering.barriers
    vk: object = vk
    recorded: list = None

    def __post_init__(self) -> None:
        self.recorded = []


def closing_barriers(resources: dict, uses: list[tuple[str, str]]) -> list:
    """The barriers `Tracker.close` adds after `uses` (each flushed as recorded)."""
    t = Tracker(vk, resources)
    for name, use in uses:
        t.use(name, use)
        t.images, t.buffers = [], []
    t.flush = lambda cmd: cmd.recorded.extend(t.images + t.buffers)  # type: ignore[method-assign]
    cmd = FakeCommands()
    t.close(cmd)
    return cmd.recorded


def test_a_recording_whose_copy_touches_a_resource_last_closes_after_it() -> None:
    from vkpbr.gpu import graph

    before = dict(graph.TAIL_WAITS)
    buf = BufferResource(FakeBuffer(vk.ffi.NULL, 64))
    (b,) = closing_barriers({"buf": buf}, [("buf", "storage"), ("buf", "transfer_src")])
    assert b.srcStageMask & vk.VK_PIPELINE_STAGE_2_COPY_BIT
    assert b.dstStageMask == vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT
    assert graph.TAIL_WAITS["buf"] == before.get("buf", 0) + 1
    img = ImageResource(vk.ffi.NULL)
    (i,) = closing_barriers({"img": img}, [("img", "storage"), ("img", "transfer_src")])
    assert (i.oldLayout, i.newLayout) == (vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,) * 2
    # None where a copy did not touch it last, or where it is `copied` (its next first use
    # waits for every earlier command).
    assert closing_barriers({"buf": buf}, [("buf", "transfer_src"), ("buf", "storage")]) == []
    assert closing_barriers({"buf": buf}, [("buf", "storage"), ("buf", "storage_read")]) == []
    copied = BufferResource(FakeBuffer(vk.ffi.NULL, 64), copied=True)
    assert closing_barriers({"buf": copied}, [("buf", "transfer_dst"), ("buf", "host_read")]) == []


def test_read_after_write_is_made_visible_once() -> None:
    t = tracker()
    t.use("img", "storage")
    barrier(t)
    t.use("img", "storage_read")
    assert barrier(t) == (COMPUTE, READ | WRITE, COMPUTE, READ, GENERAL, GENERAL)
    t.use("img", "storage_read")  # already visible there, same layout: nothing
    assert not t.pending


def test_write_after_read_waits_for_the_reader_only() -> None:
    t = tracker()
    t.use("img", "storage")
    barrier(t)
    t.use("img", "storage_read")
    barrier(t)
    t.use("img", "storage")
    src_stage, src_access, *_ = barrier(t)
    assert src_stage & COMPUTE and src_access == READ | WRITE  # the last write, and the reads
    t.use("buf", "transfer_dst")
    barrier(t)
    t.use("buf", "host_read")
    assert barrier(t)[:4] == (vk.VK_PIPELINE_STAGE_2_COPY_BIT | vk.VK_PIPELINE_STAGE_2_CLEAR_BIT,
                              vk.VK_ACCESS_2_TRANSFER_WRITE_BIT, vk.VK_PIPELINE_STAGE_2_HOST_BIT,
                              vk.VK_ACCESS_2_HOST_READ_BIT)


def test_a_new_layout_is_a_barrier_even_between_reads() -> None:
    t = tracker()
    t.use("img", "storage")
    barrier(t)
    t.use("img", "storage_read")
    barrier(t)
    t.use("img", "sampled")
    *_, old, new = barrier(t)
    assert (old, new) == (GENERAL, vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)


def test_attachments_need_no_barrier_in_one_rendering_one_across_two() -> None:
    t = tracker()
    t.use("depth", "depth_attachment", scope=0)
    barrier(t)
    t.use("depth", "depth_attachment", scope=0)
    assert not t.pending
    t.use("depth", "depth_attachment", scope=1)  # a new rendering loads what the last stored
    stages = (vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT
              | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT)
    assert barrier(t)[0] == stages


def test_two_layouts_in_one_use_of_an_image_is_refused() -> None:
    t = tracker()
    t.use("buf", "storage|transfer_dst")  # a buffer has no layout: fine
    with pytest.raises(ValueError, match="two layouts"):
        t.use("img", "storage|transfer_dst")


def test_a_recordings_kernels_are_made_at_once_and_their_errors_raised() -> None:
    """Step.kernels: made together (two makers of two steps must be under way at once to
    pass the barrier: KERNEL_THREADS is at least 2) before any step records, and a maker's
    error is the recording's."""
    together = threading.Barrier(2, timeout=30)
    made: list[str] = []

    def maker(name: str, wait: bool = True) -> Callable[[], str]:
        def make() -> str:
            if wait:
                together.wait()
            made.append(name)
            return name
        return make

    steps = [Step("a", kernels=(maker("x"), maker("y", wait=False))),
             Step("b", kernels=(maker("z"),))]
    build_kernels(steps)
    assert sorted(made) == ["x", "y", "z"]

    def broken() -> None:
        raise ValueError("no such kernel")

    with pytest.raises(ValueError, match="no such kernel"):
        build_kernels([Step("a", kernels=(broken, lambda: None))])
