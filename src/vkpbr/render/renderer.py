"""The renderer: a Scene drawn through one frame path into any frame target; a facade over
its parts (render/parts.py: each concern its own module, none calling back into it). `draw`
(render/frame_path.py) serves every target; `render`/`render_many` are it on offscreen targets
once auto's path is chosen (render/path_choice.py); `render_batch` the batch path
(render/batch_route.py); `set_scene` render/scene_swap.py. The viewer is `draw` plus a HUD."""

from __future__ import annotations

import os
import time
from collections.abc import Iterable, Iterator, Mapping
from contextlib import closing
from typing import Any

import numpy as np

from vkpbr.gpu.target import COPY_COLOR, COPY_DEPTH, FrameTarget
from vkpbr.render import outputs as O
from vkpbr.render.batch_call import WorldArgs, WorldsArg, batch_call, batch_step, world_slots
from vkpbr.render.batch_route import chunked, per_view
from vkpbr.render.environment import EnvironmentSpec
from vkpbr.render.frame_path import Submitted
from vkpbr.render.frames import FrameStats
from vkpbr.render.instances import instance_api
from vkpbr.render.lighting import LightsArg, automatic_sun
from vkpbr.render.options import RenderOptions, with_overrides
from vkpbr.render.outputs import OUTPUTS, frame_outputs
from vkpbr.render.overlay import TextOverlay
from vkpbr.render.parts import FrameParts, open_device
from vkpbr.render.scene_state import with_times
from vkpbr.render.scene_swap import SceneMaker, checked_args, checked_scene
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.types import Camera, Light, Scene
from vkpbr.scene.worlds import WorldSlots

__all__ = ["Renderer", "RenderOptions", "FrameStats", "Submitted", "COPY_COLOR", "COPY_DEPTH",
           "LightsArg", "OUTPUTS", "frame_outputs"]


class Renderer:
    """Renders a Scene (the built-in default scene when None) into NumPy arrays or a window;
    poses, visibility and animation time change between frames (docs/living-scenes.md).
    Parameters
    ----------
    scene : the scene to draw, or a Future of one (vkpbr.bake.ahead); None: the built-in chart.
    device : device name substring or index (`vkpbr info` lists them); None picks the best.
    validation : enable the Khronos validation layer; any error raises ValidationError.
        None (default): on when the environment has VKPBR_VALIDATION=1 (how the test suite
        runs scripts, such as examples/, under the layer without changing them).
    sync_validation : with `validation`, also synchronization validation.
    msaa : 1 or 4 samples per pixel (offscreen renders).
    background : linear RGB of pixels where nothing was drawn.
    depth_prepass : draw opaque geometry depth-only first, so each pixel is shaded once.
        None (default): where it was measured to win (render/path_choice.py).
    window_extensions : a window system's instance extensions (GLFW's): swapchains too.
    env_spec : cube sizes and sample counts of the environments' pre-filter (None: the GPU
        sizes, or EnvironmentSpec.cpu() on a CPU device).
    cache_dir : where the BRDF table, frame-path record and pipeline cache are kept (None: none).
    semantics : where the dataset outputs' semantic ids come from (vkpbr.scene.semantics):
        "mesh" (each mesh primitive its own class), "material", "extras" (glTF `extras:
        {"semantic": ...}` of nodes or meshes), a {node/mesh/material name: id or label}
        mapping or the path of a JSON file of one; `semantic_labels` is {id: label}.
    """

    def __init__(self, scene: Scene | None = None, device: str | int | None = None,
                 validation: bool | None = None, sync_validation: bool = False, msaa: int = 1,
                 background: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 depth_prepass: bool | None = None, window_extensions: tuple[str, ...] | None = None,
                 env_spec: EnvironmentSpec | None = None,
                 cache_dir: str | os.PathLike[str] | None = None,
                 semantics: str | os.PathLike[str] | Mapping[str, int | str] = "mesh") -> None:
        t0 = time.perf_counter()
        background = checked_args(msaa, background, env_spec)
        self.msaa, self.background, self.depth_prepass = msaa, background, depth_prepass
        self.device = open_device(device, validation, sync_validation, window_extensions, cache_dir)
        self._maker = SceneMaker(self.device, msaa, background, depth_prepass, env_spec,
                                 cache_dir, semantics)
        self._made, t_device = None, time.perf_counter() - t0
        self.set_scene(scene)
        self.timings.update(device=t_device, setup=self.timings["setup"] + t_device)

    def set_scene(self, scene: Scene | None) -> None:
        """Draw `scene` (None: the built-in one) from now on, on the same device and pipeline
        cache (render/scene_swap.py): as `Renderer(scene)` would; targets made before and
        `world_slots` are gone."""
        checked_scene(scene)  # (before the scene drawn now is gone)
        if self._made is not None:
            self._maker.unmake(self._made)
            self._made = self.parts = self.batch_path = None
        self._world_slots = self._world_materials = None  # (named in the old scene's nodes)
        try:
            made = self._maker.make(scene)
        except BaseException:
            self.close()
            raise
        self._made, self.scene, self.parts, self.timings = made, made.scene, made.parts, made.timings
        self.frame_path, self.batch_path, self.last_stats = made.frame_path, made.batch_path, FrameStats()
        self._expose(self.parts)

    def _expose(self, p: FrameParts) -> None:
        """The parts, and the methods of theirs callers use on the Renderer, by the names
        they had before the parts had modules (the parts' own methods, with their docs)."""
        self.ring, self.slots, self.set_layouts = p.ring, p.slots, p.set_layouts
        self.pipeline_layout, self.frame_buffers = p.pipeline_layout, p.frame_buffers
        self.gpu_scene, self.semantic_ids, self.semantic_labels = (
            p.gpu_scene, p.semantic_ids, p.semantic_labels)
        self.max_id = O.max_id(p.gpu_scene, p.semantic_ids)  # the largest id an output holds
        self.opaque_copies, self.recorder, self.bounds = p.opaque_copies, p.recorder, p.bounds
        self.compute_scene, self.post_kernels = p.compute, p.post  # made on their first call
        t, paths, light, fp = p.targets, p.paths, p.lighting, self.frame_path
        self.targets, self.paths, self.lighting, self.blend = t, paths, light, p.blend
        self.environments, self.shadow_frames = p.environments, p.shadow_frames
        self.shadows, self.default_camera = p.shadow_frames.maps, p.default_camera
        self.offscreen_target, self.new_offscreen_target, self.post_target = t.offscreen, t.new, t.post
        self.drop_target, self.window_target, self.text_overlay = t.drop, t.window, t.overlay
        self.prepass_for, self.compute_unavailable = paths.prepass_for, paths.compute_unavailable
        self.uses_compute, self.uses_compute_raster = paths.uses_compute, paths.uses_compute_raster
        self.compute_batch_unavailable = paths.compute_batch_unavailable
        self.default_light, self.frame_lights = light.default_light, light.frame_lights
        self.frame_lighting, self.shade_variant = light.frame_lighting, light.shade_variant
        self.screen_transmission, self.automatic_sun = light.screen_transmission, automatic_sun
        self.environment, self.bind_environment_for = p.environments.get, p.environments.bind_for
        self.blend_order, self.blend_orders = p.blend.order, p.blend.orders
        self.frame_stats, self.read_color = fp.stats, fp.read_color
        self.build_pipelines = p.recorder.build_pipelines
        self.shadow_plan, self.write_scene_shadows = p.shadow_frames.plan, p.shadow_frames.write_scene
        self.takes_compute_batch, self.read_frame_timings = paths.takes_compute_batch, fp.read_timings
        self.wait_idle, self.check_validation = self.device.wait_idle, self.device.check_validation
        st = p.state  # the living scene (vkpbr.scene.state): what the next frame shows
        self.state, self.set_pose, self.set_poses, self.reset_pose = st, st.set_pose, st.set_poses, st.reset
        self.set_visible, self.set_time, self.set_weights = st.set_visible, st.set_time, st.set_weights
        self.add_instances, self.move_instances, self.remove_instances, self.set_material = instance_api(self)

    @property
    def instances(self) -> list[dict[str, Any]]:
        """Each output instance id's {"id", "node", "mesh", "material", "semantic", "label"}
        (id = index + 1; 0: the background); outputs.instances says more."""
        return O.instances(self.scene, self.gpu_scene, self.semantic_ids, self.semantic_labels)

    def choose_paths(self, target: FrameTarget, options: RenderOptions) -> None:
        """Before auto frames of `target`: auto's path, the rule until it is measured
        (render/path_choice.py); callers of `draw` call it first (`draw` never measures)."""
        self.paths.choose(target, options, self)

    def draw(self, target: FrameTarget, camera: Camera, lights: tuple[Light, ...],
             options: RenderOptions, *, overlay: TextOverlay | None = None,
             copy: tuple[str, ...] = (), linear: bool = False, timings: bool = True,
             driver_time: bool = False) -> Submitted:
        """Draw one frame into `target` and submit it (the one frame path).

        `lights` are the frame's punctual lights as `frame_lights` resolves them (a tuple of
        at most MAX_LIGHTS frozen Lights: an unchanged tuple costs nothing to compare).
        `copy` names what the target copies out for reading (COPY_COLOR, COPY_DEPTH) into the
        frame's buffers; `timings` first reads the GPU timestamps of the frame slot's previous
        submission into its stats (a few microseconds; the viewer asks 4 times a second).
        `driver_time` measures the thread CPU time spent in the driver: the fence wait, the
        timestamp read, the target's acquire and submit (stats.driver_ms; the viewer subtracts
        it from Python's own cost, as lavapipe may spin in them). Off by default: each clock
        read is a system call.
        Returns a Submitted; `ok` False: recreate the target (a resized window).
        """
        return self.frame_path.draw(target, camera, lights, options, overlay, copy, linear,
                                    timings, driver_time)

    def render(self, camera: Camera | Any = None, lights: LightsArg = None,
               size: tuple[int, int] = (640, 480), options: RenderOptions | None = None,
               linear: bool = False, depth: bool = False, outputs: Iterable[str] | None = None,
               time: float | None = None, animation: Any = None, **option_overrides: Any
               ) -> np.ndarray | tuple[np.ndarray, np.ndarray] | dict[str, np.ndarray]:
        """Render one frame.

        Parameters
        ----------
        camera : a Camera, a 4x4 world-from-camera pose (OpenGL axes) or an
            "ex,ey,ez,tx,ty,tz" string; None: the scene's camera (or the automatic one).
        lights : None: the scene's lights (none in the scene: the automatic sun, or the
            course's default point light); a Light or a list of them; [] for no punctual
            light. Course lighting draws only the first, as a point light.
        size : (width, height) in pixels.
        options : RenderOptions; keyword overrides (view="d", brdf="blinn-phong", ...)
            update it.
        outputs : names from OUTPUTS (dataset outputs, from the same frame: "color", "depth",
            "range", "instance", "semantic", "normal", "normal_camera", "normal_geometric");
            a dict of arrays is returned instead (see `frame_outputs`).
        time, animation : `set_time(time, animation)` first (glTF animations); None: as is.

        Returns
        -------
        (H, W, 4) uint8 sRGB-encoded colour, or (H, W, 4) float32 linear colour when
        `linear`; with `depth`, a tuple (colour, depth) where depth is (H, W) float32
        view-space distance along the camera axis (inf where nothing was drawn); with
        `outputs`, {name: array}.
        """
        if time is not None:  # before the lights resolve: animation may drive them too
            self.set_time(time, animation)
        frames = self.render_many([camera], lights, size, options, linear, depth, outputs=outputs,
                                  **option_overrides)
        return next(iter(frames))

    def render_many(self, cameras: Iterable[Camera | Any], lights: LightsArg = None,
                    size: tuple[int, int] = (640, 480), options: RenderOptions | None = None,
                    linear: bool = False, depth: bool = False, readback: bool = True,
                    outputs: Iterable[str] | None = None, batch: int | None = None,
                    driver_time: bool = False, times: Iterable[float] | None = None,
                    animation: Any = None, **option_overrides: Any
                    ) -> Iterator[np.ndarray | tuple[np.ndarray, np.ndarray] | dict[str, np.ndarray] | None]:
        """Render one frame per camera, yielding what `render` returns, in order.

        Up to `ring.count` frames are queued on the GPU: while frame i renders, Python writes
        frame i+1's uniforms and submits it as a thread of the stream copies frame i-1 out of
        its mapped readback buffer (render/frame_path.py). Each is bit-for-bit `render`'s.
        `readback=False` yields None per finished frame instead (benchmarks: render only).
        `batch` N: the cameras N at a time through `render_batch` (one submission each; its
        shadow maps of directional lights are one map over the scene), where the device has
        layered rendering; None: frame by frame.
        `driver_time`: each frame's `last_stats.driver_ms` (`cpu_ms`' part in the driver:
        benchmarks). `times`: one animation time per camera (`render`'s `time`).
        """
        opts = with_overrides(options, option_overrides)
        cameras = with_times(self.state, cameras, times, animation)
        if batch is not None and readback and self.device.batch_views and times is None:
            for chunk, names in chunked(cameras, batch, self.default_camera(), outputs):
                got = self.render_batch(chunk, size, lights, opts, linear, depth, names)
                yield from per_view(got, len(chunk), depth)
            return
        with self.device.lock:  # (other threads' frames wait: gpu/device.py Device.lock)
            frame_lights = self.lighting.frame_lights(opts, lights)
            target = self.targets.offscreen(size, linear)
            wanted = O.check_outputs(outputs, target, self.paths, self.targets)
            self.paths.choose(target, opts, self)  # before the first frame: never inside `draw`
            frames = self.frame_path.stream(cameras, self.default_camera(), target, frame_lights,
                                            opts, linear, depth, readback, wanted, driver_time)
            with closing(frames):  # (closed with this generator, not when collected: its thread)
                for result, stats in frames:
                    self.last_stats = stats  # each frame's as it comes
                    yield result

    def render_batch(self, cameras: CameraBatch | np.ndarray | Iterable[Camera | Any],
                     size: tuple[int, int] = (128, 128), lights: LightsArg = None,
                     options: RenderOptions | None = None, linear: bool = False,
                     depth: bool = False, outputs: Iterable[str] | None = None,
                     batch: int | str = "auto", device: str = "cpu",
                     out: np.ndarray | None = None, worlds: WorldsArg = None,
                     world_of_view: Any = None, quaternion: str = "xyzw",
                     world_visible: Any = None, world_expand: str = "auto",
                     world_materials: Any = None, space: str = "world", world_lights: Any = None,
                     world_environment: Any = None, times: Any = None, animation: Any = None,
                     **option_overrides: Any
                     ) -> np.ndarray | tuple[np.ndarray, np.ndarray] | dict[str, np.ndarray] | Any:
        """Render B views of the scene in one submission, stacked (docs/batch.md).
        cameras : a CameraBatch (vkpbr.scene.camera_batch), (B, 4, 4) OpenGL world-from-camera
            poses, or a list of Cameras (anything `render` takes). size : (width, height).
        lights, options, linear, option_overrides: as `render`. depth : also (B, H, W) float32
            distances along each view's axis. outputs : as `render`'s, stacked per view.
        batch : views per submission, "auto" or a positive integer. device : "cpu": NumPy
            arrays; "cuda": a torch tensor (B, H, W, 4) on the same GPU. out : a C-contiguous
            writeable (B, H, W, 4) array the colour is written into.
        worlds : W worlds' world poses of the nodes named by `world_slots`: (W, N, 4, 4)
            matrices or (W, N, 7) position + quaternion (`quaternion` "xyzw" or "wxyz";
            `space` "world", or "local": relative to each node's parent as the state has it),
            NumPy or torch; `world_of_view` (B,) the world each view sees (omit when B = W);
            `world_visible` (W, N) bools; `world_expand` "gpu" expands NumPy poses on the
            GPU as CUDA tensors are (float32), "auto"/"host" exactly on the host;
            `world_materials` {"base_color": (W, K, 4), "metallic", "roughness": (W, K),
            "emissive": (W, K, 3)} of the K materials named by `world_slots`; `world_lights`
            {"intensity": (W, L), "color": (W, L, 3)} of the frame's L lights;
            `world_environment` {"intensity", "rotation" (degrees)}: (W,). docs/batch.md.
        times, animation : (B,) animation times, one a view (`render`'s `time`; its worlds).

        Returns (B, H, W, 4) uint8 sRGB (float32 with `linear`), (colour, depth) with `depth`,
        {name: (B, ...)} with `outputs`. pipeline="forward" (and "auto" where the compute batch
        is unavailable): view i is `render` of `CameraBatch.camera(i)` (in its world) bit for
        bit; "compute" and "auto": within 1/255 of `render(pipeline="compute")`. Shadow maps
        are shared.
        """
        return batch_call(self, cameras, size, lights, options, linear, depth, outputs, batch,
                          device, out, WorldArgs(worlds, world_of_view, quaternion, world_visible,
                                                 world_expand, world_materials, space,
                                                 world_lights, world_environment, times,
                                                 animation), option_overrides)

    def world_slots(self, nodes: Any = None, materials: Any = None) -> WorldSlots | None:
        """The nodes each world of `render_batch(worlds=)` poses, the materials it sets."""
        return world_slots(self, nodes, materials)

    batch_step = batch_step  # a loop's render_batch made once (render/batch_cache.py)

    def close(self) -> None:
        """Destroy everything (idempotent). The Renderer is unusable afterwards."""
        dev = getattr(self, "device", None)
        if dev is not None and dev.handle is not None:
            if getattr(self, "_made", None) is not None:  # (None: set_scene failed midway)
                self._maker.unmake(self._made)
            dev.close()

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
