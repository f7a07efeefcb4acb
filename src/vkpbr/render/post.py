"""The post steps: each a class here, its kernel shaders/post_<name>.comp and its option
(render/options.py POST_OPTIONS); the machinery they run on is render/post_stage.py. The
camera models' resample (`lens_frame`, `lens_steps`) runs first where the camera has a lens.

Camera models (scene/lens.py): a camera whose model is not the pinhole is drawn as the wider
pinhole `lens_frame` plans (same pose; its image covers every ray of the model's pixels, as
densely as the model's densest pixel, at most LENS_PIXELS times the output's pixels), into
the HDR target of that size; `lens_steps` then maps it to the model's image
(shaders/post_lens.comp: each output pixel's ray by Newton's method, lens.glsl, then the
source's radiance there, bilinear) and the dataset outputs through the same mapping
(post_lens_outputs.comp: ids nearest, depth bilinear in 1/z within one instance, else
nearest); the other post steps and the encode follow at the model's size.

Bloom: bright light spreading over its surroundings, as a lens and an eye see it:
Filament's and pygfx's physically based bloom (shaders/post_bloom.comp): no threshold; the
radiance downsampled into up to BLOOM_LEVELS half-size images, upsampled back averaging
them, and the result mixed in: color = mix(color, bloom, strength). Each step keeps the
image's mean at every size (a step between levels of other than 2:1, an odd size's, by
exact area weights: the post_bloom_odd build), so the frame's total radiance is kept (to
~1e-7; tests/gpu/test_post.py). `--bloom STRENGTH` (0..1; 0: off).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.graph import Step
from vkpbr.render.lens_cube import CubeFrame, cube_frame, cube_steps, is_cube
from vkpbr.render.options import POST_OPTIONS, RenderOptions, SensorNoise
from vkpbr.render.post_stage import (
    PostContext,
    PostStep,
    enabled_post,
    encode_tonemap,
    post_unavailable,
)
from vkpbr.scene import lens as lenses
from vkpbr.scene.types import Camera

__all__ = ["Bloom", "BLOOM_LEVELS", "Noise", "noise_key", "noise_keys", "post_steps",
           "BatchPost", "batch_post", "batch_post_supported", "batch_lens", "batch_draw_size",
           "batch_post_bytes", "LensFrame", "check_lens", "lens_frame", "lens_steps",
           "LENS_OUTPUTS", "LENS_PIXELS"]

BLOOM_LEVELS = 6  # the smallest is 1/64 of the frame: a glow some tens of pixels wide
_DOWN, _UP, _MIX = 0, 1, 2


def level_sizes(extent: tuple[int, int]) -> list[tuple[int, int]]:
    """The chain's sizes: each half the one above (rounded up), while at least 2 x 2."""
    sizes, (w, h) = [], extent
    while len(sizes) < BLOOM_LEVELS and min(w, h) >= 4:
        w, h = -(-w // 2), -(-h // 2)
        sizes.append((w, h))
    return sizes


def _bloom_kernel(larger: tuple[int, int], smaller: tuple[int, int]) -> str:
    """The bloom's build for a step between a level and the one below it: "post_bloom" where
    it is 2:1 in both axes (constant weights), else "post_bloom_odd" (area weights: an odd
    size's last row or column had counted twice)."""
    even = all(big == 2 * small for big, small in zip(larger, smaller, strict=True))
    return "post_bloom" if even else "post_bloom_odd"


class Bloom(PostStep):
    option = "bloom"

    def steps(self, ctx: PostContext, value: float) -> list[Step]:
        n, tw, th, rows = ctx.view_tiles()
        sizes = level_sizes((tw, th))  # a view's; a batch's levels are atlases of them
        if not sizes:
            return []
        cols = -(-n // rows)
        atlas = [(cols * w, rows * h) for w, h in sizes]
        names = [f"bloom{i}" for i in range(len(sizes))]
        views = [ctx.transient(nm, s) for nm, s in zip(names, atlas, strict=True)]

        def push(mode: int, src: tuple[int, int], dst: tuple[int, int], value: float = 0.0
                 ) -> np.ndarray:
            out = np.array([mode, 0, 0, n, rows, *src, *dst], np.uint32)
            out.view(np.float32)[1 if mode == _MIX else 2] = value
            return out

        steps, src, src_name, src_tile = [], ctx.color_view, ctx.color_name, (tw, th)
        for name, view, size, extent in zip(names, views, sizes, atlas, strict=True):
            steps.append(Step(f"bloom_down.{name}", ctx.dispatch(
                _bloom_kernel(src_tile, size), push(_DOWN, src_tile, size), src, view, extent),
                ((src_name, "storage_read"), (name, "storage")), timed=False))
            src, src_name, src_tile = view, name, size
        for k in range(len(sizes) - 2, -1, -1):  # level k becomes the mean of levels k..
            steps.append(Step(f"bloom_up.{names[k]}", ctx.dispatch(
                _bloom_kernel(sizes[k], sizes[k + 1]),
                push(_UP, sizes[k + 1], sizes[k], 1.0 / (len(sizes) - k)),
                views[k + 1], views[k], atlas[k]),
                ((names[k + 1], "storage_read"), (names[k], "storage")), timed=False))
        steps.append(Step("bloom", ctx.dispatch(
            _bloom_kernel((tw, th), sizes[0]), push(_MIX, sizes[0], (tw, th), value), views[0],
            ctx.color_view,
            ctx.extent), ((names[0], "storage_read"), (ctx.color_name, "storage"))))
        return steps


class Noise(PostStep):
    """A sensor's noise (render/options.py SensorNoise): colour noise on the radiance
    (post_noise.comp, in place), depth noise and dropouts on the dataset outputs' depth and
    range where the frame has them (post_noise_depth.comp into a transient, then
    post_noise_copy.comp back). Random numbers from the frame's key (seed and view:
    `noise_key`), so the command buffer is the same for every frame."""

    option = "noise"

    def steps(self, ctx: PostContext, value: SensorNoise) -> list[Step]:
        steps = []
        if value.colour:
            n, tw, th, rows = ctx.view_tiles()
            push = np.array([ctx.first_key(), 0, 0, tw, th, rows, n], np.uint32)
            push.view(np.float32)[1:3] = (value.full_well, value.read_noise)
            steps.append(Step("noise", ctx.dispatch("post_noise", push, ctx.color_view,
                                                    ctx.color_view, ctx.extent, keys=True),
                              ((ctx.color_name, "storage"),)))
        if value.depth and ctx.outputs:
            steps += _depth_noise(ctx, value)
        return steps


def _depth_noise(ctx: PostContext, value: SensorNoise) -> list[Step]:
    depth_name = ctx.outputs_prefix + "out_depth_range"
    normal_name = ctx.outputs_prefix + "out_normal"
    depth, normal = ctx.resources[depth_name].view, ctx.resources[normal_name].view
    noisy = ctx.transient("noise_depth", ctx.extent)
    push = np.zeros(10, np.float32)
    push.view(np.uint32)[0] = ctx.frame_index
    push[1:] = (value.baseline, value.disparity_sigma, value.disparity_step, value.lateral_sigma,
                value.grazing_start, value.grazing_end, value.edge_jump, value.edge_rate,
                value.max_range)
    record = ctx.dispatch("post_noise_depth", push, depth, noisy, ctx.extent, normal, keys=True)
    back = ctx.dispatch("post_noise_copy", np.zeros(1, np.uint32), noisy, depth, ctx.extent)
    return [Step("noise_depth", record, ((depth_name, "storage_read"), (normal_name, "storage_read"),
                                         ("noise_depth", "storage")), timed=False),
            Step("noise_depth_copy", back, (("noise_depth", "storage_read"), (depth_name, "storage")))]


def noise_key(noise: SensorNoise, camera: Camera, extent: tuple[int, int]) -> np.ndarray:
    """The frame key of `camera` at `extent` with `noise` (noise.glsl FrameKey, 128 bytes):
    a hash of the seed and the camera (pose, intrinsics, lens: the view, `view_hashes`), the
    output's K and camera-from-world rotation (OpenCV axes)."""
    K = camera.intrinsics(extent)
    R = camera.world_from_camera("opencv")[:3, :3].T
    intr = camera.pixel_intrinsics if camera.pixel_intrinsics is not None else (math.nan,) * 6
    key = np.zeros(32, np.float32)
    key.view(np.uint32)[0] = view_hashes(
        noise.seed, extent, np.array([camera.eye]), np.array([camera.target]),
        np.array([camera.up]), np.array([camera.yfov_deg]), np.array([intr], np.float64),
        ((camera.model, tuple(camera.distortion)),))[0]
    key[4:8] = (K[0, 0], K[1, 1], K[0, 2], K[1, 2])
    for i in range(3):
        key[8 + 4 * i: 11 + 4 * i] = R[i]
    return key


def noise_keys(noise: SensorNoise, views: Any, extent: tuple[int, int]) -> np.ndarray:
    """(B, 32) float32: each view's frame key for a compute batch's colour noise: the hash
    `noise_key` gives views.camera(i) (the camera a batch view is rendered alone as), made
    for all views at once; K and the rotation are left 0 (the depth noise's, not the
    batch's)."""
    n = len(views)
    intr = views.intrinsics if views.intrinsics is not None else np.full((n, 6), math.nan)
    keys = np.zeros((n, 32), np.float32)
    keys.view(np.uint32)[:, 0] = view_hashes(noise.seed, extent, views.eye, views.target,
                                             views.up, views.yfov_deg, intr, views.lenses)
    return keys


_SPLITMIX = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB))


def view_hashes(seed: int, extent: tuple[int, int], eye: np.ndarray, target: np.ndarray,
                up: np.ndarray, yfov: np.ndarray, intrinsics: np.ndarray,
                lenses_: Any) -> np.ndarray:
    """(B,) uint32: a hash of the seed and each view (its float64 eye, target, up, vertical
    field of view, pixel intrinsics (NaN: none), lens model and distortion, and the output
    size), SplitMix64's finaliser folded over the values' bits: vectorised, so a batch's
    4,096 keys take about 14 ms, and bit for bit the hash a single frame's camera gets."""
    n = len(eye)
    lens_rows = np.zeros((n, 9))
    if lenses_ is not None:
        for i, (model, distortion) in enumerate(lenses_):
            lens_rows[i, 0] = lenses.MODEL_IDS[model]
            lens_rows[i, 1:1 + len(distortion)] = distortion
    rows = np.concatenate([np.asarray(a, np.float64).reshape(n, -1) for a in
                           (eye, target, up, yfov, intrinsics, lens_rows,
                            np.broadcast_to(np.array(extent, np.float64), (n, 2)))], axis=1)
    bits = np.ascontiguousarray(rows).view(np.uint64)
    h = np.full(n, ((seed & 0xFFFFFFFF) * int(_SPLITMIX[0])) & 0xFFFFFFFFFFFFFFFF, np.uint64)
    with np.errstate(over="ignore"):  # (uint64 arithmetic wraps, as the hash means it to)
        for col in bits.T:
            h = (h ^ col) + _SPLITMIX[0]
            h = (h ^ (h >> np.uint64(30))) * _SPLITMIX[1]
            h = (h ^ (h >> np.uint64(27))) * _SPLITMIX[2]
            h = h ^ (h >> np.uint64(31))
    return ((h ^ (h >> np.uint64(32))) & np.uint64(0xFFFFFFFF)).astype(np.uint32)


def batch_post_supported(options: RenderOptions, views: Any, size: tuple[int, int],
                         depth: bool) -> bool:
    """Whether a compute batch takes `options`' post steps and `views`' lenses itself
    (render/batch_route.py; else its views render one by one): colour noise, over the atlas
    in one dispatch, each tile its view's key; bloom, each tile its own chain; a camera
    model where every view has the same one (model, distortion, intrinsics: one source
    size, `batch_lens`). Not yet: the depth noise and a lens batch's depth (the batch reads
    its depth buffer, not the outputs that carry them), views of different lenses."""
    wanted = dict(enabled_post(options))
    if views.lenses is not None and (depth or batch_lens(views, size) is None):
        return False
    noise = wanted.pop("noise", None)
    wanted.pop("bloom", None)
    return not wanted and not (depth and noise is not None and noise.depth)


def batch_lens(views: Any, size: tuple[int, int], max_side: int = 1 << 14
               ) -> tuple[LensFrame, Any] | None:
    """(view 0's LensFrame, the batch of source pinholes to draw) where every view of `views`
    has one lens and one set of intrinsics (so one source plan: view i's source is view 0's
    at view i's pose, as `lens_frame` plans it alone), else None (and None without lenses)."""
    if views.lenses is None or any(lens != views.lenses[0] for lens in views.lenses):
        return None
    for values in (views.intrinsics, views.yfov_deg):
        if values is not None and not (np.isnan(values).all() or (values == values[0]).all()):
            return None
    frame = lens_frame(views.camera(0), size, max_side)
    if frame is None or isinstance(frame, CubeFrame):  # (cube faces: view by view)
        return None
    src = frame.camera
    intr = np.tile(np.array(src.pixel_intrinsics, np.float64), (len(views), 1))
    source = dataclasses.replace(views, intrinsics=intr, lenses=None,
                                 yfov_deg=np.full(len(views), src.yfov_deg))
    return frame, source


@dataclasses.dataclass(frozen=True)
class BatchPost:
    """A compute batch's post stage (render/batch_path.py): the HDR atlas it draws into
    (None: no post steps), the steps, the encode's tone map, the options and linear flag
    its shading takes (no tone map: the encode's); with a lens the views drawn (the source
    pinholes), their tile size and the resample's marker for FrameSpec.lens."""

    drawn: Any
    post: tuple[tuple[str, Any], ...]
    tonemap: int
    shading: RenderOptions
    linear: bool
    views: Any = None
    size: tuple[int, int] = (0, 0)
    lens: tuple[float, ...] = ()


def batch_post(parts: Any, options: RenderOptions, views: Any, size: tuple[int, int],
               grid: tuple[int, int], target: Any, copy: tuple[str, ...], linear: bool
               ) -> BatchPost:
    """The post stage of a compute batch of `views` (tiles of `size`, `grid` columns and
    rows) into the atlas `target`: with post steps or lenses, the HDR atlas it draws into and
    every view's noise key and lens constants written (the device waited for and the
    recordings dropped where their buffers grow)."""
    post = enabled_post(options)
    lens = batch_lens(views, size, int(parts.device.limits.maxImageDimension2D))
    if not post and lens is None:
        return BatchPost(None, (), 0, options, linear, views, size)
    kernels = parts.post()
    rows: list[tuple[str, np.ndarray]] = []
    if options.noise is not None and options.noise.colour:
        rows.append(("keys", noise_keys(options.noise, views, size)))
    drawn_views, drawn_size, marker = views, size, ()
    if lens is not None:
        frame, drawn_views = lens
        drawn_size, marker = frame.extent, (float(frame.extent[0]), float(frame.extent[1]))
        rows.append(("lens", np.tile(_lens_push(frame.push), (len(views), 1))))
    if any(kernels.view_keys_stale(len(views), name) for name, _ in rows):
        parts.device.wait_idle()
        parts.recorder.free()
    for name, data in rows:
        kernels.write_view_keys(data, name)
    shading = options if options.tonemap is None else dataclasses.replace(options, tonemap=None)
    extent = (grid[0] * drawn_size[0], grid[1] * drawn_size[1])
    return BatchPost(parts.targets.post(target, copy, extent), post,
                     encode_tonemap(options, linear), shading, True, drawn_views, drawn_size,
                     marker)


def batch_draw_size(views: Any, size: tuple[int, int], max_side: int) -> tuple[int, int]:
    """The tile size a compute batch of `views` draws: `size`, or a lens batch's source."""
    lens = batch_lens(views, size, max_side)
    return size if lens is None else lens[0].extent


def batch_post_bytes(options: RenderOptions, views: Any, size: tuple[int, int],
                     drawn: tuple[int, int]) -> int:
    """Device bytes a compute batch's post stage adds per output pixel (for its views per
    submission): the HDR atlas (RGBA32F at the `drawn` tile size: a lens batch's sources
    are larger) and a transient of the output's size (the resample's, the bloom's levels
    and the noise's are at most that)."""
    if not enabled_post(options) and views.lenses is None:
        return 0
    return 16 * -(-drawn[0] * drawn[1] // (size[0] * size[1])) + 16


def post_steps() -> dict[str, type[PostStep]]:
    """Every post step by its option, in POST_OPTIONS' order (each row needs its class)."""
    classes = {cls.option: cls for cls in PostStep.__subclasses__()}
    return {row.field: classes[row.field] for row in POST_OPTIONS}


# --- camera models -----------------------------------------------------------------------
LENS_PIXELS = 8  # the source pinhole's pixels at most this many times the output's
LENS_GRANULE = 64  # source sizes in whole 64s: similar intrinsics share one HDR target
# The dataset outputs the resample maps, in post_lens_outputs.comp's binding order.
LENS_OUTPUTS = ("out_ids", "out_depth_range", "out_normal", "out_normal_geometric")


class LensFrame(tuple):
    """(source camera, source size (W, H), the resample's push constants as a tuple): what
    a frame of a camera with a lens draws and resamples (hashable: FrameSpec keeps the push)."""

    @property
    def camera(self) -> Camera:
        return self[0]

    @property
    def extent(self) -> tuple[int, int]:
        return self[1]

    @property
    def push(self) -> tuple[float, ...]:
        return self[2]


def check_lens(camera: Camera, target: object, compute_path: bool) -> None:
    """UsageError where frames of `target` cannot resample to `camera`'s model."""
    why = post_unavailable(target, compute_path)
    if why is not None:
        raise UsageError(f"camera model {camera.model!r} not available here: {why}")


def lens_frame(camera: Camera, extent: tuple[int, int], max_side: int
               ) -> LensFrame | CubeFrame | None:
    """The wide pinhole a frame of `camera` at `extent` is drawn as, and the resample's
    constants; None for a pinhole (drawn directly); a fisheye wider than one pinhole renders
    (150 degrees) its cube faces (render/lens_cube.py). UsageError for an `opencv` lens
    beyond 150 degrees."""
    if camera.model == "pinhole":
        return None
    K = camera.intrinsics(extent)
    if _wide(camera.model, tuple(camera.distortion), tuple(K.ravel().tolist()), extent):
        return cube_frame(camera, K, extent, LENS_PIXELS * extent[0] * extent[1], max_side)
    plan = _plan(camera.model, tuple(camera.distortion), tuple(K.ravel().tolist()), extent,
                 max_side)
    f, cx, cy, (w, h) = plan
    source = Camera(eye=camera.eye, target=camera.target, up=camera.up, znear=camera.znear,
                    zfar=camera.zfar, yfov_deg=math.degrees(2.0 * math.atan(h / (2.0 * f))),
                    pixel_intrinsics=(f, f, cx, cy, w, h))
    c = lenses.distortion_vector(camera.model, camera.distortion).tolist()
    c += [0.0] * (8 - len(c))
    push = (K[0, 0], K[1, 1], K[0, 2], K[1, 2], f, f, cx, cy, *c,
            float(lenses.MODEL_IDS[camera.model]))
    return LensFrame((source, (w, h), tuple(float(v) for v in push)))


@functools.lru_cache(maxsize=64)
def _wide(model: str, distortion: tuple[float, ...], k: tuple[float, ...],
          extent: tuple[int, int]) -> bool:
    """Whether a fisheye's rays reach beyond what one pinhole renders (scene/lens.py)."""
    return model in ("opencv_fisheye", "equidistant") and lenses.widest_ray(
        model, distortion, np.array(k).reshape(3, 3), extent) > lenses.MAX_PINHOLE_ANGLE_DEG + 1e-9


@functools.lru_cache(maxsize=64)
def _plan(model: str, distortion: tuple[float, ...], k: tuple[float, ...],
          extent: tuple[int, int], max_side: int) -> tuple[float, float, float, tuple[int, int]]:
    """scene/lens.py source_view, kept per lens and size (a run of frames has one)."""
    view = lenses.source_view(model, distortion, np.array(k).reshape(3, 3),
                              extent, LENS_PIXELS * extent[0] * extent[1], max_side,
                              LENS_GRANULE)
    return view.focal, view.cx, view.cy, view.size


def _lens_push(push: tuple[float, ...]) -> np.ndarray:
    """lens.glsl's LensPush: 16 floats, then the model as an int (and padding)."""
    out = np.zeros(20, np.float32)
    out[:16] = push[:16]
    out.view(np.int32)[16] = int(push[16])
    return out


def lens_batch_steps(ctx: PostContext, extent: tuple[int, int]) -> list[Step]:
    """A compute batch's resample (post_lens_batch.comp): every view's tile of the HDR atlas
    ("color": source tiles) into its tile of the output atlas (`extent`: the transient
    "lens", which the steps after read: ctx then names it and its tiles), each view with its
    lens constants (PostKernels buffer "lens", batch_post)."""
    n, sw, sh, rows = ctx.view_tiles()
    cols = -(-n // rows)
    tw, th = extent[0] // cols, extent[1] // rows
    push = np.array([tw, th, rows, n, sw, sh], np.uint32)
    view = ctx.transient("lens", extent)
    record = ctx.dispatch("post_lens_batch", push, ctx.color_view, view, extent,
                          set1=ctx.kernels.view_key_set("lens"))
    step = Step("lens", record, ((ctx.color_name, "storage_read"), ("lens", "storage")))
    ctx.color_view, ctx.color_name, ctx.extent = view, "lens", extent
    ctx.tiles = (n, tw, th, rows)
    return [step]


def lens_steps(ctx: PostContext, push: tuple[float, ...], extent: tuple[int, int],
               outputs: bool) -> list[Step]:
    """The resample of the frame's HDR radiance ("color", the source's size) into the model's
    image of `extent` (the transient "lens", which the steps after read: ctx now names it),
    and with `outputs` of the frame's dataset outputs into the output target's ("out.");
    over a compute batch's atlas (ctx.tiles), `lens_batch_steps`."""
    if ctx.tiles is not None:
        return lens_batch_steps(ctx, extent)
    if is_cube(push):
        return cube_steps(ctx, push, extent, outputs)
    data = _lens_push(push)
    steps = []
    if outputs:  # (untimed: FrameStats.pass_ms["lens"] times both kernels)
        src = [ctx.resources[n].view for n in LENS_OUTPUTS]
        dst = [ctx.resources["out." + n].view for n in LENS_OUTPUTS]
        record = ctx.dispatch("post_lens_outputs", data, src[0], src[1], extent, *src[2:], *dst)
        uses = (*((n, "storage_read") for n in LENS_OUTPUTS),
                *(("out." + n, "storage") for n in LENS_OUTPUTS))
        steps.append(Step("lens_outputs", record, uses, timed=False))
    view = ctx.transient("lens", extent)
    steps.append(Step("lens", ctx.dispatch("post_lens", data, ctx.color_view, view, extent),
                      ((ctx.color_name, "storage_read"), ("lens", "storage"))))
    ctx.color_view, ctx.color_name, ctx.extent = view, "lens", extent
    ctx.outputs_prefix = "out."
    return steps
