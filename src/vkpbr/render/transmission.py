"""KHR_materials_transmission through the scene: a copy of the opaque scene, as the
glTF-Sample-Viewer makes it.

In a scene with a transmissive material, each frame (of the physically based glTF BRDF)
first draws its opaque and masked draws -- those whose material does not transmit -- and the
environment behind them into a square RGBA16F image as *linear* radiance (pbr.frag's and
background.frag's OPAQUE_COPY builds: no exposure, no tone map, the final view whatever the
frame shows), mip-maps it by blits, and binds it in set 2 (`opaque_copy`). The frame's
transmissive surfaces then see what is behind them there: shade.glsl projects the refracted
ray's exit point (the surface point itself for a thin wall, `thickness` along the refracted
direction into a volume) with the frame's camera and samples the copy at lod log2(1024) x
roughness x clamp(2 ior - 2, 0, 1) (the Sample Viewer's getTransmissionSample; in a smaller
copy, the lod that blurs the same share of the screen); where the point leaves the screen,
the environment. Only the copy's pixels within the camera's view exist, so transmissive
surfaces never see one another (nor themselves), as in the Sample Viewer.

The copy is square whatever the frame's aspect (the projection maps the view onto it as onto
the frame); its side is the power of two nearest the frame's longer side, at most 1024 (the
Sample Viewer's fixed size), remade when frames change size class. It is drawn on the
frame's own path -- the fragment passes, or the compute path's visibility pass, binning and
shade.comp into its level 0 (then the environment behind) -- one per slot of the frame ring.
Batches (render_batch) keep the environment: their views share a slot. Until a frame needs
one, and in scenes where nothing transmits, a 1x1 stand-in is bound and no copy drawn.
"""

from __future__ import annotations

import math
from typing import Any

from vkpbr.gpu.descriptors import DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.mip_target import MipmappedTarget
from vkpbr.render import layouts as L
from vkpbr.render.gpu_scene import GpuScene

__all__ = ["OpaqueCopies", "COPY_BINDING", "COPY_PASSES", "TRANSMISSIVE", "copy_classes", "copy_size"]

COPY_FORMAT = "VK_FORMAT_R16G16B16A16_SFLOAT"  # linear radiance beyond 1, blits, filters
COPY_BINDING = next(b for b, _, _, name in L.SETS[2] if name == "opaque_copy")  # layouts.SETS
# The passes of the pass table (render/passes.py) the copy draws.
COPY_PASSES = ("prepass_opaque", "prepass_opaque_double", "opaque", "opaque_double", "mask",
               "background")


def transmits(gs: GpuScene) -> list[bool]:
    """Per draw: whether its material lets light through (KHR_materials_transmission)."""
    return [gs.materials[d.material].transmission_factor > 0.0 for d in gs.draws]


TRANSMISSIVE = "transmissive"  # the copy's class of the draws it leaves out


def copy_classes(classes: list[str], transmissive: list[bool]) -> list[str]:
    """The draw classes of the copy's passes: a transmissive draw is in none of them."""
    return [TRANSMISSIVE if t else c for c, t in zip(classes, transmissive, strict=True)]


def copy_size(extent: tuple[int, int]) -> int:
    """The copy's side for frames of `extent`: the power of two nearest its longer side (in
    octaves), at most OPAQUE_COPY_MAX_SIZE. The copy is a second drawing of the opaque scene:
    at 640 x 360 on lavapipe a 1024 x 1024 one took 650-850 ms beside the frame's 264 ms."""
    side = max(1, int(max(extent)))
    return min(1 << round(math.log2(side)), L.OPAQUE_COPY_MAX_SIZE)


class OpaqueCopies:
    """One MipmappedTarget a frame slot, bound as each slot's set 2 `opaque_copy`, when `gs`
    has a transmissive draw; made (and remade) by `fit` for the frame's size. Until then,
    and in scenes where nothing transmits, the scene's 1x1 stand-in is bound."""

    def __init__(self, device: Device, gs: GpuScene, sets2: list[Any],
                 clear_color: tuple[float, ...]) -> None:
        self.device, self.sets2 = device, sets2
        self.transmissive = transmits(gs)
        self.present = any(self.transmissive)  # whether frames draw a copy
        self.clear_color = clear_color  # the renderer's background, linear
        self.targets: list[MipmappedTarget] = []
        self.size = 0  # the targets' side (0: none yet)
        # Never sampled: a frame that samples the copy fits it first; batches never do.
        view, sampler = gs.stand_in()
        writer = DescriptorWriter(device)
        for set2 in sets2:
            writer.sampler(set2, COPY_BINDING, view, sampler)
        writer.update()

    def stale(self, extent: tuple[int, int]) -> bool:
        """Whether frames of `extent` need copies of another size than the ones made."""
        return self.present and copy_size(extent) != self.size

    def fit(self, extent: tuple[int, int]) -> None:
        """Make the copies for frames of `extent` and bind them. The caller waits for the
        device and drops the recorded command buffers first (they name the old ones)."""
        self._destroy_targets()
        self.size = copy_size(extent)
        writer = DescriptorWriter(self.device)
        for i, set2 in enumerate(self.sets2):
            target = MipmappedTarget(self.device, (self.size, self.size), COPY_FORMAT,
                                     name=f"opaque copy {i}", clear_color=self.clear_color,
                                     compute=self.device.compute_path)
            self.targets.append(target)
            writer.sampler(set2, COPY_BINDING, target.view, target.sampler)
        writer.update()

    def _destroy_targets(self) -> None:
        for target in self.targets:
            target.destroy()
        self.targets = []

    def destroy(self) -> None:
        self._destroy_targets()
