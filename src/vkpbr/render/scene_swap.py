"""A Renderer's scene made and unmade on one device: `Renderer.set_scene` without a new device.

`SceneMaker` holds what a Renderer was made with besides its scene (msaa, background, ...)
and the `DeviceParts` its scenes share (render/parts.py: the frame ring and slots, the
pre-filtered environments, the shadow maps' images, the offscreen targets and compute-batch
atlases), and makes a scene's `FrameParts` with
the frame and batch paths that draw them, noting how many device children existed before;
`unmake` closes them and destroys every device child made since (buffers, images,
descriptor pools and sets, ...), newest first. What is kept: the device, its queue and
command pool, its pipeline cache (gpu/pipeline_cache.py), the handles it keeps (gpu/kept.py:
set and pipeline layouts, pipelines and samplers, shared by every wrapper of the same
definition, so the new scene's pipelines are neither compiled nor looked up in the driver's
cache), the `DeviceParts` (made under `Device.keeping`: outside the scenes' count; the
ambient occlusion's images and kernels among them, made with the first scene) and auto's
frame-path record. A Renderer after `set_scene(b)` renders what `Renderer(b)`
renders, bit for bit, and a second round of swaps makes no Vulkan object the first did not
(tests/gpu/test_scene_swap.py).

Timings of a scene's making (`Renderer.timings`): "setup" (all of it, seconds), "parts" (the
GPU objects besides the scene's upload), "load_wait" (the wait for a scene loading on a thread,
vkpbr.bake.ahead, once the device was made), the scene upload's "geometry", "textures" and
"materials", and the pipeline cache's totals so far ("pipelines_built", "pipeline_hits",
"pipelines_s").
"""

from __future__ import annotations

import os
import time
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

from vkpbr.errors import UsageError
from vkpbr.gpu.device import Device
from vkpbr.render import kernels_ahead
from vkpbr.render.batch_path import BatchPath
from vkpbr.render.environment import EnvironmentSpec
from vkpbr.render.frame_path import FramePath
from vkpbr.render.parts import DeviceParts, FrameParts, make_parts
from vkpbr.scene._checks import vec3
from vkpbr.scene.types import Scene

__all__ = ["SceneMaker", "MadeScene", "pipeline_timings"]


@dataclass
class MadeScene:
    """One scene's parts and the paths that draw them, and the device children before them."""

    scene: Scene
    parts: FrameParts
    frame_path: FramePath
    batch_path: BatchPath
    mark: int  # device.live_children before the parts were made
    timings: dict[str, float]


def pipeline_timings(device: Device) -> dict[str, float]:
    """The device's pipeline builds so far: how many, the driver's cache hits, seconds."""
    cache = getattr(device, "pipeline_cache", None)
    if cache is None:
        return {"pipelines_built": 0, "pipeline_hits": 0, "pipelines_s": 0.0}
    st = cache.stats
    return {"pipelines_built": st.built, "pipeline_hits": st.hits, "pipelines_s": st.seconds}


def checked_args(msaa: Any, background: Any, env_spec: Any) -> tuple[float, float, float]:
    """The Renderer's msaa, background and env_spec checked before a device is opened (one
    line each; a background of a string had reached Vulkan's clear value as a TypeError, an
    env_spec of another type the pre-filter as an AttributeError); the background as 3 floats."""
    if msaa not in (1, 4):
        raise UsageError(f"msaa {msaa}: choose 1 or 4")
    if env_spec is not None and not isinstance(env_spec, EnvironmentSpec):
        raise UsageError(f"env_spec: expected an EnvironmentSpec, got {type(env_spec).__name__}")
    return vec3(background, "background")


def checked_scene(scene: Any) -> None:
    """A UsageError unless `scene` is a Scene, a Future of one or None (a path had failed deep
    in the parts' making with an AttributeError)."""
    if scene is not None and not isinstance(scene, Scene | Future):
        raise UsageError(f"scene: expected a Scene (vkpbr.load_scene(path) loads a file), a "
                         f"Future of one or None, got {type(scene).__name__}")


class SceneMaker:
    """Makes a scene's parts on `device` with a Renderer's other arguments (their names)."""

    def __init__(self, device: Device, msaa: int, background: tuple[float, float, float],
                 depth_prepass: bool | None, env_spec: EnvironmentSpec | None,
                 cache_dir: str | os.PathLike[str] | None, semantics: Any) -> None:
        self.device = device
        self.shared = DeviceParts.make(device, env_spec, cache_dir)  # (the scenes' shared)
        self.args = (msaa, background, depth_prepass, self.shared, cache_dir, semantics)
        # The device's first scene makes its first frame's likely kernels while it uploads
        # (render/kernels_ahead.py): with nothing cached, most of its first frame's time.
        # A later scene's are mostly made (kept handles) or in the pipeline cache.
        # (not for a window's device or MSAA: their frames take the fragment path)
        self.kernels_ahead = (kernels_ahead.wanted(device) and msaa <= 1
                              and "VK_KHR_swapchain" not in device.extensions)

    def make(self, scene: Scene | Future | None) -> MadeScene:
        """The parts of `scene` (None: the built-in PBR chart; a Future of one, such as
        vkpbr.bake.ahead's SceneAhead: waited for here, after the device was made, and its
        images decoded ahead used); on failure, whatever was made for it is destroyed again
        before the error propagates."""
        t0 = time.perf_counter()
        ahead = scene if isinstance(scene, Future) else None
        if ahead is not None:
            scene = ahead.result()  # (a load's error is raised here, as load_scene raises it)
        load_wait = time.perf_counter() - t0  # (the part of the load the device did not hide)
        if scene is None:
            from vkpbr.scene.default import default_scene

            scene = default_scene()
        with self.device.lock:  # (another thread's frames finish first)
            mark = self.device.live_children
            try:
                parts = make_parts(self.device, scene, *self.args, ahead=ahead,
                                   kernels_ahead=self.kernels_ahead)
                self.kernels_ahead = False
            except BaseException:
                self.device.wait_idle()
                self.device.destroy_children(mark)
                raise
        setup = time.perf_counter() - t0
        upload = parts.gpu_scene.timings
        timings = {"setup": setup, "load_wait": load_wait,
                   "parts": setup - load_wait - sum(upload.values()), **upload,
                   **pipeline_timings(self.device)}
        return MadeScene(scene, parts, FramePath(parts), BatchPath(parts), mark, timings)

    def unmake(self, made: MadeScene) -> None:
        """Close `made`'s parts and paths and destroy the device children made for them
        (a stream of its frames left open: the collect under way first, the rest dropped)."""
        with self.device.lock:  # (another thread's frames finish first)
            self.device.stop_background("collect")
            self.device.wait_idle()
            made.batch_path.close()
            made.parts.close()
            self.device.destroy_children(made.mark)
