"""The renderer: a Scene drawn through one frame path into any frame target.

`Renderer.draw(target, camera, ...)` is the frame path for every target: take the next frame
of the ring (gpu/frames.py; waits for its previous submission), acquire an image of the
target (gpu/target.py: offscreen images, or a window's swapchain), write the frame's uniform
blocks, pick the command buffer recorded for this (target image, frame, modes) or record it
(the pass table of render/passes.py, an optional overlay, the target's begin/end), submit.
`render` / `render_many` are that path on offscreen targets plus the readback; the viewer
(app/viewer.py) is that path on a swapchain or on an offscreen target, with a HUD overlay.

Per frame, Python does a handful of things: debug view, BRDF, exposure, tone mapping, lights
and camera are uniforms (the lights a storage buffer), so changing them re-records nothing; the TBN path, alpha masking,
the blended draws' order, the overlay and the readback select among recorded buffers.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import logging
import math
import os
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import OutOfDeviceMemoryError, UsageError
from vkpbr.gpu.descriptors import BindingSpec, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import COMPUTE_PATH_FEATURES, Device, DeviceRequest
from vkpbr.gpu.frames import Frame, FrameRing
from vkpbr.gpu.pipeline import PipelineLayout
from vkpbr.gpu.swapchain import Surface, Swapchain
from vkpbr.gpu.target import COPY_COLOR, COPY_DEPTH, COPY_OUTPUTS, FrameTarget, OffscreenTarget
from vkpbr.render import layouts as L
from vkpbr.render.batch import draw_spheres
from vkpbr.render.batch_path import BatchPath
from vkpbr.render.camera import as_camera, linear_depth, validate_camera
from vkpbr.render.compute_path import ComputeScene, ShadeVariant
from vkpbr.render.environment import Environment, EnvironmentBaker, EnvironmentSpec
from vkpbr.render.frames import (
    Bounds,
    FrameLighting,
    FrameSlot,
    FrameStats,
    bind_instances,
    create_slots,
    write_frame_blocks,
    write_frame_view,
)
from vkpbr.render.gpu_scene import GpuScene
from vkpbr.render.options import RenderOptions
from vkpbr.render.overlay import TextOverlay
from vkpbr.render.path_choice import RULE_CPU, RULE_GPU, PathChoice, frame_paths_mode, is_auto
from vkpbr.render.path_choice import resolve as resolve_paths
from vkpbr.render.paths import choose_path
from vkpbr.render.post_stage import PostKernels, check_post, enabled_post, encode_tonemap
from vkpbr.render.recorder import STAMPS, FrameRecorder
from vkpbr.render.shadows import ShadowMaps, ShadowPlan, plan_shadows
from vkpbr.render.steps import NO_OBJECTS, FrameObjects, FrameSpec
from vkpbr.render.transmission import OpaqueCopies
from vkpbr.scene.camera_batch import CameraBatch, as_camera_batch
from vkpbr.scene.environment import load_panorama
from vkpbr.scene.lights import course_point_light
from vkpbr.scene.semantics import semantic_ids
from vkpbr.scene.sky import sun_radiometry
from vkpbr.scene.types import Camera, Light, Scene
from vkpbr.scene.validate import validate_lights
from vkpbr.shading import AMBIENT, SUN_DIRECTION

# What a caller may give as the lights of a frame: None (the scene's, or the lighting mode's
# default), one Light, or a sequence of them (empty: no punctual light at all).
LightsArg = Light | Iterable[Light] | None

__all__ = ["Renderer", "RenderOptions", "FrameStats", "Submitted", "COPY_COLOR", "COPY_DEPTH"]

log = logging.getLogger(__name__)

@dataclass
class Submitted:
    """A frame handed to the GPU: `ok` is False when the target must be recreated (the
    frame was still submitted, or `frame` is None when no image could be acquired)."""

    frame: Frame | None
    image: int
    ok: bool


class Renderer:
    """Renders a Scene (the built-in default scene when None) into NumPy arrays or a window.

    Parameters
    ----------
    scene : the scene to draw; None renders the built-in PBR chart.
    device : device name substring or index (`vkpbr info` lists them); None picks the best.
    validation : enable the Khronos validation layer; any error raises ValidationError.
        None (default): on when the environment has VKPBR_VALIDATION=1 (how the test suite
        runs scripts, such as examples/, under the layer without changing them).
    sync_validation : with `validation`, also synchronization validation.
    msaa : 1 or 4 samples per pixel (offscreen renders).
    background : linear RGB of pixels where nothing was drawn.
    depth_prepass : draw opaque geometry depth-only first, so each pixel is shaded once.
        None (default): on where it was measured to win (BENCHMARKS.md), i.e. on a GPU when
        the scene has no more triangles than the target has pixels. It halves the shading of
        a fragment-bound frame (Sponza at 1920x1080 on an H200: 6.02 -> 4.13 ms) but doubles
        the vertex work, which loses on geometry-bound frames (5.1 M triangles at 1080p:
        10.3 -> 18.1 ms) and on lavapipe, whose vertex work runs on the same cores.
    window_extensions : instance extensions a window system needs (the viewer's GLFW list);
        the device then also enables swapchains.
    env_spec : cube sizes and sample counts of the environments' pre-filter (None: the GPU
        sizes, or EnvironmentSpec.cpu() on a CPU device).
    cache_dir : where the split-sum BRDF table is kept between processes (None: made once
        per process).
    semantics : where the dataset outputs' semantic ids come from (vkpbr.scene.semantics):
        "mesh" (each mesh primitive its own class), "material", "extras" (glTF `extras:
        {"semantic": ...}` of nodes or meshes), a {node/mesh/material name: id or label}
        mapping or the path of a JSON file of one; `semantic_labels` is {id: label}.
    """

    def __init__(
        self,
        scene: Scene | None = None,
        device: str | int | None = None,
        validation: bool | None = None,
        sync_validation: bool = False,
        msaa: int = 1,
        background: tuple[float, float, float] = (0.0, 0.0, 0.0),
        depth_prepass: bool | None = None,
        window_extensions: tuple[str, ...] | None = None,
        env_spec: EnvironmentSpec | None = None,
        cache_dir: str | os.PathLike[str] | None = None,
        semantics: str | os.PathLike[str] | Mapping[str, int | str] = "mesh",
    ) -> None:
        t0 = time.perf_counter()
        if msaa not in (1, 4):
            raise UsageError(f"msaa {msaa}: choose 1 or 4")
        if scene is None:
            from vkpbr.scene.default import default_scene

            scene = default_scene()
        self.scene, self.msaa, self.background = scene, msaa, background
        if window_extensions is not None:
            device = DeviceRequest(device, tuple(window_extensions), ("VK_KHR_swapchain",))
        if validation is None:
            validation = os.environ.get("VKPBR_VALIDATION") == "1"
        self.device = Device(device, validation=validation, sync_validation=sync_validation)
        self.depth_prepass = depth_prepass
        self._targets: dict[tuple, OffscreenTarget] = {}
        self._env_spec, self._cache_dir = env_spec, cache_dir
        self._baker: EnvironmentBaker | None = None
        self._environments: dict[tuple, Environment] = {}  # by _env_key
        self._bound_env: Environment | None = None  # what every slot's set 2 samples
        try:
            self.ring = FrameRing(self.device, queries_per_frame=STAMPS)
            self._create_layouts()
            self.frame_buffers, self._frame_pool, self.slots = create_slots(
                self.device, self.set_layouts[0], self.set_layouts[2], self.ring.count)
            self.gpu_scene = GpuScene(self.device, scene, self.set_layouts[1])
            bind_instances(self.device, [s.set0 for s in self.slots], self.gpu_scene.instance_buffer)
            self.semantic_ids, self.semantic_labels = semantic_ids(
                scene, self.gpu_scene.draws, Path(semantics) if isinstance(semantics, os.PathLike)
                else semantics)
            self._compute_scene: ComputeScene | None = None
            self._post_kernels: PostKernels | None = None
            self._last_post_options: tuple[RenderOptions, RenderOptions] | None = None
            self._last_post: tuple[RenderOptions, tuple] | None = None
            self._batch_path: BatchPath | None = None
            # Bound in every slot's set 2 before anything is recorded (render/transmission.py).
            self.opaque_copies = OpaqueCopies(self.device, self.gpu_scene,
                                              [s.set2 for s in self.slots], (*background, 1.0))
            self.recorder = FrameRecorder(self.device, self.gpu_scene, self.pipeline_layout,
                                          self.ring, self.slots, self.prepass_for, self.shadows,
                                          self.compute_scene, self.opaque_copies,
                                          self.post_kernels)
            self._shadow_plan: tuple[tuple, ShadowPlan] = ((), ShadowPlan())
            self._shadow_rows: dict[int, tuple[tuple, np.ndarray | None]] = {}
            self.bounds = Bounds.of(*scene.bounds())
            blend = [d.center for d in self.gpu_scene.draws if d.alpha_mode == "blend"]
            self._blend_centers = np.array(blend, dtype=np.float64).reshape(-1, 3)
            self._last_lighting: tuple[RenderOptions, FrameLighting] | None = None
            self._auto_choice: PathChoice | None = None  # what auto measured (path_choice.py)
            self.last_stats = FrameStats()
            self.timings = {"setup": time.perf_counter() - t0, **self.gpu_scene.timings}
        except BaseException:
            self.close()
            raise

    def _create_layouts(self) -> None:
        self.set_layouts = [
            DescriptorSetLayout(self.device, [BindingSpec(b, k, s, n) for b, k, s, n in rows])
            for i, rows in sorted(L.SETS.items()) if i != 3
        ]
        # Set 3 is the shadow maps' own layout (L.SETS[3]'s rows); their sets are per slot.
        self.shadows = ShadowMaps(self.device, self.set_layouts[1], self.ring.count)
        self.set_layouts.append(self.shadows.set_layout)
        self.pipeline_layout = PipelineLayout(self.device, self.set_layouts, L.PUSH.size)

    # --- targets ----------------------------------------------------------------------------
    def offscreen_target(self, size: tuple[int, int], linear: bool = False) -> OffscreenTarget:
        """The renderer's offscreen target of `size` (W, H): sRGB uint8, or float32 `linear`."""
        w, h = size
        limit = int(self.device.limits.maxImageDimension2D)
        if not (isinstance(w, int | np.integer) and isinstance(h, int | np.integer)) or w <= 0 or h <= 0:
            raise UsageError(f"image size {w}x{h}: width and height must be positive integers")
        if w > limit or h > limit:
            raise UsageError(f"image size {w}x{h} exceeds this device's limit of {limit}x{limit}")
        key = (int(w), int(h), linear)
        if key not in self._targets:
            self._targets[key] = self.new_offscreen_target((int(w), int(h)), linear)
        return self._targets[key]

    def new_offscreen_target(self, size: tuple[int, int], linear: bool) -> OffscreenTarget:
        """A new offscreen target of `size` the caller owns (the compute batch's atlases:
        render/batch_path.py; give it back with `drop_target`)."""
        return OffscreenTarget(self.device, size, "float" if linear else "srgb", self.msaa,
                               (*self.background, 1.0), compute=self.device.compute_path)

    def post_target(self, target: FrameTarget, copy: tuple[str, ...]) -> OffscreenTarget:
        """The HDR target frames of `target` with post steps draw into (render/post_stage.py): the
        float colour (and depth, ids, outputs) of its size, the renderer's own."""
        key = (*target.extent, "post")
        if key not in self._targets:
            self._targets[key] = self.new_offscreen_target(target.extent, True)
        hdr = self._targets[key]
        if COPY_OUTPUTS in copy:
            self._ensure_outputs(hdr)
        return hdr

    def post_kernels(self) -> PostKernels:
        """The post steps' kernels and transient images (render/post_stage.py), made on first use."""
        if self._post_kernels is None:
            self._post_kernels = PostKernels(self.device)
        return self._post_kernels

    def _post_of(self, options: RenderOptions) -> tuple[tuple[str, float], ...]:
        """The post steps `options` turn on (the last answer kept, as frame_lighting's)."""
        last = self._last_post
        if last is None or last[0] is not options:
            last = self._last_post = (options, enabled_post(options))
        return last[1]

    def _shading_options(self, options: RenderOptions, post: bool) -> RenderOptions:
        """The options the shading sees: with post steps, no tone map (the encode's; the
        last such copy kept: a run of frames has one options object)."""
        if not post or options.tonemap is None:
            return options
        last = self._last_post_options
        if last is None or last[0] is not options:
            last = self._last_post_options = (options, dataclasses.replace(options, tonemap=None))
        return last[1]

    def drop_target(self, target: OffscreenTarget) -> None:
        """Destroy a target from `new_offscreen_target` and everything recorded or made for
        it (command buffers, the compute path's per-target buffers). Waits for the device."""
        self.device.wait_idle()
        self.recorder.free(id(target))
        if self._compute_scene is not None:
            self._compute_scene.forget_target(target, destroy=True)
        target.destroy()

    def window_target(self, create_surface: Callable[[Any, Any], int], size: tuple[int, int],
                      vsync: bool = True) -> Swapchain:
        """A swapchain target on a window surface. `create_surface(instance, out)` makes the
        VkSurfaceKHR into the pointer `out` and returns a VkResult (GLFW's
        `glfw.create_window_surface(instance, window, None, out)`)."""
        surface = Surface(self.device, create_surface)
        return Swapchain(self.device, surface, size, vsync=vsync,
                         clear_color=(*self.background, 1.0))

    def text_overlay(self, atlas: np.ndarray, target: FrameTarget) -> TextOverlay:
        """A textured-quad overlay (the viewer's HUD) drawn over frames of `target`'s formats."""
        return TextOverlay(self.device, atlas, target, self.ring.count)

    def prepass_for(self, target: FrameTarget) -> bool:
        """Whether frames of `target` run the depth pre-pass (see `depth_prepass`)."""
        if self.depth_prepass is not None:
            return bool(self.depth_prepass)
        w, h = target.extent
        return self.device.info.kind != "cpu" and self.scene.triangle_count <= w * h

    def compute_scene(self) -> ComputeScene:
        """The compute path's resources (render/compute_path.py), made on its first frame."""
        if self._compute_scene is None:
            self._compute_scene = ComputeScene(
                self.device, self.gpu_scene, dict(enumerate(self.set_layouts)), self.slots,
                self.semantic_ids, draw_spheres(self.scene, self.gpu_scene.draws)
                if self.gpu_scene.draws else None)
        return self._compute_scene

    def compute_unavailable(self, target: FrameTarget) -> str | None:
        """Why frames of `target` cannot take the compute path, or None when they can."""
        if not self.device.compute_path:
            return "the device lacks " + ", ".join(COMPUTE_PATH_FEATURES)
        if not getattr(target, "compute", False):
            return "it needs a single-sample offscreen target (not MSAA, not a window)"
        w, h = target.extent
        limit = int(self.device.limits.maxStorageBufferRange)
        if 4 * w * h > limit:  # the pixel list: 4 bytes a pixel in one storage binding
            return f"{w}x{h} exceeds its pixel list's limit here ({limit // 4:,} pixels)"
        return None

    def uses_compute(self, target: FrameTarget, options: RenderOptions) -> bool:
        """Whether frames of `target` with `options` take the compute path (UsageError when
        it is asked for and cannot: say why and what to use)."""
        if options.pipeline == L.PipelinePath.COMPUTE:
            why = self.compute_unavailable(target)
            if why is not None:
                raise UsageError(f"--pipeline compute is not available here: {why}; use "
                                 "--pipeline forward or auto")
            return True
        if options.pipeline == L.PipelinePath.FORWARD:
            return False
        # auto: on GPUs, what measured fastest on the device (render/path_choice.py; until it
        # is measured, the compute path where the target allows it: the H200 measured it
        # 1.5-3.9x faster at 128x128 to 1920x1080); the fragment path on CPUs (lavapipe: the
        # slower of the two).
        if self._auto_choice is not None:  # measured (or read back) for this device
            return self._auto_choice.compute and self.compute_unavailable(target) is None
        return self.device.info.kind != "cpu" and self.compute_unavailable(target) is None

    def compute_batch_unavailable(self) -> str | None:
        """Why `render_batch(pipeline="compute")` cannot take the compute batch (its views
        are then rendered one by one on the compute path), or None."""
        if not self.device.compute_raster:
            return "the device lacks 64-bit storage-buffer atomics"
        if self.msaa > 1:
            return "MSAA"
        if self._blend_centers.size:  # the blended draws' centres (blend_orders' input)
            return "the scene has blended materials (drawn by the fragment path)"
        return None

    def takes_compute_batch(self, options: RenderOptions) -> bool:
        """Whether render_batch takes the compute batch: pipeline "compute", or "auto" on a GPU
        (the fragment path's layered batch on CPUs), where `compute_batch_unavailable` is None."""
        if options.pipeline == L.PipelinePath.FORWARD or self.compute_batch_unavailable():
            return False
        return options.pipeline == L.PipelinePath.COMPUTE or self.device.info.kind != "cpu"

    def uses_compute_raster(self, options: RenderOptions, target: FrameTarget) -> bool:
        """Whether the compute path's visibility buffer comes from the compute rasteriser
        (UsageError when it is asked for and the device or the target's size cannot; auto
        takes it on GPUs where it can, the raster units otherwise)."""
        if options.raster == L.RasterPath.HARDWARE:
            return False
        w, h = target.extent
        limit = int(self.device.limits.maxStorageBufferRange)
        if options.raster == L.RasterPath.AUTO:
            wanted = (self._auto_choice.compute_raster if self._auto_choice is not None
                      else self.device.info.kind != "cpu")
            return wanted and bool(self.device.compute_raster) and 8 * w * h <= limit
        if not self.device.compute_raster:
            raise UsageError("--raster compute is not available here: the device lacks 64-bit "
                             "storage-buffer atomics (shaderInt64, shaderBufferInt64Atomics); "
                             "use --raster hardware")
        if 8 * w * h > limit:  # 8 bytes a pixel in one storage binding
            raise UsageError(f"--raster compute is not available for {w}x{h} here: at most "
                             f"{limit // 8:,} pixels; use --raster hardware")
        return True

    def build_pipelines(self, target: FrameTarget) -> None:
        """Create every pipeline and vertex stream (all TBN paths and passes) for `target`
        now, so that no later mode switch waits for one (the viewer calls this)."""
        self.recorder.build_pipelines(target)

    def blend_order(self, eye: Any) -> tuple[int, ...]:
        """Indices into the blended draws, farthest first from `eye` (painter's order)."""
        if len(self._blend_centers) < 2:  # no order to find: the frame path's usual case
            return tuple(range(len(self._blend_centers)))
        return tuple(self.blend_orders(np.asarray(eye, dtype=np.float64)[None])[0].tolist())

    def blend_orders(self, eyes: np.ndarray) -> np.ndarray:
        """For each of (B, 3) eyes, indices into the blended draws farthest first (painter's
        order): (B, blended draws) int. `blend_order` is one row of it."""
        centers = self._blend_centers
        if len(centers) < 2:
            return np.broadcast_to(np.arange(len(centers)), (len(eyes), len(centers)))
        d = np.sum((centers[None, :, :] - eyes[:, None, :]) ** 2, axis=2)
        return np.argsort(-d, axis=1, kind="stable")

    # --- the frame path ---------------------------------------------------------------------
    def default_camera(self) -> Camera:
        if self.scene.cameras:
            return self.scene.cameras[0]
        from vkpbr.scene.geometry import auto_camera

        return auto_camera(self.scene)

    def default_light(self) -> Light:
        """The course's light: the scene's first, else a white point light at (0, 2, 0)."""
        return self.scene.lights[0] if self.scene.lights else Light()

    def automatic_sun(self, env_rotation: float = 0.0) -> Light:
        """The physically based mode's key light when the scene has none: the built-in sky's
        sun (vkpbr.shading.SUN_DIRECTION, colour and illuminance from scene.sky's
        sun_radiometry), turned with the environment by `env_rotation` degrees about +Y."""
        return _automatic_sun(float(env_rotation))

    def frame_lights(self, options: RenderOptions, lights: LightsArg = None) -> tuple[Light, ...]:
        """The lights frames are drawn with, resolved once per call (not per frame).

        None: the scene's lights; with none in the scene, the physically based mode's
        automatic sun, the course's default point light. Course lighting draws one point
        light: the first light, as `scene.lights.course_point_light` sees it.
        """
        if lights is None:
            if self.scene.lights:
                chosen: tuple[Light, ...] = tuple(self.scene.lights)
            elif options.lighting == L.Lighting.COURSE:
                chosen = (Light(),)
            else:
                chosen = (self.automatic_sun(options.env_rotation),)
        else:
            chosen = (lights,) if isinstance(lights, Light) else tuple(lights)
            validate_lights(chosen)
        if options.lighting == L.Lighting.COURSE:
            return (course_point_light(chosen[0], self.scene.bounds()),) if chosen else ()
        return chosen

    def frame_lighting(self, options: RenderOptions) -> FrameLighting:
        """What lights a frame besides its punctual lights, for `options`' lighting mode
        (the last answer kept: a run of frames has one options object)."""
        last = self._last_lighting
        if last is not None and last[0] is options:
            return last[1]
        lighting = self._frame_lighting(options)
        self._last_lighting = (options, lighting)
        return lighting

    def shade_variant(self, options: RenderOptions) -> ShadeVariant:
        """What the compute path's shading kernels are specialised for with `options`: the
        frame's lighting flags and BRDF (render/compute_path.py ShadeVariant)."""
        return ShadeVariant(self.frame_lighting(options).flags, int(options.shading_brdf))

    def screen_transmission(self, options: RenderOptions) -> bool:
        """Whether frames with `options` draw the copy of the opaque scene that transmissive
        surfaces see through (render/transmission.py): the scene has one, and the frame
        shades with the physically based mode's glTF BRDF (the layers' only)."""
        return (self.opaque_copies.present and options.lighting == L.Lighting.PBR
                and options.shading_brdf == L.Brdf.GLTF)

    def _frame_lighting(self, options: RenderOptions) -> FrameLighting:
        if options.lighting == L.Lighting.COURSE:
            return FrameLighting(mode=int(L.Lighting.COURSE), ambient=AMBIENT)
        flags = ((L.LIGHTING_SHADOWS if options.shadows else 0)
                 | (L.LIGHTING_SCREEN_TRANSMISSION if self.screen_transmission(options) else 0))
        if not options.has_environment:
            return FrameLighting(mode=int(L.Lighting.PBR), flags=flags)
        flags |= L.LIGHTING_IBL | (L.LIGHTING_BACKGROUND if options.draws_background else 0)
        return FrameLighting(mode=int(L.Lighting.PBR), flags=flags,
                             env_intensity=options.env_intensity,
                             env_rotation=math.radians(options.env_rotation),
                             env_max_lod=float(self.environment(options).max_lod))

    def shadow_plan(self, lights: tuple[Light, ...], options: RenderOptions) -> ShadowPlan:
        """Which of the frame's lights get shadow maps (none in course mode or with shadows
        off); remade only when the lights or the option change."""
        enabled = options.shadows and options.lighting == L.Lighting.PBR
        key = (lights, enabled)
        if key != self._shadow_plan[0]:
            self._shadow_plan = (key, plan_shadows(lights, enabled, self.shadows.cubes_supported))
        return self._shadow_plan[1]

    def _write_shadows(self, slot: FrameSlot, plan: ShadowPlan, lights: tuple[Light, ...],
                       camera: Camera, size: tuple[int, int]) -> np.ndarray | None:
        """The slot's shadow matrices for this frame (skipped when its inputs repeat) and the
        lights' LightRecord.shadow rows; None without shadow maps. The cascades take the
        frame's planes from its view record: write_frame_view comes first."""
        if not plan.entries:
            return None
        sm = self.shadows
        c = camera  # mutable: its values are the key
        # Only directional lights' cascades follow the camera: spot and point lights' maps
        # are the same for every view, so a moving camera does not remake them.
        view = ((c.eye, c.target, c.up, c.yfov_deg, c.znear, c.zfar, c.pixel_intrinsics, tuple(size))
                if plan.follows_camera else None)
        key = (view, plan, lights, sm.resolution)
        last = self._shadow_rows.get(slot.index)
        if last is not None and last[0] == key:
            return last[1]
        rows = sm.write(slot.index, plan, lights, camera, size, slot.znear, slot.zfar,
                        self.bounds.corners[0], self.bounds.corners[-1])
        self._shadow_rows[slot.index] = (key, rows)
        return rows

    # --- the environment --------------------------------------------------------------------
    @property
    def environment_baker(self) -> EnvironmentBaker:
        """The environment compute pipelines (made on first use)."""
        if self._baker is None:
            spec = self._env_spec
            if spec is None:
                spec = EnvironmentSpec.cpu() if self.device.info.kind == "cpu" else EnvironmentSpec()
            cache = Path(self._cache_dir) if self._cache_dir is not None else None
            self._baker = EnvironmentBaker(self.device, spec, cache)
        return self._baker

    def environment(self, options: RenderOptions) -> Environment:
        """The environment frames with `options` sample (pre-filtered on first use, then
        kept): the sky, a panorama file's, or a black one where none lights the frame.

        Raises SceneError (one line naming the file) for an unreadable panorama."""
        key = _env_key(options)
        env = self._environments.get(key)
        if env is None:
            baker = self.environment_baker
            if key[0] == "black":
                env = baker.from_constant((0.0, 0.0, 0.0))
            elif key[0] == "sky":
                env = baker.from_sky(SUN_DIRECTION)
            else:
                env = baker.from_panorama(load_panorama(key[1]), key[1])
            self._environments[key] = env
        return env

    def _bind_environment(self, env: Environment) -> None:
        """Point every slot's set 2 samplers at `env`. Rare (a new environment): the sets
        may be in use by queued frames and their recorded command buffers, so wait for the
        device and drop the recordings (an updated set invalidates them)."""
        self.device.wait_idle()
        self._free_recordings()
        writer = DescriptorWriter(self.device)
        for slot in self.slots:
            for binding, image in ((2, env.specular), (3, env.irradiance), (4, env.brdf_lut)):
                writer.sampler(slot.set2, binding, image.view, image.sampler)
        writer.update()
        self._bound_env = env

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
        if self._auto_choice is None and is_auto(options):
            self._choose_auto_paths(target)
        t0 = time.perf_counter()
        self.bind_environment_for(options)
        transmission = self.screen_transmission(options)
        if transmission and self.opaque_copies.stale(target.extent):
            self._fit_opaque_copies(target.extent)
        clock = time.thread_time if driver_time else _no_clock
        c0 = clock()
        frame = self.ring.begin()  # waits for the frame's previous submission
        slot = self.slots[frame.index]
        if timings:
            self._read_timings(frame, slot)
        image = target.acquire(frame)
        driver = clock() - c0
        if image is None:
            return Submitted(None, -1, False)
        plan = self.shadow_plan(lights, options)
        if options.shadow_resolution != self.shadows.resolution:
            self.shadows.set_resolution(options.shadow_resolution)
        self._ensure_shadow_maps(plan)
        wanted = self._post_of(options)
        post = bool(wanted) and check_post(options, target, self.device.compute_path)
        drawn = self.post_target(target, copy) if post else target  # (HDR with post steps)
        # The camera's maths, once: the shadow cascades take its planes from the slot.
        write_frame_view(slot, camera, target.extent, self.bounds)
        write_frame_blocks(slot, lights, self._shading_options(options, post), linear or post,
                           self.frame_lighting(options),
                           self._write_shadows(slot, plan, lights, camera, target.extent))
        if overlay is not None:
            overlay.prepare(frame.index)
        redraw = self.shadows.stale(slot.index, plan, options.alpha_mask)
        compute = self.uses_compute(drawn, options)
        path = choose_path(compute, compute and self.uses_compute_raster(options, drawn),
                           COPY_OUTPUTS in copy)
        spec = FrameSpec(path, options.tbn, options.alpha_mask, plan, redraw, copy,
                         transmission, self.shade_variant(options), id(overlay),
                         post=wanted, post_tonemap=encode_tonemap(options, linear) if post else 0)
        order = self.blend_order(camera.eye)
        objects = FrameObjects(order, overlay) if order or overlay is not None else NO_OBJECTS
        try:
            cmd = self.recorder.command_buffer(target, frame, image, spec, objects,
                                               drawn=drawn if post else None)
            c0 = clock()
            ok = target.submit(frame, cmd, image)
        except BaseException:
            self.shadows.forget()
            raise
        if not ok:
            self.shadows.forget()
        slot.stats.driver_ms = (driver + clock() - c0) * 1e3
        frame.stamped = self.ring.query_pool is not None
        slot.stats.cpu_ms = (time.perf_counter() - t0) * 1e3
        return Submitted(frame, image, ok)

    def _fit_opaque_copies(self, extent: tuple[int, int]) -> None:
        """Copies of the opaque scene for frames of `extent` (render/transmission.py). Rare (a
        new size class): the old ones may be in use by queued frames and named by recorded
        command buffers, so wait for the device and drop the recordings."""
        self.device.wait_idle()
        self._free_recordings()
        if self._compute_scene is not None:  # the compute path's buffers and sets for the old
            for old in self.opaque_copies.targets:
                self._compute_scene.forget_target(old, destroy=True)
        self.opaque_copies.fit(extent)

    def _choose_auto_paths(self, target: FrameTarget) -> None:
        """Before the first auto frame on a GPU that `target` lets take the compute path:
        the recorded choice for the device, or the candidates measured now (path_choice.py;
        explicit options, so their frames do not come back here)."""
        mode = frame_paths_mode()  # VKPBR_FRAME_PATHS: auto, measure (CPUs too) or rule
        cpu = self.device.info.kind == "cpu"
        if mode == "rule" or (cpu and mode != "measure"):  # decided once, not per frame
            self._auto_choice = RULE_CPU if cpu else RULE_GPU
            return
        if self.compute_unavailable(target) is not None:  # a window: decided by a later target
            return
        self._auto_choice = RULE_GPU  # while measuring, and if measuring fails
        try:
            self._auto_choice = resolve_paths(self, target.extent, self._cache_dir)
        except (OutOfDeviceMemoryError, UsageError) as exc:  # a candidate cannot run here
            log.warning("frame paths not measured (%s); auto takes %s", exc, RULE_GPU.label)

    def _ensure_shadow_maps(self, plan: ShadowPlan, options: RenderOptions | None = None) -> None:
        if options is not None and options.shadow_resolution != self.shadows.resolution:
            self.shadows.set_resolution(options.shadow_resolution)
        if self.shadows.ensure(plan):  # new images: the recorded buffers name the old ones
            self._free_recordings()
            self._shadow_rows.clear()

    def _free_recordings(self) -> None:
        self.recorder.free()
        if self._batch_path is not None:
            self._batch_path.free_recordings()

    @property
    def batch_path(self) -> BatchPath:
        """The batched-views path (render/batch_path.py), made on the first batch."""
        if self._batch_path is None:
            self._batch_path = BatchPath(self)
        return self._batch_path

    def bind_environment_for(self, options: RenderOptions) -> None:
        """Make every frame slot sample the environment `options` ask for."""
        env = self.environment(options)
        if env is not self._bound_env:
            self._bind_environment(env)

    def write_scene_shadows(self, slot: FrameSlot, plan: ShadowPlan, lights: tuple[Light, ...],
                            options: RenderOptions) -> np.ndarray | None:
        """A batch's shadow maps in `slot`: the camera-independent fits (directional lights
        over the whole scene) and the lights' LightRecord.shadow rows; None without maps."""
        self._ensure_shadow_maps(plan, options)
        if not plan.entries:
            return None
        self._shadow_rows.pop(slot.index, None)  # the slot's cascades are overwritten
        return self.shadows.write(slot.index, plan, lights, None, (1, 1), 0.0, 0.0,
                                  self.bounds.corners[0], self.bounds.corners[-1])

    def read_frame_timings(self, frame: Frame) -> FrameStats:
        """The GPU timestamps of `frame` (waited for) into its slot's stats, returned."""
        slot = self.slots[frame.index]
        self._read_timings(frame, slot)
        return slot.stats

    def _read_timings(self, frame: Frame, slot: FrameSlot) -> None:
        """The frame's timestamps: one after each timed step of its recording (its
        `stamp_names`, set when it was looked up) into the slot's stats."""
        names = frame.stamp_names
        t = self.ring.timings_ms(frame, len(names) + 1)
        slot.stats.gpu_ms = t[-1] if t else float("nan")
        bounds = [0.0, *t]
        slot.stats.pass_ms = {n: bounds[i + 1] - bounds[i] for i, n in enumerate(names)}

    def frame_stats(self, frame: Frame) -> FrameStats:
        """The stats of the frame slot `frame` (after `draw` with timings, or a collect)."""
        return self.slots[frame.index].stats

    def render(
        self,
        camera: Camera | Any = None,
        lights: LightsArg = None,
        size: tuple[int, int] = (640, 480),
        options: RenderOptions | None = None,
        linear: bool = False,
        depth: bool = False,
        outputs: Iterable[str] | None = None,
        **option_overrides: Any,
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

        Returns
        -------
        (H, W, 4) uint8 sRGB-encoded colour, or (H, W, 4) float32 linear colour when
        `linear`; with `depth`, a tuple (colour, depth) where depth is (H, W) float32
        view-space distance along the camera axis (inf where nothing was drawn); with
        `outputs`, {name: array}.
        """
        frames = self.render_many([camera], lights, size, options, linear, depth,
                                  outputs=outputs, **option_overrides)
        return next(iter(frames))

    def render_many(
        self,
        cameras: Iterable[Camera | Any],
        lights: LightsArg = None,
        size: tuple[int, int] = (640, 480),
        options: RenderOptions | None = None,
        linear: bool = False,
        depth: bool = False,
        readback: bool = True,
        outputs: Iterable[str] | None = None,
        batch: int | None = None,
        driver_time: bool = False,
        **option_overrides: Any,
    ) -> Iterator[np.ndarray | tuple[np.ndarray, np.ndarray] | dict[str, np.ndarray] | None]:
        """Render one frame per camera, yielding what `render` returns, in order.

        Up to `ring.count` frames are queued on the GPU: while frame i renders, Python
        writes frame i+1's uniforms and submits it, and copies frame i-1 out of its own
        persistently mapped readback buffer. Nothing is allocated per frame but the returned
        arrays. Each frame is bit-for-bit what `render` gives for its camera.
        `readback=False` yields None per finished frame instead (benchmarks: render only).
        `batch` N: the cameras N at a time through `render_batch` (one submission each; its
        shadow maps of directional lights are one map over the scene), where the device has
        layered rendering; None: frame by frame.
        `driver_time`: each frame's `last_stats.driver_ms` (the part of `cpu_ms` spent in the
        driver: `draw`'s), for benchmarks that split Python from the driver.
        """
        opts = dataclasses.replace(options or RenderOptions(), **option_overrides)
        if batch is not None and readback and self.device.batch_views:
            yield from self._render_many_batched(cameras, batch, lights, size, opts, linear,
                                                 depth, outputs)
            return
        frame_lights = self.frame_lights(opts, lights)
        target = self.offscreen_target(size, linear)
        wanted = self._check_outputs(outputs, target)
        copy = ((COPY_COLOR, COPY_DEPTH) if depth else (COPY_COLOR,)) if readback else ()
        if wanted and readback:
            copy = (*copy, COPY_OUTPUTS)
        base = self.default_camera()
        pending: collections.deque[Frame] = collections.deque()
        try:
            for camera in cameras:
                camera = base if camera is None else as_camera(camera, base)
                validate_camera(camera)
                if len(pending) == self.ring.count:
                    yield self._collect(pending.popleft(), target, depth, readback, wanted)
                sub = self.draw(target, camera, frame_lights, opts, copy=copy, linear=linear,
                                timings=False, driver_time=driver_time)
                pending.append(sub.frame)  # type: ignore[arg-type] - offscreen: always a frame
            while pending:
                yield self._collect(pending.popleft(), target, depth, readback, wanted)
        finally:
            # An abandoned generator leaves frames queued: finish them before anything reuses them.
            for frame in pending:
                frame.wait()

    def render_batch(
        self,
        cameras: CameraBatch | np.ndarray | Iterable[Camera | Any],
        size: tuple[int, int] = (128, 128),
        lights: LightsArg = None,
        options: RenderOptions | None = None,
        linear: bool = False,
        depth: bool = False,
        outputs: Iterable[str] | None = None,
        batch: int | str = "auto",
        device: str = "cpu",
        out: np.ndarray | None = None,
        **option_overrides: Any,
    ) -> np.ndarray | tuple[np.ndarray, np.ndarray] | dict[str, np.ndarray] | Any:
        """Render B views of the scene in one submission and return them stacked.

        Parameters
        ----------
        cameras : a CameraBatch (vkpbr.scene.camera_batch: from eye/target arrays, (B, 4, 4)
            poses or OpenCV K + poses, no Python object per view), a (B, 4, 4) array of
            OpenGL world-from-camera poses, or a list of Cameras (anything `render` takes).
        size : (width, height) of every view.
        lights, options, linear, option_overrides : as `render`.
        depth : also return (B, H, W) float32 distances along each view's axis.
        outputs : as `render`'s, stacked per view; "color" comes from the batch, the others
            (depth, range, ids, normals) from the dataset outputs' pass, view by view (as
            `render` makes them).
        batch : views per submission: "auto" (as many as fit in a quarter of the free device
            memory and of the free host-visible memory for the readback, at most 65,536) or a
            positive integer; larger batches are split into several submissions.
        device : "cpu": NumPy arrays; "cuda": a torch.uint8 (or float32 with `linear`)
            tensor (B, H, W, 4) on the same GPU, never through host memory: the frames are
            copied into Vulkan memory that CUDA imports (gpu/cuda.py), then into a tensor of
            torch's own on its current stream. Colour only; needs torch with CUDA and
            cuda-python (the `cuda` extra) and the renderer on that NVIDIA GPU.
        out : a C-contiguous writeable (B, H, W, 4) uint8 array (float32 with `linear`) the
            colour is written into and returned as, instead of a new array: a loop reusing
            one array skips the page faults of fresh memory (at 4,096 views of 128x128, 0.27 GB:
            90-350 ms a call, against 30 ms into a reused array, on the 2-core CI machine).

        Returns
        -------
        (B, H, W, 4) uint8 sRGB (float32 linear with `linear`); with `depth` a tuple (colour,
        depth); with `outputs` {name: (B, ...) array}. pipeline="forward" (and "auto" on
        CPUs): view i equals `render` of view i (`CameraBatch.camera(i)`) with
        pipeline="forward" bit for bit (but for transmissive materials, which see the
        environment through them in a batch, not the copy of the opaque scene:
        render/transmission.py). pipeline="compute" (and "auto" on GPUs that have
        64-bit atomics, for scenes without blended materials) is the compute batch (one
        atlas, rasterised and shaded in compute shaders: each view within 1/255 of
        `render(pipeline="compute", raster="compute")`, docs/batch.md). Either way
        directional lights' shadow maps are one map over the whole scene, shared by the
        views (docs/batch.md).
        """
        base = self.default_camera()
        views = as_camera_batch(cameras, base)
        opts = dataclasses.replace(options or RenderOptions(), **option_overrides)
        if device not in ("cpu", "cuda"):
            raise UsageError(f"device {device!r}: choose 'cpu' (NumPy) or 'cuda' (a torch tensor)")
        if out is not None:
            _check_out(out, (len(views), size[1], size[0], 4), np.float32 if linear else np.uint8,
                       device)
        post = bool(enabled_post(opts))  # batches have no post stage yet: view by view
        if device == "cuda":
            if depth or outputs:
                raise UsageError("device='cuda' returns the colour only: ask depth and dataset "
                                 "outputs with device='cpu'")
            if post:
                raise UsageError("device='cuda' batches have no post steps (--bloom) yet: "
                                 "render them with device='cpu'")
            return self.batch_path.render_cuda(views, size, lights, opts, linear, batch)
        wanted = self._check_outputs(outputs, self.offscreen_target(size, linear)) if outputs else ()
        # The dataset outputs but colour come from their own pass (as `render` makes them).
        extra = tuple(n for n in wanted if n != "color")
        # "compute" is the compute batch (all views in one atlas, rasterised and shaded in
        # compute shaders) where the device has the compute rasteriser and no draw blends,
        # else view by view; "auto" takes the compute batch on GPUs where it can (the H200
        # measured it 4-5x the layered batch: BENCHMARKS.md), else batches on the fragment
        # path (render/batch.py), bit for bit what `render` draws with pipeline="forward".
        explicit_compute = (opts.pipeline == L.PipelinePath.COMPUTE
                            and self.uses_compute(self.offscreen_target(size, linear), opts))
        if self.takes_compute_batch(opts) and not extra and not post:
            color, dist = self.batch_path.render_compute(views, size, lights, opts, linear,
                                                         depth, batch, out=out)
            if not wanted:
                return (color, dist) if depth else color
            return {"color": color}
        if not self.device.batch_views or self.msaa > 1 or explicit_compute or post:
            # No layered rendering here, MSAA (the batch target is single-sample), the
            # compute path asked for or post steps (not yet in batches): view by view, each
            # exactly as `render` draws it.
            frames = list(self.render_many((views.camera(i) for i in range(len(views))), lights,
                                           size, opts, linear, depth, outputs=wanted or None))
            return _stack_frames(frames, depth, wanted, out)
        color, dist = self.batch_path.render(views, size, lights, opts, linear, depth, batch, out)
        if not wanted:
            return (color, dist) if depth else color
        result: dict[str, np.ndarray] = {}
        if "color" in wanted:
            result["color"] = color
        if extra:
            frames = list(self.render_many((views.camera(i) for i in range(len(views))), lights,
                                           size, opts, linear, outputs=extra))
            for name in extra:
                result[name] = np.stack([f[name] for f in frames])
        return {n: result[n] for n in wanted}

    def _render_many_batched(self, cameras: Iterable[Camera | Any], batch: int, lights: LightsArg,
                             size: tuple[int, int], opts: RenderOptions, linear: bool,
                             depth: bool, outputs: Iterable[str] | None) -> Iterator[Any]:
        """render_many through render_batch, `batch` cameras at a time, yielding per view."""
        if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
            raise UsageError(f"batch {batch!r}: expected a positive number of views")
        base = self.default_camera()
        # Once, as a tuple: `outputs` may be an iterator, and every batch asks it again.
        wanted = None if outputs is None else (
            (outputs,) if isinstance(outputs, str) else tuple(outputs))
        pending: list[Camera] = []

        def flush() -> Iterator[Any]:
            got = self.render_batch(pending, size, lights, opts, linear, depth, wanted)
            for i in range(len(pending)):
                if isinstance(got, dict):
                    yield {k: v[i] for k, v in got.items()}
                else:
                    yield (got[0][i], got[1][i]) if depth else got[i]
            pending.clear()

        for camera in cameras:
            pending.append(base if camera is None else as_camera(camera, base))
            if len(pending) == batch:
                yield from flush()
        if pending:
            yield from flush()

    def _check_outputs(self, outputs: Iterable[str] | None, target: OffscreenTarget) -> tuple[str, ...]:
        """The dataset outputs asked for, checked; their images made on first use."""
        if outputs is None:
            return ()
        wanted = tuple(outputs) if not isinstance(outputs, str) else (outputs,)
        unknown = [n for n in wanted if n not in OUTPUTS]
        if unknown:
            raise UsageError(f"unknown output {unknown[0]!r}; choose from {', '.join(OUTPUTS)}")
        why = self.compute_unavailable(target)
        if why is not None:
            raise UsageError(f"dataset outputs are not available here: the compute path's "
                             f"visibility pass makes them and {why}")
        self._ensure_outputs(target)
        return wanted

    def _ensure_outputs(self, target: OffscreenTarget) -> None:
        """The dataset outputs' images of `target`, made on first use."""
        formats = {name: (fmt, nbytes) for name, (fmt, nbytes, _, _) in L.OUTPUT_IMAGES.items()}
        if target.ensure_outputs(formats) and self._compute_scene is not None:
            # The target's compute set bound stand-ins: rebuild it (and what recorded it).
            self.device.wait_idle()
            self.recorder.free()
            self._compute_scene.forget_target(target)

    @property
    def max_id(self) -> int:
        """The largest instance or semantic id the outputs can hold (id images must fit it)."""
        return max(len(self.gpu_scene.draws), int(self.semantic_ids.max(initial=0)))

    @property
    def instances(self) -> list[dict[str, Any]]:
        """What each instance id of the outputs is: [{"id", "node", "mesh", "material",
        "semantic", "label"}], id = index + 1 (0 is the background). The semantic id comes
        from the Renderer's `semantics` (vkpbr.scene.semantics; by default the mesh's index
        + 1, each glTF mesh primitive its own), `label` its name ("" for 0)."""
        gs, scene = self.gpu_scene, self.scene
        out = []
        for i, d in enumerate(gs.draws):
            mesh = scene.meshes[d.mesh]
            sem = int(self.semantic_ids[i])
            out.append({"id": i + 1, "mesh": mesh.name, "semantic": sem,
                        "label": self.semantic_labels.get(sem, ""),
                        "material": gs.materials[d.material].name,
                        "node": scene.nodes[d.node].name if 0 <= d.node < len(scene.nodes) else ""})
        return out

    def _collect(self, frame: Frame, target: OffscreenTarget, depth: bool, readback: bool,
                 outputs: tuple[str, ...] = ()) -> Any:
        slot = self.slots[frame.index]
        stats = slot.stats
        t0 = time.perf_counter()
        frame.wait()
        t1 = time.perf_counter()
        stats.wait_ms = (t1 - t0) * 1e3
        self._read_timings(frame, slot)
        if not readback:
            self.last_stats = dataclasses.replace(stats, readback_ms=0.0)
            return None
        color = target.read_color(frame.index)
        out_depth = linear_depth(target.read_depth(frame.index), slot.znear) if depth else None
        result: Any = (color, out_depth) if depth else color
        if outputs:
            dtypes = {name: (dt, ch) for name, (_, _, dt, ch) in L.OUTPUT_IMAGES.items()}
            result = frame_outputs(target.read_outputs(frame.index, dtypes), color, outputs,
                                   np.asarray(slot.camera_rotation).reshape(3, 3).T)
        stats.readback_ms = (time.perf_counter() - t1) * 1e3
        self.last_stats = dataclasses.replace(stats)
        self.device.check_validation()
        return result

    def read_color(self, target: FrameTarget, sub: Submitted) -> np.ndarray:
        """Wait for a frame drawn with copy=(COPY_COLOR,) and return its (H, W, 4) pixels."""
        sub.frame.wait()  # type: ignore[union-attr]
        return target.read_color(sub.frame.index)  # type: ignore[attr-defined, union-attr]

    def wait_idle(self) -> None:
        self.device.wait_idle()

    def check_validation(self) -> None:
        self.device.check_validation()

    # --- lifetime ---------------------------------------------------------------------------
    def close(self) -> None:
        """Destroy everything (idempotent). The Renderer is unusable afterwards."""
        dev = getattr(self, "device", None)
        if dev is None or dev.handle is None:
            return
        dev.wait_idle()
        if getattr(self, "recorder", None) is not None:
            self.recorder.free()
        if getattr(self, "_batch_path", None) is not None:
            self._batch_path.close()
            self._batch_path = None
        if getattr(self, "shadows", None) is not None:
            self.shadows.destroy()
        if getattr(self, "opaque_copies", None) is not None:
            self.opaque_copies.destroy()
        if getattr(self, "_post_kernels", None) is not None:
            self._post_kernels.destroy()
        for env in getattr(self, "_environments", {}).values():
            env.destroy()
        self._environments = {}
        if getattr(self, "_baker", None) is not None:
            self._baker.destroy()
            self._baker = None
        dev.close()

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _check_out(out: Any, shape: tuple[int, ...], dtype: type, device: str) -> None:
    """render_batch's `out`: a NumPy array render_batch can write the colour into."""
    if device != "cpu":
        raise UsageError("out= takes a NumPy array: it is for device='cpu'")
    if not isinstance(out, np.ndarray) or out.shape != shape or out.dtype != dtype \
            or not out.flags.c_contiguous or not out.flags.writeable:
        got = (f"{type(out).__name__}" if not isinstance(out, np.ndarray) else
               f"{out.dtype} {out.shape}{'' if out.flags.c_contiguous else ' not contiguous'}"
               f"{'' if out.flags.writeable else ' read-only'}")
        raise UsageError(f"out= must be a C-contiguous writeable {np.dtype(dtype)} array of "
                         f"shape {shape}; got {got}")


def _stack_frames(frames: list[Any], depth: bool, wanted: tuple[str, ...],
                  out: np.ndarray | None = None) -> Any:
    """render_many's frames stacked as render_batch returns them (the colour into `out`)."""
    if wanted:
        return {n: np.stack([f[n] for f in frames], out=out if n == "color" else None)
                for n in wanted}
    if depth:
        return np.stack([f[0] for f in frames], out=out), np.stack([f[1] for f in frames])
    return np.stack(frames, out=out)


def _no_clock() -> float:
    return 0.0


def _env_key(options: RenderOptions) -> tuple:
    """Which environment `options` sample: ("black",), ("sky",) or ("file", absolute path)."""
    if not options.has_environment:
        return ("black",)
    if options.env == "sky":
        return ("sky",)
    return ("file", os.path.abspath(options.env))


@functools.lru_cache(maxsize=64)
def _automatic_sun(env_rotation_deg: float) -> Light:
    """The sky's sun as a directional Light, turned by R_y(+theta) like the environment
    (whose lookups turn by R_y(-theta), shaders/env_common.glsl env_rotate)."""
    color, illuminance = sun_radiometry(SUN_DIRECTION)
    t = math.radians(env_rotation_deg)
    x, y, z = SUN_DIRECTION
    direction = (math.cos(t) * x + math.sin(t) * z, y, -math.sin(t) * x + math.cos(t) * z)
    return Light(kind="directional", direction=direction, color=color, intensity=illuminance,
                 falloff="inverse_square")


# Dataset outputs of render(outputs=...): name -> what it is (docs/outputs.md).
OUTPUTS = {
    "color": "the frame's colour, as render returns it",
    "depth": "(H, W) float32 distance along the view axis; inf where nothing was drawn",
    "range": "(H, W) float32 distance to the camera centre; inf where nothing was drawn",
    "instance": "(H, W) uint32 instance id: Renderer.instances[id - 1]; 0 = background",
    "semantic": "(H, W) uint32 semantic id (Renderer(semantics=...): by default the mesh's index + 1; "
                "Renderer.semantic_labels names them); 0 = background or no class",
    "normal": "(H, W, 3) float32 world shading normal (normal-mapped); 0 = background",
    "normal_camera": "(H, W, 3) float32 the shading normal in camera axes (OpenGL: x right, "
                     "y up, z towards the viewer); 0 = background",
    "normal_geometric": "(H, W, 3) float32 world interpolated vertex normal (before normal "
                        "mapping); 0 = background",
}


def frame_outputs(images: dict[str, np.ndarray], color: np.ndarray, wanted: tuple[str, ...],
                  camera_rotation: np.ndarray) -> dict[str, np.ndarray]:
    """The outputs' arrays from the target's output images (render/layouts.py OUTPUT_IMAGES).
    Blended and background pixels are not in the ids (only what the visibility pass draws:
    opaque and alpha-masked surfaces, alpha-masked texels cut out as from the colour)."""
    ids, dr = images["out_ids"], images["out_depth_range"]
    normal = images["out_normal"][..., :3]
    available = {
        "color": lambda: color,
        "depth": lambda: dr[..., 0].copy(),
        "range": lambda: dr[..., 1].copy(),
        "instance": lambda: ids[..., 0].copy(),
        "semantic": lambda: ids[..., 1].copy(),
        "normal": lambda: normal.copy(),
        # float32 throughout: a float64 rotation made NumPy promote and loop (40 ms at
        # 1080p on the CI machine, against 7 ms; within 5e-7 of it).
        "normal_camera": lambda: normal @ np.asarray(camera_rotation, np.float32),
        "normal_geometric": lambda: images["out_normal_geometric"][..., :3].copy(),
    }
    return {name: available[name]() for name in wanted}
