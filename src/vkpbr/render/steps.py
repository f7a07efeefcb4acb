"""The steps a path's groups stand for (render/paths.py), for one recording.

`FrameSteps(recorder, target, frame_index, image, spec)` turns a path's group names into
gpu/graph.py steps: each declares what it reads and writes (the target's "color", "depth",
"ids" (the visibility image), the compute path's buffers, ...) and records its commands; the graph derives
the barriers and renderings. Consecutive fragment passes share one rendering over the
target's colour and depth: cleared, unless a compute step already wrote the colour (the
compute path's shading) or the depth (a visibility pass, the compute rasteriser), when the
passes draw over it (and test that depth without writing it: a pre-pass for them).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NamedTuple

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.graph import Rendering, Step
from vkpbr.gpu.target import COPY_DEPTH, COPY_OUTPUTS
from vkpbr.render import layouts as L
from vkpbr.render.ao import PREPASS_ROWS, AoSpec
from vkpbr.render.compute_path import GENERAL_SHADING, ShadeVariant
from vkpbr.render.lens_cube import store_only
from vkpbr.render.passes import PASSES, PassContext, PassSpec, classify, pass_makers, record_pass
from vkpbr.render.paths import COPY_PATHS, PATHS
from vkpbr.render.post import lens_steps, post_steps
from vkpbr.render.post_stage import PostContext, encode_step
from vkpbr.render.shadow_raster import make_steps as shadow_compute_steps
from vkpbr.render.shadows import ShadowPlan
from vkpbr.render.transmission import TRANSMISSIVE, copy_classes

__all__ = ["FrameSpec", "FrameObjects", "NO_OBJECTS", "FrameSteps", "OUTPUT_CLEAR"]

_PASS_BY_NAME = {p.name: p for p in PASSES}
_VISIBILITY_ROWS = ("opaque", "opaque_double", "mask")  # the coverage: not blending
# The dataset outputs' clear values (render/layouts.py OUTPUT_IMAGES): ids 0, normals 0,
# distances +inf.
OUTPUT_CLEAR = {"out_ids": ("uint32", (0, 0, 0, 0)),
                "out_depth_range": ("float32", (float("inf"), float("inf"), 0.0, 0.0))}


class FrameSpec(NamedTuple):
    """What a recording depends on besides its target, image and frame slot: its key (a
    tuple: built and hashed every frame in a few hundred nanoseconds). The path
    (render/paths.py), the TBN path, alpha masking, the shadow plan and which of its layers
    are redrawn, what the target copies out, the transmission's copy, what the compute
    path's shading is specialised for, the ids of the objects in FrameObjects, a compute
    batch's atlas tiles, a layered batch's own inputs, the post steps and their encode, the
    ambient occlusion (render/ao.py; None: none)."""

    path: str
    tbn: L.TbnMode = L.TbnMode.VECTORS
    alpha_mask: bool = True
    plan: ShadowPlan = ShadowPlan()
    redraw: tuple[range, ...] | None = None
    copy: tuple[str, ...] = ()
    transmission: bool = False
    variant: ShadeVariant = GENERAL_SHADING
    overlay_id: int = 0
    set0_id: int = 0
    external_id: int = 0
    tiles: tuple[int, int, int, int] | None = None
    batch: tuple = ()  # what a layered batch's own groups depend on (render/batch.py)
    post: tuple[tuple[str, float], ...] = ()  # the post steps on (post_stage.enabled_post)
    post_tonemap: int = 0  # the encode's tone map (TONEMAP_*)
    lens: tuple[float, ...] = ()  # a camera model's resample constants (render/post.py)
    ao: AoSpec | None = None  # the "ao" group's GTAO (render/ao.py ao_spec)


class FrameObjects(NamedTuple):
    """The objects a recording draws with that its key names by id (FrameSpec's *_id) or
    not at all: the blended draws' order (a new order re-records; a compute batch's: its
    groups of views, PassContext.blend_groups), the overlay, a batch's views' set 0 and the
    CUDA buffer the colour goes into."""

    blend_order: tuple = ()
    overlay: Any = None
    set0: Any = None
    external: Any = None


NO_OBJECTS = FrameObjects()


class FrameSteps:
    """The steps of one recording: `steps()` expands the spec's path."""

    def __init__(self, recorder: Any, target: Any, frame_index: int, image: int,
                 spec: FrameSpec, objects: FrameObjects = NO_OBJECTS,
                 groups: dict[str, Callable[[FrameSteps], list[Step]]] | None = None,
                 output: Any = None) -> None:
        # `groups`: the steps of groups a caller makes (the layered batch's "cull", "chunks");
        # `output`: with post steps, the target the encode writes ("out." resources), while
        # the path draws into `target`, the HDR one.
        self.groups = groups or {}
        self.output = target if output is None else output
        self.r, self.target, self.frame_index, self.image, self.spec = (
            recorder, target, frame_index, image, spec)
        self.objects = objects
        self.gs = recorder.gpu_scene
        self.slot = recorder.slots[frame_index]
        self.material_sets = self.gs.slot_material_sets[frame_index]  # the slot's copies
        self.streams = recorder.stream_names(spec.tbn)
        self.classes = [classify(d.alpha_mode, d.double_sided, spec.alpha_mask)
                        for d in self.gs.draws]
        self.shadow_set = (None if recorder.shadows is None
                           else recorder.shadows.sets[frame_index])
        self.set0 = objects.set0 if objects.set0 is not None else self.slot.set0
        self.resources: dict[str, Any] = dict(target.resources(image, frame_index))
        if self.output is not target:
            # (a camera model's frame draws a larger image than its output: the output's own
            # renderings, the encode's and the overlay's, take the output's size)
            own = self.output.extent if self.output.extent != target.extent else None
            self.resources.update({f"out.{k}": _sized(v, own) for k, v in
                                   self.output.resources(image, frame_index).items()})
        self._color_written = self._depth_written = False
        self._raster_depths = False  # (the compute rasteriser drew: its depths in a buffer)
        self._rendering: Rendering | None = None

    # --- the path -------------------------------------------------------------------------
    def steps(self) -> list[Step]:
        """The path's steps, group by group."""
        return [step for group in PATHS[self.spec.path] for step in self.group(group)]

    def group(self, name: str) -> list[Step]:
        if name in _PASS_BY_NAME:
            return self._fragment_pass(_PASS_BY_NAME[name])
        if name in self.groups:
            return self.groups[name](self)
        return getattr(self, "_" + name)()

    # --- the head ---------------------------------------------------------------------------
    def _deform(self) -> list[Step]:
        """Skins and morph targets posed from the slot's scene state (render/deform.py),
        before anything reads the vertex streams; none in a scene without them."""
        deform = self.r.deform
        if deform is None:
            return []
        self.resources.update(deform.resources())
        return deform.steps(self.frame_index)

    def _worlds(self) -> list[Step]:
        """A batch of worlds' records from poses on the GPU (render/worlds.py WorldKernel):
        the batch path gives the step where its call has such worlds; none otherwise."""
        return []

    def _shadows(self) -> list[Step]:
        """The shadow maps' redrawn layers. Their partial redraw keeps the other layers, so
        ShadowMaps' layered images take their own transitions (gpu/layered.py) and leave
        every layer sampled, as the shading steps read them."""
        sm, spec, gs = self.r.shadows, self.spec, self.gs
        if sm is None or not spec.plan.entries or (spec.redraw is not None and not any(spec.redraw)):
            return [Step("shadows", timed=True)]
        if sm.compute:  # drawn by compute shaders (render/shadow_raster.py)
            return shadow_compute_steps(sm, self.r, self.frame_index, spec.plan, spec.redraw,
                                        self.classes, self.material_sets, self.set0, self.resources,
                                        copy=not sm.reads_buffer)

        def record(cmd: Commands) -> None:
            sm.record(cmd, self.frame_index, spec.plan, gs.draws, self.classes, self.material_sets,
                      gs.streams, gs.index_buffer, gs.has_colors, spec.redraw, self.set0)

        return [Step("shadows", record,
                     kernels=sm.makers(spec.plan, gs.draws, self.classes, gs.has_colors))]

    def _transmission(self) -> list[Step]:
        """The frame slot's copy of the opaque scene: the opaque and masked draws that do not
        transmit and the environment, in linear radiance, then its mip chain; drawn as the
        frame is (the compute path's kernels, or the fragment path's passes)."""
        if not self.spec.transmission:
            return [Step("transmission")]
        copies = self.r.copies
        copy_target = copies.targets[self.frame_index]
        compute = self.spec.path.startswith("compute") and copy_target.storage_view is not None
        sub = _CopySteps(self, copy_target, compute)
        steps = sub.steps(COPY_PATHS["compute" if compute else "forward"])
        return [*(dataclasses.replace(s, name=f"transmission.{s.name}", timed=False)
                  for s in steps), Step("transmission")]

    # --- fragment passes --------------------------------------------------------------------
    def _rendering_for(self) -> Rendering:
        """The rendering the next fragment passes draw in: the one open, or a new one over
        the target (cleared unless a step wrote it already)."""
        if self._rendering is None:
            t = self.target
            self._rendering = Rendering(
                "color", "depth", None if self._color_written else t.clear_color,
                None if self._depth_written else 0.0, store_depth=t.stores_depth)
        return self._rendering

    def _close_rendering(self) -> None:
        self._rendering = None

    def _fragment_pass(self, p: PassSpec) -> list[Step]:
        over_visibility = self._depth_written  # test its depth, write none
        prepass = (self.r.prepass_for(self.target) and not over_visibility
                   and self.spec.path == "forward")
        if p.prepass and not prepass:
            return []
        if not p.fullscreen and p.draw_class not in self.classes:
            # Nothing to draw: no rendering begun for it (after the compute path's shading,
            # the colour stays as the kernels left it), none ended (inside an open one).
            return [Step(p.name, rendering=self._rendering)]
        ctx = self._context(visibility=False, prepass=prepass or over_visibility)
        shades = self.spec.ao is not None and not (p.prepass or p.fullscreen)
        return [_pass_step(p.name, ctx, p, (("ao", "sampled"),) if shades else (),
                           rendering=self._rendering_for())]

    def _context(self, visibility: bool, prepass: bool, target: Any = None,
                 classes: list[str] | None = None, copy: bool = False) -> PassContext:
        target = self.target if target is None else target
        tbn = self.spec.tbn
        # A compute batch's blended draws: each group of views sharing an order (the batch
        # path's FrameObjects.blend_order) drawn into their tiles of the atlas.
        atlas = self.spec.path == "compute_batch"
        return PassContext(
            draws=self.gs.draws, classes=self.classes if classes is None else classes,
            pipeline=lambda p: self.r.pipeline(target, tbn, p, prepass, visibility, batch=atlas,
                                               copy=copy, atlas=atlas),
            frame_sets=(self.set0, self.slot.set2), material_sets=self.material_sets,
            vertex_buffers=[self.gs.streams[n] for n in self.streams],
            index_buffer=self.gs.index_buffer,
            blend_order=() if atlas else self.objects.blend_order,
            blend_groups=self.objects.blend_order if atlas else None,
            atlas=target.extent if atlas else None, prepass=prepass, shadow_set=self.shadow_set)

    def _visibility(self) -> list[Step]:
        """The opaque and masked rows into the visibility image (draw + 1, primitive) with
        pbr.frag's own coverage, over the cleared depth (their own pre-pass)."""
        ctx = self._context(visibility=True, prepass=False)
        rendering = Rendering("ids", "depth", (0.0, 0.0, 0.0, 0.0), 0.0)
        self._depth_written = True
        self._close_rendering()
        # The fragment path's own passes follow (forward_outputs) and take the timestamps.
        timed = self.spec.path.startswith("compute")
        return [_pass_step(n, ctx, _PASS_BY_NAME[n], rendering=rendering, timed=timed)
                for n in _VISIBILITY_ROWS]

    # --- the compute path -------------------------------------------------------------------
    def _compute(self) -> Any:
        cs = self.r.compute_scene()
        if "bins" not in self.resources:
            self.resources.update(cs.buffers(self.target))
        return cs

    def _frame_sets(self) -> dict[int, Any]:
        return self.r.compute_sets(self.frame_index, self.objects.set0)

    def _raster(self) -> list[Step]:
        cs, spec = self._compute(), self.spec
        depth = (COPY_DEPTH in spec.copy or "blend" in self.classes
                 or not spec.path.startswith("compute"))
        # The raster's depths: copied where anything reads them, else undefined, and nothing
        # after tests them (no blended draw): the passes after load it, never clear it. GTAO
        # reads them where the raster left them (its copy took 0.1 ms at 1080p on the H200).
        self._depth_written = self._raster_depths = True
        self._color_written = True  # the resolve writes the clear colour where nothing covers
        self._close_rendering()
        return cs.raster_steps(self.target, self.frame_index, spec.alpha_mask,
                               self.material_sets, spec.tiles, self.set0, depth)

    def _classify(self) -> list[Step]:
        if self.spec.path == "forward_outputs" and COPY_OUTPUTS not in self.spec.copy:
            return []  # (a visibility pass for GTAO's depth alone: nothing to bin)
        counted = "raster" in PATHS[self.spec.path]
        cs = self._compute()
        self._close_rendering()
        return [cs.classify_step(self.target, self.frame_index, self._frame_sets(),
                                 self.material_sets, self.target.clear_color, counted)]

    def _shaded(self) -> list[int]:
        return shaded_materials(self.gs.draws, self.classes)

    def _shading(self) -> list[Step]:
        if not self.spec.path.startswith("compute"):
            return []
        cs, spec = self._compute(), self.spec
        self._color_written = True
        step = cs.shading_step(self.target, self.frame_index, spec.tbn, self._frame_sets(),
                               self.material_sets, self._shaded(), spec.tiles,
                               variant=spec.variant)
        if spec.ao is not None:  # reads the frame's GTAO (set 2 ao_map)
            step = dataclasses.replace(step, uses=(*step.uses, ("ao", "sampled")))
        return [step]

    def _ao(self) -> list[Step]:
        """GTAO from the depth written so far, then its denoise, into the slot's "ao"
        image (render/ao.py); the fragment passes after load that depth."""
        if self.spec.ao is None:
            return []
        self._close_rendering()
        self._depth_written = True
        copy_out = COPY_OUTPUTS in self.spec.copy and "out_ao" in self.resources
        # Timed on the compute paths; the fragment path's passes take the timestamps after
        # its visibility pass (paths.STEP_NAMES' one order).
        return self.r.ao.steps(self.resources, self.set0, self.frame_index, self.spec.ao,
                               self.target.extent, self.spec.tiles, copy_out,
                               self.spec.path.startswith("compute"), self.target.generation,
                               depth_buffer=self.resources["raster_depths"].buffer
                               if self._raster_depths else None)

    def _ao_prepass(self) -> list[Step]:
        """The depth GTAO reads where the frame has no visibility image (render/ao.py
        PREPASS_ROWS: opaque rows depth-only, masked rows alpha-tested), in a rendering of
        its own whose depth is stored (a multisampled one's resolved: sample 0). A
        single-sample frame's passes then draw over it; a multisampled one's draw their depth
        again (its samples are not kept between renderings)."""
        if self.spec.ao is None:
            return []
        ctx = self._context(visibility=False, prepass=False)
        rendering = Rendering("color", "depth", self.target.clear_color, 0.0)
        self._close_rendering()
        self._depth_written = self.target.samples == 1
        return [_pass_step(p.name, ctx, p, rendering=rendering, timed=False)
                for p in PREPASS_ROWS if p.draw_class in self.classes or p is PREPASS_ROWS[0]]

    def _outputs(self) -> list[Step]:
        if COPY_OUTPUTS not in self.spec.copy:
            return []
        cs = self._compute()
        names = tuple(self.target.outputs)
        return [cs.outputs_step(self.target, self.frame_index, self.spec.tbn, self._frame_sets(),
                                self.material_sets, self._shaded(), names, self.spec.tiles)]

    def _outputs_clear(self) -> list[Step]:
        if COPY_OUTPUTS not in self.spec.copy:
            return []
        outputs = self.target.outputs
        return [Step("outputs_clear", lambda cmd: _clear_outputs(cmd, outputs),
                     tuple((n, "clear") for n in outputs), timed=False)]

    def _background_compute(self) -> list[Step]:
        cs = self._compute()
        self._color_written = True
        self._close_rendering()
        return [cs.background_step(self.target, self.frame_index, self._frame_sets(),
                                   self.spec.tiles)]

    # --- the tail ---------------------------------------------------------------------------
    def _overlay(self) -> list[Step]:
        overlay = self.objects.overlay
        if overlay is None:
            return []
        if self.output is not self.target and (self._rendering is None
                                               or self._rendering.color != "out.color"):
            # After the post steps: over the encoded image (out.color), not the HDR one.
            self._rendering = Rendering("out.color", "out.depth", None, None,
                                        store_depth=self.output.stores_depth)
        return [Step("overlay", lambda cmd: overlay.record(cmd, self.frame_index,
                                                           self.output.extent),
                     rendering=self._rendering_for(), timed=False)]

    def _post(self) -> list[Step]:
        """The post steps on "color" (HDR radiance), then the encode into "out.color"; a
        camera model's resample first (render/post.py lens_steps)."""
        if not self.spec.post and not self.spec.lens:
            return []
        kernels, tiles = self.r.post_kernels(), self.spec.tiles
        ctx = PostContext(kernels, self.target.extent, self.resources,
                          self.target.storage_view.handle, frame_index=self.frame_index,
                          outputs=COPY_OUTPUTS in self.spec.copy, tiles=tiles,
                          key_set=kernels.view_key_set() if tiles is not None else None)
        steps = (lens_steps(ctx, self.spec.lens, self.output.extent, COPY_OUTPUTS in self.spec.copy)
                 if self.spec.lens else [])
        if store_only(self.spec.lens):  # a cube face's frame: a later one encodes
            return _with_kernels(steps, ctx.makers)
        registry = post_steps()
        steps += [s for option, value in self.spec.post if option in registry
                  for s in registry[option]().steps(ctx, value)]  # ("hdr": none, post_stage)
        encode = encode_step(ctx, self.output, self.spec.post_tonemap)
        self._rendering = encode.rendering  # (the overlay draws on in it: out.color)
        return _with_kernels([*steps, encode], ctx.makers)

    def _finish(self) -> list[Step]:
        if self.output is not self.target:  # depth and outputs from the frame's HDR target
            # (a camera model's resample wrote the output target's own outputs)
            tiles = self.spec.tiles
            if tiles is not None and self.spec.lens:  # a lens batch: the output's own tiles
                n, _, _, rows = tiles
                w, h = self.output.extent
                tiles = (n, w // -(-n // rows), h // rows, rows)
            sources = None if self.spec.lens else self.target
            if tiles is None and self.objects.external is None:  # (a window's too)
                return self.output.finish_steps(self.image, self.frame_index, self.spec.copy,
                                                prefix="out.", sources=sources)
            return self.output.finish_steps(self.image, self.frame_index, self.spec.copy,
                                            tiles, self.objects.external, prefix="out.",
                                            sources=sources)
        if self.spec.tiles is not None:
            return self.target.finish_steps(self.image, self.frame_index, self.spec.copy,
                                            self.spec.tiles, self.objects.external)
        return self.target.finish_steps(self.image, self.frame_index, self.spec.copy)


class _CopySteps:
    """The transmission's copy of the opaque scene as steps on its own target, whose
    resources are the frame's under "copy." names."""

    def __init__(self, frame: FrameSteps, target: Any, compute: bool) -> None:
        self.f, self.target, self.compute = frame, target, compute
        frame.resources.update(target.resources("copy."))
        self.classes = copy_classes(frame.classes, frame.r.copies.transmissive)

    def steps(self, groups: tuple[str, ...]) -> list[Step]:
        f, t = self.f, self.target
        out: list[Step] = []
        if not self.compute:
            prepass = f.r.prepass_for(t)  # the frame's rule (GPUs: each pixel shaded once)
            ctx = f._context(False, prepass, t, self.classes, copy=True)
            rendering = Rendering("copy.color", "copy.depth", t.clear_color, 0.0)
            for name in groups[:-1]:
                p = _PASS_BY_NAME[name]
                if p.prepass and not prepass:
                    continue
                out.append(_pass_step(name, ctx, p, rendering=rendering))
            return [*out, t.mip_step("mips", "copy.")]
        cs = f.r.compute_scene()
        f.resources.update(cs.buffers(t, "copy."))
        vis = f._context(True, False, t, self.classes)
        rendering = Rendering("copy.ids", "copy.depth", (0.0, 0.0, 0.0, 0.0), 0.0)
        out += [_pass_step(n, vis, _PASS_BY_NAME[n], rendering=rendering)
                for n in _VISIBILITY_ROWS]
        sets = f.r.compute_sets(f.frame_index)
        materials = shaded_materials(f.gs.draws, self.classes)
        out += [cs.classify_step(t, f.frame_index, sets, f.material_sets, t.clear_color,
                                 copy=True, prefix="copy."),
                cs.shading_step(t, f.frame_index, f.spec.tbn, sets, f.material_sets,
                                materials, copy=True, variant=f.spec.variant, prefix="copy.")]
        ctx = f._context(False, False, t, self.classes, copy=True)
        out.append(_pass_step("background", ctx, _PASS_BY_NAME["background"],
                              rendering=Rendering("copy.color", "copy.depth", None, None)))
        return [*out, t.mip_step("mips", "copy.")]


def _sized(resource: Any, extent: tuple[int, int] | None) -> Any:
    """`resource` with its own `extent` where one is given (ImageResources only)."""
    if extent is None or not hasattr(resource, "extent"):
        return resource
    return dataclasses.replace(resource, extent=extent)


def _with_kernels(steps: list[Step], makers: list[Callable[[], Any]]) -> list[Step]:
    """`steps` with `makers` (the post kernels their records bind, made by PostContext.
    dispatch) added to the first one's kernels: the frame graph makes them all at once."""
    if not steps or not makers:
        return steps
    return [dataclasses.replace(steps[0], kernels=(*steps[0].kernels, *makers)), *steps[1:]]


def _pass_step(name: str, ctx: PassContext, p: PassSpec, uses: tuple[tuple[str, str], ...] = (),
               rendering: Rendering | None = None, timed: bool = True) -> Step:
    """Step `name` recording pass `p` (record_pass) with `ctx`; its pipeline made ahead
    (Step.kernels) where the pass draws anything."""
    return Step(name, lambda cmd: record_pass(cmd, ctx, p), uses, rendering, timed,
                kernels=pass_makers(ctx, (p,)))


def _clear_outputs(cmd: Commands, outputs: dict[str, tuple[Any, Any]]) -> None:
    """Clear the dataset outputs (OUTPUT_CLEAR: ids and normals 0, distances +inf)."""
    vk = cmd.vk
    full = vk.VkImageSubresourceRange(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0,
                                      levelCount=1, baseArrayLayer=0, layerCount=1)
    for name, (img, _) in outputs.items():
        kind, value = OUTPUT_CLEAR.get(name, ("float32", (0.0, 0.0, 0.0, 0.0)))
        clear = vk.VkClearColorValue(**{kind: list(value)})
        vk.vkCmdClearColorImage(cmd.handle, img.handle, vk.VK_IMAGE_LAYOUT_GENERAL, clear, 1,
                                [full])


def shaded_materials(draws: list, classes: list[str]) -> list[int]:
    """The materials the compute path shades: those of every draw but the blended ones (and
    the transmissive ones, in the copy of the opaque scene)."""
    return sorted({d.material for d, c in zip(draws, classes, strict=True)
                   if c not in ("blend", TRANSMISSIVE)})

