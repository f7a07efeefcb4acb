"""The kernels a GPU's first frame will bind, compiled on the device's threads while the
scene uploads.

With nothing cached (a fresh machine, new shaders), Sponza's first frame on an H200 compiles
18 kernels: 2.7 s of compiling, done about 0.6 s after the first began on 8 threads at once
(gpu/graph.py build_kernels). They began only when the frame recorded: after the scene's
upload, the rest of the set-up and the environment's pre-filter, ~0.3 s after the frame's
set layouts existed. Most need nothing the upload makes: the compute rasteriser's, the
classification's and the background's (compute_path.first_frame_kernels), the shadow maps'
compute rasteriser's (shadow_raster.KERNELS) and the ambient occlusion's
(ao.first_frame_kernels) need only the set layouts and whether the scene has masked
materials. The shading kernels, the longest to compile (~0.5 s), are specialised for each
kind of material the draws shade and for the lighting, which `start` derives from the scene
as GpuScene will (gpu_scene.drawn, material_block) before it uploads anything. `start` has
the device make them all on its background threads (Device.in_background) as soon as the
layouts exist, the shading kernels first, on threads of their own; each list is begun
longest first (by its SPIR-V's size).

A kernel made here is the device's kept handle (gpu/kept.py) of the same definition that
the frame's steps make (the same SPIR-V, set layouts, push constants and specialisation):
the frame's recording then finds it made, or waits for its maker (KeptHandles.get). What it
guesses is auto's rule on a GPU (the compute path with its rasteriser, compute-drawn shadow
maps, render/path_choice.py) with the default options (GTAO, the sky): a frame that takes
another path or other options makes what it binds itself, as before, and a wrong guess costs
only the background threads' time (CPU cores the set-up leaves idle). On CPUs (lavapipe, where
auto takes the forward path) nothing is made ahead. VKPBR_KERNELS_AHEAD=0 turns it off; =1
turns it on for CPUs too (tests/gpu/test_kernels_ahead.py).
"""

from __future__ import annotations

import functools
import logging
import os
from collections.abc import Callable
from types import SimpleNamespace

from vkpbr.gpu.compute import KERNEL_THREADS, ComputePipeline
from vkpbr.gpu.descriptors import DescriptorSetLayout
from vkpbr.gpu.device import Device
from vkpbr.render import ao, compute_path, shadow_raster
from vkpbr.render import layouts as L
from vkpbr.render.gpu_scene import default_layer_mask, drawn, material_block
from vkpbr.render.lighting import lighting_flags
from vkpbr.render.options import RenderOptions
from vkpbr.render.passes import classify
from vkpbr.render.steps import shaded_materials
from vkpbr.scene.types import Material, Scene

__all__ = ["wanted", "start"]

log = logging.getLogger(__name__)

Maker = Callable[[], ComputePipeline]


def wanted(device: Device) -> bool:
    """Whether frames on `device` are likely to take the compute path with its rasteriser
    (auto's rule on a GPU that can), or VKPBR_KERNELS_AHEAD says so; and whether the device
    keeps handles (a Renderer's: what is made here would otherwise not be shared)."""
    if device.kept is None or not (device.compute_path and device.compute_raster):
        return False
    mode = os.environ.get("VKPBR_KERNELS_AHEAD", "")
    return mode == "1" if mode in ("0", "1") else device.info.kind != "cpu"


def start(device: Device, frame_layouts: list[DescriptorSetLayout], scene: Scene,
          options: RenderOptions | None = None) -> None:
    """Begin, on `device`'s background threads, the kernels a first frame of `scene` with
    `options` (default: RenderOptions()) binds, given the frame's set layouts (0-3:
    parts.create_layouts): the shading kernels first, on threads of their own (the longest
    to compile, not queued behind the others), then the rest."""
    options = options or RenderOptions()
    with device.keeping():  # (the layouts' wrappers: the device's, not the scene's children)
        layouts = compute_path.compute_layouts(device, dict(enumerate(frame_layouts)))
        shadows = shadow_raster.raster_layouts(device, frame_layouts[0], frame_layouts[1])
        ao_layout = ao.ao_set_layout(device)
    materials = [*scene.materials, Material(name="vkpbr-default")]
    draws = [SimpleNamespace(material=m, alpha_mode=materials[m].alpha_mode,
                             double_sided=materials[m].double_sided)
             for _, _, _, m in drawn(scene)]
    kernel, push = compute_path.shading_kernel(options.tbn), compute_path.bin_push_bytes(None)
    _begin(device, [(kernel, functools.partial(compute_path.compute_kernel, device, layouts,
                                               kernel, push, c))
                    for c in _shading_constants(materials, draws, options)],
           group="ahead-shading", threads=2)
    masked = any(d.alpha_mode == "mask" for d in draws)
    makers = [(name, functools.partial(compute_path.compute_kernel, device, layouts, name, push))
              for name, push in compute_path.first_frame_kernels(compute_path.aggregates(device),
                                                                 masked)]
    if options.shadows:
        # (the save kernel serves 2D layers: the automatic sun's cascades where the scene has
        # no lights, a directional or spot light's; a point light's cube never scrolls)
        flat = not scene.lights or any(getattr(light, "kind", "point") != "point"
                                       and getattr(light, "shadows", True) for light in scene.lights)
        makers += [(f"shadow_{name}", functools.partial(shadow_raster.raster_kernel, device,
                                                        shadows, name))
                   for name in shadow_raster.KERNELS
                   if (masked or name != "masked") and (flat or name != "save")]
    if options.ao != L.Ao.OFF and options.has_environment:
        quality = ao.PRESETS.get(options.ao, ao.PRESETS[L.Ao.GTAO])
        makers += [(name, functools.partial(ao.ao_kernel, device, frame_layouts[0], ao_layout, name))
                   for name in ao.first_frame_kernels(quality, depth_buffer=True)]
    _begin(device, makers)


def _shading_constants(materials: list[Material], draws: list[SimpleNamespace],
                       options: RenderOptions) -> list[tuple[int, ...]]:
    """The shading kernel's specialisations a first frame with `options` takes for `draws`
    (material, alpha_mode, double_sided each), as GpuScene will make its material blocks
    (each texture a material names taken as bound) and Lighting its flags."""
    classes = [classify(d.alpha_mode, d.double_sided, options.alpha_mask) for d in draws]
    blocks = [material_block(m, {slot: getattr(m, f"{slot}_texture") is not None
                                 for slot in L.MATERIAL_TEXTURES}) for m in materials]
    layered = [not d for d in default_layer_mask(blocks).tolist()]
    transmissive = any(materials[d.material].transmission_factor > 0.0 for d in draws)
    ao_on = options.ao != L.Ao.OFF and options.has_environment
    # A first frame draws every map layer for casters it has not seen, and its shading reads
    # them from the buffer by hand (ShadowMaps._choose_reads)
    variant = compute_path.ShadeVariant(lighting_flags(options, transmissive, ao_on),
                                        int(options.shading_brdf), hand_reads=True)
    return compute_path.shading_constants(layered, shaded_materials(draws, classes), variant)


def _begin(device: Device, makers: list[tuple[str, Maker]], group: str = "ahead",
           threads: int = KERNEL_THREADS) -> None:
    """Each of `makers` ((its SPIR-V's name, the maker)) on the device's background threads,
    the largest SPIR-V first (the longest compile, roughly); their pipelines' wrappers let go
    at once (the handles are the device's: KeptHandles)."""
    def size(name: str) -> int:
        path = compute_path.SPV_DIR / f"{name}.comp.spv"
        return path.stat().st_size if path.is_file() else 0

    for _, make in sorted(makers, key=lambda m: -size(m[0])):
        device.in_background(functools.partial(_make, device, make), threads, group)


def _make(device: Device, make: Maker) -> None:
    """One kernel made under the device's keeping (outside any scene's children)."""
    try:
        with device.keeping():
            make().destroy()
    except Exception as err:  # the frame makes it itself (KeptHandles lets the next maker)
        log.debug("a kernel made ahead failed: %s", err)
