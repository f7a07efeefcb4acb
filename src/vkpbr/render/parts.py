"""What frames of one scene are drawn with, made in order and given to those that draw.

`make_parts` makes the scene's GPU objects (descriptor layouts, the scene's GPU copy, the
opaque copies transmission samples, the shadow maps, the recorder) and the concerns that
draw with them, each its own module's and given only what it needs: targets
(render/targets.py), path choice (render/path_choice.py), environments
(render/environments.py), lighting (render/lighting.py), shadow maps per frame
(render/shadow_frames.py) and the blended draws' order (render/blend_order.py). What depends
on no scene is the device's `DeviceParts`, made once and shared by a Renderer's scenes
(render/scene_swap.py): the frame ring and slots, the pre-filtered environments, the shadow
maps' images, the offscreen targets and the compute batch's atlases. The frame path (render/frame_path.py) and the batch path
(render/batch_path.py) draw with the `FrameParts`; the Renderer (render/renderer.py) holds
them. Every GPU object is a child of the device, which destroys what was made if making the
rest fails.
"""

from __future__ import annotations

import os
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout
from vkpbr.gpu.device import Device, DeviceRequest
from vkpbr.gpu.frames import FrameRing
from vkpbr.gpu.kept import KeptHandles
from vkpbr.gpu.pipeline import PipelineLayout
from vkpbr.gpu.pipeline_cache import PipelineCache
from vkpbr.gpu.target import OffscreenTarget
from vkpbr.render import layouts as L
from vkpbr.render.ao import AoImages
from vkpbr.render.batch import draw_spheres
from vkpbr.render.blend_order import BlendOrder
from vkpbr.render.compute_path import ComputeScene
from vkpbr.render.deform import DeformKernel, DeformLayout
from vkpbr.render.environment import EnvironmentSpec
from vkpbr.render.environments import Environments, EnvironmentStore
from vkpbr.render.frames import Bounds, FrameSlot, bind_instances, create_slots, fresh_slots
from vkpbr.render.gpu_scene import GpuScene
from vkpbr.render.lighting import Lighting
from vkpbr.render.path_choice import FramePaths, shaders_digest
from vkpbr.render.post_stage import PostKernels
from vkpbr.render.recorder import STAMPS, FrameRecorder
from vkpbr.render.scene_state import GpuSceneState, LiveBounds, scene_state
from vkpbr.render.shadow_frames import ShadowFrames
from vkpbr.render.shadow_images import ShadowImages
from vkpbr.render.shadows import ShadowMaps
from vkpbr.render.targets import Lazy, Targets
from vkpbr.render.transmission import OpaqueCopies
from vkpbr.scene.semantics import semantic_ids
from vkpbr.scene.state import SceneState
from vkpbr.scene.types import Camera, Scene, scene_bounds

__all__ = ["DeviceParts", "FrameParts", "create_layouts", "make_parts", "open_device", "lazy_compute"]


@dataclass(frozen=True, slots=True)
class DeviceParts:
    """What a Renderer's scenes share on its device, made once with it (render/scene_swap.py)
    under `Device.keeping` (outside a scene's count of device children): the frame ring, the
    frame slots' buffers, pool and sets (each scene takes them as new slots, `fresh_slots`,
    and writes its own bindings in their sets: instances, opaque copy, ambient occlusion,
    environment), the pre-filtered environments, the shadow maps' images (a scene takes
    those of its sizes, render/shadow_images.py), the offscreen targets `render` draws
    into and the compute batch's atlases (render/targets.py), the ambient occlusion's
    images and kernels (render/ao.py, made with the first scene). The device's kept handles (gpu/kept.py:
    layouts, pipelines, samplers) are shared the same way; everything else is a scene's
    `FrameParts`."""

    ring: FrameRing
    frame_buffers: list[Buffer]
    frame_pool: DescriptorPool
    slots: list[FrameSlot]
    environments: EnvironmentStore
    shadow_images: ShadowImages  # the shadow maps' images (render/shadow_images.py)
    targets: dict[tuple, OffscreenTarget]  # render/targets.py Targets' kept ones
    atlases: OrderedDict[tuple, OffscreenTarget]  # compute-batch atlases a scene gave back
    # The ambient occlusion's images and kernels (render/ao.py), made with the first scene
    # and taken by each next one (AoImages.new_scene): a scene change had made and destroyed
    # ~70 of its ~200 Vulkan objects and waited for the device twice for them
    ao: list[AoImages] = field(default_factory=list)

    @staticmethod
    def make(device: Device, env_spec: EnvironmentSpec | None,
             cache_dir: str | os.PathLike[str] | None) -> DeviceParts:
        with device.keeping():
            ring = FrameRing(device, queries_per_frame=STAMPS)
            set0, set2 = (DescriptorSetLayout(device, [BindingSpec(*row) for row in L.SETS[i]])
                          for i in (0, 2))
            buffers, pool, slots = create_slots(device, set0, set2, ring.count)
        return DeviceParts(ring, buffers, pool, slots, EnvironmentStore(device, env_spec, cache_dir),
                           ShadowImages(device), {}, OrderedDict())

    def ao_images(self, device: Device, slots: list[FrameSlot], set0_layout: DescriptorSetLayout,
                  stand_in: tuple[Any, Any]) -> AoImages:
        """The device's AoImages for a new scene (made with the first; the device idle)."""
        sets2 = [s.set2 for s in slots]
        if not self.ao:
            self.ao.append(AoImages(device, sets2, set0_layout, stand_in))
        else:
            self.ao[0].new_scene(sets2, set0_layout)
        return self.ao[0]

    def frame_slots(self) -> tuple[FrameRing, list[FrameSlot]]:
        """The ring and slots for a new scene, as new ones (the device idle)."""
        self.ring.restart()
        return self.ring, fresh_slots(self.slots)


@dataclass(frozen=True, slots=True)
class FrameParts:
    """What frames of `scene` are drawn with (see the module's docstring)."""

    device: Device
    scene: Scene
    ring: FrameRing
    set_layouts: list[DescriptorSetLayout]
    pipeline_layout: PipelineLayout
    frame_buffers: list[Buffer]  # the slots' uniform blocks and light records
    frame_pool: DescriptorPool  # the slots' sets
    slots: list[FrameSlot]
    gpu_scene: GpuScene
    semantic_ids: np.ndarray  # (draws,) uint32: the dataset outputs' class per draw
    semantic_labels: dict[int, str]
    opaque_copies: OpaqueCopies
    compute: Lazy[ComputeScene]  # the compute path's resources, made on its first frame
    post: Lazy[PostKernels]  # the post steps' kernels, made on first use
    recorder: FrameRecorder
    state: SceneState  # what changes between frames (vkpbr.scene.state)
    deform: DeformKernel | None  # skins and morph targets posed each frame (render/deform.py)
    gpu_state: GpuSceneState  # its copy per frame slot (render/scene_state.py)
    bounds: LiveBounds  # the scene's bounds, following the state
    blend: BlendOrder
    paths: FramePaths
    targets: Targets
    environments: Environments
    lighting: Lighting
    shadow_frames: ShadowFrames
    ao: AoImages  # the ambient occlusion's images and kernels (render/ao.py)

    def default_camera(self) -> Camera:
        """The scene's first camera, else the automatic one (scene/geometry.py auto_camera)."""
        if self.scene.cameras:
            return self.state.cameras()[0]  # (its field of view may be animated)
        from vkpbr.scene.geometry import auto_camera

        return auto_camera(self.scene)

    def close(self) -> None:
        """Destroy what is not the device's to destroy (the caller waits for the device)."""
        self.recorder.free()
        self.gpu_state.destroy()
        if self.deform is not None:
            self.deform.destroy()
        self.shadow_frames.maps.destroy()
        self.opaque_copies.destroy()  # (the AO images are the device's: DeviceParts.ao)
        if self.post.made is not None:
            self.post.made.destroy()


def open_device(device: str | int | None, validation: bool | None, sync_validation: bool,
                window_extensions: tuple[str, ...] | None,
                cache_dir: str | os.PathLike[str] | None = None) -> Device:
    """The Renderer's device (its arguments of those names): with a window system's instance
    extensions, swapchains too; `validation` None: on where VKPBR_VALIDATION=1. Its pipeline
    cache is kept in `cache_dir` (None: in memory), keyed by the device and the SPIR-V."""
    if window_extensions is not None:
        device = DeviceRequest(device, tuple(window_extensions), ("VK_KHR_swapchain",))
    if validation is None:
        validation = os.environ.get("VKPBR_VALIDATION") == "1"
    dev = Device(device, validation=validation, sync_validation=sync_validation)
    dev.kept = KeptHandles()  # layouts, pipelines, samplers shared across set_scene
    try:
        t = time.perf_counter()
        dev.pipeline_cache = PipelineCache(dev, cache_dir, shaders_digest())
        dev.timings["pipeline_cache"] = time.perf_counter() - t  # (its file read and checked)
    except BaseException:
        dev.close()
        raise
    return dev


def create_layouts(device: Device, frames: int, images: ShadowImages | None = None
                   ) -> tuple[list[DescriptorSetLayout], ShadowMaps, PipelineLayout]:
    """The frame's descriptor set layouts (L.SETS), the shadow maps (whose own layout is set
    3: their sets are per frame slot, `frames` of them; their images from `images`) and the
    pipeline layout of all four."""
    layouts = [DescriptorSetLayout(device, [BindingSpec(b, k, s, n) for b, k, s, n in rows])
               for i, rows in sorted(L.SETS.items()) if i != 3]
    shadows = ShadowMaps(device, layouts[1], frames, frame_layout=layouts[0], images=images)
    layouts.append(shadows.set_layout)
    return layouts, shadows, PipelineLayout(device, layouts, L.PUSH.size)


def lazy_compute(device: Device, scene: Scene, gs: GpuScene, layouts: list[DescriptorSetLayout],
                 slots: list[FrameSlot], ids: np.ndarray, gpu_state: GpuSceneState,
                 deform: DeformKernel | None) -> Lazy[ComputeScene]:
    """The compute path's resources for the scene's draws as they are now, made on first use."""
    return Lazy(lambda: ComputeScene(device, gs, dict(enumerate(layouts)), slots, ids,
                                     draw_spheres(scene, gs.draws, gs.mesh_box) if gs.draws
                                     else None,
                                     gpu_state, deform.prev_positions if deform else None))


def make_parts(device: Device, scene: Scene, msaa: int, background: tuple[float, float, float],
               depth_prepass: bool | None, shared: DeviceParts,
               cache_dir: str | os.PathLike[str] | None, semantics: Any,
               ahead: Any = None, kernels_ahead: bool = False) -> FrameParts:
    """The parts of frames of `scene` on `device` (the Renderer's arguments of those names;
    `shared`: what the device's scenes share; `ahead`: the SceneAhead it was loaded by, whose
    decoded images GpuScene takes; `kernels_ahead`: begin a first frame's likely kernels on
    the device's threads as soon as what they need exists, render/kernels_ahead.py)."""
    ring, slots = shared.frame_slots()
    layouts, shadows, pipeline_layout = create_layouts(device, ring.count, shared.shadow_images)
    if kernels_ahead:
        from vkpbr.render import kernels_ahead as ahead_kernels

        ahead_kernels.start(device, layouts, scene)
    buffers, pool = shared.frame_buffers, shared.frame_pool
    gs = GpuScene(device, scene, layouts[1], ring.count, ahead=ahead)
    layout = DeformLayout(scene, gs.deformed) if gs.deformed else None
    state = scene_state(scene, gs.draws, layout, gs.mesh_box)
    gpu_state = GpuSceneState(device, state, ring.count, scene, layout)
    gpu_state.first_posed = min(gs.posed_offsets, default=0)
    gpu_state.gpu_scene = gs
    deform = (DeformKernel(device, scene, gs, layout, [gpu_state.deform_region(s.index) for s in slots])
              if layout is not None else None)
    bind_instances(device, [s.set0 for s in slots], [gpu_state.region(s.index) for s in slots])
    ids, labels = semantic_ids(scene, gs.draws, Path(semantics)
                               if isinstance(semantics, os.PathLike) else semantics)
    # Bound in every slot's set 2 before anything is recorded (render/transmission.py).
    copies = OpaqueCopies(device, gs, [s.set2 for s in slots], (*background, 1.0))
    compute = lazy_compute(device, scene, gs, layouts, slots, ids, gpu_state, deform)
    post = Lazy(lambda: PostKernels(device))
    blend = BlendOrder(gs.draws, state)
    paths = FramePaths(device, msaa, scene.triangle_count, len(blend) > 0, depth_prepass,
                       cache_dir)
    ao = shared.ao_images(device, slots, layouts[0], gs.stand_in())
    recorder = FrameRecorder(device, gs, pipeline_layout, ring, slots, paths.prepass_for,
                             shadows, compute, copies, post, deform, ao)
    bounds = LiveBounds(state, Bounds.of(*scene_bounds(scene, gs.mesh_box)))
    environments = Environments(device, slots, recorder, shared.environments)
    return FrameParts(
        device, scene, ring, layouts, pipeline_layout, buffers, pool, slots, gs, ids, labels,
        copies, compute, post, recorder, state, deform, gpu_state, bounds, blend, paths,
        Targets(device, msaa, background, ring.count, recorder, compute, post, shared.targets,
                shared.atlases),
        environments,
        Lighting(scene, copies, environments, state, shadows),
        ShadowFrames(shadows, bounds, recorder, state,
                     np.array([d.casts_shadows for d in gs.draws], bool), paths), ao)
