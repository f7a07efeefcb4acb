"""Screen-space ambient occlusion of the image-based light: GTAO as XeGTAO makes it, a step of
the frame graph between the depth and the shading.

The image-based light reaches every surface as if nothing stood around it; the sky lit
Sponza's arcades as brightly as its courtyard. Direct light has its shadows; the environment
gets this. `--ao gtao` (the default in the physically based mode with an environment;
`--ao off`, the course mode and `--env none` have none) adds the "ao" group to a frame's path
(render/paths.py), after whatever makes its depth -- the visibility pass (the fragment path
takes it as its pre-pass, as for dataset outputs: alpha-masked surfaces are in its depth),
the compute rasteriser, a compute batch's atlas -- and before the shading:

0. `ao_prefilter` (shaders/ao_prefilter.comp): XeGTAO's depth prefilter, the view-space
   depth and DEPTH_MIPS - 1 coarser levels of it (its weighted average) in one dispatch.
1. `ao_gtao` (shaders/ao_gtao.comp, a build per preset's slices x steps): GTAO (Jimenez et
   al. 2016) as XeGTAO's main pass, at the preset's resolution (PRESETS: the default half,
   one pixel of each 2 x 2): the view-space normal made from the full-resolution depth in
   place, `slices` directions of `steps` samples a side (the far ones read from the coarser
   levels), the cosine-weighted visible arc integrated within the effect radius
   (`RenderOptions.ao_radius`; 0: RADIUS_SHARE of the scene's bounding radius as loaded,
   which a moving or animated scene does not change), with the
   depth edges packed beside it.
2. `ao_denoise` (shaders/ao_denoise.comp), `passes` times: XeGTAO's edge-aware 3x3 spatial
   denoise; at full resolution the last pass writes the frame slot's "ao" image (R32F), at
   half resolution `ao_upsample` (shaders/ao_upsample.comp) does, a depth-aware bilinear
   upsample.
3. The shading (shade.glsl through shaders/ao.glsl) reads "ao" at its pixel (set 2 `ao_map`)
   and occludes the image-based light only: min(GTAO, the occlusion texture), as Filament
   combines them, with GTAO's multi-bounce approximation on the diffuse albedo and
   Lagarde's specular occlusion. Blended surfaces take none (GTAO saw what is behind them).

The step runs wherever the target's depth can be sampled (`depth_sampled`): on the compute
path and the compute batch after their visibility pass or rasteriser; on the fragment path
after the visibility pass where the target has one, else after a depth pre-pass of its own
(paths.py "forward_ao", PREPASS_ROWS: multisampled frames, whose pre-pass resolves sample 0,
and windows); in the layered batch (render/batch.py) after each chunk's layered depth
pre-pass, its kernels' AO_LAYERED builds over every layer at once (a view a layer; ao_map is
an array image for them, frames read layer 0). Frames without it clear the LIGHTING_AO flag
(the shading never reads an image the frame did not make), and so does the transmission's
copy of the opaque scene.
The `ao` dataset output is the last pass's image, copied into the target's "out_ao".

Correctness: tests/gpu/test_ao.py compares it with a NumPy Monte Carlo reference that ray
casts the same triangles (cosine-weighted rays of the same radius) on a box corner, a sphere on
a plane and a crop of Sponza (docs/ambient-occlusion.md states the errors).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import ComputePipeline, groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import ImageResource, Step
from vkpbr.gpu.image import Image, ImageView, Sampler, SamplerSpec
from vkpbr.render import layouts as L
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.options import RenderOptions
from vkpbr.render.passes import PASSES, PassSpec

__all__ = ["AoImages", "AoQuality", "AoSpec", "ao_spec", "prepare_ao", "AO_BINDING", "PRESETS",
           "RADIUS_SHARE", "RADIUS_MULTIPLIER", "FALLOFF", "AO_MASK_PASS", "PREPASS_ROWS",
           "ao_pixel_bytes"]

AO_BINDING = next(b for b, _, _, name in L.SETS[2] if name == "ao_map")  # layouts.SETS
AO_GROUP = (8, 8, 1)  # ao_common.glsl's work group
FALLOFF = 0.2  # the last fifth of the radius fades a sample's weight to 0 (XeGTAO: 0.615)
# The search radius over the effect radius: XeGTAO's default, which its authors fitted to ray
# traced ground truth of the same radius (screen space sees less than the scene holds). Here
# it brought the box corner's mean error against the ray-cast reference from 0.030 to 0.019,
# the sphere's from 0.025 to 0.013 (tests/gpu/test_ao.py).
RADIUS_MULTIPLIER = 1.457
RADIUS_SHARE = 0.15  # the automatic radius: 15% of the scene's bounding radius (Sponza: 2.7 m)
# XeGTAO's depth MIP chain (ao_prefilter.comp): levels of the view-space depth; a work group
# of the prefilter makes a 16 x 16 block's levels, the image is a whole number of blocks.
DEPTH_MIPS, MIP_ALIGN = 5, 16
_SETS_PER_POOL = 16
_PUSH = np.dtype([("tile", "<u4", 4), ("radius", "<f4"), ("falloff", "<f4"), ("slices", "<u4"),
                  ("steps", "<u4"), ("final_pass", "<u4"), ("read_mid", "<u4"), ("scale", "<u4"),
                  ("first_view", "<u4"), ("fused", "<u4"), ("mip_offset", "<f4"),
                  ("depth_row", "<u4")])
# XeGTAO's DepthMIPSamplingOffset: a sample len pixels out reads MIP level
# round(log2(len) - MIP_OFFSET) (ao_gtao.comp); larger: finer levels, more cache lines.
MIP_OFFSET = 3.3


@dataclass(frozen=True)
class AoQuality:
    """A GTAO preset: `scale` 1 (full resolution) or 2 (half: GTAO and the denoise on one pixel
    of each 2 x 2, then ao_upsample.comp's depth-aware upsample); `slices` directions of
    `steps` samples a side; `passes` of the denoise (at the working resolution)."""

    scale: int
    slices: int
    steps: int
    passes: int


# The `--ao` presets. GTAO_FULL is XeGTAO's High preset at full resolution (2 denoise passes,
# XeGTAO's choice without temporal accumulation); the default GTAO runs it on a quarter of the
# pixels, the XeGTAO High sample pattern over the same screen radius: the cost of GTAO (the
# step's largest part) falls by about 4, its error against the ray-cast reference rises a
# little (docs/ambient-occlusion.md has both); GTAO_LOW takes XeGTAO's Medium sampling
# (2 slices of 2 samples) on top.
PRESETS: dict[L.Ao, AoQuality] = {
    L.Ao.GTAO: AoQuality(2, 3, 3, 1),
    L.Ao.GTAO_FULL: AoQuality(1, 3, 3, 2),
    L.Ao.GTAO_LOW: AoQuality(2, 2, 2, 1),
}


@dataclass(frozen=True)
class AoSpec:
    """What a recording's ambient occlusion depends on (FrameSpec.ao): the effect radius in
    world units; whether the shading reads it (else only the `ao` output does); the preset."""

    radius: float
    shading: bool = True
    quality: AoQuality = PRESETS[L.Ao.GTAO]


def ao_spec(options: RenderOptions, target: Any, scene_radius: float, output: bool
            ) -> AoSpec | None:
    """The frame's ambient occlusion (None: none): where `options` turn it on (GTAO, the
    physically based mode with an environment) or the `ao` `output` is asked for, on targets
    whose depth the step can read (`depth_sampled`: offscreen ones on devices with the compute
    path's features, multisampled ones through their resolved depth, windows)."""
    shading = options.ao != L.Ao.OFF and options.has_environment
    if not (shading or output) or not getattr(target, "depth_sampled", False):
        return None
    radius = options.ao_radius if options.ao_radius > 0 else RADIUS_SHARE * scene_radius
    return AoSpec(float(radius), shading, PRESETS.get(options.ao, PRESETS[L.Ao.GTAO]))


# The depth pre-pass of frames without a visibility image (render/paths.py "forward_ao":
# multisampled frames, windows): the opaque rows depth-only (passes.py's pre-pass rows) and
# the masked ones through pbr.frag's DEPTH_ONLY build (its alpha test, no output), so that
# GTAO sees what the compute path's visibility pass sees (alpha-masked surfaces included).
AO_MASK_PASS = PassSpec("ao_prepass_mask", "mask", lambda s: dataclasses.replace(
    s, cull="none", fragment_shader="pbr_depth_mask.frag.spv", color_write=False))
PREPASS_ROWS = (*(p for p in PASSES if p.prepass), AO_MASK_PASS)


def ao_pixel_bytes(options: RenderOptions, slots: int) -> int:
    """Device bytes a view's pixel takes for GTAO where `options` turn it on (a batch's
    memory budget): each of the `slots` frame slots' "ao" image and the two working images,
    4 bytes a pixel each, and the depth MIPs, 4 / (1 - 1/4) times their tiles' rounding up
    to 16 pixels (up to 1.5 in area: 8) (made for the largest frame or chunk of layers)."""
    return 4 * (slots + 2) + 8 if options.ao != L.Ao.OFF and options.has_environment else 0


@dataclass
class _Handle:
    """A raw Vulkan handle where DescriptorWriter takes an object with `.handle`."""

    handle: Any


class AoImages:
    """Each frame slot's "ao" image (bound as its set 2 `ao_map`), the working images the
    kernels share (frames in flight take turns: a frame's first use waits for the frames
    before, gpu/graph.py), the kernels and their descriptor sets. Made (and remade) by
    `fit` for the frame's size and layers (arrays: the layered batch's views are layers;
    frames and compute batches use layer 0 through 2D views); until then a 1x1 stand-in is
    bound, never read."""

    def __init__(self, device: Device, sets2: list[Any], set0_layout: DescriptorSetLayout,
                 stand_in: tuple[Any, Any]) -> None:
        with device.keeping():
            self._make(device, sets2, set0_layout, stand_in)

    def _make(self, device: Device, sets2: list[Any], set0_layout: DescriptorSetLayout,
              stand_in: tuple[Any, Any]) -> None:
        self.device, self.sets2, self.set0_layout = device, sets2, set0_layout
        self.size: tuple[int, int] | None = None
        self.layers = 1
        # Benchmarks (bench_ao.py --profile) time each kernel apart: FrameStats.pass_ms
        # "ao_gtao", "ao_denoise0", ..., "ao_upsample" and "ao" (the last one's). Set before the
        # first frame (recordings are kept).
        self.profile = False
        # At half resolution, the last denoise pass run by ao_upsample.comp on the working
        # pixels it blends (one dispatch and barrier fewer, more loads a pixel: on a GPU the
        # dispatches' gaps may cost more than the loads; benchmarks/bench_ao.py --fuse
        # measures both). Off until measured; set before the first frame, as `profile`.
        self.fuse = False
        # The MIP level offset (MIP_OFFSET; bench_ao.py --mip-offsets tries others: at half
        # resolution neighbouring working pixels are 2 pixels apart, so 2.3, a level coarser,
        # may keep their far samples in cache as 3.3 does at full resolution; the accuracy
        # tests hold for the default, docs/ambient-occlusion.md has 2.3's errors). Set before
        # the first frame, as `profile`.
        self.mip_offset = MIP_OFFSET
        # (image, its layer 0's 2D view, its array view) each
        self.images: list[tuple[Image, ImageView, ImageView]] = []
        self.work: list[tuple[Image, ImageView, ImageView]] = []  # ao_raw, ao_mid (R32_UINT)
        # The view-space depth MIPs: (image, [its sampled view (every level), each level's
        # storage view] of layer 0 (2D), the same as array views)
        self.mips: tuple[Image, list[ImageView], list[ImageView]] | None = None
        self.mip_size = (0, 0)  # its level 0's
        self._kernels: dict[str, ComputePipeline] = {}
        self._layout: DescriptorSetLayout | None = None
        self._sampler: Sampler | None = None
        self._pools: list[DescriptorPool] = []
        self._free = 0
        self._sets: dict[tuple[int, int, bool, int], Any] = {}
        self._spare: list[Any] = []  # sets `forget` dropped: the next _set's (no new pools)
        self._stand_in_buffer = Buffer(device, 16, "storage", name="ao depths stand-in")
        # The stand-in: ao_map is an array (the layered batch's layers), so a 1x1 array.
        vk = device.vk
        image = Image(device, 1, 1, vk.VK_FORMAT_R32_SFLOAT, vk.VK_IMAGE_USAGE_SAMPLED_BIT,
                      name="ao stand-in")
        self._stand_in = (image, ImageView(image, kind="2d_array"))
        with device.one_time_commands() as handle:
            Commands(device, handle).image_barrier(image, "undefined", "shader_read", "none",
                                                   "sampled")
        writer = DescriptorWriter(device)
        for set2 in sets2:
            writer.sampler(set2, AO_BINDING, self._stand_in[1], stand_in[1])
        writer.update()

    def stale(self, extent: tuple[int, int], layers: int = 1,
              tile: tuple[int, int] | None = None) -> bool:
        """Whether frames of `extent` (`layers`: a layered batch's chunk; `tile`: a compute
        batch's views' tile size) need larger images than the ones made (they only grow: a
        smaller frame uses their top-left corner, so frames and batches of other sizes in
        turn neither wait for the device nor re-record)."""
        mips = mip_extent(extent, tile)
        return (self.size is None or extent[0] > self.size[0] or extent[1] > self.size[1]
                or layers > self.layers or mips[0] > self.mip_size[0]
                or mips[1] > self.mip_size[1])

    def new_scene(self, sets2: list[Any], set0_layout: DescriptorSetLayout) -> None:
        """Taken by another scene of the device (render/parts.py DeviceParts): the images
        and kernels stay (and stay bound in the slots' set 2, which the scenes share); the
        kernels' sets, which named the last scene's depth views and buffers, are made
        anew. `set0_layout`: the new scene's (the same kept handle; the last scene's
        wrapper is gone). The caller waits for the device first."""
        self.sets2, self.set0_layout = sets2, set0_layout
        for pool in self._pools:
            pool.destroy()
        self._pools, self._free, self._sets, self._spare = [], 0, {}, []

    def fit(self, extent: tuple[int, int], layers: int = 1,
            tile: tuple[int, int] | None = None) -> None:
        """Images for frames of `extent` and `layers` (`tile`: as `stale`'s; and of any size
        made before), bound in every slot's set 2 (left in the sampled layout, as frames
        leave them). The caller waits for the device and drops the recorded command buffers
        first (they name the old images)."""
        with self.device.keeping():  # (the device's, as the images: shared by its scenes)
            self._fit(extent, layers, tile)

    def _fit(self, extent: tuple[int, int], layers: int,
             tile: tuple[int, int] | None) -> None:
        old, layers = self.size or (0, 0), max(int(layers), self.layers)
        (mw, mh), (ow, oh) = mip_extent(extent, tile), self.mip_size
        mips = (max(mw, ow), max(mh, oh))
        self._destroy_images()
        vk = self.device.vk
        w, h = max(int(extent[0]), old[0]), max(int(extent[1]), old[1])
        usage = (vk.VK_IMAGE_USAGE_STORAGE_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
                 | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT)
        names = [(f"ao {i}", vk.VK_FORMAT_R32_SFLOAT, usage) for i in range(len(self.sets2))]
        for i, (name, fmt, use) in enumerate(
                [*names, *((n, vk.VK_FORMAT_R32_UINT, vk.VK_IMAGE_USAGE_STORAGE_BIT)
                           for n in ("ao raw", "ao mid"))]):
            image = Image(self.device, w, h, fmt, use, layers=layers, name=name)
            made = (image, ImageView(image), ImageView(image, kind="2d_array"))
            (self.images if i < len(names) else self.work).append(made)
        self.mips = _depth_mips(self.device, *mips, layers)
        self.mip_size = mips
        with self.device.one_time_commands() as handle:
            cmd = Commands(self.device, handle)
            for image, _, _ in self.images:
                cmd.image_barrier(image, "undefined", "shader_read", "none", "sampled")
        writer = DescriptorWriter(self.device)
        for set2, (_, _, view) in zip(self.sets2, self.images, strict=True):
            writer.sampler(set2, AO_BINDING, view, self._depth_sampler())
        writer.update()
        self.size, self.layers = (w, h), layers

    # --- the steps ----------------------------------------------------------------------------
    def steps(self, resources: dict[str, Any], set0: Any, frame_index: int, spec: AoSpec,
              extent: tuple[int, int], tiles: tuple[int, int, int, int] | None, copy_out: bool,
              timed: bool = True, generation: int = 0,
              layered: tuple[int, int] | None = None, depth_buffer: Any = None) -> list[Step]:
        """The "ao" group's steps for one recording: the depth prefilter, GTAO, the denoise
        passes, at half resolution the upsample (and, for the `ao` output, a copy into
        "out_ao"); adds "ao", "ao_raw", "ao_mid", "ao_depth" to `resources`. `extent`: the
        frame's (the images' top-left corner); `tiles`: a batch's atlas (views, tile width,
        height, tiles a column); `timed`: a timestamp after the last pass
        (FrameStats.pass_ms["ao"]); `generation`: the target's (a recreated swapchain's depth
        views are new objects); `layered`: a layered batch's chunk (its first view, views), a
        view a layer of the target's depth, every layer in one dispatch (its z);
        `depth_buffer`: the compute rasteriser's depths (resources' "raster_depths"), which
        the prefilter reads in place of the depth image (then needing no copy)."""
        w, h = extent
        assert not self.stale(extent, layered[1] if layered else 1,
                              tiles[1:3] if tiles is not None else None), "fit() first"
        image = self._resources(resources, frame_index)
        dset = self._set(resources["depth"].view, frame_index, generation, layered is not None,
                         depth_buffer)
        q = spec.quality
        tiles = tiles if tiles is not None else (1, w, h, 1)
        _, tw, th, rows = tiles
        first, depth_layers = layered if layered is not None else (0, 1)
        kernel = "_layers" if layered is not None else ""
        # The working images' corner: the tile grid at 1 / scale (tiles rounded up).
        work = (-(-w // tw) * -(-tw // q.scale), rows * -(-th // q.scale))

        def push(final: int, read_mid: int, fused: int = 0) -> np.ndarray:
            p = _push(spec, tiles, first, final, read_mid, fused)
            p["mip_offset"], p["depth_row"] = self.mip_offset, w
            return p

        def run(step: str, name: str, p: np.ndarray, size: tuple[int, int],
                uses: tuple[tuple[str, str], ...], timed: bool) -> Step:
            return Step(step, self._dispatch(name + kernel, p, set0, dset, (*size, depth_layers)),
                        uses, timed=timed,
                        kernels=(functools.partial(self._kernel, name + kernel, p.nbytes),))

        mips = mip_extent(extent, (tw, th))
        source = (("depth", "sampled") if depth_buffer is None
                  else ("raster_depths", "storage_read"))
        prefilter = "ao_prefilter" if depth_buffer is None else "ao_prefilter_buffer"
        steps = [run("ao_prefilter", prefilter, push(0, 0), (mips[0] // 2, mips[1] // 2),
                     (source, ("ao_depth", "storage")), self.profile),
                 run("ao_gtao", f"ao_gtao_{q.slices}x{q.steps}", push(0, 0), work,
                     (("ao_depth", "sampled"), ("ao_raw", "storage")), self.profile),
                 *self._filter_steps(run, push, q, work)]
        steps[-1] = dataclasses.replace(steps[-1], name="ao", timed=timed)
        if copy_out:
            steps.append(Step("ao_output", lambda cmd: _copy_image(cmd, image, resources, extent),
                              (("ao", "transfer_src"), ("out_ao", "transfer_dst")), timed=False))
        return steps

    def _filter_steps(self, run: Any, push: Any, q: Any, work: tuple[int, int]) -> list[Step]:
        """The denoise passes (ao_raw -> ao_mid -> ao_raw ... -> "ao" at full resolution)
        and at half resolution the upsample (which, fused, runs the last pass)."""
        # The denoise and the upsample name every image of their set: the shaders
        # choose between the working images by a push constant, so each statically reads and
        # writes both (and "ao", a storage image of the set, GENERAL when bound).
        both = (("ao_depth", "sampled"), ("ao_raw", "storage"), ("ao_mid", "storage"),
                ("ao", "storage"))
        steps, src = [], "ao_raw"
        fused = int(self.fuse and q.scale > 1)  # (the upsample runs the last pass)
        for k in range(q.passes - fused):
            final = k == q.passes - 1
            dst = "ao" if final and q.scale == 1 else ("ao_raw" if src == "ao_mid" else "ao_mid")
            steps.append(run(f"ao_denoise{k}", "ao_denoise", push(int(final), int(src == "ao_mid")),
                             work, both, self.profile))
            src = dst
        if q.scale > 1:
            steps.append(run("ao_upsample", "ao_upsample", push(1, int(src == "ao_mid"), fused),
                             work, both, False))
        return steps

    def _resources(self, resources: dict[str, Any], frame_index: int) -> Image:
        """"ao" (the slot's), "ao_raw", "ao_mid" into `resources`, every layer; the slot's."""
        image, _, view = self.images[frame_index]
        resources["ao"] = ImageResource(image.handle, view=view.handle, layers=self.layers)
        for name, (img, _, v) in zip(("ao_raw", "ao_mid"), self.work, strict=True):
            resources[name] = ImageResource(img.handle, view=v.handle, layers=self.layers)
        assert self.mips is not None
        resources["ao_depth"] = ImageResource(self.mips[0].handle, layers=self.layers,
                                              levels=DEPTH_MIPS)
        return image

    def _dispatch(self, name: str, push: np.ndarray, set0: Any, dset: Any,
                  size: tuple[int, int, int]) -> Any:
        def record(cmd: Any) -> None:
            cmd.bind_pipeline(self._kernel(name, push.nbytes))
            cmd.bind_set(0, set0)
            cmd.bind_set(1, dset)
            cmd.push(push)
            cmd.dispatch(*groups(size, AO_GROUP))
        return record

    # --- kernels and sets -----------------------------------------------------------------
    def _set_layout(self) -> DescriptorSetLayout:
        if self._layout is None:
            with self.device.keeping():
                self._layout = self._new_set_layout()
        return self._layout

    def _new_set_layout(self) -> DescriptorSetLayout:
        return ao_set_layout(self.device)

    def _kernel(self, name: str, push_bytes: int) -> ComputePipeline:
        if name not in self._kernels:
            with self.device.keeping():
                self._kernels[name] = ao_kernel(self.device, self.set0_layout,
                                                self._set_layout(), name, push_bytes)
        return self._kernels[name]

    def _depth_sampler(self) -> Sampler:
        if self._sampler is None:  # texelFetch only: nearest, no mips
            with self.device.keeping():
                self._sampler = Sampler(self.device, SamplerSpec("clamp", "clamp", "nearest",
                                                                 "nearest", False, 1.0))
        return self._sampler

    def _set(self, depth_view: Any, frame_index: int, generation: int = 0,
             layered: bool = False, depth_buffer: Any = None) -> Any:
        """The kernels' set 1 for a target's depth view and a slot's "ao" image. A set made
        for another generation of the target named a view since destroyed (a recreated
        swapchain's; the new one may have its handle value): made anew (the old one stays
        allocated until the images are next fitted: a few sets a window resize). `layered`:
        the layered kernels' (array views of the images; `depth_view` an array's);
        `depth_buffer`: the compute rasteriser's depths (binding 10; else a stand-in)."""
        buffer = self._stand_in_buffer if depth_buffer is None else depth_buffer
        key = (int(self.device.vk.ffi.cast("uintptr_t", depth_view)), frame_index, layered,
               int(self.device.vk.ffi.cast("uintptr_t", buffer.handle)))
        if key not in self._sets or self._sets[key][1] != generation:
            dset = self._spare.pop() if self._spare else self._new_set()
            writer = DescriptorWriter(self.device)
            writer.sampler(dset, 0, _Handle(depth_view), self._depth_sampler())
            v = 2 if layered else 1
            writer.storage_image(dset, 1, self.work[0][v])
            writer.storage_image(dset, 2, self.work[1][v])
            writer.storage_image(dset, 3, self.images[frame_index][v])
            assert self.mips is not None
            sampled, *levels = self.mips[v]
            writer.sampler(dset, 4, sampled, self._depth_sampler())
            for k, level in enumerate(levels):
                writer.storage_image(dset, 5 + k, level)
            writer.storage(dset, 10, buffer)
            writer.update()
            self._sets[key] = (dset, generation)
        return self._sets[key][0]

    def _new_set(self) -> Any:
        layout = self._set_layout()
        if not self._pools or self._free == 0:
            with self.device.keeping():
                self._pools.append(DescriptorPool(self.device, [(layout, _SETS_PER_POOL)]))
            self._free = _SETS_PER_POOL
        self._free -= 1
        return self._pools[-1].allocate(layout)

    def forget(self, depth_view: Any) -> None:
        """Drop the sets naming `depth_view` (a target's, about to be destroyed, the device
        idle and its recordings dropped: a later view may get its handle value); they are
        written again for the next targets' views (a loop of ever new sizes makes no new
        pools)."""
        handle = int(self.device.vk.ffi.cast("uintptr_t", depth_view))
        for key in [k for k in self._sets if k[0] == handle]:
            self._spare.append(self._sets.pop(key)[0])

    def _destroy_images(self) -> None:
        for image, *views in [*self.images, *self.work]:
            for view in views:
                view.destroy()
            image.destroy()
        if self.mips is not None:
            for view in (*self.mips[1], *self.mips[2]):
                view.destroy()
            self.mips[0].destroy()
        self.images, self.work, self._sets, self.mips, self.mip_size = [], [], {}, None, (0, 0)
        for pool in self._pools:
            pool.destroy()
        self._pools, self._free, self._spare, self.size = [], 0, [], None

    def destroy(self) -> None:
        self._destroy_images()
        self._stand_in[1].destroy()
        self._stand_in[0].destroy()
        self._stand_in_buffer.destroy()
        for pipe in self._kernels.values():
            pipe.destroy()
        self._kernels.clear()
        for obj in (self._layout, self._sampler):
            if obj is not None:
                obj.destroy()
        self._layout = self._sampler = None


def mip_extent(extent: tuple[int, int], tile: tuple[int, int] | None = None
               ) -> tuple[int, int]:
    """The depth MIPs' level 0 for frames of `extent` in tiles of `tile` (None: one tile):
    each tile's block rounded up to a multiple of MIP_ALIGN (ao_common.glsl ao_mip_base), so
    that each level's texels group a tile's own pixels and level k is exactly level 0 / 2^k."""
    tw, th = tile if tile is not None else extent
    up = -(-int(tw) // MIP_ALIGN) * MIP_ALIGN, -(-int(th) // MIP_ALIGN) * MIP_ALIGN
    return -(-int(extent[0]) // int(tw)) * up[0], -(-int(extent[1]) // int(th)) * up[1]


def _depth_mips(device: Device, w: int, h: int, layers: int
                ) -> tuple[Image, list[ImageView], list[ImageView]]:
    """The view-space depth MIPs, level 0 w x h (mip_extent; ao_prefilter.comp): R32F, its
    views (AoImages.mips)."""
    vk = device.vk
    image = Image(device, w, h, vk.VK_FORMAT_R32_SFLOAT,
                  vk.VK_IMAGE_USAGE_STORAGE_BIT | vk.VK_IMAGE_USAGE_SAMPLED_BIT
                  | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT,  # (tests read it back)
                  mip_levels=DEPTH_MIPS, layers=layers, name="ao depth mips")
    flat, array = [ImageView(image)], [ImageView(image, kind="2d_array")]
    for k in range(DEPTH_MIPS):
        flat.append(ImageView(image, base_mip=k, mips=1))
        array.append(ImageView(image, kind="2d_array", base_mip=k, mips=1))
    return image, flat, array


def ao_set_layout(device: Device) -> DescriptorSetLayout:
    """The kernels' set 1 (set 0: the frame's). A kept handle: one layout a device."""
    return DescriptorSetLayout(device, [
        BindingSpec(0, "sampler", ("compute",), "depth_map"),
        *(BindingSpec(b, "storage_image", ("compute",), n)
          for b, n in ((1, "ao_raw"), (2, "ao_mid"), (3, "ao_out"))),
        BindingSpec(4, "sampler", ("compute",), "depth_mips"),
        *(BindingSpec(5 + k, "storage_image", ("compute",), f"depth_mip{k}")
          for k in range(DEPTH_MIPS)),
        BindingSpec(10, "storage", ("compute",), "AoRasterDepths")])


def ao_kernel(device: Device, set0_layout: DescriptorSetLayout, set_layout: DescriptorSetLayout,
              name: str, push_bytes: int = _PUSH.itemsize) -> ComputePipeline:
    """Kernel `name` (shaders/spv/<name>.comp.spv) with the frame's set 0 and `set_layout`."""
    return ComputePipeline(device, SPV_DIR / f"{name}.comp.spv", [set0_layout, set_layout],
                           push_bytes=push_bytes)


def first_frame_kernels(quality: AoQuality, depth_buffer: bool) -> list[str]:
    """The kernels one view's `steps` bind with `quality` (`depth_buffer`: the prefilter
    reads the compute rasteriser's depths): render/kernels_ahead.py makes them ahead."""
    prefilter = "ao_prefilter_buffer" if depth_buffer else "ao_prefilter"
    return [prefilter, f"ao_gtao_{quality.slices}x{quality.steps}",
            *(["ao_denoise"] if quality.passes else []),  # (AoImages.fuse off)
            *(["ao_upsample"] if quality.scale > 1 else [])]


def _push(spec: AoSpec, tiles: tuple[int, int, int, int], first: int, final: int,
          read_mid: int, fused: int) -> np.ndarray:
    """The kernels' push constants (ao_common.glsl `Ao`): `tiles` (views, tile width, height,
    tiles a column), the first view, the denoise's and upsample's switches."""
    q, (n, tw, th, rows) = spec.quality, tiles
    p = np.zeros((), _PUSH)
    p["tile"], p["fused"] = (tw, th, rows, n), fused
    p["radius"], p["falloff"] = spec.radius * RADIUS_MULTIPLIER, FALLOFF
    p["slices"], p["steps"], p["scale"] = q.slices, q.steps, q.scale
    p["final_pass"], p["read_mid"], p["first_view"] = final, read_mid, first
    return p


def _copy_image(cmd: Any, image: Image, resources: dict[str, Any], extent: tuple[int, int]
                ) -> None:
    """The frame's corner of the slot's "ao" image into the target's "out_ao" (the `ao`
    dataset output)."""
    vk = cmd.vk
    layers = vk.VkImageSubresourceLayers(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0,
                                         baseArrayLayer=0, layerCount=1)
    region = vk.VkImageCopy(srcSubresource=layers, srcOffset=vk.VkOffset3D(0, 0, 0),
                            dstSubresource=layers, dstOffset=vk.VkOffset3D(0, 0, 0),
                            extent=vk.VkExtent3D(extent[0], extent[1], 1))
    vk.vkCmdCopyImage(cmd.handle, image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      resources["out_ao"].handle, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                      [region])


def prepare_ao(ao: AoImages, recorder: Any, options: RenderOptions, target: Any,
               bounds: Any, output: bool, tile: tuple[int, int] | None = None
               ) -> AoSpec | None:
    """The ambient occlusion of a frame into `target` (ao_spec), with the images fitted to
    its size (`tile`: a compute batch's views' tile size, which the depth MIPs' blocks
    follow): rare (a new size), so the device is waited for and the recordings that name
    the old images are dropped. `bounds`: the scene's (render/frames.py Bounds or
    render/scene_state.py LiveBounds); the automatic radius is taken from its radius as
    loaded, `rest_radius`: the spec is recorded into the frame's commands, and an animated
    scene's moving bounds had re-recorded them every frame."""
    spec = ao_spec(options, target, bounds.rest_radius, output)
    layers = getattr(target, "layers", 1)  # (a layered batch's)
    if spec is not None and ao.stale(target.extent, layers, tile):
        ao.device.wait_idle()
        recorder.free()
        ao.fit(target.extent, layers, tile)
    return spec
