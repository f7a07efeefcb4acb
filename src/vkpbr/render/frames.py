"""Per-frame uniforms: each frame of the ring (gpu/frames.py) owns its uniform blocks (views
into one mapped buffer) and the descriptor sets that point at them, so several frames can be
queued on the GPU while Python writes the next one's camera.

`write_frame_uniforms` writes the camera, settings and light blocks by field name through
the std140 layouts' struct packers (layouts.Std140Block.pack_into), skipping the maths when
the frame's inputs repeat (a static scene re-rendered).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.descriptors import DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.render import layouts as L
from vkpbr.render.camera import depth_range, forward, view_projection_columns
from vkpbr.render.options import RenderOptions
from vkpbr.scene.types import Camera, Light

__all__ = ["FrameSlot", "FrameStats", "create_slots", "write_frame_uniforms", "Bounds"]

FRAME_BLOCKS = (L.CAMERA, L.SETTINGS, L.LIGHT)


@dataclass
class FrameStats:
    cpu_ms: float = 0.0  # Python-side: uniforms + record lookup + submit (excludes the wait)
    wait_ms: float = 0.0  # waiting for the GPU
    gpu_ms: float = float("nan")  # timestamp queries around the frame's commands
    readback_ms: float = 0.0  # copying the mapped image into NumPy
    pass_ms: dict[str, float] = field(default_factory=dict)  # GPU ms per pass (timestamps)
    driver_ms: float = 0.0  # thread CPU time inside the target's acquire and submit/present


@dataclass
class FrameSlot:
    index: int
    set0: Any  # camera + settings
    set2: Any  # light
    # Zero-copy byte views of the blocks in the mapped uniform buffer.
    m_camera: memoryview
    m_settings: memoryview
    m_light: memoryview
    uniform_key: tuple | None = None  # inputs of the uniforms last written here
    znear: float = 0.0  # the near plane last written (depth readback is znear / depth)
    stats: FrameStats = field(default_factory=FrameStats)


@dataclass(frozen=True)
class Bounds:
    """The scene's world bounds as the per-frame camera maths wants them: the 8 corners as
    plain float tuples and the radius (the scale of the automatic near plane)."""

    corners: tuple[tuple[float, float, float], ...]
    radius: float

    @classmethod
    def of(cls, lo: np.ndarray, hi: np.ndarray) -> Bounds:
        ok = bool(np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)))
        lo, hi = (lo, hi) if ok else (np.zeros(3), np.zeros(3))
        corners = tuple((float(x), float(y), float(z)) for x in (lo[0], hi[0])
                        for y in (lo[1], hi[1]) for z in (lo[2], hi[2]))
        radius = float(np.linalg.norm(np.subtract(hi, lo))) / 2
        return cls(corners, radius if radius > 0 else 1.0)


def create_slots(
    device: Device, set0_layout: DescriptorSetLayout, set2_layout: DescriptorSetLayout, count: int
) -> tuple[Buffer, DescriptorPool, list[FrameSlot]]:
    """One host-visible uniform buffer holding `count` copies of the frame blocks, a pool,
    and the slots. The caller owns (and destroys) the buffer and the pool."""
    align = int(device.limits.minUniformBufferOffsetAlignment)
    offsets, offset = [], 0
    for block in FRAME_BLOCKS:
        offsets.append(offset)
        offset += (block.size + align - 1) // align * align
    stride = offset
    buffer = Buffer(device, stride * count, "uniform",
                    host_visible=True, name="frame uniforms")
    pool = DescriptorPool(device, [(set0_layout, count), (set2_layout, count)])
    writer = DescriptorWriter(device)
    slots = []
    for i in range(count):
        base = i * stride
        cam, settings, light = (base + o for o in offsets)
        set0, set2 = pool.allocate(set0_layout), pool.allocate(set2_layout)
        writer.uniform(set0, 0, buffer, L.CAMERA.size, cam)
        writer.uniform(set0, 1, buffer, L.SETTINGS.size, settings)
        writer.uniform(set2, 0, buffer, L.LIGHT.size, light)
        slots.append(FrameSlot(
            index=i, set0=set0, set2=set2,
            m_camera=memoryview(buffer.array(np.uint8, L.CAMERA.size, cam)),
            m_settings=memoryview(buffer.array(np.uint8, L.SETTINGS.size, settings)),
            m_light=memoryview(buffer.array(np.uint8, L.LIGHT.size, light)),
        ))
    writer.update()
    return buffer, pool, slots


def _camera_key(c: Camera) -> tuple:
    return (*c.eye, *c.target, *c.up, c.yfov_deg, c.znear, c.zfar, c.pixel_intrinsics)


def _light_key(li: Light) -> tuple:
    return (*li.position, *li.color, li.intensity, li.falloff, li.range)


def write_frame_uniforms(slot: FrameSlot, camera: Camera, light: Light, size: Sequence[int],
                         opts: RenderOptions, linear: bool, bounds: Bounds) -> None:
    """Write `slot`'s camera, settings and light blocks for one frame of `size` (W, H)."""
    # Frames that repeat the slot's last inputs skip the maths: the key is cheap next to it.
    key = (_camera_key(camera), _light_key(light), tuple(size), opts, linear)
    if key == slot.uniform_key:
        return
    slot.uniform_key = key
    f = forward(camera)
    znear, zfar = depth_range(camera, bounds.corners, bounds.radius, f)
    slot.znear = znear
    L.CAMERA.pack_into(slot.m_camera, VP=view_projection_columns(camera, size, znear, f))
    flags = L.SETTINGS_NORMAL_MAPPING if opts.normal_mapping else 0
    flags |= L.SETTINGS_OCCLUSION if opts.occlusion else 0
    flags |= 0 if linear else L.SETTINGS_SRGB_TARGET
    L.SETTINGS.pack_into(
        slot.m_settings, camera_forward=(*f, 0.0), view=opts.view, brdf=opts.brdf,
        tonemap=opts.tonemap, flags=flags, exposure=2.0 ** opts.exposure, znear=znear,
        zfar=zfar, pad0=0.0)
    L.LIGHT.pack_into(
        slot.m_light, lightPos=(*light.position, 1.0), color=light.color,
        intensity=light.intensity, viewPos=(*camera.eye, 1.0),
        falloff=0 if light.falloff == "none" else 1, range=light.range)
