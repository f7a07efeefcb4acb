"""`Renderer.render_batch`'s body: the route, the worlds, the results (docs/batch.md).

Kept out of renderer.py (a facade) so that the call's parts read in one place: the checks
and route (render/batch_route.py), a batch of worlds (vkpbr.scene.worlds for the poses,
render/worlds.py on the GPU), the batch path's submission (render/batch_path.py) and, view
by view where a batch cannot draw something, `render_many` with each view's world applied
to the renderer's state and the state put back afterwards.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.render.batch_cache import BatchCache, Prepared, WorldShape, batch_cache
from vkpbr.render.batch_replay import replay, replay_key
from vkpbr.render.batch_route import batch_result, stack_views
from vkpbr.render.lighting import LightsArg
from vkpbr.render.options import RenderOptions, with_overrides
from vkpbr.render.outputs import output_images
from vkpbr.render.scene_state import base_factors
from vkpbr.render.worlds import GpuWorlds, WorldCall
from vkpbr.scene._checks import frame_size
from vkpbr.scene.camera_batch import CameraBatch, as_camera_batch
from vkpbr.scene.state import SceneState
from vkpbr.scene.worlds import (
    WorldEnvironment,
    WorldLights,
    WorldMaterials,
    WorldPoses,
    WorldSlots,
    check_space,
    world_blocks,
    world_records,
)

__all__ = ["render_batch", "batch_call", "world_slots", "WorldsArg", "WorldArgs", "BatchStep",
           "batch_step"]

WorldsArg = Any  # (W, N, 4, 4) | (W, N, 7) NumPy array or torch tensor


@dataclass(frozen=True)
class WorldPlan:
    """A call's worlds as checked on the host: the slots and poses (or None: the state's
    poses in every world), the materials' factors (or None) and the world of each view."""

    slots: WorldSlots | None
    poses: WorldPoses | None
    materials: WorldMaterials | None
    index: np.ndarray
    lights: WorldLights | None = None
    environment: WorldEnvironment | None = None

    @property
    def count(self) -> int:
        """W, the number of worlds."""
        return next(x.count for x in (self.poses, self.materials, self.lights, self.environment)
                    if x is not None)


def world_slots(renderer: Any, nodes: Any = None, materials: Any = None) -> WorldSlots | None:
    """Name the N nodes whose world poses each world of a batch gives (names, paths,
    patterns or indices, in the order the worlds' arrays list them) and the K materials whose
    factors `world_materials` gives; kept by the renderer for its next batches of worlds."""
    if nodes is None and materials is None:
        raise UsageError("world_slots: name nodes (poses) or materials (factors) or both")
    renderer._world_slots = None if nodes is None else WorldSlots.of(renderer.state, nodes)
    renderer._world_materials = None if materials is None else (
        [materials] if isinstance(materials, (str, int)) else list(materials))
    if materials is not None:  # names checked now, once
        WorldMaterials.indices(renderer.state, renderer._world_materials)
    return renderer._world_slots


_OPTIONS: dict[Any, RenderOptions] = {}  # (options, overrides) -> the call's options


def _options(options: RenderOptions | None, overrides: dict[str, Any]) -> RenderOptions:
    """The call's options (checked once: a loop that passes the same ones each step does not
    build and check them again)."""
    try:
        key = (options, tuple(sorted(overrides.items())))
        hash(key)
    except TypeError:  # (an unhashable override value: made each time)
        return with_overrides(options, overrides)
    made = _OPTIONS.get(key)
    if made is None:
        if len(_OPTIONS) > 64:
            _OPTIONS.clear()
        made = _OPTIONS[key] = with_overrides(options, overrides)
    return made


def _slots(renderer: Any) -> WorldSlots:
    slots = getattr(renderer, "_world_slots", None)
    if slots is None:
        raise UsageError("worlds: name the nodes each world poses first: "
                         "renderer.world_slots(['cube', 'arm/*'])")
    slots = slots.refreshed(renderer.state)
    renderer._world_slots = slots
    return slots


def _world_plan(renderer: Any, prep: Prepared, g: WorldArgs, light_count: int) -> WorldPlan:
    """The checked worlds of a call of `prep`'s views (NumPy or CPU tensors); `light_count`:
    the frame's lights (world_lights gives each)."""
    views = len(prep.views)
    slots = poses = wm = None
    if g.worlds is not None:
        slots = _slots(renderer)
        poses = WorldPoses.of(g.worlds, len(slots), g.quaternion, g.visible, g.space)
        if poses.local and slots.nested:
            raise UsageError("worlds: space='local' with a chosen node below another chosen "
                             "node; give world poses (space='world')")
    if g.materials is not None:
        wm = _materials(renderer, g.materials)
    wl = None if g.lights is None else WorldLights.of(g.lights, light_count)
    we = None if g.environment is None else WorldEnvironment.of(g.environment)
    counts = {x.count for x in (poses, wm, wl, we) if x is not None}
    if len(counts) > 1:
        raise UsageError(f"worlds: the world arrays disagree on the number of worlds "
                         f"({sorted(counts)}); give each for every world")
    w = counts.pop()
    index = batch_cache(renderer).world_index(prep, w, g.world_of_view,
                                              lambda: _world_index(views, w, g.world_of_view))
    return WorldPlan(slots, poses, wm, index, wl, we)


def _materials(renderer: Any, given: Any) -> WorldMaterials:
    names = getattr(renderer, "_world_materials", None)
    if names is None:
        raise UsageError("world_materials: name the materials first: "
                         "renderer.world_slots(nodes, materials=['paint', ...])")
    return WorldMaterials.of(renderer.state, names, given)


def _world_index(views: int, w: int, world_of_view: Any) -> np.ndarray:
    """(views,) int64: the world each view sees (checked; omitted: view b sees world b)."""
    if world_of_view is None:
        if views != w:
            raise UsageError(f"worlds: {views} views of {w} worlds; give world_of_view, the "
                             "world each view sees ((B,) integers)")
        return np.arange(w, dtype=np.int64)
    raw = np.asarray(world_of_view.cpu() if hasattr(world_of_view, "cpu") else world_of_view)
    if raw.shape != (views,) or not np.issubdtype(raw.dtype, np.integer):
        raise UsageError(f"world_of_view: expected ({views},) integers, got shape "
                         f"{tuple(raw.shape)} of {raw.dtype}")
    index = raw.astype(np.int64)
    if views and (index.min() < 0 or index.max() >= w):
        bad = int(index.min() if index.min() < 0 else index.max())
        raise UsageError(f"world_of_view: world {bad} is out of range (0..{w - 1})")
    return index


def render_batch(renderer: Any, cameras: Any, size: tuple[int, int], lights: LightsArg,
                 options: RenderOptions | None, linear: bool, depth: bool,
                 outputs: Iterable[str] | None, batch: int | str, device: str,
                 out: np.ndarray | None, given: WorldArgs | None = None,
                 overrides: dict[str, Any] | None = None, prep: Prepared | None = None) -> Any:
    """Renderer.render_batch (its docstring says what each argument is); `prep`: the call's
    Prepared where the caller kept it (BatchStep). Other threads' frames and batches wait
    (gpu/device.py Device.lock)."""
    with renderer.device.lock:
        return _render_batch(renderer, cameras, size, lights, options, linear, depth, outputs,
                             batch, device, out, given, overrides, prep)


def _render_batch(renderer: Any, cameras: Any, size: tuple[int, int], lights: LightsArg,
                  options: RenderOptions | None, linear: bool, depth: bool,
                  outputs: Iterable[str] | None, batch: int | str, device: str,
                  out: np.ndarray | None, given: WorldArgs | None,
                  overrides: dict[str, Any] | None, prep: Prepared | None) -> Any:
    r = renderer
    # The cameras, options and route: made once for a loop's calls (render/batch_cache.py)
    if prep is None:
        prep = batch_cache(r).prepared(r, cameras, size, options, overrides or {}, linear,
                                       depth, outputs, device, out, _options)
    views, opts, route, wanted = prep.views, prep.opts, prep.route, prep.wanted
    g = given or NO_WORLDS
    if g.times is not None:
        route, call, plan = _times_of(r, views, route, g)
    else:
        route, call, plan = _worlds_of(r, prep, lights, g)
    each = _each_view(r.state, views, plan)  # view by view, as `render` draws
    if route == "views" and g.times is not None and plan is None:  # (skins, morphs, pointers)
        frames = r.render_many((views.camera(i) for i in range(len(views))), lights, size, opts,
                               linear, depth, outputs=wanted or None, times=g.times,
                               animation=g.animation)
        # (the state as it was afterwards, as where the times are worlds: a batch poses its
        # views, not the renderer)
        return stack_views(r, _restoring(frames, apply_saved(r.state)), depth, wanted, out)
    if route == "views":  # (render/batch_route.py says when)
        return stack_views(r, r.render_many(each, lights, size, opts, linear, depth,
                                            outputs=wanted or None), depth, wanted, out)
    # (outputs besides the colour: the compute batch's own, else from their own frames, view
    # by view)
    extra = tuple(n for n in wanted if n != "color") if wanted else ()
    tiled = bool(extra) and route == "compute"
    color, dist = r.batch_path.run(route, views, size, lights, opts, linear, depth, batch, out,
                                   call, output_images(extra) if tiled else ())
    frames = (list(r.render_many(each, lights, size, opts, linear, outputs=extra))
              if extra and not tiled else [])
    r.last_stats = r.batch_path.stats  # the batch's (not the outputs' passes)
    return batch_result(color, dist, depth, wanted, frames, r.batch_path.images if tiled else None)


batch_call = render_batch  # (the name renderer.py imports: its own method is render_batch)


@dataclass(frozen=True)
class WorldArgs:
    """render_batch's world arguments as given."""

    worlds: Any
    world_of_view: Any
    quaternion: str
    visible: Any
    expand: str
    materials: Any
    space: str
    lights: Any
    environment: Any
    times: Any = None  # (B,) animation times, one a view
    animation: Any = None  # which animations `times` plays (None: all)

    @property
    def any(self) -> bool:
        return not (self.worlds is None and self.materials is None and self.lights is None
                    and self.environment is None)


NO_WORLDS = WorldArgs(None, None, "xyzw", None, "auto", None, "world", None, None)


def _worlds_of(r: Any, prep: Prepared, lights: LightsArg, g: WorldArgs
               ) -> tuple[str, WorldCall | None, WorldPlan | None]:
    """(route, the call's worlds for the batch path, the host's plan for view by view)."""
    route, opts = prep.route, prep.opts
    if not g.any:
        if g.world_of_view is not None or g.visible is not None:
            raise UsageError("world_of_view and world_visible need worlds= (the worlds' poses)")
        return route, None, None
    lit = g.lights is not None or g.environment is not None
    if lit and route not in ("compute", "layered"):
        raise UsageError("world_lights and world_environment render in a batch only (no "
                         "motion output, post steps, camera models or MSAA)")
    if g.worlds is not None and _on_cuda(g.worlds):
        if route == "views" or g.materials is not None or lit:
            raise UsageError("worlds on CUDA render in the batch only, without world_materials, "
                             "world_lights or world_environment (give those with NumPy poses); "
                             "this call may render view by view (the motion output, post steps, "
                             "MSAA, the fragment path's batch)")
        return route, _cuda_call(r, prep, g.worlds, g.world_of_view, g.quaternion, g.visible,
                                 g.space), None
    # (the frame's lights: what world_lights gives per world, and the factors' base rows)
    frame = () if not lit and g.materials is None else r.frame_lights(opts, lights)
    plan = _world_plan(r, prep, g, len(frame))
    if route in ("compute", "layered") and opts.shadows and _alpha_differs(r, plan.materials):
        if lit:
            raise UsageError("world_materials: a masked or blended material's alpha differs "
                             "between worlds, which the batch's shadow maps do not follow, "
                             "and world_lights/world_environment need the batch: give every "
                             "world that material's alpha, or shadows=False")
        route = "views"  # (view by view: each world's maps drawn with its own alpha)
    return route, _host_call(r, plan, g.expand, _factor_blocks(r, plan, frame, opts)), plan


def _alpha_differs(r: Any, wm: WorldMaterials | None) -> bool:
    """Whether worlds give a masked or blended material another base colour alpha than the
    state's: its cutoff shapes the material's shadows, and the worlds' shadow maps are
    drawn with the state's factors (the material table), so such a call goes view by view
    (docs/batch.md); a world's own alpha still decides what its views see."""
    if wm is None or "base_color" not in wm.values:
        return False
    cut = np.array([r.gpu_scene.materials[int(m)].alpha_mode in ("mask", "blend")
                    for m in wm.materials], bool)
    if not cut.any():
        return False
    state_alpha = base_factors(r.gpu_scene, r.state)[wm.materials[cut], 0, 3]
    return bool(np.any(wm.values["base_color"][:, cut, 3] != state_alpha))


def _times_of(r: Any, views: CameraBatch, route: str, g: WorldArgs
              ) -> tuple[str, WorldCall | None, WorldPlan | None]:
    """A batch whose views each see the scene's animations at their own time: the distinct
    times become worlds (the animated nodes' world matrices, vkpbr.scene.animation.sample over
    all of them at once); where the animations also drive skins, morph weights,
    KHR_animation_pointer properties or instances' copied skeletons (which the worlds do not
    hold: SceneState.pose_copies), view by view instead
    ("views" and no plan: render_many(times=))."""
    from vkpbr.scene.animation import animation_indices, sample

    if g.any or g.world_of_view is not None or g.visible is not None:
        raise UsageError("times= poses every view's world itself: give it without worlds=, "
                         "world_of_view=, world_visible=, world_materials=, world_lights= or "
                         "world_environment=")
    try:
        t = np.asarray(g.times, dtype=np.float64).reshape(-1) if np.ndim(g.times) else None
    except (TypeError, ValueError):  # (strings, complex numbers, ragged lists)
        t = None
    if t is None or len(t) != len(views) or not np.isfinite(t).all():
        raise UsageError(f"times: {len(views)} finite animation times (one a view) expected")
    scene, state = r.scene, r.state
    channels = [ch for i in animation_indices(scene, g.animation)
                for ch in scene.animations[i].channels]
    nodes = sorted({ch.node for ch in channels if ch.node is not None and ch.path != "weights"})
    deforms = bool(np.any(state.skinned)) or bool(state.copies) or any(
        ch.path == "weights" or ch.kind in ("mesh", "light", "camera", "material") for ch in channels)
    if not nodes or deforms:
        return "views", None, None
    unique, inverse = np.unique(t, return_inverse=True)
    local = np.broadcast_to(state.local, (len(unique), *state.local.shape)).copy()
    local[:, nodes] = sample(scene, unique, g.animation).local[:, nodes]
    slots = WorldSlots.of(state, nodes)
    poses = WorldPoses(state.tree.world(local)[:, slots.nodes], None)
    plan = WorldPlan(slots, poses, None, inverse.astype(np.int64).reshape(-1))
    return route, _host_call(r, plan, "auto"), plan


def _factor_blocks(r: Any, plan: WorldPlan, frame: tuple[Any, ...], opts: RenderOptions
                   ) -> np.ndarray | None:
    """The worlds' WorldFactors blocks (scene/worlds.py world_blocks: materials, the frame's
    lights, the environment), or None where the worlds give none of them."""
    if plan.materials is None and plan.lights is None and plan.environment is None:
        return None
    rows = np.array([(*li.color, li.intensity) for li in frame], np.float64).reshape(-1, 4)
    environment = (opts.env_intensity, float(np.radians(opts.env_rotation)))
    return world_blocks(plan.count, base_factors(r.gpu_scene, r.state), plan.materials, rows,
                        plan.lights, environment, plan.environment)


def _host_call(renderer: Any, plan: WorldPlan, expand: str,
               factors: np.ndarray | None = None) -> WorldCall:
    """NumPy worlds: their records made here (exact: "auto", "host"), or the poses handed to
    the GPU's kernel as CUDA tensors are ("gpu": float32, what the CUDA route computes); with
    `factors`, the worlds' WorldFactors blocks ((W, S, 4): materials, lights, environment)."""
    state = renderer.state
    slots, poses, index = plan.slots, plan.poses, plan.index
    if expand not in ("auto", "host", "gpu"):
        raise UsageError(f"world_expand {expand!r}: choose 'auto', 'host' or 'gpu'")
    if poses is None or slots is None:
        return WorldCall(index, factors=factors)
    if expand != "gpu":
        return WorldCall(index, records=world_records(state, slots, poses), factors=factors,
                         moved=slots.anchor >= 0)
    # The rows as given (7 floats: the kernel makes the rotation) or the matrices (16)
    rows = poses.rows
    flat = rows if rows is not None else poses.matrices
    shown = poses.visible

    def fill(kernel: Any) -> None:
        kernel.write_numpy(flat, shown)

    gw = GpuWorlds(slots, poses.count, 7 if rows is not None else 16, poses.wxyz,
                   shown is not None, fill, local=poses.local)
    return WorldCall(index, gpu=gw, factors=factors)


def _on_cuda(value: Any) -> bool:
    return hasattr(value, "device") and getattr(value.device, "type", "") == "cuda"


def _cuda_call(renderer: Any, prep: Prepared, worlds: Any, world_of_view: Any, quaternion: str,
               visible: Any, space: str = "world") -> WorldCall:
    """Worlds whose poses are CUDA tensors: shapes and dtypes checked here (once for a loop's
    calls: BatchCache.world_shape), the values by the worlds kernel on the GPU; copied
    device to device into the kernel's inputs."""
    import torch

    cache = batch_cache(renderer)
    slots = _slots(renderer)
    shape = tuple(worlds.shape)
    ws = cache.world_shape(prep, slots, shape, worlds.dtype, quaternion, space, world_of_view,
                           lambda: _cuda_shape(prep, slots, worlds, world_of_view, quaternion,
                                               space))
    _same_gpu(renderer, cache, worlds)
    # NaN, infinity and zero quaternions are found by the worlds kernel on the GPU (no read
    # back before the batch: render/worlds.py), their worlds' draws hidden and reported.
    p = worlds if worlds.dtype == torch.float32 and not worlds.requires_grad else \
        worlds.detach().to(torch.float32)
    p = p if p.is_contiguous() else p.contiguous()
    w, n = shape[0], len(slots)
    shown = None
    if visible is not None:
        if tuple(visible.shape) != (w, n):
            raise UsageError(f"world_visible: shape {tuple(visible.shape)}, expected ({w}, {n})")
        shown = (visible.to(torch.int32) if _on_cuda(visible)
                 else torch.as_tensor(np.asarray(visible), device=p.device).to(torch.int32)).contiguous()

    def fill(kernel: Any) -> None:
        kernel.write_cuda(p, shown)

    return WorldCall(ws.index, gpu=GpuWorlds(slots, w, ws.floats, ws.wxyz, shown is not None,
                                             fill, cuda=True, local=ws.local))


def _cuda_shape(prep: Prepared, slots: WorldSlots, worlds: Any, world_of_view: Any,
                quaternion: str, space: str) -> WorldShape:
    """The checks of CUDA poses that do not read their values (shape, dtype, quaternion
    order, space, the world of each view), as a WorldShape."""
    n = len(slots)
    shape = tuple(worlds.shape)
    if len(shape) == 3 and shape[1:] == (n, 7):
        floats = 7
    elif len(shape) == 4 and shape[1:] == (n, 4, 4):
        floats = 16
    else:
        raise UsageError(f"worlds: poses of shape {shape} for {n} slot node(s); give "
                         f"(W, {n}, 4, 4) world matrices or (W, {n}, 7) position + quaternion rows")
    if quaternion not in ("xyzw", "wxyz"):
        raise UsageError(f"quaternion {quaternion!r}: choose 'xyzw' or 'wxyz'")
    local = check_space(space)
    if local and slots.nested:
        raise UsageError("worlds: space='local' with a chosen node below another chosen "
                         "node; give world poses (space='world')")
    if not worlds.is_floating_point():
        raise UsageError(f"worlds: a tensor of {worlds.dtype}; give float32 or float64")
    index = _world_index(len(prep.views), shape[0], world_of_view)
    index.flags.writeable = False  # (shared by the calls that hit the cache)
    return WorldShape(slots, floats, quaternion == "wxyz", local, index)


def _same_gpu(renderer: Any, cache: BatchCache, tensor: Any) -> None:
    dev = renderer.device
    index = cache.cuda_index(dev)  # (found once, with CUDA's availability: both are slow)
    if tensor.device.index not in (None, index):
        raise UsageError(f"worlds: a tensor on {tensor.device}, but the renderer draws on "
                         f"cuda:{index} ({dev.info.name}); move it there with .to('cuda:{index}')")


def _each_view(state: SceneState, views: CameraBatch, plan: WorldPlan | None) -> Iterator[Any]:
    """The views' cameras one by one; in a batch of worlds each taken with its world applied
    to `state` (and the state as it was once the last is drawn or the caller stops)."""
    if plan is None:
        yield from (views.camera(i) for i in range(len(views)))
        return
    saved = apply_saved(state)
    try:
        for i in range(len(views)):
            w = int(plan.index[i])
            if plan.slots is not None and plan.poses is not None:
                apply_world(state, plan.slots, plan.poses, w)
            if plan.materials is not None:
                apply_materials(state, plan.materials, w)
            yield views.camera(i)
    finally:
        saved()


def apply_saved(state: SceneState) -> Any:
    """A function that puts `state`'s poses, visibility, material overrides, morph weights,
    animation pointers and time back as they are now."""
    local, visible = state.local.copy(), state.visible.copy()
    materials = {k: dict(v) for k, v in state.materials.items()}
    animated = (dict(state.weights), dict(state.pointers), state.time, state._chosen)
    every = np.arange(len(state.tree))

    def restore() -> None:
        state.local[:] = local
        state.weights, state.pointers, state.time, state._chosen = animated
        state.set_visible(every, visible)  # (a change: the frames copy the state again)
        if state.materials != materials:
            state.materials = materials
            state.material_version += 1
            state.version += 1

    return restore


def _restoring(frames: Iterator[Any], restore: Any) -> Iterator[Any]:
    """`frames`, then `restore()` (also where the caller stops early or an error ends them)."""
    try:
        yield from frames
    finally:
        restore()


def apply_materials(state: SceneState, wm: WorldMaterials, w: int) -> None:
    """Set world `w`'s factors of the named materials on `state` (set_material)."""
    for k, material in enumerate(wm.materials):  # (the factors' names are set_material's)
        given = {f: (v[w, k] if v.shape[2] > 1 else float(v[w, k, 0]))
                 for f, v in wm.values.items()}
        state.set_material(int(material), **given)


def apply_world(state: SceneState, slots: WorldSlots, poses: WorldPoses, w: int) -> None:
    """Pose `state` as world `w`: each slot node at its world pose (parents first, so a
    chosen node below another takes its own pose) or its local one, hidden where the world
    hides it."""
    if poses.local:
        state.set_poses(slots.nodes, poses.matrices[w], space="local")
        if poses.visible is not None:
            state.set_visible(slots.nodes, poses.visible[w])
        return
    depth = np.zeros(len(state.tree), np.int64)
    for d, level in enumerate(state.tree.levels()):
        depth[level] = d
    depth = depth[slots.nodes]
    for level in np.unique(depth):
        pick = np.flatnonzero(depth == level)
        state.set_poses(slots.nodes[pick], poses.matrices[w, pick], space="world")
    if poses.visible is not None:
        state.set_visible(slots.nodes, poses.visible[w])


class BatchStep:
    """A loop's render_batch made once (Renderer.batch_step): its cameras, size, options and
    world arguments fixed, the poses (and visibility) given each call. Calling it is
    `render_batch` with those arguments, through the same cache and replays
    (render/batch_replay.py), without render_batch's argument binding each call: the
    arguments are bound here, once."""

    def __init__(self, renderer: Any, cameras: Any, size: tuple[int, int],
                 kwargs: dict[str, Any]) -> None:
        import inspect

        if not isinstance(cameras, CameraBatch):  # (so that the cache holds it)
            cameras = as_camera_batch(cameras, renderer.default_camera())
        limit = int(renderer.device.limits.maxImageDimension2D)
        self.renderer, self.cameras, self.size = renderer, cameras, frame_size(size, limit)
        for name in ("worlds", "world_visible", "cameras", "size"):
            if name in kwargs:
                raise UsageError(f"batch_step: {name} is given each call, not to batch_step")
        self.view = _frames_view(kwargs)
        self.kwargs = kwargs
        params = inspect.signature(type(renderer).render_batch).parameters
        bound = {k: v.default for k, v in params.items()
                 if k not in ("self", "cameras", "size", "option_overrides")}
        bound.update((k, v) for k, v in kwargs.items() if k in bound)
        self._bound = bound
        self._overrides = {k: v for k, v in kwargs.items() if k not in bound}
        self._prep: tuple[int, Prepared] | None = None  # (the cache's version, the Prepared)
        self._lane: _Lane | None = None  # a replayed CUDA step's short way (`_lane_step`)
        self._cuda_shape: tuple[int, ...] | None = None  # the last CUDA poses' (worlds_input)
        self.lane_steps = 0  # steps that took it (tests read it)

    def __call__(self, worlds: Any = None, world_visible: Any = None, **more: Any) -> Any:
        """render_batch(cameras, size, worlds=worlds, world_visible=world_visible, the step's
        arguments, `more`); other threads' frames and batches wait (Device.lock)."""
        with self.renderer.device.lock:
            if not self.view:
                return self._call(worlds, world_visible, more)
            path = self.renderer.batch_path
            path.frames_view = True  # (the call's CUDA frames not cloned: _cuda_tensor)
            try:
                return self._call(worlds, world_visible, more)
            finally:
                path.frames_view = False

    def _call(self, worlds: Any, world_visible: Any, more: dict[str, Any]) -> Any:
        if more:
            return self.renderer.render_batch(self.cameras, self.size, worlds=worlds,
                                              world_visible=world_visible,
                                              **{**self.kwargs, **more})
        if world_visible is None and self._lane is not None:
            got = self._lane_step(self._lane, worlds)
            if got is not None:
                return got
        b = self._bound
        prep = self._prepared(b)
        given = WorldArgs(worlds, b["world_of_view"], b["quaternion"], world_visible,
                          b["world_expand"], b["world_materials"], b["space"], b["world_lights"],
                          b["world_environment"], b["times"], b["animation"])
        replays = self.renderer.batch_path.replays
        replayed = replays.replayed
        result = render_batch(self.renderer, self.cameras, self.size, b["lights"], b["options"],
                              b["linear"], b["depth"], b["outputs"], b["batch"], b["device"],
                              b["out"], given, self._overrides, prep)
        # (a lane only once a step replayed: a loop whose steps never do, e.g. one that moves
        # the state between them, makes none and pays nothing for it)
        self._lane = (self._make_lane(prep, worlds, world_visible)
                      if replays.replayed > replayed else None)
        if _on_cuda(worlds):
            self._cuda_shape = tuple(worlds.shape)
        return result

    # --- the short way of a replayed CUDA step ----------------------------------------------
    # A simulator's loop gives the same CUDA tensor (or one alike) each step. Once a step
    # replayed (render/batch_replay.py), the next one alike needs none of render_batch's
    # argument handling: the poses' checks that do not read values (shape, dtype, device,
    # contiguity) hold for a tensor of the same signature, the Prepared and the WorldCall are
    # the last step's, and the replay key is computed afresh (so that whatever would stop a
    # replay on the full way stops it here: the state's version, the views, the kernel, the
    # ring's frame count). Any difference takes the full way.
    def _make_lane(self, prep: Prepared, worlds: Any, world_visible: Any) -> _Lane | None:
        """The lane for steps like this one, where it replayed or may replay next time."""
        b, r = self._bound, self.renderer
        if (world_visible is not None or not _on_cuda(worlds) or b["out"] is not None
                or b["lights"] is not None or b["depth"] or prep.wanted or b["times"] is not None
                or b["world_materials"] is not None or b["world_lights"] is not None
                or b["world_environment"] is not None or not _fixed(b["world_of_view"]) or self._prep is None):
            return None
        signature = _signature(worlds)
        if signature is None:
            return None
        held: list[Any] = [None]
        call = _cuda_call(r, prep, worlds, b["world_of_view"], b["quaternion"], None, b["space"])
        if call.gpu is None:
            return None

        def fill(kernel: Any) -> None:
            kernel.write_cuda(held[0], None)

        call = dataclasses.replace(call, gpu=dataclasses.replace(call.gpu, fill=fill))
        return _Lane(signature, _slots(r), self._prep[0], prep, call, held)

    def _lane_step(self, lane: _Lane, worlds: Any) -> Any:
        """This step by the lane (its frames), or None where it must take the full way."""
        r = self.renderer
        prep = lane.prep
        if (_signature(worlds) != lane.signature or _slots(r) is not lane.slots
                or batch_cache(r).version != lane.version or prep.holds[0] is not r.parts):
            return None
        b, path = self._bound, r.batch_path
        path._calls += 1
        path._finish_pending()
        path._ordered = False
        path.world_call = lane.call
        lane.held[0] = worlds
        try:
            key = replay_key(path, prep.route, prep.views, self.size, None, prep.opts,
                             b["linear"], False, b["batch"])
            got = None if key is None else replay(path, key, None)
        finally:
            path.world_call = None
            lane.held[0] = None
        if got is None:
            return None
        self.lane_steps += 1
        r.last_stats = path.stats
        return got[0]

    def worlds_input(self) -> Any:
        """The next step's poses in the renderer's own input memory: a float32 CUDA tensor of
        the last step's CUDA poses' shape, which a step given it reads in place, with no
        copy (what a simulator that can write its poses into a given tensor saves a step:
        docs/batch.md "Worlds"). Write it on torch's current stream (a step's end queues the
        wait for the batch that read it on that stream: earlier writes elsewhere must be
        ordered by the caller). Valid while the renderer is open; after a step of more
        worlds, ask again (the old one still reads as memory, but the batch no longer)."""
        shape = self._cuda_shape
        kernel = self.renderer.batch_path.world_kernel
        view = None if shape is None or kernel is None else kernel.input_view(shape)
        if view is None:
            raise UsageError("batch_step.worlds_input: call the step once with CUDA poses "
                             "(device='cuda' worlds) first: their shape sizes the input")
        return view

    def _prepared(self, b: dict[str, Any]) -> Prepared:
        """The call's Prepared: the one kept from the last call while the renderer's cache
        holds it (not cleared, the same scene's parts), else the cache's lookup (which also
        checks `out`, each call where one is given)."""
        r, cache, kept = self.renderer, batch_cache(self.renderer), self._prep
        if (kept is not None and kept[0] == cache.version and b["out"] is None
                and kept[1].holds[0] is r.parts):
            return kept[1]
        prep = cache.prepared(r, self.cameras, self.size, b["options"], self._overrides,
                              b["linear"], b["depth"], b["outputs"], b["device"], b["out"],
                              _options)
        # (kept only where the cache keeps it: a key of identities and plain values)
        self._prep = (cache.version, prep) if cache.keeps(prep) else None
        return prep


@dataclass(frozen=True)
class _Lane:
    """What a BatchStep's short way keeps (`BatchStep._make_lane`): the poses' signature
    (`_signature`), the world slots, the batch cache's version and the Prepared it was made
    at, the step's WorldCall, whose fill writes the tensor in `held[0]` (set for the step)."""

    signature: tuple
    slots: WorldSlots
    version: int
    prep: Prepared
    call: WorldCall
    held: list[Any]


def _signature(tensor: Any) -> tuple | None:
    """What `_cuda_call`'s checks read of CUDA poses, where a step may skip them: shape, dtype,
    device, contiguity, float32 without a gradient (None: not such a tensor)."""
    import torch

    if not _on_cuda(tensor) or tensor.requires_grad or tensor.dtype is not torch.float32 \
            or not tensor.is_contiguous():
        return None  # (the full way converts these: a new tensor each step)
    return (tuple(tensor.shape), tensor.device)


def _fixed(world_of_view: Any) -> bool:
    """Whether `world_of_view` cannot change between steps (BatchCache.world_shape's rule)."""
    return world_of_view is None or (isinstance(world_of_view, np.ndarray)
                                     and not world_of_view.flags.writeable)


def _frames_view(kwargs: dict[str, Any]) -> bool:
    """batch_step's `frames` ("copy", the default: each call's frames its own; "view": with
    device="cuda", the frames as a view of the renderer's exported memory, no clone a step,
    rewritten by the next call), taken out of `kwargs`."""
    frames = kwargs.pop("frames", "copy")
    if frames not in ("copy", "view"):
        raise UsageError(f"batch_step: frames {frames!r}: choose 'copy' or 'view'")
    if frames == "view" and kwargs.get("device", "cpu") != "cuda":
        raise UsageError("batch_step: frames='view' is for device='cuda' (NumPy frames: give "
                         "out= for no new array a step)")
    return frames == "view"


def batch_step(renderer: Any, cameras: Any, size: tuple[int, int] = (128, 128),
               **kwargs: Any) -> BatchStep:
    """Renderer.batch_step: a loop's render_batch made once, e.g.
    `step = r.batch_step(cams, (128, 128), device="cuda", shadows=False)`, then
    `frames = step(worlds=poses)` each step. `kwargs`: render_batch's arguments but the
    cameras, size, worlds and world_visible (given each call), and `frames`: "copy" (the
    default) or "view" (device="cuda": the frames not cloned; valid until the next call;
    work queued on torch's current stream before it reads them safely). docs/batch.md
    "Worlds"."""
    return BatchStep(renderer, cameras, size, kwargs)
