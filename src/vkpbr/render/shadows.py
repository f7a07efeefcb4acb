"""Shadow maps: their images, per-frame matrices, pipelines and depth-only passes.

Every shadowed light of a frame gets layers (`plan_shadows`): a directional light CASCADES
layers of the 2D-array image, a spot light one, a point light one cube of the cube-array
image. Each light's layers are drawn in ONE layered pass: every draw is instanced once per
layer and the vertex shader writes gl_Layer (instance - base instance) and takes the
layer's matrix (the instance), so a point light's six faces are one pass, not six
submissions. Both lavapipe and NVIDIA have the two features it needs (Vulkan 1.2
shaderOutputLayer, 1.1 shaderDrawParameters). Multiview (view mask 0x3F) was the first
choice and is what NVIDIA prefers, but Mesa 22.3's lavapipe draws a perspective pass's views
into the wrong layers (the cube faces came out mixed; orthographic cascades were right).

Frame path: `write` fills the frame slot's matrices (host-visible storage buffer, per slot)
and returns each light's `LightRecord.shadow` vec4 (`write_cascades`: only the camera-fitted
cascades, when a moving camera is all that changed); `record` draws the passes into the
frame's command buffer before the main target begins. Command buffers are recorded once per
`ShadowPlan` (which light has which layers), so lights that only move re-record nothing.

Casters: opaque draws depth-only (no fragment shader); masked and blended draws through
shadow_mask.frag, which discards below the alpha cutoff (foliage casts leaf shadows). No
face culling (single-sided sheets cast too; the lit side's acne is handled by the bias).
Materials with casts_shadows False are left out (the default scene's bulb around its light).
Depth bias: slope-scaled in the pipelines (`DEPTH_BIAS`), normal offset in shaders/shadow_sampling.glsl.

Drawn by compute shaders instead (`compute`, render/shadow_raster.py), the maps are that
rasteriser's depth buffer (`read_maps` reads it). Where the shading reads them is chosen a
frame at a time (`stale`, `reads_buffer`): a frame that redraws every layer for moved
casters (or after a frame that redrew them all) reads the buffer by hand (set 3's
ShadowDepths, named in ShadowData's header: world_layout z bit 0, w = where its cubes start),
no copy; a frame that redraws some or none (a still scene, a walking camera's nearest
cascade, a lone frame whose cascades all crossed their grid) copies the redrawn layers into
the images and compares in hardware (on the H200: copying Sponza's 4 x 2048^2 texels costs
0.73 ms, reading them by hand ~0.04-0.07 ms of every frame's shading). The images catch up
when the frames leave the buffer (every layer redrawn and copied once). One cache (`stale`)
serves both: what it says is drawn is in whichever of the two the frames draw into now, and
a switch between the raster units and the kernels forgets it (render/shadow_frames.py
choose_raster), as does a new buffer (`bind_frame_depths`).
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.descriptors import (
    BindingSpec,
    DescriptorPool,
    DescriptorSetLayout,
    DescriptorWriter,
)
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Sampler, SamplerSpec
from vkpbr.gpu.layered import LayeredDepth
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream
from vkpbr.render import layouts as L
from vkpbr.render import shadow_math as SM
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.shadow_images import ShadowImages
from vkpbr.scene.types import Camera, Light

__all__ = ["ShadowMaps", "ShadowPlan", "ShadowEntry", "Redraw", "plan_shadows", "MAX_LAYERS", "MAX_CUBES",
           "HEADER_BYTES", "MATRICES", "DEPTH_BIAS", "NORMAL_OFFSET", "PCF_RADIUS",
           "DEFAULT_RESOLUTION", "SET3_ROWS"]

MAX_LAYERS = 16  # 2D layers: 4 directional lights' cascades, or spot lights
SETTLE_FRAMES = 8  # frames redrawing less than every layer before compute-drawn maps are
# read from the images again (ShadowMaps._choose_reads)
MAX_CUBES = 4  # point lights with shadows
MATRICES = MAX_LAYERS + 6 * MAX_CUBES  # the 2D layers' matrices, then 6 per cube
HEADER_BYTES = 64  # shaders/shadow_data.glsl: cascade_far, cascade_texel, params, world_layout
HEADER_FLOATS = HEADER_BYTES // 4
# After the matrices, two sets of a uvec4 a layer (a matrix) for the compute kernels
# (shaders/shadow_raster.comp clip_row; the shading never reads them): how a redrawn layer is
# drawn this frame (ShadowMaps.stale): the texels drawn, [lo, hi) packed x | y << 16; the
# texels the kept map moves by, (dx & 0xffff) | dy << 16; and its mode: CLIP_FULL cleared and
# drawn whole, CLIP_KEEP kept as it is (unchanged, within the span of redrawn layers),
# CLIP_SCROLL moved by whole texels with the strips that came into view drawn (then the
# texels drawn are the columns [lo.x, hi.x) and the rows [lo.y, hi.y))
# (shadow_math.layer_scroll), CLIP_COPY the still casters' kept map copied in and the moving
# ones drawn over it. The frame's maps read the first set; where the still casters (those
# that did not move in the last SETTLED_FRAMES frames) have maps of their own (`Redraw`),
# those are drawn by the second.
CLIP_AT = MATRICES  # where the rows start, in mat4s after the header (4 rows a mat4)
KEPT_CLIP_AT = CLIP_AT + MATRICES // 4  # the second set's
CLIP_FULL, CLIP_KEEP, CLIP_SCROLL, CLIP_COPY = 0, 1, 2, 3
DATA_BYTES = HEADER_BYTES + 64 * MATRICES + 2 * 16 * MATRICES  # a slot's, rows included
CLIP_FLOATS = HEADER_FLOATS + 16 * CLIP_AT  # where the rows start in a slot's floats
DEFAULT_RESOLUTION = 2048
# (constant, slope) depth bias of the passes, in Vulkan's units; negative: away from the light
# under reversed-Z. Per projection: orthographic depth is linear in distance, perspective
# depth (near / d) has slopes that grow towards the light.
DEPTH_BIAS = {"directional": (-2.0, -2.0), "spot": (-2.0, -2.0), "point": (-2.0, -2.0)}
NORMAL_OFFSET = 1.0  # texels the receiver moves along its normal (shaders/shadow_sampling.glsl)
PCF_RADIUS = 1.0  # texels between PCF taps

# Set 3 ("shadows"): its rows live in layouts.SETS (binding, kind, stages, name).
SET3_ROWS = L.SETS[3]
_KIND_CODE = {"point": 0, "spot": 1, "directional": 2}


@dataclass(frozen=True)
class ShadowEntry:
    """One shadowed light: `first` 2D layer (directional, spot) or cube index (point) and
    its `count` layers (CASCADES, 1 or 6)."""

    light: int  # index into the frame's lights
    kind: str
    first: int
    count: int

    @property
    def matrix_base(self) -> int:
        """Index of its first matrix in ShadowData.layer_vp."""
        return self.first if self.kind != "point" else MAX_LAYERS + 6 * self.first


@dataclass(frozen=True)
class ShadowPlan:
    entries: tuple[ShadowEntry, ...] = ()
    layers: int = 0  # 2D layers used
    cubes: int = 0  # cubes used
    dropped: int = 0  # shadowed lights beyond MAX_LAYERS / MAX_CUBES (drawn unshadowed)

    @property
    def follows_camera(self) -> bool:
        """Whether the maps' matrices depend on the view: directional lights' cascades do,
        spot and point lights' maps do not."""
        return any(e.kind == "directional" for e in self.entries)


class Redraw(tuple):
    """A frame's redrawn layers (a range per plan entry, as `ShadowMaps.stale` returns them)
    where the still casters (render/shadow_frames.py split) keep maps of their own
    (compute-drawn maps): `kept`,
    the layers of those maps redrawn first (a range per entry), and `split`, (its id, a bool
    per draw: the casters that moved), whose casters are drawn over the kept maps copied in.
    Equal (and hashed) by all three: a recording's key (render/steps.py FrameSpec)."""

    kept: tuple[range, ...]
    split: tuple[int, np.ndarray]

    def __new__(cls, ranges: tuple[range, ...], kept: tuple[range, ...],
                split: tuple[int, np.ndarray]) -> Redraw:
        out = super().__new__(cls, ranges)
        out.kept, out.split = kept, split
        return out

    def _key(self) -> tuple:
        return tuple(self), self.kept, self.split[0]

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Redraw) and self._key() == other._key()

    def __ne__(self, other: object) -> bool:
        return not self == other

    def __hash__(self) -> int:
        return hash(self._key())


def _kind(light: Light) -> str:
    return getattr(light, "kind", "point")


def plan_shadows(lights: Sequence[Light], enabled: bool = True, cubes_supported: bool = True
                 ) -> ShadowPlan:
    """Which light draws into which layers: in order, while layers last (a light beyond
    the limits is drawn unshadowed and counted in `dropped`). `enabled` False: no shadows."""
    if not enabled:
        return ShadowPlan()
    entries, layers, cubes, dropped = [], 0, 0, 0
    for i, light in enumerate(lights):
        if not getattr(light, "shadows", True):
            continue
        kind = _kind(light)
        if kind == "point":
            if cubes < MAX_CUBES and cubes_supported:
                entries.append(ShadowEntry(i, kind, cubes, 6))
                cubes += 1
            else:
                dropped += 1
            continue
        n = SM.CASCADES if kind == "directional" else 1
        if layers + n <= MAX_LAYERS:
            entries.append(ShadowEntry(i, kind, layers, n))
            layers += n
        else:
            dropped += 1
    return ShadowPlan(tuple(entries), layers, cubes, dropped)


def _check_resolution(device: Device, resolution: Any) -> None:
    """A one-line UsageError for a shadow resolution the device cannot hold."""
    if not (isinstance(resolution, int) and 16 <= resolution <= int(device.limits.maxImageDimension2D)):
        from vkpbr.errors import UsageError

        raise UsageError(f"shadow resolution {resolution!r}: choose an integer from 16 "
                         f"to {int(device.limits.maxImageDimension2D)}")


class ShadowMaps:
    """The shadow resources of a renderer and the passes that fill them.

    Parameters
    ----------
    device : the device.
    material_layout : set 1's layout (the masked casters bind their material set).
    slots : frames in flight (one matrix block and two descriptor sets each).
    resolution : texels per side of a 2D layer; cube faces get half (a point light's six
        faces cost 1.5 2D layers then).
    readable : the images can be read back (`read_maps`, tests).
    """

    def __init__(self, device: Device, material_layout: DescriptorSetLayout, slots: int,
                 resolution: int = DEFAULT_RESOLUTION, readable: bool = False,
                 frame_layout: DescriptorSetLayout | None = None,
                 images: ShadowImages | None = None) -> None:
        _check_resolution(device, resolution)
        self.images = images  # where its images come from and go back to (None: its own)
        self.device, self.resolution, self.readable = device, resolution, readable
        self.cube_resolution, self._objects = max(resolution // 2, 16), []
        self.cubes_supported = bool(getattr(device, "image_cube_array", True))
        self.set_layout = self._own(DescriptorSetLayout(device, [
            BindingSpec(b, k, s, n) for b, k, s, n in SET3_ROWS]))
        # The passes' own set 3: the matrices only, for the vertex stage (the main set names
        # the maps, which are attachments while the passes draw).
        self.pass_layout = self._own(DescriptorSetLayout(device, [
            BindingSpec(0, "storage", ("vertex",), "ShadowData")]))
        empty = self._own(DescriptorSetLayout(device, []))
        # Set 0: the frame's (its Instances: the scene state's matrices the passes place
        # their draws with).
        self.pipeline_layout = self._own(PipelineLayout(
            device, [frame_layout or empty, material_layout, empty, self.pass_layout],
            L.PUSH.size))
        align = int(device.limits.minStorageBufferOffsetAlignment)
        self.matrix_bytes = size = DATA_BYTES
        self.stride = (size + align - 1) // align * align
        # (host memory: `_stale` reads them back every frame, uncached from device memory)
        self.buffer = self._own(Buffer(device, self.stride * slots, "storage", host_visible=True,
                                       name="shadow matrices"))
        self.pool = self._own(DescriptorPool(device, [(self.set_layout, slots), (self.pass_layout, slots)]))
        self.sets = [self.pool.allocate(self.set_layout) for _ in range(slots)]
        self.pass_sets = [self.pool.allocate(self.pass_layout) for _ in range(slots)]
        self._views = [self.buffer.array(np.float32, size // 4, i * self.stride) for i in range(slots)]
        # Each slot's matrices (16 floats each, column-major) and clip rows (2 sets).
        self._mats = [v[HEADER_FLOATS:CLIP_FLOATS].reshape(MATRICES, 16) for v in self._views]
        self._clips = [v[CLIP_FLOATS:].view(np.uint32).reshape(2, MATRICES, 4) for v in self._views]
        self.maps: LayeredDepth | None = None
        self.cubes: LayeredDepth | None = None  # (the images: `ensure`)
        self._pipelines: dict[tuple, Pipeline] = {}
        self._start_records()
        self._warned = False
        # Drawn by compute shaders (render/shadow_raster.py) instead of the raster units: the
        # frames' choice (ShadowFrames.prepare, RenderOptions.shadow_raster).
        self.compute = False
        self._layouts = (frame_layout or empty, material_layout)
        self._raster: Any = None
        # Set 3's ShadowWorldDepths (a batch of worlds' maps, render/world_shadows.py) and
        # ShadowDepths (the compute rasteriser's, once it draws the frames' maps), else a
        # stand-in no shader reads (views' shadow_base 0; ShadowData's header flag clear).
        self.world_stand_in = self._own(Buffer(device, 16, "storage", name="shadow depths stand-in"))
        self.world_depths: Buffer = self.world_stand_in
        self.frame_depths: Buffer = self.world_stand_in
        # Compute-drawn maps read from their buffer this frame (else the images; `stale`), the
        # frames in a row that redrew fewer than every layer, whether the last redrew them all.
        self.reads_buffer, self._partial_frames, self._last_whole = False, 0, False
        self.ensure(ShadowPlan())

    # (read by render/shadow_raster.py, which does not import this module)
    clip_at, kept_clip_at = CLIP_AT, KEPT_CLIP_AT

    def _start_records(self) -> None:
        """What each entry's layers hold: (image, first layer, layer) -> (its matrices, alpha
        mask, casters). The scene is static, so equal matrices draw equal maps: a frame redraws
        only the entries whose matrices changed (a camera-fitted sun's cascades when the camera
        moves; spot and point lights, and a batch's scene-wide sun, when the light does)."""
        self._drawn: dict[tuple[str, int, int], tuple] = {}
        self._kept: dict[tuple[str, int, int], tuple] = {}  # the same for the kept maps (`Redraw`)
        self._last_stale: tuple | None = None  # stale()'s last inputs, while _drawn holds them
        self.last_redrawn_layers: tuple[tuple[str, int], ...] = ()  # latest frame: (kind, layers drawn)
        # The latest frame's scrolled layers (matrix, dx, dy) and kept maps' redrawn layers.
        self.last_scrolled: tuple = ()
        self.last_kept_layers: tuple = ()

    def _own(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    # --- resources --------------------------------------------------------------------------
    def set_resolution(self, resolution: int) -> None:
        """A new map size (RenderOptions.shadow_resolution): the next `ensure` remakes the
        images (and returns True)."""
        self.resolution, self.cube_resolution = int(resolution), max(int(resolution) // 2, 16)

    def ensure(self, plan: ShadowPlan) -> bool:
        """Make the images hold `plan`'s layers; True when they were (re)made, after which
        command buffers recorded before are stale. Waits for the device when it remakes."""
        if plan.dropped and not self._warned:
            self._warned = True
            warnings.warn(f"{plan.dropped} light(s) drawn without shadows: at most "
                          f"{MAX_LAYERS} shadow layers (a directional light takes "
                          f"{SM.CASCADES}, a spot light 1) and {MAX_CUBES} point lights"
                          + ("" if self.cubes_supported else
                             "; this device has no cube-map arrays: no point-light shadows"),
                          stacklevel=2)
        need_maps, need_cubes = max(plan.layers, 1), max(plan.cubes, 1)
        size_maps = self.resolution if plan.layers else 1
        size_cubes = self.cube_resolution if plan.cubes else 1
        ok_maps = self.maps is not None and self.maps.layers >= need_maps and (
            self.maps.size == size_maps or (plan.layers == 0))
        ok_cubes = self.cubes is not None and self.cubes.layers >= 6 * need_cubes and (
            self.cubes.size == size_cubes or plan.cubes == 0)
        if ok_maps and ok_cubes:
            return False
        self.device.wait_idle()
        self.forget()
        if not ok_maps:
            self._let_go(self.maps, "shadow maps")
            self.maps = self._layered(size_maps, need_maps, False, "shadow maps")
        if not ok_cubes:
            self._let_go(self.cubes, "shadow cubes")
            self.cubes = self._layered(size_cubes, 6 * need_cubes, self.cubes_supported,
                                       "shadow cubes")
        if not hasattr(self, "sampler"):
            linear = self.maps.filterable
            self.sampler = self._own(Sampler(self.device, SamplerSpec(
                wrap_u="border", wrap_v="border", mag="linear" if linear else "nearest",
                min="linear" if linear else "nearest", mipmaps=False, anisotropy=1.0,
                compare="greater_or_equal")))
            self.face_sampler = self._own(Sampler(self.device, SamplerSpec(
                wrap_u="clamp", wrap_v="clamp", mag="nearest", min="nearest", mipmaps=False,
                anisotropy=1.0, compare="greater_or_equal")))
        w = DescriptorWriter(self.device)
        size = HEADER_BYTES + 64 * MATRICES
        for i, (s, ps) in enumerate(zip(self.sets, self.pass_sets, strict=True)):
            w.storage(s, 0, self.buffer, size, i * self.stride)
            w.sampler(s, 1, self.maps.view, self.sampler)
            w.sampler(s, 2, self.cubes.view, self.sampler)
            w.storage(s, 3, self.world_depths)
            w.storage(s, 4, self.frame_depths)
            w.sampler(s, 5, self.cubes.faces, self.face_sampler)
            w.storage(ps, 0, self.buffer, size, i * self.stride)
        w.update()
        return True

    def _layered(self, size: int, layers: int, cube: bool, name: str) -> LayeredDepth:
        """A new image (from `images`, the device's, where given)."""
        if self.images is not None:
            return self.images.take(size, layers, cube, self.readable, name)
        return LayeredDepth(self.device, size, layers, cube=cube, readable=self.readable,
                            name=name)

    def _let_go(self, image: LayeredDepth | None, name: str) -> None:
        """Done with `image`: back to `images` where given, else destroyed."""
        if image is not None and self.images is not None:
            self.images.give(image, self.readable, name)
        elif image is not None:
            image.destroy()

    def _bind_depths(self, binding: int, buffer: Buffer | None) -> Buffer:
        """`buffer` (or the stand-in) as set 3's storage `binding` in every slot's set."""
        bound = self.world_stand_in if buffer is None else buffer
        w = DescriptorWriter(self.device)
        for s in self.sets:
            w.storage(s, binding, bound)
        w.update()
        return bound

    def bind_world_depths(self, buffer: Buffer | None) -> None:
        """Set 3's ShadowWorldDepths: `buffer` (a batch of worlds' maps) or the stand-in.
        The caller waited for the device and frees the recordings (their sets changed)."""
        self.world_depths = self._bind_depths(3, buffer)

    def bind_frame_depths(self, buffer: Buffer | None) -> None:
        """Set 3's ShadowDepths: the compute rasteriser's (new) depth buffer, or the stand-in
        (it was destroyed). Waits for the device (every slot's set changes; recordings that
        bound them are stale: the caller frees them) and forgets the maps (a new buffer
        holds none of them)."""
        self.device.wait_idle()
        self.frame_depths = self._bind_depths(4, buffer)
        self.forget()

    def compute_cube_base(self) -> int:
        """Where the cubes' texels start in the compute rasteriser's depth buffer: after
        every 2D layer of the images' size (the buffer mirrors the images' layers)."""
        return self.maps.layers * self.maps.size * self.maps.size

    # --- per frame --------------------------------------------------------------------------
    def write(self, slot: int, plan: ShadowPlan, lights: Sequence[Light], camera: Camera | None,
              size: tuple[int, int], znear: float, zfar: float, scene_lo: Sequence[float],
              scene_hi: Sequence[float], resolution: int | None = None,
              world_layout: tuple[int, int] = (0, 0)) -> np.ndarray:
        """Fill frame `slot`'s ShadowData for `plan` and return every light's
        LightRecord.shadow: (len(lights), 4) float32, x = -1 for unshadowed lights.
        `camera` None: directional lights get one cascade over the whole scene (a batch's
        views share the maps; `znear`, `zfar` and `size` are then unused). `resolution`:
        the maps' size where not the images' (a batch of worlds' own maps, `world_layout`:
        render/world_shadows.py)."""
        resolution = self.resolution if resolution is None else int(resolution)
        cube_resolution = self.cube_resolution if resolution == self.resolution else max(
            resolution // 2, 16)
        out = np.zeros((len(lights), 4), np.float32)
        out[:, 0] = -1.0
        data = self._views[slot]
        mats = np.zeros((MATRICES, 4, 4))
        far = np.full(4, np.inf)
        texel = np.zeros(4)
        bounds = tuple(map(float, scene_lo)), tuple(map(float, scene_hi))  # hashable: the cache's key
        followed = []  # camera-fitted cascades: (entry, shape), written after the matrices
        for e in plan.entries:
            light = lights[e.light]
            pos = tuple(getattr(light, "position", (0.0, 0.0, 0.0)))
            if e.kind == "directional":
                if camera is None:
                    fit = SM.scene_cascade(light.direction, scene_lo, scene_hi, resolution)
                    n = len(fit.matrices)
                    mats[e.matrix_base:e.matrix_base + n] = fit.matrices
                    far[:n], texel[:n] = fit.far, fit.texel
                else:
                    shape = SM.cascade_shape(camera, size, light.direction, scene_lo, scene_hi,
                                             resolution, znear, zfar, e.count)
                    followed.append((e, shape))
                    n = len(shape.slices)
                    far[:n], texel[:n] = shape.far, shape.texel
                out[e.light] = (e.first, n, 0.0, 0.0)
                continue
            outer = float(getattr(light, "outer_cone", math.pi / 4))
            fit, near = SM.perspective_maps(
                e.kind, pos, tuple(getattr(light, "direction", (0.0, 0.0, -1.0))),
                float(getattr(light, "range", 0.0)), outer, bounds[0], bounds[1])
            mats[e.matrix_base:e.matrix_base + len(fit)] = fit
            if e.kind == "spot":
                unit = 2.0 * math.tan(SM.spot_half_angle(outer)) / resolution
                out[e.light] = (e.first, 1, near, unit)
            else:
                out[e.light] = (e.first, 6, near, 2.0 / cube_resolution)
        self._write_header(data, far, texel, resolution, cube_resolution, world_layout)
        # mat4 is column-major in GLSL: each row-major matrix transposed.
        self._mats[slot].reshape(MATRICES, 4, 4)[:] = mats.transpose(0, 2, 1)
        rows = self._clips[slot]
        rows[:, :MAX_LAYERS] = (0, resolution | resolution << 16, 0, CLIP_FULL)
        rows[:, MAX_LAYERS:] = (0, cube_resolution | cube_resolution << 16, 0, CLIP_FULL)
        for e, shape in followed:  # (already column-major: the moving camera's `write_cascades`)
            self._put_columns(data, e, SM.cascade_columns(camera, shape))
        return out

    def _write_header(self, data: np.ndarray, far: np.ndarray, texel: np.ndarray,
                      resolution: int, cube_resolution: int, world_layout: tuple[int, int]) -> None:
        """ShadowData's header: the cascades' far depths and texel sizes, the maps' sizes and
        filter constants, the worlds' layout and the flags."""
        data[0:4] = np.where(np.isfinite(far), far, SM.NO_FAR)
        data[4:8] = texel
        data[8:12] = (resolution, cube_resolution, NORMAL_OFFSET, PCF_RADIUS)
        # A batch of worlds' layout of a world's maps in ShadowWorldDepths (texels: a world's,
        # where its cubes start; render/world_shadows.py), else zeros; then flags (1: the
        # frame's maps are the compute rasteriser's buffer, ShadowDepths; 2: the sampler
        # filters linearly, and so does the by-hand compare) and that buffer's cubes' start.
        frame = self.compute and world_layout == (0, 0)
        flags = int(frame and self.reads_buffer) | 2 * int(self.maps.filterable)  # (`stale` sets bit 0)
        data[12:16].view(np.uint32)[:] = (*world_layout, flags,
                                          self.compute_cube_base() if frame else 0)

    def write_cascades(self, slot: int, plan: ShadowPlan, lights: Sequence[Light],
                       camera: Camera, size: tuple[int, int], znear: float, zfar: float,
                       scene_lo: Sequence[float], scene_hi: Sequence[float]) -> None:
        """Refit the camera-fitted cascades (directional lights) of frame `slot`, which
        `write` filled for this `plan`, `lights` and scene last: what a moving camera changes
        and nothing else, the same floats `write` would write. The walking camera's frame:
        no NumPy (a few Python float operations a cascade and one slice write), where `write`
        rebuilds every matrix and the header."""
        data = self._views[slot]
        header = None
        for e in plan.entries:
            if e.kind == "directional":
                shape = SM.cascade_shape(camera, size, lights[e.light].direction, scene_lo,
                                         scene_hi, self.resolution, znear, zfar, e.count)
                self._put_columns(data, e, SM.cascade_columns(camera, shape))
                header = shape.header  # (`write`'s far and texel: the last light's)
        if header is not None:
            data[0:8] = header

    @staticmethod
    def _put_columns(data: np.ndarray, e: ShadowEntry, columns: list[float]) -> None:
        """An entry's column-major matrices (16 floats each) into a slot's ShadowData."""
        start = HEADER_FLOATS + 16 * e.matrix_base
        data[start:start + len(columns)] = columns

    def stale(self, slot: int, plan: ShadowPlan, alpha_mask: bool, casters: int = 0,
              split: tuple[int, np.ndarray] | None = None) -> tuple[range, ...]:
        """Which layers of each of `plan`'s entries frame `slot` must draw (`_stale`); with
        compute-drawn maps, also where its shading reads them (`_choose_reads`) and how each
        redrawn layer is drawn (`_write_clips`: a cascade the camera moved by whole texels
        keeps its texels, moved, and draws the strip that came into view). `split`: (its id,
        a bool per draw) the casters that moved lately, where others did not
        (ShadowFrames.split): the maps of those that did not are kept apart and redrawn only
        when their layer's matrix changes, and a frame copies them in and draws the moved
        casters over them (a `Redraw`)."""
        redraw, casters_moved, how = self._stale(slot, plan, alpha_mask, casters)
        self.last_scrolled = self.last_kept_layers = ()
        if not self.compute:
            return redraw
        redraw = self._choose_reads(slot, plan, redraw, casters_moved)
        if split is None or not any(redraw):
            self.last_scrolled = self._write_clips(slot, 0, plan, redraw, how)
            return redraw
        kept, kept_how = self._stale_kept(slot, plan, redraw, (alpha_mask, split[0]))
        self.last_kept_layers = tuple((e.kind, len(r)) for e, r in zip(plan.entries, kept, strict=True))
        self.last_scrolled = self._write_clips(slot, 1, plan, kept, kept_how)
        self._write_copies(slot, plan, redraw)
        return Redraw(redraw, kept, split)

    def _write_clips(self, slot: int, rows_set: int, plan: ShadowPlan, redraw: tuple[range, ...],
                     how: dict[int, tuple[int, int] | None]) -> tuple[tuple[int, int, int], ...]:
        """Frame `slot`'s rows (set `rows_set`: CLIP_AT, KEPT_CLIP_AT) of the layers it
        redraws: `how` names the changed 2D ones (a shift: scrolled; None: drawn whole); the
        others in a redrawn span are kept (the buffer holds them as `_drawn` or `_kept`
        says, whichever side the shading reads); cube faces are drawn whole. Returns the
        scrolled layers (matrix, dx, dy)."""
        rows, size = self._clips[slot][rows_set], self.resolution
        full, faces = size | size << 16, self.cube_resolution | self.cube_resolution << 16
        scrolled = []
        for e, layers in zip(plan.entries, redraw, strict=True):
            if e.kind == "point":
                if layers:
                    rows[e.matrix_base:e.matrix_base + 6] = (0, faces, 0, CLIP_FULL)
                continue
            for i in layers:
                m = e.first + i
                if m not in how:
                    rows[m] = (0, 0, 0, CLIP_KEEP)
                elif how[m] is None:
                    rows[m] = (0, full, 0, CLIP_FULL)
                else:  # the strips that came into view: columns [x0, x1), rows [y0, y1)
                    dx, dy = how[m]
                    x0, x1 = (0, dx) if dx > 0 else (size + dx, size) if dx < 0 else (0, 0)
                    y0, y1 = (0, dy) if dy > 0 else (size + dy, size) if dy < 0 else (0, 0)
                    rows[m] = (x0 | y0 << 16, x1 | y1 << 16, (dx & 0xFFFF) | (dy & 0xFFFF) << 16,
                               CLIP_SCROLL)
                    scrolled.append((m, dx, dy))
        return tuple(scrolled)

    def _write_copies(self, slot: int, plan: ShadowPlan, redraw: tuple[range, ...]) -> None:
        """Frame `slot`'s first set of rows where the kept maps are copied in: every layer it
        draws starts as its kept map (CLIP_COPY) and the moved casters are drawn whole."""
        rows = self._clips[slot][0]
        for e, layers in zip(plan.entries, redraw, strict=True):
            size = self.cube_resolution if e.kind == "point" else self.resolution
            for i in layers:
                rows[e.matrix_base + i] = (0, size | size << 16, 0, CLIP_COPY)

    def write_world_rows(self, slot: int, plan: ShadowPlan, map_size: int, cube_size: int) -> None:
        """Frame `slot`'s first set of rows for a batch of worlds' maps that copy a kept map
        (render/world_shadows.py): every layer of the world `plan` copied in whole."""
        rows = self._clips[slot][0]
        for e in plan.entries:
            size = cube_size if e.kind == "point" else map_size
            rows[e.matrix_base:e.matrix_base + e.count] = (0, size | size << 16, 0, CLIP_COPY)

    def matrices_bytes(self, slot: int) -> bytes:
        """Frame `slot`'s matrices as ShadowData holds them (what its maps are drawn with)."""
        return self._mats[slot].tobytes()

    def _stale_kept(self, slot: int, plan: ShadowPlan, redraw: tuple[range, ...], key: tuple
                    ) -> tuple[tuple[range, ...], dict[int, tuple[int, int] | None]]:
        """Of the layers frame `slot` draws, those whose kept map (the still casters, `key`:
        the alpha mask and the split's id) holds other matrices or other casters, as spans per
        entry, and how each changed 2D one is drawn (`_compare`). Marks them drawn."""
        out, how = [], {}
        for e, layers in zip(plan.entries, redraw, strict=True):
            indices = (range(1) if layers else range(0)) if e.kind == "point" else layers
            drawn, _ = self._compare(self._kept, self._mats[slot], e, indices, key, how)
            out.append(drawn)
        return tuple(out), how

    def _compare(self, held: dict, mats: np.ndarray, e: ShadowEntry, indices: range, key: tuple,
                 how: dict[int, tuple[int, int] | None]) -> tuple[range, bool]:
        """Entry `e`'s layers `indices` (a cube's six faces are its layer 0: one position)
        against what `held` (the maps' records: `_drawn`, `_kept`) says they hold, marked as
        holding `mats`' matrices and `key` (what else they were drawn with) from now on.
        Returns the span of those that differ and whether any differs in `key` (or is
        unknown); records in `how` each differing 2D layer's drawing: the whole texels its map
        moved by where a directional light's matrix moved alone (`layer_scroll`), else None."""
        image, point = ("cubes", True) if e.kind == "point" else ("maps", False)
        changed, other_key = [], False
        for i in indices:
            rows = mats[e.matrix_base:e.matrix_base + 6] if point else mats[e.matrix_base + i]
            now, before = (rows.tobytes(), key), held.get((image, e.first, i))
            if before != now:
                changed.append(i)
                moved = before is None or before[1] != key
                other_key |= moved
                if not point:
                    how[e.first + i] = None if moved or e.kind != "directional" else \
                        SM.layer_scroll(np.frombuffer(before[0], np.float32), rows, self.resolution)
            held[(image, e.first, i)] = now
        span = range(0) if not changed else range(0, 6) if point else range(changed[0], changed[-1] + 1)
        return span, other_key

    def _choose_reads(self, slot: int, plan: ShadowPlan, redraw: tuple[range, ...],
                      casters_moved: bool) -> tuple[range, ...]:
        """`reads_buffer` for frame `slot` (its ShadowData header's bit 0 set to match): a
        frame that redraws every layer for moved casters (or maps of unknown contents), or
        after a frame that did too, reads the buffer (a copy would cost more than the by-hand
        compare); so do the next SETTLE_FRAMES - 1 frames (casters that move every other
        frame do not pay a catch-up each time); after them the images catch up: every layer
        is redrawn and copied (the redraw returned), and frames compare in hardware.
        A lone frame that redraws every layer for new matrices alone (a walking camera whose
        cascades all crossed their grid at once) copies them instead, as a frame that redraws
        some does: reading the buffer would cost a catch-up redraw of every layer 8 frames on
        (on the H200, Sponza's 4 sun cascades: ~2.9 ms for that frame)."""
        whole = tuple(range(6) if e.kind == "point" else range(e.count) for e in plan.entries)
        is_whole = bool(plan.entries) and redraw == whole
        buffer = is_whole and (casters_moved or self._last_whole)
        self._last_whole = is_whole
        if buffer:
            self._partial_frames, reads = 0, True
        else:
            self._partial_frames += 1
            reads = self.reads_buffer and self._partial_frames < SETTLE_FRAMES
            if self.reads_buffer and not reads:
                redraw = whole  # the images lack what the buffer's frames drew
                self.last_redrawn_layers = tuple((e.kind, len(r)) for e, r in zip(plan.entries, whole, strict=True))
        self.reads_buffer = reads
        header = self._views[slot][12:16].view(np.uint32)
        header[2] = (header[2] & ~np.uint32(1)) | np.uint32(reads)
        return redraw

    def _stale(self, slot: int, plan: ShadowPlan, alpha_mask: bool, casters: int = 0
               ) -> tuple[tuple[range, ...], bool, dict[int, tuple[int, int] | None]]:
        """Which layers of each of `plan`'s entries frame `slot` must draw (a range of the
        entry's layers, empty for none): the span of those that hold other matrices (as
        `write` left them for the slot) or other casters; whether any is redrawn for its
        casters or unknown contents (not for a new matrix alone: `_choose_reads`); and the
        changed 2D layers by matrix index: the whole texels a cascade's map moved by where
        its matrix moved alone (`layer_scroll`), else None. A walking camera usually changes
        only its nearest cascade (shadow_math's snapping grid). Marks them drawn: the frame's
        commands draw them and submissions run in order (`forget` if it is not submitted)."""
        mats = self._mats[slot]
        # The usual frame: the same matrices, casters and plan as the previous call (any
        # slot), whose layers are drawn already: nothing to compare entry by entry.
        # `casters`: the scene state's version that last moved a caster (0: never).
        key = (mats.tobytes(), (alpha_mask, casters), plan)  # a plan is kept while its lights are
        last = self._last_stale
        if last is not None and last[2] is plan and last[1] == key[1] and last[0] == key[0]:
            self.last_redrawn_layers = tuple((e.kind, 0) for e in plan.entries)
            return tuple(range(0) for _ in plan.entries), False, {}
        self._last_stale = key
        casters_moved = False
        out, how = [], {}
        for e in plan.entries:
            indices = range(1) if e.kind == "point" else range(e.count)
            drawn, moved = self._compare(self._drawn, mats, e, indices, key[1], how)
            out.append(drawn)
            casters_moved |= moved
        self.last_redrawn_layers = tuple((e.kind, len(r)) for e, r in zip(plan.entries, out, strict=True))
        return tuple(out), casters_moved, how

    @property
    def hand_reads(self) -> bool:
        """Whether this frame's shading reads the frame's maps by hand (compute-drawn, from
        their buffer): its shading kernels are the ones built with the by-hand code
        (compute_path.ShadeVariant.hand_reads; the others compare only in hardware)."""
        return self.compute and self.reads_buffer

    @property
    def last_redraw(self) -> tuple[tuple[str, bool], ...]:
        """The latest frame's (kind, whether any of its layers were drawn) per plan entry."""
        return tuple((kind, n > 0) for kind, n in self.last_redrawn_layers)

    def forget(self) -> None:
        """The maps' contents are unknown (a frame marked drawn was not submitted)."""
        self._drawn.clear()
        self._kept.clear()
        self._last_stale = None

    # --- pipelines and passes ---------------------------------------------------------------
    def pipeline(self, kind: str, masked: bool, colors_stride0: bool) -> Pipeline:
        key = (kind, masked, colors_stride0)
        if key not in self._pipelines:
            if masked:
                streams = (VertexStream(0, 0, "vec3"), VertexStream(1, 1, "vec2"),
                           VertexStream(2, 2, "vec2"),
                           VertexStream(3, 3, "unorm16x4", 0 if colors_stride0 else None))
            else:
                streams = (VertexStream(0, 0, "vec3"),)
            spec = PipelineSpec(
                vertex_shader="shadow_mask.vert.spv" if masked else "shadow_opaque.vert.spv",
                fragment_shader="shadow_mask.frag.spv" if masked else None,
                streams=streams, color_format=None, depth_format=self.maps.format,
                cull="none", depth_compare="greater_or_equal", color_write=False,
                depth_bias=DEPTH_BIAS[kind])
            self._pipelines[key] = Pipeline(self.device, spec, self.pipeline_layout, SPV_DIR)
        return self._pipelines[key]

    def makers(self, plan: ShadowPlan, draws: Sequence[Any], classes: Sequence[str],
               has_colors: bool) -> tuple[Callable[[], Pipeline], ...]:
        """Calls that make the pipelines `record` binds for `plan` (a Step's kernels: the
        frame graph makes them at once), one per light kind and caster kind drawn."""
        kinds = {c for d, c in zip(draws, classes, strict=True) if getattr(d, "casts_shadows", True)}
        masked = [m for m, wanted in ((False, ("opaque", "opaque_double")), (True, ("mask", "blend")))
                  if kinds & set(wanted)]
        return tuple(functools.partial(self.pipeline, kind, m, not has_colors)
                     for kind in sorted({e.kind for e in plan.entries}) for m in masked)

    def record(self, cmd: Commands, slot: int, plan: ShadowPlan, draws: Sequence[Any],
               classes: Sequence[str], material_sets: Sequence[Any], streams: dict[str, Any],
               index_buffer: Any, has_colors: bool, redraw: tuple[range, ...] | None = None,
               set0: Any = None) -> None:
        """Record `plan`'s passes for frame `slot` (before the main target begins).

        draws / classes: render.gpu_scene.Draw and passes.classify of each; streams: the
        scene's vertex buffers by name (positions, texcoords, texcoords1, colors); redraw:
        per entry, the range of its layers to draw (`stale`; None: all); the others keep
        their contents; set0: a frame set 0 (its Instances: the scene state's matrices)."""
        if redraw is None:
            redraw = tuple(range(e.count) for e in plan.entries)
        if not any(redraw):
            return
        casters = [(i, d, c) for i, (d, c) in enumerate(zip(draws, classes, strict=True))
                   if getattr(d, "casts_shadows", True)]
        opaque = [(i, d) for i, d, c in casters if c in ("opaque", "opaque_double")]
        masked = [(i, d) for i, d, c in casters if c in ("mask", "blend")]
        keep = not all(len(r) == e.count for e, r in zip(plan.entries, redraw, strict=True))
        self.maps.record_begin_writes(cmd, keep)
        self.cubes.record_begin_writes(cmd, keep)
        cmd.bind_index_buffer(index_buffer)
        for e, layers in zip(plan.entries, redraw, strict=True):
            if not layers:
                continue
            image = self.cubes if e.kind == "point" else self.maps
            image.begin(cmd, e.first * (6 if e.kind == "point" else 1) + layers.start, len(layers))
            for group, is_masked in ((opaque, False), (masked, True)):
                if not group:
                    continue
                cmd.bind_pipeline(self.pipeline(e.kind, is_masked, not has_colors))
                cmd.bind_set(0, set0)  # the scene state's matrices (Instances)
                cmd.bind_set(3, self.pass_sets[slot])
                names = ("positions", "texcoords", "texcoords1", "colors") if is_masked \
                    else ("positions",)
                cmd.bind_vertex_buffers([streams[n] for n in names])
                bound = None
                for index, d in group:
                    if is_masked and d.material != bound:
                        cmd.bind_set(1, material_sets[d.material])
                        bound = d.material
                    cmd.push(L.draw_push(index))
                    cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset,
                                     first_instance=e.matrix_base + layers.start,
                                     instances=len(layers))
            image.end(cmd)
        self.maps.record_end_writes(cmd)
        self.cubes.record_end_writes(cmd)

    def compute_bytes(self) -> int:
        """Bytes the compute rasteriser's depth buffer takes for the current images (every
        layer's texels: one storage binding, at most the device's maxStorageBufferRange)."""
        return 4 * (self.maps.layers * self.maps.size ** 2 + self.cubes.layers * self.cubes.size ** 2)

    def compute_raster(self, gs: Any) -> Any:
        """The compute rasteriser of these maps for the scene `gs` (made on first use)."""
        if self._raster is None:
            from vkpbr.render.shadow_raster import ShadowRaster

            self._raster = ShadowRaster(self.device, self, gs, *self._layouts, len(self.sets),
                                        MAX_LAYERS, DEPTH_BIAS)
        return self._raster

    def read_maps(self, cubes: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """(2D layers, cube layers or None without `cubes`) as float32 arrays (tests): the
        images (needs `readable`), or the compute rasteriser's buffer where the frames' maps
        are drawn there."""
        if not self.compute or self._raster is None:
            return self.maps.read(), self.cubes.read() if cubes else None
        depths, base = self._raster.read_depths(), self.compute_cube_base()
        m, c = self.maps, self.cubes
        return (depths[:base].reshape(m.layers, m.size, m.size),
                depths[base:base + c.layers * c.size ** 2].reshape(c.layers, c.size, c.size))

    def destroy(self) -> None:
        if self._raster is not None:
            self._raster.destroy()
            self._raster = None
        for p in self._pipelines.values():
            p.destroy()
        self._pipelines.clear()
        self._let_go(self.maps, "shadow maps")
        self._let_go(self.cubes, "shadow cubes")
        self.maps = self.cubes = None
        while self._objects:
            self._objects.pop().destroy()
