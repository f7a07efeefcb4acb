"""Which way `Renderer.render_batch` takes a call, and its results in the shape it returns.

`batch_route` checks the call's arguments (where the result goes, `out=`, the dataset
outputs, post steps) and picks one of ROUTES: "cuda" (the colour into a torch tensor on the
GPU), "compute" (the compute batch: all views in one atlas, rasterised and shaded in compute
shaders; blended draws by the raster units into each view's tile) where the device has the
compute rasteriser (and, for a scene with blended draws, clip distances), "layered" (the
fragment path's batch: render/batch.py), or "views": view by view through render_many, each
exactly as `render` draws it, where the device has no layered rendering, with MSAA (the batch
target is single-sample), the compute path asked for, or post steps the compute batch does
not take (render/post.py batch_post_supported; the layered batch takes none).
"auto" takes the compute batch where it can (the H200 measured it 4-5x the layered batch:
BENCHMARKS.md; lavapipe 1.2-5x at 128x128 and more), else the layered batch, bit for bit
what `render` draws with pipeline="forward". `render_many(batch=N)` goes through
render_batch N cameras at a time (`chunked`), yielding view by view (`per_view`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.render import layouts as L
from vkpbr.render.camera import as_camera
from vkpbr.render.options import RenderOptions
from vkpbr.render.outputs import OUTPUTS, check_outputs, frame_outputs
from vkpbr.render.parts import FrameParts
from vkpbr.render.post import batch_post_supported
from vkpbr.render.post_stage import enabled_post
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.types import Camera

__all__ = ["ROUTES", "TILED_OUTPUTS", "batch_result", "batch_route", "check_out", "chunked",
           "per_view", "stack_frames"]

ROUTES = ("cuda", "compute", "layered", "views")


# The dataset outputs the compute batch writes itself (render/batch_path.py, shade.comp's
# BATCH OUTPUTS build; "ao" from its GTAO over the views' tiles): all but "motion" (a
# batch's views are no sequence: render_many's frames give each view's motion from the
# view before).
TILED_OUTPUTS = frozenset(OUTPUTS) - {"motion"}


def batch_route(parts: FrameParts, batch: CameraBatch, size: tuple[int, int], opts: RenderOptions,
                linear: bool, depth: bool, outputs: Iterable[str] | None, device: str,
                out: np.ndarray | None) -> tuple[str, tuple[str, ...]]:
    """(one of ROUTES, the dataset outputs asked for) for the views of `batch` of `size`
    (UsageError for what cannot be done: say what to do instead)."""
    views = len(batch)
    if device not in ("cpu", "cuda"):
        raise UsageError(f"device {device!r}: choose 'cpu' (NumPy) or 'cuda' (a torch tensor)")
    if out is not None:
        check_out(out, (views, size[1], size[0], 4), np.float32 if linear else np.uint8, device)
    # Post steps: the compute batch takes colour noise, bloom and a lens its views share
    # (render/post.py batch_post_supported); the others (depth noise, views of different
    # lenses, a lens with depth) go view by view.
    post = bool(enabled_post(opts)) or batch.lenses is not None
    tiled_post = batch_post_supported(opts, batch, size, depth)
    if device == "cuda":
        if depth or outputs:
            raise UsageError("device='cuda' returns the colour only: ask depth and dataset "
                             "outputs with device='cpu'")
        if post:
            raise UsageError("device='cuda' batches have no post steps (--bloom, --noise, "
                             "camera models) yet: render them with device='cpu'")
        return "cuda", ()
    targets, paths = parts.targets, parts.paths
    wanted = (check_outputs(outputs, targets.offscreen(size, linear), paths, targets)
              if outputs else ())
    # The compute batch writes the dataset outputs of TILED_OUTPUTS in its own pass over
    # the atlas (not with post steps); the others come from their own frames, view by view
    # (as `render` makes them).
    extra = any(n != "color" for n in wanted)
    tiled = not extra or (set(wanted) <= TILED_OUTPUTS and not post)
    explicit_compute = (opts.pipeline == L.PipelinePath.COMPUTE
                        and paths.uses_compute(targets.offscreen(size, linear), opts))
    if paths.takes_compute_batch(opts) and tiled and tiled_post:
        return "compute", wanted
    if not parts.device.batch_views or targets.msaa > 1 or explicit_compute or post:
        return "views", wanted
    return "layered", wanted


def batch_result(color: Any, dist: np.ndarray | None, depth: bool, wanted: tuple[str, ...],
                 frames: Sequence[dict[str, np.ndarray]] = (),
                 images: dict[str, np.ndarray] | None = None) -> Any:
    """What render_batch returns: the colour (and depth), or {name: (B, ...) array} of
    `wanted` with the outputs but colour from the compute batch's output `images` (BatchPath
    .images) or else from `frames` (render_many's, a dict each)."""
    if not wanted:
        return (color, dist) if depth else color
    if images is not None:
        return frame_outputs(images, color, wanted, images["camera_rotation"])
    result: dict[str, np.ndarray] = {"color": color} if "color" in wanted else {}
    for name in wanted:
        if name != "color":
            result[name] = np.stack([f[name] for f in frames])
    return {n: result[n] for n in wanted}


def stack_frames(frames: list[Any], depth: bool, wanted: tuple[str, ...],
                 out: np.ndarray | None = None) -> Any:
    """render_many's frames stacked as render_batch returns them (the colour into `out`)."""
    if wanted:
        return {n: np.stack([f[n] for f in frames], out=out if n == "color" else None)
                for n in wanted}
    if depth:
        return np.stack([f[0] for f in frames], out=out), np.stack([f[1] for f in frames])
    return np.stack(frames, out=out)


def stack_views(renderer: Any, frames: Iterator[Any], depth: bool, wanted: tuple[str, ...],
                out: np.ndarray | None = None) -> Any:
    """The "views" route: render_many's `frames` stacked (`stack_frames`), and the call's
    timings as the batch routes give them, every view's summed into `renderer.last_stats`
    (not the last view's alone)."""
    from vkpbr.render.frames import summed_stats

    got, total = [], None
    for frame in frames:
        got.append(frame)
        stats = dataclasses.replace(renderer.last_stats)  # the slot's object is reused
        total = stats if total is None else summed_stats(total, stats)
    result = stack_frames(got, depth, wanted, out)
    if total is not None:
        renderer.last_stats = total
    return result


def check_out(out: Any, shape: tuple[int, ...], dtype: type, device: str) -> None:
    """render_batch's `out`: a NumPy array render_batch can write the colour into."""
    if device != "cpu":
        raise UsageError("out= takes a NumPy array: it is for device='cpu'")
    if not isinstance(out, np.ndarray) or out.shape != shape or out.dtype != dtype \
            or not out.flags.c_contiguous or not out.flags.writeable:
        got = (f"{type(out).__name__}" if not isinstance(out, np.ndarray) else
               f"{out.dtype} {out.shape}{'' if out.flags.c_contiguous else ' not contiguous'}"
               f"{'' if out.flags.writeable else ' read-only'}")
        raise UsageError(f"out= must be a C-contiguous writeable {np.dtype(dtype)} array of "
                         f"shape {shape}; got {got}")


def chunked(cameras: Iterable[Camera | Any], batch: int, base: Camera,
            outputs: Iterable[str] | None) -> Iterator[tuple[list[Camera], tuple[str, ...] | None]]:
    """`render_many(batch=N)`'s cameras as Cameras (None: `base`), N at a time, each chunk
    with the outputs asked for (a tuple, read once: `outputs` may be an iterator)."""
    if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
        raise UsageError(f"batch {batch!r}: expected a positive number of views")
    names = None if outputs is None else (
        (outputs,) if isinstance(outputs, str) else tuple(outputs))
    pending: list[Camera] = []
    for camera in cameras:
        pending.append(base if camera is None else as_camera(camera, base))
        if len(pending) == batch:
            yield pending, names
            pending = []
    if pending:
        yield pending, names


def per_view(got: Any, views: int, depth: bool) -> Iterator[Any]:
    """render_batch's result for `views` views, view by view as render_many yields them."""
    for i in range(views):
        if isinstance(got, dict):
            yield {k: v[i] for k, v in got.items()}
        else:
            yield (got[0][i], got[1][i]) if depth else got[i]
