"""Pipelines and recorded command buffers: how a frame's commands come to exist.

A `FrameRecorder` builds the PBR pipelines each pass (render/passes.py) needs, for a
target's formats, and records one command buffer per (target, image, frame of the ring,
FrameSpec), reused frame after frame: the path's steps (render/paths.py, made by
render/steps.py) through gpu/graph.py, which derives their barriers and renderings, with a
timestamp after each timed step. A buffer is used by one frame of the ring only, whose
previous submission has finished when it is looked up: it can be re-recorded (a new
blended-draw order) or freed at once.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.device import Device
from vkpbr.gpu.frames import Frame, FrameRing
from vkpbr.gpu.graph import Step, record_steps
from vkpbr.gpu.pipeline import Pipeline, PipelineLayout, PipelineSpec, VertexStream
from vkpbr.gpu.target import FrameTarget
from vkpbr.render import layouts as L
from vkpbr.render.codegen import SPV_DIR
from vkpbr.render.compute_path import ComputeScene
from vkpbr.render.frames import FrameSlot
from vkpbr.render.gpu_scene import GpuScene
from vkpbr.render.passes import PASSES, PassSpec, pipeline_spec
from vkpbr.render.shadows import ShadowMaps
from vkpbr.render.steps import NO_OBJECTS, FrameObjects, FrameSpec, FrameSteps
from vkpbr.render.transmission import OpaqueCopies

__all__ = ["FrameRecorder", "STAMPS", "FrameSpec", "FrameObjects"]

# shadow_sampling.glsl's SHADOW_HAND_READS (shade.glsl's constants 0-2 are the compute path's).
SHADOW_HAND_READS_ID = 3

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
# Timestamp queries a frame slot has: the start and one after each timed step (the longest
# path times about 20).
STAMPS = 48
# Recordings kept per frame slot, the least recently used freed past it: a key holds values a
# loop may change every call (a post step's noise seed or bloom strength, a camera model's
# constants), and each new value records anew; the viewer's every mode is far fewer.
RECORDINGS_KEPT = 32


@dataclass
class _Recorded:
    cmd: Commands
    blend_order: tuple[int, ...]
    stamp_names: tuple[str, ...]
    targets: tuple[int, ...]  # id() of the targets it draws into (the user's, an HDR one)
    used: int = 0  # when it was last handed out (FrameRecorder._uses)


class _Stamps:
    """A recording's timestamps: the start, then one after each timed step."""

    def __init__(self, ring: FrameRing, cmd: Commands, frame: Frame) -> None:
        self.ring, self.cmd, self.frame = ring, cmd, frame
        self.names: list[str] = []
        ring.stamp(cmd, frame, 0)

    def __call__(self, name: str) -> None:
        if len(self.names) + 1 >= STAMPS:
            raise ValueError(f"a frame times at most {STAMPS - 1} steps")
        self.names.append(name)
        self.ring.stamp(self.cmd, self.frame, len(self.names))


def _pipeline_key(target: FrameTarget, tbn: L.TbnMode, p: PassSpec, prepass: bool,
                  visibility: bool = False, batch: bool = False, copy: bool = False,
                  atlas: bool = False) -> tuple:
    """What a pass's pipeline for `target` depends on (FrameRecorder.pipeline's arguments)."""
    return (target.color_format, target.depth_format, target.samples,
            None if p.fullscreen else tbn, p.name, prepass and p.after_prepass, visibility,
            batch, copy, atlas)


class FrameRecorder:
    """Pipelines and command buffers for drawing `gpu_scene` with the frame ring `ring`."""

    def __init__(self, device: Device, gpu_scene: GpuScene, layout: PipelineLayout,
                 ring: FrameRing, slots: list[FrameSlot],
                 prepass_for: Callable[[FrameTarget], bool],
                 shadows: ShadowMaps | None = None,
                 compute_scene: Callable[[], ComputeScene] | None = None,
                 copies: OpaqueCopies | None = None,
                 post_kernels: Callable[[], Any] | None = None, deform: Any = None,
                 ao: Any = None) -> None:
        self.device, self.gpu_scene, self.pipeline_layout = device, gpu_scene, layout
        self.shadows = shadows  # records its passes first; binds its set 3 in the main passes
        self.copies = copies  # the opaque scene's copies (transmission), drawn after the shadows
        self.ring, self.slots, self.prepass_for = ring, slots, prepass_for
        self.compute_scene = compute_scene  # the compute path's resources, made on first use
        self.post_kernels = post_kernels  # the post steps' (render/post.py), made on first use
        self.deform = deform  # skins and morph targets (render/deform.py); None: none
        self.ao = ao  # the ambient occlusion's images and kernels (render/ao.py AoImages)
        self._recorded: dict[tuple, _Recorded] = {}
        self._uses = 0  # recordings handed out (_Recorded.used: the least recently used go)
        self._generations: dict[int, int] = {}
        self._kernels_made: set[tuple] = set()  # (spec, reads buffer) of recordings made
        self._pipelines: dict[tuple, Pipeline] = {}
        self._by_spec: dict[PipelineSpec, Pipeline] = {}

    # --- pipelines --------------------------------------------------------------------------
    def pipeline(self, target: FrameTarget, tbn: L.TbnMode, p: PassSpec, prepass: bool,
                 visibility: bool = False, batch: bool = False, copy: bool = False,
                 atlas: bool = False) -> Pipeline:
        """The pipeline of pass `p` for `target`; `visibility`: its compute-path variant,
        writing (draw + 1, primitive) with pbr.frag's own coverage instead of a colour;
        `batch`: its batched-views variant (render/batch.py: the shaders' BATCH builds);
        `copy`: its opaque-copy variant, writing linear radiance (render/transmission.py);
        `atlas` (with `batch`): a compute batch's, each view drawn into its tile of the atlas.
        A frame's shading passes lack the by-hand shadow reads (pbr.frag built with
        shadow_sampling.glsl SHADOW_HAND_READS 0) unless it reads compute-drawn maps from their
        buffer (ShadowMaps.hand_reads; the recording is keyed on it); a batch's keep them (a
        batch of worlds reads its worlds' maps by hand)."""
        hand = batch or visibility or self.shadows is None or self.shadows.hand_reads
        key = (*_pipeline_key(target, tbn, p, prepass, visibility, batch, copy, atlas), hand)
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
                    spec, vertex_shader=spec.vertex_shader.replace(
                        "pbr_", "pbr_atlas_" if atlas else "pbr_batch_").replace(
                        "background.vert", "background_batch.vert"),
                    fragment_shader=frag if frag is None else frag.replace(
                        "pbr_", "pbr_batch_").replace("background.frag", "background_batch.frag"))
            if not hand and (spec.fragment_shader or "").startswith("pbr_"):
                spec = dataclasses.replace(spec, fragment_constants=((SHADOW_HAND_READS_ID, 0),))
            # (passes the constant does not touch share one pipeline across `hand`)
            if spec not in self._by_spec:
                self._by_spec[spec] = Pipeline(self.device, spec, self.pipeline_layout, SPV_DIR)
            self._pipelines[key] = self._by_spec[spec]
        return self._pipelines[key]

    def build_pipelines(self, target: FrameTarget, threads: int | None = None) -> None:
        """Create every pipeline and vertex stream (all TBN paths and passes) for `target`
        now, so that no later mode switch waits for one (the viewer calls this). The driver
        compiles them on `threads` threads at once (default: up to 8): the binding releases
        the GIL in its calls, the device's pipeline cache is internally synchronised, and
        each pipeline is its own key here."""
        self.gpu_scene.ensure_streams()
        keys = {_pipeline_key(target, tbn, p, prepass): (tbn, p, prepass) for tbn in L.TbnMode
                for p in PASSES for prepass in (False, True)}  # (resized across the bound)
        workers = threads or min(8, os.cpu_count() or 1)
        with ThreadPoolExecutor(max(1, workers)) as pool:
            list(pool.map(lambda k: self.pipeline(target, *k), keys.values()))  # one per key

    # --- command buffers --------------------------------------------------------------------
    def stream_names(self, tbn: L.TbnMode) -> list[str]:
        """The vertex streams' names for `tbn` (made on first use)."""
        names = [n for n, _ in _BASE_STREAMS + _TBN_STREAMS[tbn]]
        self.gpu_scene.ensure_streams(tuple(names))  # the quat / packed streams on first use
        return names

    def command_buffer(self, target: FrameTarget, frame: Frame, image: int, spec: FrameSpec,
                       objects: FrameObjects = NO_OBJECTS,
                       groups: dict[str, Callable[[FrameSteps], list[Step]]] | None = None,
                       drawn: FrameTarget | None = None) -> Commands:
        """The command buffer recorded for `spec` into `target`'s `image` by `frame`'s slot,
        recorded on first use (re-recorded when only the blended draws' order changed);
        `groups`: the steps of groups the caller makes (the layered batch's); `drawn`: with
        post steps, the HDR target the path draws into before the encode into `target`. Sets
        `frame.stamp_names` to the timed steps' names (FrameStats.pass_ms' keys)."""
        tid = id(target)
        if self._generations.get(tid, target.generation) != target.generation:
            self.free(tid)  # recreated swapchain: its images and buffers are new
        self._generations[tid] = target.generation
        # (+ where the shading reads compute-drawn shadow maps this frame: their buffer, or the
        # images the redrawn layers are copied into; ShadowMaps.stale chooses)
        sm = self.shadows
        key = (tid, image, frame.index, spec, sm is not None and sm.compute and sm.reads_buffer)
        rec = self._recorded.get(key)
        made = rec is None or rec.blend_order != objects.blend_order
        if made:
            if rec is not None:  # the camera moved enough to reorder blended draws
                rec.cmd.free()
            steps = FrameSteps(self, drawn or target, frame.index, image, spec, objects, groups,
                               output=target if drawn is not None else None)
            ids = (tid,) if drawn is None else (tid, id(drawn))
            # (a step's kernels are made on threads once a plan: another slot's or image's
            # recording of it, or a new blend order, finds them made)
            planned = key[3:]
            rec = self._record(frame, steps.steps(), steps.resources, (drawn or target).extent,
                               ids, objects.blend_order, build=planned not in self._kernels_made)
            self._kernels_made.add(planned)
            self._recorded[key] = rec
        self._uses += 1
        rec.used = self._uses  # type: ignore[union-attr]
        if made and len(self._recorded) > RECORDINGS_KEPT:
            self._evict(frame.index)
        frame.stamp_names = rec.stamp_names
        return rec.cmd

    def _evict(self, slot: int) -> None:
        """Free frame slot `slot`'s least recently used recordings past RECORDINGS_KEPT. Only
        the slot being recorded: its last submission has finished (FrameRing.begin waited
        for it), so none of its recordings is pending; other slots' may be."""
        mine = [k for k in self._recorded if k[2] == slot]
        if len(mine) <= RECORDINGS_KEPT:
            return
        mine.sort(key=lambda k: self._recorded[k].used)
        for k in mine[:len(mine) - RECORDINGS_KEPT]:
            self._recorded.pop(k).cmd.free()

    def _record(self, frame: Frame, steps: list[Step], resources: dict[str, Any],
                extent: tuple[int, int], targets: tuple[int, ...], order: tuple[int, ...],
                build: bool = True) -> _Recorded:
        """Record `steps` (with the start timestamp and one after each timed step; the time
        after the last timed step is "copy"); `build`: their kernels made first, at once."""
        cmd = Commands(self.device).begin()
        stamps = _Stamps(self.ring, cmd, frame)
        if not any(s.name == "copy" and s.timed for s in steps):
            steps = [*steps, Step("copy")]
        record_steps(cmd, steps, resources, extent, stamps, build)
        cmd.end()
        return _Recorded(cmd, order, tuple(stamps.names), targets)

    def compute_sets(self, frame_index: int, set0: object = None) -> dict[int, object]:
        """The frame's sets the compute path's kernels bind: 0 (the frame's view; `set0`: a
        batch's views), 2 (lighting) and 3 (the shadow maps, where there are any)."""
        slot = self.slots[frame_index]
        sets = {0: slot.set0 if set0 is None else set0, 2: slot.set2}
        if self.shadows is not None:
            sets[3] = self.shadows.sets[frame_index]
        return sets

    def free(self, target_id: int | None = None,
             paths: tuple[str, ...] | None = None) -> None:
        """Free the recorded command buffers: of one target (its id; None: every target's),
        of the paths named in `paths` (None: every path's; render/batch.py frees its own)."""
        for key in [k for k, r in self._recorded.items()
                    if (target_id is None or target_id in r.targets)
                    and (paths is None or k[3].path in paths)]:
            self._recorded.pop(key).cmd.free()
