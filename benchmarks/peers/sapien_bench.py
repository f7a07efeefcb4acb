"""The batch scenario (common.py) with SAPIEN 3 (Vulkan, svulkan2), as a user would: the glTF
as a static actor's visual (`ActorBuilder.add_visual_from_file`, loaded by assimp with its
textures), one point light and an ambient term, cameras from `Scene.add_camera`.

    python benchmarks/peers/sapien_bench.py --batch --scene sponza --size 128x128 --poses p.npy
    python benchmarks/peers/sapien_bench.py --batch --scene helmet --mode group --poses p.npy

Two ways to render the B views (`--mode`):

- `cameras` (default; what plain SAPIEN offers on any GPU): one scene holding B cameras, one at
  each pose; per pass one `scene.update_render()`, then `take_picture()` per camera (SAPIEN
  renders one camera per submission and waits for it) and, into NumPy,
  `get_picture("Color")` per camera ((H, W, 4) float32, SAPIEN's own format, not converted).
  Render only: `take_picture()` per camera.
- `group` (SAPIEN's batched cameras, as ManiSkill3 renders; CUDA only): the same scene and B
  cameras, a `sapien.render.RenderSystemGroup` over its render system and one
  `RenderCameraGroup` over the B cameras: per pass one `take_picture()` renders every camera
  with no wait between them and copies all B pictures into one CUDA buffer, which CUDA waits
  for through an exported semaphore; into NumPy,
  `get_picture_cuda("Color").torch().cpu().numpy()` ((B, H, W, 4) float32). Render only:
  `take_picture()` then `torch.cuda.synchronize()`. (SAPIEN's camera group takes cameras of
  any scenes of one size; ManiSkill3 uses one scene per environment, one camera each.)

SAPIEN's camera looks along its +x with +z up (+y left); the poses (OpenGL: -z forward, +y up)
are turned into its axes by `sapien_pose`. Needs sapien 3 (with transforms3d, lxml, networkx,
opencv, pyperclip, requests) and, for `group`, torch with CUDA. On a device SAPIEN rejects (Mesa's
lavapipe: "failed to find a rendering device") it exits at once with that one-line reason.
"""

from __future__ import annotations

import math
import os
import sys
import time

import common as c

# SAPIEN's camera axes (x forward, y left, z up) as columns in OpenGL camera axes
# (x right, y up, z backward): forward = -z, left = -x, up = +y.
GL_FROM_SAPIEN = c.np.array([[0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0],
                             [-1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def sapien_pose(pose_gl):  # noqa: ANN001, ANN201
    """A sapien.Pose of the camera entity from an OpenGL world-from-camera 4x4."""
    import sapien

    return sapien.Pose((pose_gl @ GL_FROM_SAPIEN).astype(c.np.float32))


def make_scene(sapien, path: str):  # noqa: ANN001, ANN201
    scene = sapien.Scene()
    scene.set_ambient_light([0.3, 0.3, 0.3])
    scene.add_point_light(list(c.LIGHT_POS), list(c.LIGHT_COLOR), shadow=False)
    builder = scene.create_actor_builder()
    builder.add_visual_from_file(path)
    builder.build_static(name="gltf")
    return scene


def main() -> None:
    args = c.parse_batch_args("sapien", lambda ap: ap.add_argument(
        "--mode", choices=("cameras", "group"), default="cameras",
        help="cameras: B cameras in one scene, one picture each; group: a RenderCameraGroup "
             "over the B cameras, one wait (CUDA)"))
    t0 = time.perf_counter()
    import numpy as np
    import sapien

    try:
        probe = sapien.render.RenderSystem()
    except RuntimeError as e:
        raise SystemExit(f"sapien {sapien.__version__}: no device SAPIEN can render on ({e})") from None
    del probe
    if args.mode == "group":  # SAPIEN's camera group hands its pictures to CUDA
        try:
            import torch
        except ImportError:
            raise SystemExit("sapien --mode group needs torch with CUDA: torch is not installed") from None
        if not torch.cuda.is_available():
            raise SystemExit("sapien --mode group needs CUDA: torch.cuda.is_available() is False")
    poses = args.pose_array
    w, h, fovy = args.width, args.height, math.radians(c.YFOV_DEG)
    path = str(args.scene_path)
    scene = make_scene(sapien, path)
    cams = []  # one camera a view, all in the one scene
    for i, pose in enumerate(poses):
        cam = scene.add_camera(f"view{i}", w, h, fovy, c.ZNEAR, c.ZFAR)
        cam.entity.set_pose(sapien_pose(pose))
        cams.append(cam)
    if args.mode == "cameras":
        scene.update_render()
        cams[0].take_picture()
        image = cams[0].get_picture("Color")

        def readback() -> None:
            scene.update_render()
            for cam in cams:
                cam.take_picture()
                cam.get_picture("Color")

        def render_only() -> None:
            scene.update_render()
            for cam in cams:
                cam.take_picture()

        mode = "per-view loop (B cameras in one scene)"
    else:
        scene.update_render()  # the cameras' poses, before the group snapshots the scene
        group = sapien.render.RenderSystemGroup([scene.render_system])
        cam_group = group.create_camera_group(cams, ["Color"])
        cam_group.take_picture()
        image = cam_group.get_picture_cuda("Color").torch().cpu().numpy()[0]

        def readback() -> None:
            cam_group.take_picture()
            cam_group.get_picture_cuda("Color").torch().cpu().numpy()

        def render_only() -> None:
            cam_group.take_picture()
            torch.cuda.synchronize()

        mode = "batched (RenderCameraGroup: B cameras, one wait, one CUDA buffer)"
    load_s = time.perf_counter() - t0
    assert image.shape == (h, w, 4), image.shape
    vps_readback = c.views_per_s(readback, len(poses), args.reps)
    vps_render_only = c.views_per_s(render_only, len(poses), args.reps)
    try:  # the summary's first line: "GPU: <name>" (informative only)
        first = sapien.render.get_device_summary().strip().splitlines()[0]
        gpu = first.split(":", 1)[1].strip() if ":" in first else first
    except Exception:  # noqa: BLE001
        gpu = None
    png = (np.clip(np.asarray(image)[..., :3], 0, 1) * 255 + 0.5).astype(np.uint8)
    c.report_batch(args, "sapien", sapien.__version__, vps_readback, vps_render_only, load_s, gpu,
                   f"mode {args.mode}; Color float32 (H, W, 4); ambient 0.3 + one point light",
                   mode, 1.0, png)
    # SAPIEN 3.0.3 can crash in its teardown (seen on lavapipe, after Sponza): the result is
    # out, so leave without running it.
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    if "--batch" not in sys.argv:
        sys.argv.append("--batch")  # SAPIEN runs the batch scenario only
    main()
