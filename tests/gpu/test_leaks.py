"""Leaks (issue 11, class 7): every Vulkan object a Renderer makes is gone after close(), and
load/render/close cycles and frame loops do not grow the process.

The cause found on Mesa 22.3's lavapipe: it recompiled pbr.frag at each draw that bound other
uniform values (uniform inlining) and never freed the old compile, 37 MB a frame of the
default scene that survived close(). The shading now hides its branch uniforms from that pass
(shaders/frame_output.glsl, `opaque_zero`), and the compute path reads its frame and material
data from storage buffers, which lavapipe does not inline. RSS is read from /proc/self/statm
(Linux), after a warm-up: the first cycles grow the heap to its working size. These renderers
run without the validation layer, whose own bookkeeping would be measured too (every other
GPU test runs with it).

`VKPBR_SPV_DIR` (a folder of SPIR-V to load instead of the committed one) lets a reviewer
run these tests against the old shaders and watch them fail.
"""

from __future__ import annotations

import dataclasses
import gc
import os
from pathlib import Path

import numpy as np
import pytest

from vkpbr.gpu.device import Device, live_objects, live_objects_by_kind
from vkpbr.render import renderer as renderer_module
from vkpbr.render.renderer import COPY_COLOR, Renderer, RenderOptions
from vkpbr.scene.default import default_scene

MIB = 2**20
statm = Path("/proc/self/statm")
pytestmark = pytest.mark.skipif(not statm.exists(), reason="RSS is read from /proc/self/statm")


@pytest.fixture(autouse=True)
def spv_dir(monkeypatch: pytest.MonkeyPatch) -> None:
    if os.environ.get("VKPBR_SPV_DIR"):
        monkeypatch.setattr(renderer_module, "SPV_DIR", Path(os.environ["VKPBR_SPV_DIR"]))


def rss() -> int:
    """Resident set size of this process in bytes."""
    return int(statm.read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def small_scene():  # noqa: ANN201
    """The default scene cut to two spheres and the textured floor: three draws binding other
    material uniforms each frame (what made lavapipe recompile), at a third of its cost."""
    scene = default_scene()
    return dataclasses.replace(scene, nodes=[scene.nodes[0], scene.nodes[7], scene.nodes[-3]])


def median_mib(samples: list[int]) -> float:
    return float(np.median(samples)) / MIB


def test_live_objects_counts_creates_and_destroys() -> None:
    """The count follows the handles themselves: +1 per create or allocate, -1 per destroy or
    free, and a pool's command buffers go with the pool."""
    start, kinds = live_objects(), live_objects_by_kind()
    dev = Device()
    vk = dev.vk
    assert live_objects() == start + 3  # instance, device, command pool
    fence = vk.vkCreateFence(dev.handle, vk.VkFenceCreateInfo(), None)
    assert live_objects_by_kind().get("Fence", 0) == kinds.get("Fence", 0) + 1
    cmds = [dev.allocate_command_buffer() for _ in range(3)]
    assert live_objects() == start + 3 + 1 + 3
    dev.free_command_buffer(cmds[0])
    assert live_objects() == start + 3 + 1 + 2
    vk.vkDestroyFence(dev.handle, fence, None)
    assert live_objects() == start + 3 + 2
    dev.close()  # the pool takes its two remaining command buffers with it
    assert live_objects() == start
    assert live_objects_by_kind() == kinds


def test_close_destroys_every_vulkan_object(make_renderer, default_scene_cached) -> None:
    """All the objects a Renderer can make (targets of both kinds, every pipeline, recorded
    command buffers, a text overlay) are destroyed by close()."""
    start, kinds = live_objects(), live_objects_by_kind()
    r = make_renderer(default_scene_cached)
    r.render(size=(48, 32))
    list(r.render_many([None] * 4, size=(40, 30), linear=True, depth=True))
    target = r.offscreen_target((40, 30))
    r.build_pipelines(target)
    overlay = r.text_overlay(np.full((8, 8, 4), 255, np.uint8), target)
    sub = r.draw(target, r.default_camera(), (r.default_light(),), RenderOptions(),
                 overlay=overlay, copy=(COPY_COLOR,))
    r.read_color(target, sub)
    made = live_objects_by_kind()
    assert made["Pipeline"] - kinds.get("Pipeline", 0) >= 6  # every TBN path and pass
    assert live_objects() > start + 50
    r.close()
    assert live_objects() == start
    assert live_objects_by_kind() == kinds


@pytest.fixture(scope="module")
def default_scene_cached():  # noqa: ANN201
    return default_scene()


def test_load_render_close_cycles_are_flat() -> None:
    """22 cycles of Renderer -> render 32x32 -> close: the object count is back at its start
    after every close, and RSS over the last 10 grows by under 16 MiB, comparing the medians
    of their first and last 5 samples (the heap grows in steps of ~2.5-6.5 MiB; the code
    before this fix grew 3.3 MiB a cycle on this scene, 37 MiB on the default one). The first
    12 warm the heap up: on lavapipe's compute path (auto's on CPUs since session 26) RSS
    rises in 6.5 MiB steps over its first 8-10 cycles, then stays within 0.7 MiB for 36 more
    (the fragment path's plateau comes a few cycles sooner); sampled from cycle 6, one run in
    four had taken a third step inside the window."""
    scene = small_scene()
    start = live_objects()
    samples = []
    for i in range(22):
        r = Renderer(scene)
        r.render(size=(32, 32))
        r.close()
        assert live_objects() == start, (i, live_objects_by_kind())
        if i >= 12:
            gc.collect()
            samples.append(rss())
    growth = median_mib(samples[-5:]) - median_mib(samples[:5])
    assert growth < 16, [round(s / MIB, 1) for s in samples]


def test_frame_loop_is_flat() -> None:
    """One renderer, 60 frames after a warm-up of 30: RSS grows by under 4 MiB (before the
    fix: ~4 MiB a frame on this scene) and no Vulkan object is made per frame. (The warm-up
    outlasts the shadow maps' settling, render/shadows.py SETTLE_FRAMES, after which a GPU's
    frames first read the maps' images: 2 objects made once there, after a warm-up of 10.)"""
    with Renderer(small_scene()) as r:
        list(r.render_many([None] * 30, size=(32, 32)))
        gc.collect()
        before, objects, kinds = rss(), live_objects(), live_objects_by_kind()
        for _ in range(3):
            list(r.render_many([None] * 20, size=(32, 32)))
        gc.collect()
        assert live_objects() == objects, (kinds, live_objects_by_kind())
        assert rss() - before < 4 * MIB, (rss() - before) / MIB



def test_compute_path_frames_are_flat() -> None:
    """The compute path on lavapipe, a new exposure every frame (new frame values): RSS grows by
    under 8 MiB over 30 frames (reading uniform blocks, it grew ~30 MiB a frame)."""
    with Renderer(small_scene()) as r:
        if not r.device.compute_path:
            pytest.skip(f"{r.device.info.name} lacks the compute path's features")
        for i in range(30):  # (past the shadow maps' settling: test_frame_loop_is_flat)
            r.render(size=(32, 32), pipeline="compute", exposure=0.001 * i)
        gc.collect()
        before, objects, kinds = rss(), live_objects(), live_objects_by_kind()
        for i in range(30):
            r.render(size=(32, 32), pipeline="compute", exposure=0.1 + 0.01 * i)
        gc.collect()
        assert live_objects() == objects, (kinds, live_objects_by_kind())
        assert rss() - before < 8 * MIB, (rss() - before) / MIB


def test_ever_new_sizes_and_values_are_flat(monkeypatch) -> None:  # noqa: ANN001
    """A dataset's loop: every image its own size, bloom strength, noise seed and panorama,
    with GTAO and dataset outputs, then batches of their own sizes. Past the renderer's
    bounds on what it keeps (docs/architecture.md: targets, environments, recordings, lowered
    here to reach them within a few frames), no Vulkan object is made per image: each target,
    post-step image and environment destroyed goes with the recordings and descriptor sets
    that named it, the sets recycled. Before, every size kept its targets, their post images
    and GTAO sets (pools), every value a recording, every panorama its cubes."""
    from PIL import Image as PILImage

    from vkpbr.render import batch_path, environments, recorder, targets

    monkeypatch.setattr(targets, "TARGETS_KEPT", 2)
    monkeypatch.setattr(environments, "ENVIRONMENTS_KEPT", 1)
    monkeypatch.setattr(recorder, "RECORDINGS_KEPT", 2)
    monkeypatch.setattr(batch_path, "BATCH_TARGETS_KEPT", 1)
    rng = np.random.default_rng(5)
    folder = Path(os.environ.get("TMPDIR", "/tmp")) / f"vkpbr-leaks-{os.getpid()}"
    folder.mkdir(exist_ok=True)

    def image(r: Renderer, i: int) -> None:
        size = (int(rng.integers(24, 64)), int(rng.integers(16, 48)))
        env = folder / f"env{i % 5}.png"
        if not env.exists():
            PILImage.fromarray(rng.integers(0, 256, (16, 32, 3), dtype=np.uint8)).save(env)
        r.render(size=size, bloom=float(rng.uniform(0.05, 0.3)), noise=f"zed2,seed={i}",
                 ao="gtao", env=str(env), outputs=["color", "depth", "normal"])
        r.render_batch([r.default_camera()] * 2, size, pipeline="forward", ao="gtao")

    def made() -> dict[str, int]:
        """Live objects by kind but device memory: freed allocations wait in Device.memory
        for reuse, within its own bounds (gpu/memory.py, test_memory.py)."""
        return {k: n for k, n in live_objects_by_kind().items() if k != "Memory"}

    with Renderer(small_scene()) as r:
        for i in range(12):
            image(r, i)
        gc.collect()
        before = made()
        for i in range(12, 30):
            image(r, i)
        gc.collect()
        after = made()
        assert all(after.get(k, 0) <= n for k, n in before.items()) and after.keys() <= before.keys(), (
            {k: (before.get(k), after.get(k)) for k in before.keys() | after.keys()
             if before.get(k) != after.get(k)})
