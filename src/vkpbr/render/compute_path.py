"""The compute rendering path: a visibility buffer rasterised, then shaded in compute shaders.

On H100/H200 only 4 of 132 SMs run fragment shaders; compute shaders run on all of them. The
compute path keeps the rasteriser for what it does well -- coverage and depth -- and moves the
shading off the fragment units:

1. Visibility pass: the opaque and masked draws through pbr.vert and pbr.frag's VISIBILITY
   variant (the same coverage, the same alpha test) write (draw index + 1, primitive index)
   into an R32G32_UINT image, with the target's depth buffer.
2. Classification (shaders/classify.comp): pixels are binned by material -- counted, given list
   offsets and one indirect dispatch size per material, scattered into a pixel list; pixels
   nothing covers get the clear colour.
3. Shading (shaders/shade.comp): one indirect dispatch per material, with that material's own
   descriptor set bound (the fragment path's, so no texture arrays or non-uniform indexing,
   which lavapipe lacks), one invocation per pixel of its bin: the triangle is fetched from the
   scene's storage buffers, the pixel's ray intersected with it (perspective-correct
   barycentrics, ray-differential texture gradients), and shade.glsl -- the fragment path's
   own shading function -- writes the target's colour through a storage view.
4. The rest as in the fragment path: blended draws back to front over the result, the
   overlay, the copies.

`ComputeScene` owns what these read besides the frame's and the materials' sets: the draw
table, the bins, the pixel list (per target) and one descriptor set per target. The
recorder (render/recorder.py) records the steps; FramePaths.uses_compute (render/path_choice.py)
picks the path.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import astuple, dataclass
from typing import Any

import numpy as np

from vkpbr.gpu.buffer import Buffer, download_buffer, upload_buffer
from vkpbr.gpu.compute import ComputePipeline, groups
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.graph import BufferResource, Step
from vkpbr.gpu.rendering import copy_buffer_to_image
from vkpbr.render import layouts as L
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.gpu_scene import GpuScene, default_layer_mask

__all__ = ["ComputeScene", "SHADE_GROUP", "ShadeVariant", "GENERAL_SHADING"]

SHADE_GROUP = 64  # shade.comp's work group: pixels of one bin
# The compute rasteriser (shaders/raster.comp): its work groups and draw-table flags.
RASTER_SMALL_GROUP = 64  # raster_small: one triangle an invocation
RASTER_DOUBLE_SIDED, RASTER_MASKED, RASTER_BLENDED = 1, 2, 4
MAX_GROUPS_X = 65535  # maxComputeWorkGroupCount[0] every Vulkan device has
CLEAR_GROUP = 256  # raster.comp's KERNEL 7 (raster_clear): an element of each buffer an invocation
RASTER_PUSH_BYTES = 96  # raster.comp's push constants (20 uints, then the clear colour)


@dataclass(frozen=True)
class ShadeVariant:
    """What a frame's shading kernels are specialised for (shade.glsl's specialisation
    constants): its lighting flags (FrameLighting.flags: shadows, image-based light, screen
    transmission) and BRDF (Settings.brdf), and whether it reads any shadow map by hand
    (`hand_reads`: compute-drawn maps from their buffer, ShadowMaps.hand_reads, or a batch's
    worlds' maps; false: every compare is the images' sampler's, and the driver drops the
    by-hand code, shadow_sampling.glsl SHADOW_HAND_READS). The default is the general kernel.
    Each material adds whether it has layers other than the defaults
    (gpu_scene.has_default_layers)."""

    lighting_flags: int = 0xFFFFFFFF
    brdf: int = -1
    hand_reads: bool = True

    def constants(self, layers: bool) -> tuple[int, int, int, int]:
        """shade.glsl's constants 0-3 for a material with (`layers`) or without layers."""
        return self.lighting_flags, self.brdf, int(layers), int(self.hand_reads)


GENERAL_SHADING = ShadeVariant()


@dataclass(frozen=True)
class RasterTuning:
    """The compute rasteriser's work split (raster.comp's pc.big_area .. masked_chunk),
    measured on the H200 (BENCHMARKS.md; benchmarks/bench_raster.py sweeps them): opaque
    triangles whose screen box exceeds `big_area` pixels are drawn by work groups, in bands of
    rows of about `big_chunk` box pixels; masked ones likewise above `masked_area`, in bands
    of `masked_chunk` (each pixel's alpha test costs more than the set-up a band repeats)."""

    # Sponza on the H200, raster ms at 1080p / 480p: 256/16384/256/4096 0.562/0.328; masked
    # 64/1024 0.492/0.255 (kept); masked 32 0.943/0.246; opaque 64 0.609/0.263.
    big_area: int = 256
    big_chunk: int = 16384
    masked_area: int = 64
    masked_chunk: int = 1024


RASTER_TUNING = RasterTuning()
# Entries of a masked draw's segment of big-triangle chunks (raster.comp: masked_chunk box
# pixels each; what does not fit is drawn by the work group that found it, 64 invocations
# for what a band's work groups would share: on the H200 Sponza's walk overflowed 4,096
# entries, 1,654,586 box pixels of one foliage draw, and raster_masked took 0.58 ms instead of
# 0.08). Sized per target by masked_capacity; a number here overrides it (tests: 1).
MASKED_CAPACITY: int | None = None
MASKED_SCREENS = 8  # box pixels a masked draw's segment holds, in target pixels
MASKED_BYTES = 64 << 20  # all masked draws' segments together at most


def masked_capacity(pixels: int, draws: int) -> int:
    """Entries of each of `draws` masked draws' segments for a target of `pixels`: MASKED_SCREENS
    targets of box pixels, at least 4,096, at most MAX_GROUPS_X (an entry is a work group of
    the segment's indirect dispatch) and MASKED_BYTES over all segments."""
    if MASKED_CAPACITY is not None:
        return MASKED_CAPACITY
    wanted = max(4096, MASKED_SCREENS * pixels // RASTER_TUNING.masked_chunk)
    return max(1, min(wanted, MAX_GROUPS_X, MASKED_BYTES // (12 * max(draws, 1))))
CLASSIFY_GROUP = (16, 16, 1)  # classify.comp's count and scatter, raster_resolve: bin_tiles.glsl's tile


def _draw_records(gs: GpuScene, semantic: np.ndarray | None) -> np.ndarray:
    """The draw table (L.DRAW_RECORD a draw; its matrices are the scene state's Instances
    records, render/scene_state.py): first index, vertex offset, material,
    and the dataset ids: instance = the draw's index + 1 (one node's mesh:
    Renderer.instances), semantic = `semantic[i]` (vkpbr.scene.semantics; default its mesh's
    index + 1); 0 is the background for both."""
    draws = np.zeros(max(len(gs.draws), 1), L.DRAW_RECORD.dtype)
    for i, d in enumerate(gs.draws):
        draws[i]["info"] = (d.first_index, d.vertex_offset, d.material, int(gs.has_colors))
    for i, d in enumerate(gs.draws):
        draws[i]["ids"] = (i + 1, d.mesh + 1 if semantic is None else int(semantic[i]), 0, 0)
    return draws


def _raster_table(gs: GpuScene) -> tuple[np.ndarray, int, list[tuple[int, int, int]]]:
    """The compute rasteriser's draw table, a row a draw in the raster units' submission
    order (opaque, two-sided, masked, blended; each in draw order: raster.comp breaks depth
    ties as they do): its first triangle, flags, the draw. Masked draws are two-sided when
    rasterised (alpha masking off). With the scene's triangle count and (row, material,
    triangles) of the masked draws (raster_masked's dispatches)."""
    def rank(d: Any) -> int:
        return {"blend": 3, "mask": 2}.get(d.alpha_mode, 1 if d.double_sided else 0)

    order = sorted(range(len(gs.draws)), key=lambda i: (rank(gs.draws[i]), i))
    raster = np.zeros((max(len(gs.draws), 1), 4), np.uint32)
    first = 0
    masked = []
    for row, i in enumerate(order):
        d = gs.draws[i]
        flags = ((RASTER_DOUBLE_SIDED if d.double_sided or d.alpha_mode == "mask" else 0)
                 | (RASTER_MASKED if d.alpha_mode == "mask" else 0)
                 | (RASTER_BLENDED if d.alpha_mode == "blend" else 0))
        raster[row, :3] = first, flags, i
        if d.alpha_mode == "mask" and d.index_count >= 3:
            masked.append((row, d.material, d.index_count // 3))
        first += d.index_count // 3
    return raster, first, masked


class _TargetResources:
    """Per target: the bins, their dispatch sizes, the pixel list and the descriptor set."""

    def __init__(self, scene: ComputeScene, target: Any) -> None:
        dev, gs = scene.device, scene.gs
        w, h = target.extent
        m = len(gs.materials)
        self.owned: list[Any] = []
        self.bins = self._own(Buffer(dev, 16 * m, "storage|transfer_dst|transfer_src",
                                     name="material bins"))
        self.args = self._own(Buffer(dev, 12 * m, "storage|indirect", name="bin dispatches"))
        self.pixels = self._own(Buffer(dev, 4 * w * h, "storage|transfer_src", name="pixel list"))
        # The compute rasteriser's (raster.comp): depth|triangle per pixel and the big
        # triangles' list, one entry a triangle at most (16-byte stand-ins without it, and
        # for targets it never draws: the transmission's copies, `rasterised` False, whose
        # list would be 12 bytes a triangle of the scene each).
        raster = dev.compute_raster and getattr(target, "rasterised", True)
        self.raster = self._own(Buffer(dev, 8 * w * h if raster else 16, "storage|transfer_dst",
                                       name="raster depth|ids"))
        self.raster_depths = self._own(Buffer(dev, 4 * w * h if raster else 16,
                                              "storage|transfer_src", name="raster depths"))
        # (triangle, view, chunk) entries (raster.comp BIG_ENTRY): every triangle once for
        # one view, or a sixteenth of the target's pixels (what does not fit is drawn by the
        # invocation that found it, slowly but right).
        self.big_capacity = max(scene.triangles, w * h // 16)
        self.raster_big = self._own(Buffer(dev, 4 * (4 + 3 * self.big_capacity) if raster else 16,
                                           "storage|transfer_dst|indirect",
                                           name="raster big triangles"))
        # The masked draws' big triangles: a segment of masked_capacity entries each.
        masked = len(scene.masked_rows)
        self.masked_capacity = masked_capacity(w * h, masked)
        self.raster_masked_big = self._own(Buffer(
            dev, 4 * (4 * masked + 3 * masked * self.masked_capacity) if raster and masked else 16,
            "storage|transfer_dst|indirect", name="raster masked big triangles"))
        self._write_sets(scene, target)

    def _write_sets(self, scene: ComputeScene, target: Any) -> None:
        """The target's descriptor sets, one per frame of the ring: the scene's buffers,
        these, the target's images and the frame's blocks (L.COMPUTE_SET)."""
        dev, gs, slots = scene.device, scene.gs, scene.slots
        pool = self._own(DescriptorPool(dev, [(scene.set_layout, len(slots))]))
        # One set per frame of the ring: the frame's blocks are that frame's.
        self.sets = [pool.allocate(scene.set_layout) for _ in slots]
        buffers = {"Draws": scene.draw_table, "Indices": gs.index_buffer,
                   "Positions": gs.streams["positions"], "Texcoords0": gs.streams["texcoords"],
                   "Texcoords1": gs.streams["texcoords1"], "Colors": gs.streams["colors"],
                   "Normals": gs.streams["normals"], "Tangents": gs.streams["tangents"],
                   "QTangents": gs.streams["qtangents"],
                   "PackedFrames": gs.streams["packed_frames"], "Bins": self.bins,
                   "BinArgs": self.args, "PixelList": self.pixels,
                   "RasterDraws": scene.raster_draws,
                   "RasterDepthIds": self.raster, "RasterBig": self.raster_big,
                   "RasterSpheres": scene.raster_spheres, "RasterDepths": self.raster_depths,
                   "RasterMaskedBig": self.raster_masked_big,
                   "PrevPositions": scene.prev_positions}
        images = {"out_image": target.storage_view, "visibility": target.visibility_view}
        # The dataset outputs' images once the target has them, else 1x1 stand-ins (no kernel
        # but the outputs one touches them; every binding is written all the same).
        outputs = getattr(target, "outputs", None) or scene.output_stand_ins()
        images.update({name: view for name, (_, view) in outputs.items()})
        sizes = {b.name: b.size for b in L.BLOCKS}
        writer = DescriptorWriter(dev)
        for dset, slot in zip(self.sets, slots, strict=True):
            for binding, kind, name in L.COMPUTE_SET:
                if name == "Motion":  # the slot's own table
                    writer.storage(dset, binding, *_at(scene.motion.motion_region(slot.index)))
                elif name == "Materials":  # the slot's own copy
                    writer.storage(dset, binding, *_at(gs.material_table_region(slot.index)))
                elif kind == "storage":
                    writer.storage(dset, binding, buffers[name])
                elif kind == "block":
                    buf, offset = slot.block_ranges[name]
                    writer.storage(dset, binding, buf, sizes[name], offset)
                else:
                    writer.storage_image(dset, binding, images[name])
        writer.update()

    def _own(self, obj: Any) -> Any:
        self.owned.append(obj)
        return obj


def _at(region: tuple[Any, int, int]) -> tuple[Any, int, int]:
    """(buffer, size, offset) for DescriptorWriter.storage of a (buffer, offset, size)."""
    buffer, offset, size = region
    return buffer, size, offset


def bin_push_bytes(tiles: tuple[int, int, int, int] | None) -> int:
    """A bin kernel's push constants: the material, and a batch's atlas where `tiles`."""
    return 32 if tiles else 16


def aggregates(device: Device) -> bool:
    """Whether the classification's kernels aggregate their atomics over subgroups: on GPUs;
    on CPUs one atomic a pixel, where the subgroup loop costs ~10x more (classify.comp)."""
    return device.info.kind != "cpu"


def compute_layouts(device: Device, frame_layouts: dict[int, DescriptorSetLayout]
                    ) -> list[DescriptorSetLayout]:
    """The compute path's kernels' set layouts: the frame's (by set number), then the compute
    set (L.COMPUTE_SET). Kept handles (gpu/kept.py): equal definitions make one layout, so
    kernels made ahead (render/kernels_ahead.py) are the frame's own."""
    set_layout = DescriptorSetLayout(device, [
        BindingSpec(b, "storage" if kind == "block" else kind, ("compute",), name)
        for b, kind, name in L.COMPUTE_SET])
    return [frame_layouts[i] for i in range(max(frame_layouts) + 1)] + [set_layout]


def compute_kernel(device: Device, layouts: list[DescriptorSetLayout], name: str,
                   push_bytes: int, constants: tuple[int, ...] = ()) -> ComputePipeline:
    """The compute path's kernel `name` (shaders/spv/<name>.comp.spv), specialised for
    `constants`."""
    return ComputePipeline(device, SPV_DIR / f"{name}.comp.spv", layouts, push_bytes=push_bytes,
                           specialization=constants)


def first_frame_kernels(aggregate: bool, masked: bool) -> list[tuple[str, int]]:
    """(name, push bytes) of the kernels a frame of one view through the compute rasteriser
    binds besides its shading (raster_steps, classify_step counted, background_step):
    render/kernels_ahead.py makes them while the scene uploads (tests/gpu/test_kernels_ahead.py
    checks them against a first frame's). `aggregate`: ComputeScene.aggregate; `masked`: the
    scene has masked draws."""
    names = ["raster_clear", "raster_small", "raster_args", "raster_big",
             *(["raster_masked", "raster_masked_big"] if masked else []), "raster_resolve"]
    return ([(n, RASTER_PUSH_BYTES) for n in names]
            + [("classify_offsets", 32), (f"classify_scatter{'' if aggregate else '_plain'}", 32),
               ("background_view", 16)])


def shading_kernel(tbn: L.TbnMode, tiles: bool = False, copy: bool = False) -> str:
    """The shading step's kernel for vertices of `tbn` (a compute batch's atlas: `tiles`;
    the transmission's copy: `copy`)."""
    return f"shade_{'batch_' if tiles else 'copy_' if copy else ''}{tbn.name.lower()}"


def layered_materials(gs: GpuScene) -> list[bool]:
    """Per material, whether it shades with layers other than the defaults (ShadeVariant)."""
    return [not d for d in default_layer_mask(gs.material_blocks).tolist()]


def shading_constants(layered: list[bool], materials: list[int], variant: ShadeVariant
                      ) -> list[tuple[int, ...]]:
    """The shading kernel's specialisations for `materials` (ComputeScene.layered: each
    material's), one per kind of material they are."""
    return sorted({variant.constants(layered[m]) for m in materials})


class ComputeScene:
    """The compute path's view of a GpuScene (built on the path's first frame).

    `frame_layouts`: the graphics pipeline layout's set layouts by set number (0 frame,
    1 material, 2 lighting, ...); the compute set comes after the last of them.
    """

    def __init__(self, device: Device, gs: GpuScene, frame_layouts: dict[int, DescriptorSetLayout],
                 slots: list[Any], semantic: np.ndarray | None = None,
                 draw_spheres: np.ndarray | None = None, motion: Any = None,
                 prev_positions: Any = None) -> None:
        # motion: the scene state's motion tables (render/scene_state.py GpuSceneState);
        # prev_positions: the deform step's previous posed positions (render/deform.py).
        self.device, self.gs, self.slots = device, gs, slots
        self.motion = motion
        self._owned: list[Any] = []
        gs.ensure_streams()  # every TBN path's stream exists: the sets bind them all
        draws = _draw_records(gs, semantic)
        self.draw_table = self._own(upload_buffer(device, draws, "storage", name="draw records"))
        raster, self.triangles, self.masked_rows = _raster_table(gs)
        self.raster_draws = self._own(upload_buffer(device, raster, "storage",
                                                    name="raster draw table"))
        # Per draw its world bounding sphere (raster.comp skips a draw outside the view).
        spheres = (np.ascontiguousarray(draw_spheres[:, :4]) if draw_spheres is not None
                   and len(draw_spheres) else np.zeros((1, 4), np.float32))
        if draw_spheres is None or not len(draw_spheres):
            spheres[:, 3] = np.inf  # unknown: never culled
        self.raster_spheres = self._own(upload_buffer(device, spheres, "storage",
                                                      name="raster draw spheres"))
        self.prev_positions = prev_positions if prev_positions is not None else self._own(
            upload_buffer(device, np.zeros(3, np.float32), "storage", name="no posed vertices"))
        self.set_index = max(frame_layouts) + 1
        self.layouts = compute_layouts(device, frame_layouts)
        self.set_layout = self._own(self.layouts[-1])
        self.material_count = len(gs.materials)
        # (tests set it to run both kinds of kernels on lavapipe)
        self.aggregate = aggregates(device)
        # Which materials any opaque or masked draw uses: only those get a shading dispatch.
        self._pipelines: dict[tuple[str, tuple[int, ...]], ComputePipeline] = {}
        # Per material, whether it shades with layers other than the defaults (ShadeVariant).
        self.layered = layered_materials(gs)
        self._stand_ins: dict[str, tuple[Any, Any]] | None = None
        self._targets: dict[int, _TargetResources] = {}

    def _own(self, obj: Any) -> Any:
        self._owned.append(obj)
        return obj

    def makers(self, *kernels: tuple[Any, ...]) -> tuple[Callable[[], ComputePipeline], ...]:
        """Calls that make the kernels of `kernels` ((name, push bytes[, constants]) each),
        for a Step's `kernels` (the frame graph makes them ahead, at once)."""
        return tuple(functools.partial(self._pipeline, *k) for k in kernels)

    def _bin_makers(self, kernel: str, materials: list[int],
                    tiles: tuple[int, int, int, int] | None = None,
                    variant: ShadeVariant | None = None) -> tuple[Callable[[], ComputePipeline], ...]:
        """The makers of `_dispatch_bins`'s kernels: one per specialisation its materials use."""
        push_bytes = bin_push_bytes(tiles)
        constants = ([()] if variant is None
                     else shading_constants(self.layered, materials, variant))
        return self.makers(*((kernel, push_bytes, c) for c in constants))

    def _bin_constants(self, material: int, variant: ShadeVariant | None) -> tuple[int, ...]:
        """A bin kernel's specialisation for `material` (none without a variant)."""
        return variant.constants(self.layered[material]) if variant is not None else ()

    def _pipeline(self, name: str, push_bytes: int, constants: tuple[int, ...] = ()
                  ) -> ComputePipeline:
        """Kernel `name` (shaders/spv/<name>.comp.spv), specialised for `constants`."""
        key = (name, constants)
        if key not in self._pipelines:
            self._pipelines[key] = self._own(compute_kernel(self.device, self.layouts, name,
                                                            push_bytes, constants))
        return self._pipelines[key]

    def kernel_statistics(self) -> dict[str, dict[str, float | int | bool]]:
        """Per kernel the frames so far used, the driver's statistics of its compiled code
        (registers, shared memory, instructions: what bounds its occupancy), from a twin
        pipeline made to capture them (benchmarks/probe_kernels.py; a device with
        `pipeline_statistics`)."""
        out = {}
        for (name, constants), used in sorted(self._pipelines.items()):
            twin = ComputePipeline(self.device, SPV_DIR / f"{name}.comp.spv", self.layouts,
                                   push_bytes=used.push_bytes,
                                   capture_statistics=True, specialization=constants)
            try:
                label = f"{name} {constants}" if constants else name
                out[label] = twin.statistics()
            finally:
                twin.destroy()
        return out

    def _resources(self, target: Any) -> _TargetResources:
        key = id(target)
        if key not in self._targets:
            res = _TargetResources(self, target)
            self._owned.extend(res.owned)
            self._targets[key] = res
        return self._targets[key]

    # --- recording --------------------------------------------------------------------------
    def output_stand_ins(self) -> dict[str, tuple[Any, Any]]:
        """1x1 images of the outputs' formats, bound where a target has no outputs yet."""
        if self._stand_ins is None:
            from vkpbr.gpu.image import Image, ImageView

            vk = self.device.vk
            self._stand_ins = {}
            for name, (fmt, _, _, _) in L.OUTPUT_IMAGES.items():
                image = self._own(Image(self.device, 1, 1, getattr(vk, fmt),
                                        vk.VK_IMAGE_USAGE_STORAGE_BIT, name=f"{name} stand-in"))
                self._stand_ins[name] = (image, self._own(ImageView(image)))
        return self._stand_ins

    # --- steps (render/paths.py lists them; gpu/graph.py derives their barriers) ----------
    def buffers(self, target: Any, prefix: str = "") -> dict[str, BufferResource]:
        """`target`'s buffers as graph resources, named as the steps below use them (the
        raster depths `copied`: the depth's copy reads them last)."""
        res = self._resources(target)
        return {prefix + name: BufferResource(getattr(res, name), copied=name == "raster_depths")
                for name in ("bins", "args", "pixels", "raster", "raster_depths", "raster_big",
                             "raster_masked_big")}

    def classify_step(self, target: Any, frame_index: int, frame_sets: dict[int, Any],
                      material_sets: list[Any], clear_color: tuple[float, ...],
                      counted: bool = False, copy: bool = False, prefix: str = "") -> Step:
        """"classify": the visibility image's pixels binned by material (counted, offsets,
        scattered into the pixel list: three kernels; `counted`: the compute rasteriser's
        resolve counted them and cleared the pixels nothing covers, so it starts at the
        offsets; `copy`: the transmission's copy, linear radiance)."""
        res = self._resources(target)
        compute_set = res.sets[frame_index]
        push = np.zeros(8, np.float32)
        push[:4] = clear_color
        push.view(np.uint32)[4:6] = (self.material_count, SHADE_GROUP)
        pixel_groups = groups((*target.extent, 1), CLASSIFY_GROUP)
        plain = "" if self.aggregate else "_plain"
        suffix = "_copy" if copy else ""
        kernels = ((f"classify_count{plain}{suffix}", pixel_groups),
                   ("classify_offsets", (1, 1, 1)), (f"classify_scatter{plain}", pixel_groups))

        def record(cmd: Any) -> None:
            if not counted:
                cmd.fill(res.bins, 0)
                cmd.memory_barrier("transfer", "compute")
            for name, size in kernels[1:] if counted else kernels:
                cmd.bind_pipeline(self._pipeline(name, 32))
                self._bind_frame_sets(cmd, frame_sets, material_sets[0], compute_set)
                cmd.push(push)
                cmd.dispatch(*size)
                if name != kernels[-1][0]:  # the kernels' own order; the graph orders the rest
                    cmd.memory_barrier("compute", "compute")

        p = prefix
        uses = ((p + "ids", "storage_read"), (p + "color", "storage"),
                (p + "bins", "storage" if counted else "storage|transfer_dst"), (p + "args", "storage"),
                (p + "pixels", "storage"))
        counted_kernels = kernels[1:] if counted else kernels
        return Step("classify", record, uses,
                    kernels=self.makers(*((name, 32) for name, _ in counted_kernels)))

    def shading_step(self, target: Any, frame_index: int, tbn: L.TbnMode,
                     frame_sets: dict[int, Any], material_sets: list[Any], materials: list[int],
                     tiles: tuple[int, int, int, int] | None = None, copy: bool = False,
                     variant: ShadeVariant = GENERAL_SHADING, prefix: str = "") -> Step:
        """"shading": each material of `materials` (those the visibility pass drew) shaded
        over its bin with its own set 1 bound (`tiles`: a compute batch's atlas; `copy`: the
        transmission's copy; `variant`: what the kernels are specialised for)."""
        res = self._resources(target)
        kernel = shading_kernel(tbn, tiles is not None, copy)

        def record(cmd: Any) -> None:
            self._dispatch_bins(cmd, res, frame_index, kernel, frame_sets, material_sets,
                                materials, tiles, variant)

        return Step("shading", record, self._bin_uses(prefix),
                    kernels=self._bin_makers(kernel, materials, tiles, variant))

    def outputs_step(self, target: Any, frame_index: int, tbn: L.TbnMode,
                     frame_sets: dict[int, Any], material_sets: list[Any],
                     materials: list[int], outputs: tuple[str, ...],
                     tiles: tuple[int, int, int, int] | None = None) -> Step:
        """"outputs": the dataset outputs (ids, normals, distances) of the classified pixels
        (shade.comp's OUTPUTS variant, per material: the shading normal reads its normal
        map) into the images named `outputs` (`tiles`: a compute batch's atlas)."""
        res = self._resources(target)

        kernel = f"shade_{'batch_' if tiles else ''}outputs_{tbn.name.lower()}"

        def record(cmd: Any) -> None:
            self._dispatch_bins(cmd, res, frame_index, kernel, frame_sets, material_sets,
                                materials, tiles)

        return Step("outputs", record,
                    self._bin_uses("") + tuple((name, "storage") for name in outputs),
                    kernels=self._bin_makers(kernel, materials, tiles))

    @staticmethod
    def _bin_uses(p: str) -> tuple[tuple[str, str], ...]:
        return ((p + "ids", "storage_read"), (p + "color", "storage"),
                (p + "bins", "storage_read"), (p + "args", "indirect"),
                (p + "pixels", "storage_read"))

    def background_step(self, target: Any, frame_index: int, frame_sets: dict[int, Any],
                        tiles: tuple[int, int, int, int] | None = None) -> Step:
        """"background": the environment behind the shaded pixels (background.comp), every
        pixel nothing covers, in the camera's direction (`tiles`: each view's of an atlas)."""
        kernel = "background_batch" if tiles else "background_view"

        def record(cmd: Any) -> None:
            cmd.bind_pipeline(self._pipeline(kernel, 16))
            self._bind_frame_sets(cmd, frame_sets, None, self._resources(target).sets[frame_index])
            cmd.push(np.array(tiles or (1, *target.extent, 1), np.uint32))
            cmd.dispatch(*groups((*target.extent, 1), (8, 8, 1)))

        return Step("background", record, (("ids", "storage_read"), ("color", "storage")),
                    kernels=self.makers((kernel, 16)))

    def raster_steps(self, target: Any, frame_index: int, alpha_mask: bool,
                     material_sets: list[Any], tiles: tuple[int, int, int, int] | None = None,
                     set0: Any = None, depth: bool = True) -> list[Step]:
        """The compute rasteriser (raster.comp): every opaque and masked draw's triangles into
        the depth|triangle buffer (masked ones alpha-tested per pixel with their material's
        set 1, one dispatch a masked draw), then the visibility image resolved from it with
        the winners' depths, copied into the depth buffer (`depth` False: nothing reads it
        this frame, not copied). `tiles` (views, tile width, tile height, tiles a column: the
        atlas is column-major): a compute batch's atlas. `set0`: the frame's set 0 or a batch's, whose view
        records the kernels read."""
        res = self._resources(target)
        w, h = target.extent
        views, tile_w, tile_h, rows = tiles or (1, w, h, 1)
        suffix = "_batch" if tiles else ""
        push = self._raster_push(res, target, alpha_mask, (views, tile_w, tile_h, rows))
        dset = res.sets[frame_index]

        def kernel(step: str, name: str, size: tuple[int, int, int] | None,
                   uses: tuple[tuple[str, str], ...], timed: bool = True) -> Step:
            def record(cmd: Any) -> None:
                cmd.bind_pipeline(self._pipeline(name, RASTER_PUSH_BYTES))
                if set0 is not None:
                    cmd.bind_set(0, set0)
                cmd.bind_set(self.set_index, dset)
                cmd.push(push)
                if size is None:
                    cmd.dispatch_indirect(res.raster_big, 4)
                elif size[0] and size[1]:
                    cmd.dispatch(*size)
            return Step(step, record, uses, timed=timed,
                        kernels=self.makers((name, RASTER_PUSH_BYTES)))

        # raster_clear zeroes the per-pixel buffer, the bins (raster_resolve counts them) and
        # the lists' heads (raster.comp KERNEL 7).
        cleared = ("raster", "raster_big", "raster_masked_big", "bins")
        words = max(res.raster.size // 8, 4 * len(self.masked_rows), res.bins.size // 16, 4)
        c = -(-words // CLEAR_GROUP)
        n = -(-self.triangles // RASTER_SMALL_GROUP)
        # raster_args sizes raster_big's dispatch from the count raster_small listed.
        small = (min(n, MAX_GROUPS_X), -(-n // MAX_GROUPS_X), views)
        big = (("raster", "storage"), ("raster_big", "storage|indirect"))
        steps = [
            kernel("raster_clear", "raster_clear", (min(c, MAX_GROUPS_X), -(-c // MAX_GROUPS_X), 1),
                   tuple((b, "storage") for b in cleared), timed=False),
            kernel("raster_small", f"raster_small{suffix}", small,
                   (("raster", "storage"), ("raster_big", "storage"))),
            # (it also sizes the masked draws' raster_masked_big dispatches)
            kernel("raster_args", "raster_args", (1, 1, 1),
                   (("raster_big", "storage"), ("raster_masked_big", "storage")), timed=False),
            kernel("raster_big", f"raster_big{suffix}", None, big)]
        if alpha_mask and self.masked_rows:
            steps += self._masked_steps(res, dset, push, material_sets, views, set0, suffix)
        steps.append(kernel("raster_resolve", "raster_resolve", groups((w, h, 1), CLASSIFY_GROUP),
                            (("raster", "storage"), ("ids", "storage"), ("color", "storage"),
                             ("bins", "storage"), ("raster_depths", "storage"))))
        if depth:
            steps.append(Step("depth_copy", lambda cmd: copy_buffer_to_image(
                cmd, res.raster_depths, target.depth.handle, True, target.extent),
                (("raster_depths", "transfer_src"), ("depth", "transfer_dst")), timed=False))
        return steps

    def _raster_push(self, res: _TargetResources, target: Any, alpha_mask: bool,
                     tiles: tuple[int, int, int, int]) -> np.ndarray:
        """The rasteriser kernels' push constants (raster.comp) for frames of `target`."""
        w, h = target.extent
        push = np.zeros(RASTER_PUSH_BYTES // 4, np.uint32)
        push[:20] = (self.triangles, len(self.gs.draws), int(alpha_mask), res.big_capacity,
                     w, h, 0, 0, *tiles,
                     len(self.masked_rows) if alpha_mask else 0, 0, res.masked_capacity,
                     *astuple(RASTER_TUNING), int(target.color_kind == "srgb"))
        push.view(np.float32)[20:24] = target.clear_color
        return push

    def _masked_steps(self, res: _TargetResources, dset: Any, push: np.ndarray,
                      material_sets: list[Any], views: int, set0: Any, suffix: str) -> list[Step]:
        """raster_masked: one invocation a triangle of each masked draw, its material bound,
        then each draw's big triangles listed by it (raster_masked_big: one work group an
        entry, an indirect dispatch a draw)."""
        def draws(kernel: str, big: bool) -> Callable[[Any], None]:
            def record(cmd: Any) -> None:
                cmd.bind_pipeline(self._pipeline(kernel, RASTER_PUSH_BYTES))
                if set0 is not None:
                    cmd.bind_set(0, set0)
                cmd.bind_set(self.set_index, dset)
                for segment, (k, material, count) in enumerate(self.masked_rows):
                    cmd.bind_set(1, material_sets[material])
                    push[6:8] = k, material
                    push[13] = segment
                    cmd.push(push)
                    if big:
                        cmd.dispatch_indirect(res.raster_masked_big, 16 * segment + 4)
                    else:
                        n = -(-count // RASTER_SMALL_GROUP)
                        cmd.dispatch(min(n, MAX_GROUPS_X), -(-n // MAX_GROUPS_X), views)
            return record

        return [Step("raster_masked", draws(f"raster_masked{suffix}", False),
                     (("raster", "storage"), ("raster_masked_big", "storage")),
                     kernels=self.makers((f"raster_masked{suffix}", RASTER_PUSH_BYTES))),
                Step("raster_masked_big", draws(f"raster_masked_big{suffix}", True),
                     (("raster", "storage"), ("raster_masked_big", "storage|indirect")),
                     kernels=self.makers((f"raster_masked_big{suffix}", RASTER_PUSH_BYTES)))]

    def _dispatch_bins(self, cmd: Any, res: _TargetResources, frame_index: int, kernel: str,
                       frame_sets: dict[int, Any], material_sets: list[Any],
                       materials: list[int], tiles: tuple[int, int, int, int] | None = None,
                       variant: ShadeVariant | None = None) -> None:
        """One indirect dispatch of `kernel` per material of `materials`, its set 1 bound;
        `variant`: the kernel specialised per material (ShadeVariant), else the general one."""
        push_bytes = bin_push_bytes(tiles)
        bound = None
        material = np.zeros(8 if tiles else 4, np.uint32)
        if tiles:
            material[1:5] = tiles
        for m in materials:
            constants = self._bin_constants(m, variant)
            if constants != bound:  # pipelines share the layout: the sets stay bound
                cmd.bind_pipeline(self._pipeline(kernel, push_bytes, constants))
                if bound is None:
                    self._bind_frame_sets(cmd, frame_sets, None, res.sets[frame_index])
                bound = constants
            cmd.bind_set(1, material_sets[m])
            material[0] = m
            cmd.push(material)
            cmd.dispatch_indirect(res.args, 12 * m)

    def _bind_frame_sets(self, cmd: Any, frame_sets: dict[int, Any], material_set: Any,
                         compute_set: Any) -> None:
        for index, dset in frame_sets.items():
            cmd.bind_set(index, dset)
        if material_set is not None:  # classify.comp reads no material: any valid set
            cmd.bind_set(1, material_set)
        cmd.bind_set(self.set_index, compute_set)

    def pixel_bins(self, target: Any) -> list[np.ndarray]:
        """Per material, the pixel indices (y * width + x) that the last classification of
        `target` listed for it, in list order (tests and diagnostics: reads the GPU's copy)."""
        res = self._resources(target)
        bins = download_buffer(self.device, res.bins, np.uint32).reshape(-1, 4)
        pixels = download_buffer(self.device, res.pixels, np.uint32)
        return [pixels[offset:offset + count] for count, offset in bins[:, :2]]

    def forget_target(self, target: Any, destroy: bool = False) -> None:
        """Make `target`'s buffers and sets again on its next use (its images changed);
        `destroy`: free the old ones now (the target itself is going)."""
        res = self._targets.pop(id(target), None)
        if res is not None and destroy:
            gone = {id(obj) for obj in res.owned}
            self._owned = [obj for obj in self._owned if id(obj) not in gone]
            for obj in reversed(res.owned):
                obj.destroy()

    def destroy(self) -> None:
        while self._owned:
            self._owned.pop().destroy()

