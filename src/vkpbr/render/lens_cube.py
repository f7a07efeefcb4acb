"""Fisheyes wider than one pinhole can render (up to 360 degrees): drawn as cube faces.

A fisheye camera (`opencv_fisheye`, `equidistant`) whose rays reach more than
scene/lens.py MAX_PINHOLE_ANGLE_DEG (75 degrees) off its axis is drawn as the cube faces its
pixels see (scene/lens.py `cube_view`: usually 5 for a forward fisheye of up to 270 degrees,
the back face left out; all 6 beyond), each a square pinhole of the same eye whose 90
degrees fill all but CUBE_MARGIN texels each side, as densely as the model's densest pixel.

One frame a face (`draw_cube`), through the frame path's own draw (render/frame_path.py
FramePath.draw with `source=` the face's pinhole): every face frame draws its face into the
HDR target of the face's size and copies its radiance and dataset outputs into that face's
own images (post_cube_store*.comp, PostKernels transients "cube<slot>.*"); the last face's
frame then resamples the model's image from all of them (post_lens_cube.comp,
post_lens_cube_outputs.comp: each pixel's ray, the face its major axis picks, bilinear
within that face), runs the other post steps and the encode, and is the frame `render`
reads. The earlier faces' images reach it through one barrier (`_faces_in`: they stay in
GENERAL between frames, which the graph would otherwise discard at its first use).

The motion output: each face frame's "previous frame" is the same face of the previous
cube frame (its view kept per face: `_FacesPrev`), so that the face's motion says where the
point was in that face's previous image.

Cost: faces x face pixels drawn (at most LENS_PIXELS times the output's) and copied, then
one resample over the output; a face frame is a whole frame (shadow maps, culling).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.gpu.graph import Step
from vkpbr.gpu.target import COPY_OUTPUTS, OffscreenTarget
from vkpbr.render.post_stage import PostContext
from vkpbr.scene import lens as lenses
from vkpbr.scene.types import Camera

__all__ = ["CubeFrame", "cube_frame", "is_cube", "store_only", "cube_steps", "draw_cube",
           "face_source"]

PUSH_WORDS = 28  # lens.glsl's LensPush with LENS_CUBE
STORE, RESAMPLE = 1, 2  # a face frame's role (the marker's last number)
FACE_IMAGES = (("color", "VK_FORMAT_R32G32B32A32_SFLOAT"), ("ids", "VK_FORMAT_R32G32_UINT"),
               ("depth", "VK_FORMAT_R32G32B32A32_SFLOAT"),
               ("normal", "VK_FORMAT_R32G32B32A32_SFLOAT"),
               ("geometric", "VK_FORMAT_R32G32B32A32_SFLOAT"))
# The frame's dataset outputs stored per face, in post_cube_store_outputs.comp's order.
_OUTPUTS = ("out_ids", "out_depth_range", "out_normal", "out_normal_geometric")


class CubeFrame(tuple):
    """(the cube plan: scene/lens.py CubeView, the resample's push constants as a tuple):
    what a frame of a wide fisheye draws (a face frame each) and resamples."""

    @property
    def view(self) -> lenses.CubeView:
        return self[0]

    @property
    def push(self) -> tuple[float, ...]:
        return self[1]


def cube_frame(camera: Camera, K: np.ndarray, extent: tuple[int, int], max_pixels: int,
               max_side: int) -> CubeFrame:
    """The cube plan of `camera` (intrinsics `K` at `extent`) and its resample's constants."""
    view = _plan(camera.model, tuple(camera.distortion), tuple(K.ravel().tolist()), extent,
                 max_pixels, max_side)
    c = lenses.distortion_vector(camera.model, camera.distortion).tolist()
    c += [0.0] * (8 - len(c))
    slots = [-1] * 8
    for slot, face in enumerate(view.faces):
        slots[face] = slot
    centre = (view.size - 1) / 2.0
    push = (K[0, 0], K[1, 1], K[0, 2], K[1, 2], view.focal, view.focal, centre, centre, *c,
            lenses.MODEL_IDS[camera.model], 0, view.size, 0, *slots)
    return CubeFrame((view, tuple(float(v) for v in push)))


@functools.lru_cache(maxsize=64)
def _plan(model: str, distortion: tuple[float, ...], k: tuple[float, ...],
          extent: tuple[int, int], max_pixels: int, max_side: int) -> lenses.CubeView:
    """scene/lens.py cube_view, kept per lens and size (a run of frames has one)."""
    return lenses.cube_view(model, distortion, np.array(k).reshape(3, 3), extent, max_pixels,
                            max_side, granule=8)


def face_source(camera: Camera, plan: CubeFrame, slot: int) -> tuple[Camera, tuple[int, int],
                                                                       tuple[float, ...]]:
    """(the face camera, its size, the frame's lens marker) of `plan`'s face `slot`: a
    pinhole at the camera's eye along the face's axes (scene/lens.py FACES)."""
    view = plan.view
    face = view.faces[slot]
    pose = camera.world_from_camera("opencv")
    face_pose = pose.copy()
    face_pose[:3, :3] = pose[:3, :3] @ lenses.FACES[face].T
    n = view.size
    cam = Camera.from_opencv(view.K(), face_pose, (n, n))
    cam = dataclasses.replace(cam, znear=camera.znear, zfar=camera.zfar)
    role = RESAMPLE if slot == len(view.faces) - 1 else STORE
    return cam, (n, n), (*plan.push, float(slot), float(role))


def is_cube(marker: tuple[float, ...]) -> bool:
    """Whether a frame's lens marker (FrameSpec.lens) is a cube face frame's."""
    return len(marker) == PUSH_WORDS + 2


def store_only(marker: tuple[float, ...]) -> bool:
    """Whether the frame only stores its face (no post steps, no encode: a later face's
    frame resamples and encodes)."""
    return is_cube(marker) and int(marker[-1]) == STORE


def _push(marker: tuple[float, ...]) -> np.ndarray:
    out = np.zeros(PUSH_WORDS, np.float32)
    out[:16] = marker[:16]
    out.view(np.int32)[16:] = np.array(marker[16:PUSH_WORDS], np.float64).astype(np.int32)
    return out


def _face(ctx: PostContext, slot: int, kind: str, size: int) -> tuple[str, Any, Any]:
    """(resource name, view, Image) of face `slot`'s image `kind` (a kept transient)."""
    name, fmt = f"cube{slot}.{kind}", dict(FACE_IMAGES)[kind]
    view = ctx.transient(name, (size, size), fmt)
    return name, view, ctx.kernels.transient(name, (size, size), fmt, ctx.extent)[0]


def cube_steps(ctx: PostContext, marker: tuple[float, ...], extent: tuple[int, int],
               outputs: bool) -> list[Step]:
    """A face frame's post steps: its face stored; the last face's frame then the resample
    of every face into the model's image of `extent` ("lens", and with `outputs` the output
    target's dataset outputs, "out."): ctx names "lens" after it, as lens_steps does."""
    slot, role = int(marker[PUSH_WORDS]), int(marker[PUSH_WORDS + 1])
    size, push = int(marker[18]), _push(marker)
    kinds = ("color", "ids", "depth", "normal", "geometric") if outputs else ("color",)
    faces = {k: [_face(ctx, s, k, size) for s in range(int((push.view(np.int32)[20:] >= 0).sum()))]
             for k in kinds}
    steps = [_store(ctx, faces, slot, outputs)]
    if role == STORE:
        return steps
    others = [f for k in kinds for s, f in enumerate(faces[k]) if s != slot]
    if others:
        steps.append(_faces_in(others))
    pad = lambda views: [*views, *[views[0]] * (6 - len(views))]  # noqa: E731 (unused slots)
    if outputs:
        src = [v for k in kinds[1:] for v in pad([f[1] for f in faces[k]])]
        dst = [ctx.resources["out." + n].view for n in _OUTPUTS]
        views = [*src, *dst]
        uses = (*((f[0], "storage_read") for k in kinds[1:] for f in faces[k]),
                *(("out." + n, "storage") for n in _OUTPUTS))
        steps.append(Step("lens_outputs", ctx.dispatch(
            "post_lens_cube_outputs", push, views[0], views[1], extent, *views[2:]), uses,
            timed=False))
    color = pad([f[1] for f in faces["color"]])
    view = ctx.transient("lens", extent)
    steps.append(Step("lens", ctx.dispatch("post_lens_cube", push, color[0], color[1], extent,
                                           *color[2:], view),
                      (*((f[0], "storage_read") for f in faces["color"]), ("lens", "storage"))))
    ctx.color_view, ctx.color_name, ctx.extent = view, "lens", extent
    ctx.outputs_prefix = "out."
    return steps


def _store(ctx: PostContext, faces: dict[str, list], slot: int, outputs: bool) -> Step:
    """The face frame's radiance (and outputs) into face `slot`'s images."""
    size = ctx.extent
    color = faces["color"][slot]
    none = np.zeros(1, np.uint32)
    records = [ctx.dispatch("post_cube_store", none, ctx.color_view, color[1], size)]
    uses = [(ctx.color_name, "storage_read"), (color[0], "storage")]
    if outputs:
        pairs = [(n, faces[k][slot]) for n, k in zip(_OUTPUTS, ("ids", "depth", "normal", "geometric"),
                                                      strict=True)]
        views = [v for n, f in pairs for v in (ctx.resources[n].view, f[1])]
        records.append(ctx.dispatch("post_cube_store_outputs", none, views[0], views[1], size,
                                    *views[2:]))
        uses += [u for n, f in pairs for u in ((n, "storage_read"), (f[0], "storage"))]

    def record(cmd: Any) -> None:
        for r in records:
            r(cmd)
    return Step("cube_store", record, tuple(uses), timed=False)


def _faces_in(faces: list[tuple[str, Any, Any]]) -> Step:
    """The earlier face frames' images, as they left them (GENERAL after compute writes),
    made visible to this frame's resample without the graph's discard at a first use."""

    def record(cmd: Any) -> None:
        for _, _, image in faces:
            cmd.image_barrier(image, "general", "general", "compute", "compute")
    return Step("cube_faces", record, (), timed=False,
                leaves=tuple((f[0], "storage_read") for f in faces))


# --- drawing: a frame a face -----------------------------------------------------------------
def draw_cube(path: Any, target: Any, camera: Camera, plan: CubeFrame, **draw: Any) -> Any:
    """The frames of `camera`'s cube faces (FramePath.draw's keywords in `draw`); the last
    one's Submitted (the frame that resamples and encodes: what its caller reads). Each face
    frame's previous view (its motion's) is the same face's in the previous cube frame
    (`path.cube_prev`), with the previous frame's draw matrices."""
    if not isinstance(target, OffscreenTarget):
        raise UsageError(f"camera model {camera.model!r} wider than "
                         f"{2 * lenses.MAX_PINHOLE_ANGLE_DEG:g} degrees renders offscreen only "
                         "(render, render_many), not into a window")
    p = path.parts
    state = p.gpu_state
    start = state._prev  # (VP, draw matrices, version) of the frame before (scene_state.py)
    copy, overlay = draw.pop("copy", ()), draw.pop("overlay", None)
    face_copy = tuple(c for c in copy if c == COPY_OUTPUTS)
    sub = None
    last = len(plan.view.faces) - 1
    for slot, face in enumerate(plan.view.faces):
        cam, size, marker = face_source(camera, plan, slot)
        key = (face, marker[:PUSH_WORDS])
        if start is not None:
            state._prev = (path.cube_prev.get(key, start[0]), start[1], start[2])
        final = slot == last
        sub = path.draw(target, camera, copy=copy if final else face_copy,
                        overlay=overlay if final else None, source=(cam, size, marker), **draw)
        if sub.frame is None:
            return sub
        frame_slot = p.slots[sub.frame.index]
        path.cube_prev[key] = frame_slot.vp
    # The dataset outputs' camera-space normals: the lens camera's rotation, not the last
    # face's (the slot's view is made again by its next frame).
    rotation = camera.world_from_camera("opengl")[:3, :3]
    frame_slot.camera_rotation = tuple(float(v) for v in rotation.T.ravel())
    frame_slot.view_key = None
    return sub
