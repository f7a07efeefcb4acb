"""The pass table: every pass of a frame, declared once, in drawing order.

A pass names the class of draws it takes (`classify` below puts a draw in a class; the
compute path's rasteriser ranks draws in the same order, render/compute_path.py), how its
pipeline differs from the base PBR pipeline (vkguide derives its transparent pipeline from
its opaque one the same way), whether it sorts its draws back to front, and whether it
belongs to the optional depth pre-pass. Each row is a step of the paths that list it
(render/paths.py); `record_pass` records one. A new fragment pass is a row here, its
shaders, and its name in the paths that draw it.

The depth pre-pass draws the opaque classes depth-only (no fragment shader) with the same
vertex shader (`invariant gl_Position`), after which the opaque passes test
GREATER_OR_EQUAL without writing depth, so each pixel is shaded once (reversed-Z: nearer
is greater). Masked draws need their texture to decide coverage and are not pre-passed.

The background pass (`fullscreen`: one triangle, no draws) comes after the opaque and masked
passes, where only pixels no surface covered still hold the cleared depth 0, and before the
blended draws, which composite over it.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.pipeline import PipelineSpec
from vkpbr.render.layouts import draw_push

if TYPE_CHECKING:
    from vkpbr.render.gpu_scene import MaterialSets

__all__ = ["PassSpec", "PASSES", "classify", "record_pass", "record_passes", "PassContext"]

_Derive = Callable[[PipelineSpec], PipelineSpec]


def classify(alpha_mode: str, double_sided: bool, alpha_mask: bool) -> str:
    """The draw class (= the main pass) of a material: "opaque", "opaque_double", "mask" or
    "blend". With alpha masking off, masked materials are drawn opaque, without culling
    (they are mostly foliage and fences, modelled as single sheets)."""
    if alpha_mode == "blend":
        return "blend"
    if alpha_mode == "mask":
        return "mask" if alpha_mask else "opaque_double"
    return "opaque_double" if double_sided else "opaque"


@dataclass(frozen=True)
class PassSpec:
    name: str
    draw_class: str  # the draws it takes (classify)
    derive: _Derive  # base pipeline spec -> this pass's
    back_to_front: bool = False  # sort draws far to near (blending)
    prepass: bool = False  # part of the optional depth pre-pass
    after_prepass: bool = False  # with the pre-pass on: test its depth, write none
    fullscreen: bool = False  # one screen-covering triangle (no draws, no vertex streams)


def _same(spec: PipelineSpec) -> PipelineSpec:
    return spec


def _two_sided(spec: PipelineSpec) -> PipelineSpec:
    return dataclasses.replace(spec, cull="none")


def _depth_only(spec: PipelineSpec) -> PipelineSpec:
    return dataclasses.replace(spec, fragment_shader=None, color_write=False)


def _background(spec: PipelineSpec) -> PipelineSpec:
    """The environment behind the scene (background.vert/.frag): at the far plane, where the
    depth is still the clear value 0 (reversed-Z), before the blended draws cover it."""
    return dataclasses.replace(spec, vertex_shader="background.vert.spv",
                               fragment_shader="background.frag.spv", streams=(), cull="none",
                               depth_write=False)


PASSES: tuple[PassSpec, ...] = (
    PassSpec("prepass_opaque", "opaque", _depth_only, prepass=True),
    PassSpec("prepass_opaque_double", "opaque_double",
             lambda s: _depth_only(_two_sided(s)), prepass=True),
    PassSpec("opaque", "opaque", _same, after_prepass=True),
    PassSpec("opaque_double", "opaque_double", _two_sided, after_prepass=True),
    PassSpec("mask", "mask",
             lambda s: dataclasses.replace(s, cull="none", fragment_shader="pbr_mask.frag.spv")),
    PassSpec("background", "", _background, fullscreen=True),
    PassSpec("blend", "blend",
             lambda s: dataclasses.replace(s, cull="none", blend=True, depth_write=False),
             back_to_front=True),
)


def pipeline_spec(p: PassSpec, base: PipelineSpec, prepass: bool) -> PipelineSpec:
    """The pipeline a pass draws with, given whether the depth pre-pass runs this frame."""
    spec = p.derive(base)
    if prepass and p.after_prepass:
        spec = dataclasses.replace(spec, depth_write=False)
    return spec


@dataclass
class PassContext:
    """What recording needs beyond the command buffer: the draws and their classes, the
    frame's descriptor sets, and a pipeline lookup."""

    draws: list[Any]  # render.gpu_scene.Draw
    classes: list[str]  # classify() of each draw, for this frame's options
    pipeline: Callable[[PassSpec], Any]  # pass -> gpu.pipeline.Pipeline
    frame_sets: tuple[Any, Any]  # set 0 (camera, settings), set 2 (lighting)
    material_sets: MaterialSets  # the frame slot's (made as passes prepare them)
    vertex_buffers: list[Any]
    index_buffer: Any
    blend_order: tuple[int, ...] = ()  # indices into the blend-class draws, far to near
    prepass: bool = False
    shadow_set: Any = None  # set 3 (render/shadows.py ShadowMaps.sets), bound when given
    # A batch (render/batch.py): each draw is the indirect command at (indirect_base + its
    # index) of `indirect` (instanced over the views that see it), and the fullscreen passes
    # draw one instance per view of `views` = (first view, count).
    indirect: Any = None
    indirect_base: int = 0
    views: tuple[int, int] | None = None
    # A batch's blended draws: per group of views sharing one back-to-front order, (order,
    # first instance, instances): the group's views are listed from that first instance on.
    blend_groups: tuple[tuple[tuple[int, ...], int, int], ...] | None = None
    # A compute batch's atlas size: its blended draws map each view into its tile (pbr.vert
    # ATLAS, told the size by the push); None elsewhere.
    atlas: tuple[int, int] | None = None


def pass_makers(ctx: PassContext, passes: Iterable[PassSpec]) -> tuple[Callable[[], Any], ...]:
    """Calls that make the pipelines `record_pass` binds for `passes` with `ctx` (a Step's
    kernels: the frame graph makes them at once): those of the passes that draw anything."""
    return tuple(functools.partial(ctx.pipeline, p) for p in passes
                 if p.fullscreen or p.draw_class in ctx.classes)


def recorded_passes(ctx: PassContext, names: tuple[str, ...] | None = None) -> list[PassSpec]:
    """The passes `record_passes` records with `ctx` (those in `names`, default all)."""
    return [p for p in PASSES
            if (names is None or p.name in names) and not (p.prepass and not ctx.prepass)]


def record_passes(cmd: Commands, ctx: PassContext, names: tuple[str, ...] | None = None) -> None:
    """Record the enabled passes of PASSES (those in `names`, default all) in one rendering
    (a batch's chunk of views: render/batch.py)."""
    for p in recorded_passes(ctx, names):
        record_pass(cmd, ctx, p)


def record_pass(cmd: Commands, ctx: PassContext, p: PassSpec) -> None:
    """Record pass `p` (a step of a path: render/steps.py). Each draw is instanced from its own
    index in ctx.draws (gl_InstanceIndex: the compute path's visibility pass writes it per
    pixel); the records of one node's instances (EXT_mesh_gpu_instancing) are one draw call
    of K instances."""
    cmd.bind_index_buffer(ctx.index_buffer)
    if p.fullscreen:
        cmd.bind_pipeline(ctx.pipeline(p))
        cmd.bind_set(0, ctx.frame_sets[0])
        cmd.bind_set(2, ctx.frame_sets[1])
        if ctx.views is None:
            cmd.draw(3)
        else:
            cmd.draw(3, instances=ctx.views[1], first_instance=ctx.views[0])
        return
    draws = [(i, d) for i, (d, c) in enumerate(zip(ctx.draws, ctx.classes, strict=True))
             if c == p.draw_class]
    if p.back_to_front and ctx.blend_groups is not None:
        for order, first, count in ctx.blend_groups:
            if draws:
                _record_draws(cmd, ctx, p, [draws[i] for i in order], (first, count))
        return
    if p.back_to_front and len(ctx.blend_order) == len(draws):
        draws = [draws[i] for i in ctx.blend_order]
    if draws:
        _record_draws(cmd, ctx, p, draws)


def _record_draws(cmd: Commands, ctx: PassContext, p: PassSpec, draws: list[tuple[int, Any]],
                  instanced: tuple[int, int] | None = None) -> None:
    """`instanced`: (first instance, instances) of every draw (a batch's group of views)."""
    cmd.bind_pipeline(ctx.pipeline(p))
    cmd.bind_set(0, ctx.frame_sets[0])
    cmd.bind_set(2, ctx.frame_sets[1])
    if ctx.shadow_set is not None:
        cmd.bind_set(3, ctx.shadow_set)
    cmd.bind_vertex_buffers(ctx.vertex_buffers)
    ctx.material_sets.prepare(d.material for _, d in draws)  # (made at once: one write)
    bound = None
    runs = [(i, d, 1) for i, d in draws] if (instanced is not None or ctx.indirect is not None
                                             or p.back_to_front) else _instance_runs(draws)
    for index, d, count in runs:
        if d.material != bound:
            cmd.bind_set(1, ctx.material_sets[d.material])
            bound = d.material
        cmd.push(draw_push(index, ctx.atlas or (0, 0), d.material))
        if instanced is not None:
            cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset,
                             first_instance=instanced[0], instances=instanced[1])
        elif ctx.indirect is not None:
            cmd.draw_indexed_indirect(ctx.indirect, (ctx.indirect_base + index) * 20)
        else:  # `count` instances of one node: records index.. (pbr.vert reads their matrices)
            cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset, first_instance=index,
                             instances=count)


def _instance_runs(draws: list[tuple[int, Any]]) -> list[tuple[int, Any, int]]:
    """(first record, draw, instances): consecutive records of one node's one mesh (its
    EXT_mesh_gpu_instancing instances, GpuScene keeps them adjacent) become one draw call."""
    runs: list[tuple[int, Any, int]] = []
    for index, d in draws:
        if runs:
            first, head, count = runs[-1]
            if (index == first + count and d.node == head.node and d.mesh == head.mesh
                    and d.vertex_offset == head.vertex_offset):  # (deformed: a region each)
                runs[-1] = (first, head, count + 1)
                continue
        runs.append((index, d, 1))
    return runs
