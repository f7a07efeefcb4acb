"""Per-frame uniforms: each frame of the ring (gpu/frames.py) owns its uniform blocks (views
into one mapped buffer) and the descriptor sets that point at them, so several frames can be
queued on the GPU while Python writes the next one's camera.

`write_frame_view` writes the slot's view record (render/views.py: record 0 of set 0's Views,
what every shader reads the camera from), `write_frame_blocks` the settings and lighting
blocks by field name through the std140 layouts' struct packers
(layouts.Std140Block.pack_into) and the punctual lights as one NumPy array into the slot's
storage buffer (`write_frame_uniforms`: both), each skipping the work when its inputs repeat
(a static scene re-rendered; the lights are a tuple of frozen Lights, so an unchanged tuple
compares equal at once).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.descriptors import DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.render import layouts as L
from vkpbr.render.options import RenderOptions
from vkpbr.render.views import camera_view_terms, pack_view
from vkpbr.scene.types import Camera, Light

__all__ = ["FrameSlot", "FrameStats", "FrameLighting", "create_slots", "fresh_slots", "write_frame_uniforms",
           "write_frame_view", "write_frame_blocks", "bind_instances",
           "light_records", "Bounds"]

FRAME_BLOCKS = (L.VIEW_RECORD, L.SETTINGS, L.LIGHTING)  # the view: one record
LIGHTS_BYTES = L.LIGHT_RECORD.size * L.MAX_LIGHTS  # one slot's storage buffer of lights
INSTANCES_BINDING = next(b for b, _, _, name in L.SETS[0] if name == "Instances")


@dataclass
class FrameStats:
    cpu_ms: float = 0.0  # Python-side: uniforms + record lookup + submit (excludes the wait)
    wait_ms: float = 0.0  # waiting for the GPU
    gpu_ms: float = float("nan")  # timestamp queries around the frame's commands
    readback_ms: float = 0.0  # copying the mapped image into NumPy
    pass_ms: dict[str, float] = field(default_factory=dict)  # GPU ms per pass (timestamps)
    driver_ms: float = 0.0  # thread CPU time inside the target's acquire and submit/present


def summed_stats(a: FrameStats, b: FrameStats) -> FrameStats:
    """Two submissions' timings as one call's (a batch split into several submissions)."""
    passes = dict(a.pass_ms)
    for name, ms in b.pass_ms.items():
        passes[name] = passes.get(name, 0.0) + ms
    return FrameStats(a.cpu_ms + b.cpu_ms, a.wait_ms + b.wait_ms, a.gpu_ms + b.gpu_ms,
                      a.readback_ms + b.readback_ms, passes, a.driver_ms + b.driver_ms)


@dataclass
class FrameSlot:
    index: int
    set0: Any  # the view + settings
    set2: Any  # lighting: the Lighting block, the lights, the environment's maps
    # Zero-copy byte views of the blocks in the mapped uniform buffer.
    m_view: memoryview  # the frame's view record (Views[0])
    m_settings: memoryview
    m_lighting: memoryview
    lights: np.ndarray  # (MAX_LIGHTS, 20) float32 view of the slot's mapped light records
    # (buffer, offset) of each frame block by GLSL name: the compute path binds them as
    # storage buffers (render/compute_path.py).
    block_ranges: dict[str, tuple[Buffer, int]] = field(default_factory=dict)
    view_key: tuple | None = None  # the camera and size of the view record written here
    settings_key: tuple | None = None  # inputs of the Settings block last written here
    lighting_key: tuple | None = None  # inputs of the Lighting block last written here
    lights_written: tuple = ()  # (lights, shadow rows' bytes) of the records the slot holds
    znear: float = 0.0  # the view's near plane (depth readback is znear / depth)
    zfar: float = 0.0  # the view's far plane (the shadow cascades' range)
    # World-from-camera rotation of the frame's camera, column-major (OpenGL axes as columns:
    # right, up, backward): the dataset outputs' camera-space normals.
    camera_rotation: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    stats: FrameStats = field(default_factory=FrameStats)
    vp: tuple[float, ...] = ()  # the view's clip-from-world, column-major (the motion output)


@dataclass(frozen=True)
class Bounds:
    """The scene's world bounds as the per-frame camera maths wants them: the 8 corners as
    plain float tuples and the radius (the scale of the automatic near plane)."""

    corners: tuple[tuple[float, float, float], ...]
    radius: float

    @property
    def rest_radius(self) -> float:
        """The radius of the scene as loaded (a still scene's: `radius`; LiveBounds')."""
        return self.radius

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
) -> tuple[list[Buffer], DescriptorPool, list[FrameSlot]]:
    """Host-visible buffers holding `count` copies of the frame blocks (uniform) and of the
    light records (storage), a pool, and the slots. The caller owns (and destroys) the
    buffers and the pool; the environment's bindings of set 2 are written by its owner."""
    # Aligned for uniform and storage views alike (the compute path reads the blocks as
    # storage buffers).
    align = max(int(device.limits.minUniformBufferOffsetAlignment),
                int(device.limits.minStorageBufferOffsetAlignment))
    offsets, offset = [], 0
    for block in FRAME_BLOCKS:
        offsets.append(offset)
        offset += (block.size + align - 1) // align * align
    stride = offset
    buffer = Buffer(device, stride * count, "uniform|storage",
                    host_visible=True, device_local=True, name="frame uniforms")
    s_align = int(device.limits.minStorageBufferOffsetAlignment)
    s_stride = (LIGHTS_BYTES + s_align - 1) // s_align * s_align
    lights = Buffer(device, s_stride * count, "storage", host_visible=True, device_local=True,
                    name="frame lights")
    pool = DescriptorPool(device, [(set0_layout, count), (set2_layout, count)])
    writer = DescriptorWriter(device)
    slots = []
    for i in range(count):
        base = i * stride
        view, settings, lighting = (base + o for o in offsets)
        set0, set2 = pool.allocate(set0_layout), pool.allocate(set2_layout)
        writer.storage(set0, 0, buffer, L.VIEW_RECORD.size, view)  # a frame's one view
        writer.uniform(set0, 1, buffer, L.SETTINGS.size, settings)
        writer.uniform(set2, 0, buffer, L.LIGHTING.size, lighting)
        writer.storage(set2, 1, lights, LIGHTS_BYTES, i * s_stride)
        # Stand-ins for the batch's visible lists and world factors (render/batch.py binds
        # its own set 0): every binding written, none read by the frame shaders.
        writer.storage(set0, 2, lights, LIGHTS_BYTES, i * s_stride)
        writer.storage(set0, 3, lights, LIGHTS_BYTES, i * s_stride)  # the scene's: bind_instances
        writer.storage(set0, 4, lights, LIGHTS_BYTES, i * s_stride)  # (a batch's WorldFactors)
        slots.append(FrameSlot(
            index=i, set0=set0, set2=set2,
            m_view=memoryview(buffer.array(np.uint8, L.VIEW_RECORD.size, view)),
            m_settings=memoryview(buffer.array(np.uint8, L.SETTINGS.size, settings)),
            m_lighting=memoryview(buffer.array(np.uint8, L.LIGHTING.size, lighting)),
            lights=lights.array(np.float32, LIGHTS_BYTES // 4, i * s_stride).reshape(L.MAX_LIGHTS, 20),
            block_ranges={"Views": (buffer, view), "Settings": (buffer, settings),
                          "Lighting": (buffer, lighting), "Lights": (lights, i * s_stride)},
        ))
    writer.update()
    return [buffer, lights], pool, slots


def fresh_slots(slots: list[FrameSlot]) -> list[FrameSlot]:
    """`slots`' sets and blocks as new slots: nothing remembered of what they were written
    with and the blocks zeroed, as `create_slots` made them (a renderer's next scene reuses
    its slots; their sets' scene bindings are written again by the scene's parts)."""
    out = []
    for s in slots:
        for block in (s.m_view, s.m_settings, s.m_lighting):
            block[:] = bytes(len(block))
        s.lights[:] = 0.0
        out.append(FrameSlot(s.index, s.set0, s.set2, s.m_view, s.m_settings, s.m_lighting,
                             s.lights, s.block_ranges))
    return out


def bind_instances(device: Device, sets0: list[Any],
                   regions: list[tuple[Buffer, int, int]]) -> None:
    """Point binding 3 of each of frame sets `sets0` at its slot's copy of the scene
    state's matrices ((buffer, offset, size): render/scene_state.py)."""
    writer = DescriptorWriter(device)
    for set0, (buffer, offset, size) in zip(sets0, regions, strict=True):
        writer.storage(set0, INSTANCES_BINDING, buffer, size, offset)
    writer.update()


def _camera_key(c: Camera) -> tuple:
    return (*c.eye, *c.target, *c.up, c.yfov_deg, c.znear, c.zfar, c.pixel_intrinsics)


_KIND = {"point": L.LightKind.POINT, "spot": L.LightKind.SPOT,
         "directional": L.LightKind.DIRECTIONAL}


def light_records(lights: Sequence[Light]) -> np.ndarray:
    """(n, 20) float32: each light as shaders/lights.glsl reads it (layouts.LIGHT_RECORD),
    the spot cone as KHR_lights_punctual's angle scale and offset."""
    out = np.zeros((len(lights), 20), dtype=np.float32)
    for i, li in enumerate(lights):
        cos_outer, cos_inner = math.cos(li.outer_cone), math.cos(li.inner_cone)
        scale = 1.0 / max(1e-3, cos_inner - cos_outer)
        out[i] = (*li.position, li.range, *li.direction, _KIND[li.kind],
                  *(c * li.intensity for c in li.color), 0.0 if li.falloff == "none" else 1.0,
                  scale, -cos_outer * scale, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0)
    return out


@dataclass(frozen=True)
class FrameLighting:
    """What lights a frame besides the punctual lights: resolved once per render call from
    the options (render/lighting.py), a plain value so that frames compare it cheaply."""

    mode: int = 0  # Lighting
    flags: int = 0  # LIGHTING_* bits
    ambient: float = 0.0  # the course's ambient weight
    env_intensity: float = 1.0
    env_rotation: float = 0.0  # radians about +Y
    env_max_lod: float = 0.0


def write_frame_view(slot: FrameSlot, camera: Camera, size: Sequence[int], bounds: Any) -> None:
    """Write `slot`'s view record for `camera` and frames of `size` (W, H): the batch of one
    (render/views.py), once per new camera or size (a repeat is a tuple comparison). The
    view's planes and rotation stay on the slot for the depth readback, the dataset outputs
    and the shadow cascades, so that nothing computes the camera again."""
    # `bounds` (Bounds, or render/scene_state.py's LiveBounds with a version) set the
    # automatic planes: a moved scene makes a new view.
    key = (_camera_key(camera), size[0], size[1], getattr(bounds, "version", 0))
    if key == slot.view_key:
        return
    slot.view_key = key
    terms = camera_view_terms(camera, size, bounds.corners, bounds.radius)
    pack_view(slot.m_view, terms, (0, 0, int(size[0]), int(size[1])))
    slot.znear, slot.zfar, slot.camera_rotation = terms.znear, terms.zfar, terms.rotation
    slot.vp = terms.vp


def write_frame_uniforms(slot: FrameSlot, camera: Camera, lights: tuple[Light, ...],
                         size: Sequence[int], opts: RenderOptions, linear: bool, bounds: Bounds,
                         lighting: FrameLighting = FrameLighting(),
                         shadow: np.ndarray | None = None) -> None:
    """Write `slot`'s view record (`write_frame_view`), settings and lighting blocks and its
    light records (`write_frame_blocks`) for one frame of `size` (W, H)."""
    write_frame_view(slot, camera, size, bounds)
    write_frame_blocks(slot, lights, opts, linear, lighting, shadow)


def write_frame_blocks(slot: FrameSlot, lights: tuple[Light, ...], opts: RenderOptions,
                       linear: bool, lighting: FrameLighting = FrameLighting(),
                       shadow: np.ndarray | None = None) -> None:
    """Write what a frame's views share: `slot`'s settings and lighting blocks and its light
    records. `shadow`: (len(lights), 4) float32, each record's `shadow` vec4
    (render/shadows.py ShadowMaps.write); None: no light has a shadow map."""
    # Frames that repeat the slot's last inputs skip the packing: the key is cheap next to it.
    key = (opts, linear)
    if key != slot.settings_key:
        slot.settings_key = key
        flags = L.SETTINGS_NORMAL_MAPPING if opts.normal_mapping else 0
        flags |= L.SETTINGS_OCCLUSION if opts.occlusion else 0
        flags |= 0 if linear else L.SETTINGS_SRGB_TARGET
        L.SETTINGS.pack_into(slot.m_settings, view=opts.view, brdf=opts.shading_brdf,
                             tonemap=opts.tonemap_for(linear), flags=flags,
                             exposure=2.0 ** opts.exposure)
    # The shadow rows change with the shadow plan and the map sizes only (not the camera).
    records = (lights, None if shadow is None else shadow.tobytes())
    lighting_key = (records, lighting)
    if lighting_key != slot.lighting_key:
        slot.lighting_key = lighting_key
        if records != slot.lights_written:
            rows = light_records(lights)
            if shadow is not None:
                rows[:, 16:20] = shadow
            slot.lights[:len(lights)] = rows
            slot.lights_written = records
        a, rot = lighting.ambient, lighting.env_rotation
        L.LIGHTING.pack_into(
            slot.m_lighting, light_count=len(lights),
            mode=lighting.mode, flags=lighting.flags, env_intensity=lighting.env_intensity,
            env_rotation=(math.cos(rot), math.sin(rot), lighting.env_max_lod, 0.0),
            ambient_color=(a, a, a, 0.0))
