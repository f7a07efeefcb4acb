"""Pipelines and recorded command buffers: how a frame's commands come to exist.

A `FrameRecorder` builds the PBR pipelines each pass of the pass table (render/passes.py)
needs, for a target's formats, and records one command buffer per (target image, frame of
the ring, TBN path, alpha masking, overlay, copies, shadow plan), reused frame after frame:
the frame's start timestamp, the shadow-map passes (render/shadows.py) and a timestamp, the
target's begin, every pass with a timestamp after each, the overlay, the target's end
(copies), the end timestamp. A buffer is used by one frame of the ring
only, whose previous submission has finished when it is looked up: it can be re-recorded
(a new blended-draw order) or freed at once.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.frames import Frame, FrameRing
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream
from vkpbr.gpu.target import COPY_DEPTH, FrameTarget
from vkpbr.render import layouts as L
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.compute_path import GENERAL_SHADING, ComputeScene, ShadeVariant
from vkpbr.render.frames import FrameSlot
from vkpbr.render.gpu_scene import GpuScene
from vkpbr.render.overlay import TextOverlay
from vkpbr.render.passes import (
    PASSES,
    PassContext,
    PassSpec,
    classify,
    pipeline_spec,
    record_passes,
)
from vkpbr.render.shadows import ShadowMaps, ShadowPlan
from vkpbr.render.transmission import COPY_PASSES, TRANSMISSIVE, OpaqueCopies, copy_classes

__all__ = ["FrameRecorder", "STAMPS", "STAMP_NAMES"]

_TBN_STREAMS = {
    L.TbnMode.VECTORS: (("normals", "vec3"), ("tangents", "vec4")),
    L.TbnMode.QUAT: (("qtangents", "vec4"),),
    L.TbnMode.PACKED: (("packed_frames", "uint"),),
}
# Vertex inputs before the tangent frame: location = binding, one stream each (pbr.vert).
# "texcoords1" is the TEXCOORD_0 buffer again in scenes without TEXCOORD_1 (GpuScene).
# "colors" (COLOR_0) is one white value read with stride 0 in scenes without vertex colours.
_BASE_STREAMS = (("positions", "vec3"), ("texcoords", "vec2"), ("texcoords1", "vec2"),
                 ("colors", "unorm16x4"))
# Timestamps per frame: start, after the shadow passes, after the transmission's copy of the
# opaque scene (render/transmission.py), after each pass, end (after copies);
# STAMP_NAMES names the intervals between them up to the last pass.
# The compute path's shading step (render/compute_path.py) comes after the passes that draw
# coverage, before the background; the forward path stamps it at once (it takes no time).
_BEFORE_SHADING = tuple(p.name for p in PASSES[:[q.name for q in PASSES].index("mask") + 1])
_PREPASSES = tuple(p.name for p in PASSES if p.prepass)
# The compute path's own steps (render/compute_path.py): the compute rasteriser's kernels
# before the visibility passes (on its frames "opaque" is then the depths' write alone), the
# pixels' classification before the shading.
RASTER_STEPS = ("raster_small", "raster_big", "raster_masked", "raster_masked_big", "raster_resolve")
STAMP_NAMES = ("shadows", "transmission", *_PREPASSES, *RASTER_STEPS,
               *(n for n in _BEFORE_SHADING if n not in _PREPASSES), "classify", "shading",
               *(p.name for p in PASSES if p.name not in _BEFORE_SHADING))
# The compute path's visibility pass draws these passes' draws (the coverage: not blending);
# after its shading step the frame goes on with the rest.
VISIBILITY_PASSES = tuple(p.name for p in PASSES if p.name in _BEFORE_SHADING and not p.prepass)
AFTER_SHADING = tuple(p.name for p in PASSES if p.name not in _BEFORE_SHADING)
_COMPUTE_AFTER_SHADING = tuple(n for n in AFTER_SHADING if n != "background")
STAMPS = len(STAMP_NAMES) + 2
_NO_SHADOWS = ShadowPlan()


class FrameStamps:
    """A frame's timestamps, written in STAMP_NAMES order: `after(name)` writes every slot
    up to `name`'s, and the slots of the `untimed` steps (those this frame's path does not
    take) right after the slot before them, so they read as taking no time, each step's
    time is its own, and every query of the frame is written once (an unwritten one would
    never be ready). A step already passed is left as written."""

    def __init__(self, ring: FrameRing, cmd: Commands, frame: Frame,
                 untimed: frozenset[str] = frozenset()) -> None:
        self.ring, self.cmd, self.frame, self.untimed = ring, cmd, frame, untimed
        self.written = 0
        ring.stamp(cmd, frame, 0)  # the frame's start

    def after(self, *names: str) -> None:
        for name in names:
            self._up_to(1 + STAMP_NAMES.index(name))

    def end(self) -> None:
        """The frame's last timestamp (after its copies)."""
        self._up_to(STAMPS - 1)

    def _up_to(self, slot: int) -> None:
        while self.written < slot or (self.written < len(STAMP_NAMES)
                                      and STAMP_NAMES[self.written] in self.untimed):
            self.written += 1
            self.ring.stamp(self.cmd, self.frame, self.written)


@dataclass
class _Recorded:
    cmd: Commands
    blend_order: tuple[int, ...]



class FrameRecorder:
    """Pipelines and command buffers for drawing `gpu_scene` with the frame ring `ring`."""

    def __init__(self, device: Device, gpu_scene: GpuScene, layout: PipelineLayout,
                 ring: FrameRing, slots: list[FrameSlot],
                 prepass_for: Callable[[FrameTarget], bool],
                 shadows: ShadowMaps | None = None,
                 compute_scene: Callable[[], ComputeScene] | None = None,
                 copies: OpaqueCopies | None = None) -> None:
        self.device, self.gpu_scene, self.pipeline_layout = device, gpu_scene, layout
        self.shadows = shadows  # records its passes first; binds its set 3 in the main passes
        self.copies = copies  # the opaque scene's copies (transmission), drawn after the shadows
        self.ring, self.slots, self.prepass_for = ring, slots, prepass_for
        self.compute_scene = compute_scene  # the compute path's resources, made on first use
        self._recorded: dict[tuple, _Recorded] = {}
        self._generations: dict[int, int] = {}
        self._pipelines: dict[tuple, Pipeline] = {}

    # --- pipelines --------------------------------------------------------------------------
    def pipeline(self, target: FrameTarget, tbn: L.TbnMode, p: PassSpec, prepass: bool,
                 visibility: bool = False, batch: bool = False, copy: bool = False) -> Pipeline:
        """The pipeline of pass `p` for `target`; `visibility`: its compute-path variant,
        writing (draw + 1, primitive) with pbr.frag's own coverage instead of a colour;
        `batch`: its batched-views variant (render/batch.py: the shaders' BATCH builds);
        `copy`: its opaque-copy variant, writing linear radiance (render/transmission.py)."""
        key = (target.color_format, target.depth_format, target.samples,
               None if p.fullscreen else tbn, p.name, prepass and p.after_prepass, visibility,
               batch, copy)
        if key not in self._pipelines:
            gs = self.gpu_scene
            streams = [VertexStream(i, i, fmt, 0 if name == "colors" and not gs.has_colors else None)
                       for i, (name, fmt) in enumerate(_BASE_STREAMS + _TBN_STREAMS[tbn])]
            base = PipelineSpec(
                vertex_shader=f"pbr_{tbn.name.lower()}.vert.spv",
                fragment_shader="pbr_opaque.frag.spv", streams=tuple(streams),
                color_format=target.color_format, depth_format=target.depth_format,
                samples=target.samples)
            spec = pipeline_spec(p, base, prepass)
            if visibility:
                vis = spec.fragment_shader.replace("pbr_", "pbr_vis_")  # type: ignore[union-attr]
                spec = dataclasses.replace(spec, fragment_shader=vis, blend=False,
                                           color_format=getattr(self.device.vk, L.VISIBILITY_FORMAT))
            if copy and spec.fragment_shader is not None:  # (the pre-pass has none)
                spec = dataclasses.replace(spec, fragment_shader=spec.fragment_shader.replace(
                    "pbr_", "pbr_copy_").replace("background.frag", "background_copy.frag"))
            if batch:
                frag = spec.fragment_shader
                spec = dataclasses.replace(
                    spec, vertex_shader=spec.vertex_shader.replace("pbr_", "pbr_batch_").replace(
                        "background.vert", "background_batch.vert"),
                    fragment_shader=frag if frag is None else frag.replace("pbr_", "pbr_batch_"))
            self._pipelines[key] = Pipeline(self.device, spec, self.pipeline_layout, SPV_DIR)
        return self._pipelines[key]

    def build_pipelines(self, target: FrameTarget) -> None:
        """Create every pipeline and vertex stream (all TBN paths and passes) for `target`
        now, so that no later mode switch waits for one (the viewer calls this)."""
        self.gpu_scene.ensure_streams()
        for tbn in L.TbnMode:
            for p in PASSES:
                for prepass in (False, True):  # the window may be resized across the bound
                    self.pipeline(target, tbn, p, prepass)

    # --- command buffers --------------------------------------------------------------------
    def begin_frame(self, frame: Frame, tbn: L.TbnMode, alpha_mask: bool, plan: ShadowPlan,
                    redraw: tuple[range, ...] | None = None, transmission: bool = False,
                    compute: bool = False, untimed: frozenset[str] = frozenset(),
                    variant: ShadeVariant = GENERAL_SHADING,
                    ) -> tuple[Commands, FrameStamps, list[str], list[str]]:
        """Begin a frame's command buffer (a single frame's or a batch's, render/batch.py):
        its start timestamp, the shadow-map passes (`redraw`: per plan entry, the range of its
        layers to draw; ShadowMaps.stale), the timestamp after them, the copy of the opaque
        scene (`transmission`: render/transmission.py; on the compute path with `compute`) and
        the timestamp after it. Returns the buffer, its timestamps (`untimed`: the steps
        this frame does not take), the vertex streams' names for `tbn` and every draw's
        class."""
        gs, ring = self.gpu_scene, self.ring
        names = [n for n, _ in _BASE_STREAMS + _TBN_STREAMS[tbn]]
        gs.ensure_streams(tuple(names))  # the quat / packed streams on first use
        classes = [classify(d.alpha_mode, d.double_sided, alpha_mask) for d in gs.draws]
        cmd = Commands(self.device).begin()
        stamps = FrameStamps(ring, cmd, frame, untimed)
        if self.shadows is not None:
            self.shadows.record(cmd, frame.index, plan, gs.draws, classes, gs.material_sets,
                                gs.streams, gs.index_buffer, gs.has_colors, redraw)
        stamps.after("shadows")
        if transmission:
            self._record_opaque_copy(cmd, frame, tbn, names, classes, compute, variant)
        stamps.after("transmission")
        return cmd, stamps, names, classes

    def _record_opaque_copy(self, cmd: Commands, frame: Frame, tbn: L.TbnMode, names: list[str],
                            classes: list[str], compute: bool,
                            variant: ShadeVariant = GENERAL_SHADING) -> None:
        """The frame slot's copy of the opaque scene: the opaque and masked draws that do not
        transmit and the environment, in linear radiance, then its mip chain. `compute`: as
        the compute path draws a frame (visibility, binning, shading in compute shaders, the
        environment behind), else as the fragment path with the frame's pre-pass rule."""
        copies, gs, slot = self.copies, self.gpu_scene, self.slots[frame.index]
        assert copies is not None and copies.present
        target = copies.targets[frame.index]
        classes = copy_classes(classes, copies.transmissive)
        shadow_set = None if self.shadows is None else self.shadows.sets[frame.index]

        def context(visibility: bool, prepass: bool) -> PassContext:
            return PassContext(
                draws=gs.draws, classes=classes,
                pipeline=lambda p: self.pipeline(target, tbn, p, prepass, visibility,  # type: ignore[arg-type]
                                                 copy=not visibility),
                prepass=prepass, frame_sets=(slot.set0, slot.set2),
                material_sets=gs.material_sets, vertex_buffers=[gs.streams[n] for n in names],
                index_buffer=gs.index_buffer, shadow_set=shadow_set)

        if compute and target.storage_view is not None:
            target.record_visibility_begin(cmd, 0)
            record_passes(cmd, context(True, False), VISIBILITY_PASSES)
            target.record_shading_begin(cmd)
            self.compute_scene().record_shading(  # type: ignore[misc]
                cmd, target, frame.index, tbn, self._compute_sets(frame), gs.material_sets,
                _shaded_materials(gs.draws, classes), target.clear_color, copy=True,
                variant=variant)
            target.record_resume(cmd)
            record_passes(cmd, context(False, False), ("background",))
        else:
            prepass = self.prepass_for(target)  # the frame's rule (GPUs: each pixel shaded once)
            target.record_begin(cmd)
            record_passes(cmd, context(False, prepass), COPY_PASSES)
        target.record_end(cmd)

    def _record(self, target: FrameTarget, frame: Frame, image: int, tbn: L.TbnMode,
                alpha_mask: bool, order: tuple[int, ...], overlay: TextOverlay | None,
                copy: tuple[str, ...], plan: ShadowPlan, compute: bool = False,
                outputs: bool = False, redraw: tuple[range, ...] | None = None,
                raster: bool = False, transmission: bool = False,
                variant: ShadeVariant = GENERAL_SHADING) -> Commands:
        gs = self.gpu_scene
        slot = self.slots[frame.index]
        prepass = self.prepass_for(target) and not compute  # visibility: its own pre-pass
        untimed = {*RASTER_STEPS} if not raster else set()
        if compute or outputs:
            untimed |= {*_PREPASSES}  # the visibility pass is its own pre-pass
        if not compute:
            untimed.add("classify")  # (the outputs' classification is the next step's time)
        cmd, stamps, names, classes = self.begin_frame(frame, tbn, alpha_mask, plan, redraw,
                                                       transmission, compute, frozenset(untimed),
                                                       variant)
        shadow_set = None if self.shadows is None else self.shadows.sets[frame.index]

        def context(visibility: bool, after_visibility: bool = False,
                    timed: bool = True) -> PassContext:
            # after_visibility: the fragment path's passes over a visibility pass's depth,
            # which is a depth pre-pass for them (test it, write none). The visibility pass
            # itself writes depth whatever the target's pre-pass choice: none ran before it.
            pre = after_visibility or (prepass and not visibility)
            return PassContext(
                draws=gs.draws, classes=classes,
                pipeline=lambda p: self.pipeline(target, tbn, p, pre, visibility),
                frame_sets=(slot.set0, slot.set2), material_sets=gs.material_sets,
                vertex_buffers=[gs.streams[n] for n in names], index_buffer=gs.index_buffer,
                blend_order=order, prepass=pre,
                stamp=stamps.after if timed else (lambda name: None),
                shadow_set=shadow_set)

        ctx = context(False)
        if compute or outputs:
            # render/compute_path.py: the visibility pass, the pixels binned by material, then
            # the compute path's shading (or the fragment path's passes over that depth) and
            # the dataset outputs' kernel.
            if outputs:
                target.record_outputs_clear(cmd)  # type: ignore[attr-defined]
            vis_ctx = context(True, timed=compute)
            if raster:
                # The compute rasteriser (render/compute_path.py): the opaque and masked draws
                # on all SMs, then their depths into the depth buffer where anything reads
                # it: the blended draws, depth readback, the fragment path's passes.
                depth = not compute or COPY_DEPTH in copy or "blend" in classes
                self._record_compute_raster(cmd, target, frame, alpha_mask, stamps, depth=depth)
                for name in VISIBILITY_PASSES:
                    vis_ctx.stamp(name)
            else:
                target.record_visibility_begin(cmd, image)  # type: ignore[attr-defined]
                # The fragment path's own passes follow and take the timestamps.
                record_passes(cmd, vis_ctx, VISIBILITY_PASSES)
                target.record_shading_begin(cmd)  # type: ignore[attr-defined]
            drawn = _shaded_materials(gs.draws, classes)
            frame_sets = self._compute_sets(frame)
            cs = self.compute_scene()
            cs.record_shading(cmd, target, frame.index, tbn, frame_sets, gs.material_sets,
                              drawn, target.clear_color, shade=compute,
                              stamp=vis_ctx.stamp, variant=variant,  # type: ignore[attr-defined]
                              counted=raster)
            if outputs:
                cs.record_outputs(cmd, target, frame.index, tbn, frame_sets, gs.material_sets,
                                  drawn)
            if compute:
                ctx.stamp("shading")
                cs.record_background(cmd, target, frame.index, frame_sets)
                ctx.stamp("background")
                target.record_resume(cmd)  # type: ignore[attr-defined]
            else:
                target.record_resume(cmd, clear=True)  # type: ignore[attr-defined]
                ctx = context(False, after_visibility=True)
                record_passes(cmd, ctx, VISIBILITY_PASSES)
                ctx.stamp("shading")
        else:
            target.record_begin(cmd, image)
            record_passes(cmd, ctx, _BEFORE_SHADING)
            ctx.stamp("shading")
        # The compute path drew its background in compute (above).
        record_passes(cmd, ctx, _COMPUTE_AFTER_SHADING if compute else AFTER_SHADING)
        if overlay is not None:
            overlay.record(cmd, frame.index, target.extent)
        target.record_end(cmd, image, frame, copy)
        stamps.end()
        cmd.end()
        return cmd

    def command_buffer(self, target: FrameTarget, frame: Frame, image: int, tbn: L.TbnMode,
                        alpha_mask: bool, order: tuple[int, ...], overlay: TextOverlay | None,
                        copy: tuple[str, ...], plan: ShadowPlan = _NO_SHADOWS,
                        compute: bool = False, outputs: bool = False,
                        redraw: tuple[range, ...] | None = None, raster: bool = False,
                        transmission: bool = False,
                        variant: ShadeVariant = GENERAL_SHADING) -> Commands:
        """The command buffer recorded for these inputs, recorded on first use. A buffer is
        used by one frame of the ring only, whose previous submission has finished: it can be
        re-recorded (new blend order) or freed at once. `plan`: the shadow maps' (a new plan
        records new buffers; lights that only move keep theirs); `transmission`: draw the
        copy of the opaque scene first (render/transmission.py); `variant`: what the compute
        path's shading kernels are specialised for (the frame's lighting)."""
        tid = id(target)
        if self._generations.get(tid, target.generation) != target.generation:
            self.free(tid)  # recreated swapchain: its images and buffers are new
        self._generations[tid] = target.generation
        key = (tid, image, frame.index, tbn, alpha_mask, id(overlay), copy, plan, compute, outputs,
               redraw, raster, transmission, variant)
        rec = self._recorded.get(key)
        if rec is not None and rec.blend_order == order:
            return rec.cmd
        if rec is not None:  # the camera moved enough to reorder blended draws
            rec.cmd.free()
        cmd = self._record(target, frame, image, tbn, alpha_mask, order, overlay, copy, plan,
                           compute, outputs, redraw, raster, transmission, variant)
        self._recorded[key] = _Recorded(cmd, order)
        return cmd

    def compute_batch(self, target: FrameTarget, frame: Frame, tbn: L.TbnMode, alpha_mask: bool,
                      plan: ShadowPlan, redraw: tuple[range, ...], tiles: tuple[int, int, int, int],
                      set0: object, copy: tuple[str, ...], external: object = None,
                      variant: ShadeVariant = GENERAL_SHADING) -> Commands:
        """A compute batch's commands (render/batch_path.py), recorded on first use: `tiles`
        (views, tile width, tile height, tiles a column, column-major) of an atlas `target`, every view
        rasterised and shaded in compute shaders (its ViewRecord in `set0`, BatchViews'), the
        environment behind them, the copies (the colour into the exported buffer `external`,
        for CUDA, where given). No blended draws (the layered batch takes those)."""
        key = ("compute batch", id(target), frame.index, tbn, alpha_mask, plan, redraw, tiles,
               id(set0), copy, id(external), variant)
        rec = self._recorded.get(key)
        if rec is not None:
            return rec.cmd
        gs = self.gpu_scene
        cmd, stamps, _, classes = self.begin_frame(frame, tbn, alpha_mask, plan, redraw,
                                                   untimed=frozenset(_PREPASSES))
        cs = self.compute_scene()
        self._record_compute_raster(cmd, target, frame, alpha_mask, stamps, tiles, set0,
                                    depth=COPY_DEPTH in copy)
        stamps.after("mask")  # the depths' copy is "opaque"'s, as a single frame's
        frame_sets = self._compute_sets(frame, set0)
        drawn = _shaded_materials(gs.draws, classes)
        cs.record_shading(cmd, target, frame.index, tbn, frame_sets, gs.material_sets, drawn,
                          target.clear_color, tiles=tiles, stamp=stamps.after,  # type: ignore[attr-defined]
                          variant=variant, counted=True)
        stamps.after("shading")
        cs.record_background(cmd, target, frame.index, frame_sets, tiles)
        target.record_resume(cmd)  # type: ignore[attr-defined]
        stamps.after(*AFTER_SHADING)
        target.record_end(cmd, 0, frame, copy, tiles, external)  # type: ignore[call-arg]
        stamps.end()
        cmd.end()
        self._recorded[key] = _Recorded(cmd, ())
        return cmd

    def _compute_sets(self, frame: Frame, set0: object = None) -> dict[int, object]:
        """The frame's sets the compute path's kernels bind: 0 (the frame's view; `set0`: a
        batch's views), 2 (lighting) and 3 (the shadow maps, where there are any)."""
        slot = self.slots[frame.index]
        sets = {0: slot.set0 if set0 is None else set0, 2: slot.set2}
        if self.shadows is not None:
            sets[3] = self.shadows.sets[frame.index]
        return sets

    def _record_compute_raster(self, cmd: Commands, target: FrameTarget, frame: Frame,
                               alpha_mask: bool, stamps: FrameStamps,
                               tiles: tuple[int, int, int, int] | None = None,
                               set0: object = None, depth: bool = True) -> None:
        """The compute rasteriser (render/compute_path.py): the opaque and masked draws into the
        visibility image on all SMs, their depths into the depth buffer (`depth`: where this
        frame reads it); the target is then ready for the shading (as after
        record_shading_begin)."""
        target.record_raster_begin(cmd)  # type: ignore[attr-defined]
        views = self.slots[frame.index].set0 if set0 is None else set0  # the frame's or batch's
        self.compute_scene().record_raster(cmd, target, frame.index, alpha_mask,
                                           self.gpu_scene.material_sets, tiles, views,
                                           stamp=stamps.after, depth=depth)

    def free(self, target_id: int | None = None) -> None:
        """Free the recorded command buffers (of one target: its id; None: all)."""
        def of_target(key: tuple) -> bool:
            # A frame's key starts with its target's id, a compute batch's with its name.
            return key[0] == target_id or (key[0] == "compute batch" and key[1] == target_id)

        for key in [k for k in self._recorded if target_id is None or of_target(k)]:
            self._recorded.pop(key).cmd.free()


def _shaded_materials(draws: list, classes: list[str]) -> list[int]:
    """The materials the compute path shades: those of every draw but the blended ones (and
    the transmissive ones, in the copy of the opaque scene)."""
    return sorted({d.material for d, c in zip(draws, classes, strict=True)
                   if c not in ("blend", TRANSMISSIVE)})
