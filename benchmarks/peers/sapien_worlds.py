"""The tabletop worlds (issue 32) in SAPIEN 3, as ManiSkill3 renders its GPU-parallel envs.

    python benchmarks/peers/sapien_worlds.py [--worlds 4096] [--size 128x128] [--variant tabletop]
        [--shadows 0|512|2048] [--json OUT.jsonl] [--png world0.png]

One `sapien.Scene` a world (a sub-scene: its own render system, no physics system), each
holding the static floor, table and legs, the 17 moving bodies (a RenderBodyComponent each:
SAPIEN's box, sphere and capsule primitives with the glTF's base colour, metallic and roughness;
the sample models as `RenderShapeTriangleMesh(file, scale)`, loaded by assimp), a directional
light (`--shadows`: shadow map size, 0 for none, ManiSkill's default), an ambient 0.3 and one
camera. Every moving shape gets `set_gpu_pose_batch_index(w * N + n)`, then, as ManiSkill's
`_sapien_setup_gpu_rendering` does with PhysX's body buffer:

    group = sapien.render.RenderSystemGroup([scene.render_system for scene in scenes])
    group.set_cuda_poses(sapien.CudaArray(buffer))     # (W * N, 7) float32: p, q (w, x, y, z)
    cameras = group.create_camera_group([one camera a scene], ["Color"])
    # a step:
    buffer.copy_(poses.view(-1, 7))                    # the simulator's poses, on the GPU
    group.update_render()                              # SAPIEN's CUDA kernel: poses -> matrices
    cameras.take_picture()                             # every scene's camera, one submission
    cameras.get_picture_cuda("Color").torch()          # (W, H, W, 4) on the GPU, no copy

on torch's current stream (`group.set_cuda_stream`). "Color" is asked for as r8g8b8a8unorm
(`set_picture_format`), as vkpbr's uint8 frames; SAPIEN's default is float32. Needs sapien 3.0
(benchmarks/peers/fetch_wheels.sh's slimmed tree) and torch with CUDA. `--device cpu` builds the
worlds and renders each scene's camera alone (`take_picture`, no camera group: that needs
CUDA): a dry run where SAPIEN finds a Vulkan device, not a benchmark.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
import worlds_common as c

tabletop = c.tabletop
# SAPIEN's camera axes (x forward, y left, z up) as columns in OpenGL camera axes.
GL_FROM_SAPIEN = np.array([[0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0],
                           [-1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
X_TO_Z = (math.sqrt(0.5), 0.0, -math.sqrt(0.5), 0.0)  # w, x, y, z: SAPIEN's capsule axis x -> z


def extra(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--shadows", type=int, default=0,
                    help="the sun's shadow map size (0: no shadow, ManiSkill's default)")


def wxyz(q) -> list[float]:  # noqa: ANN001
    return [float(q[3]), float(q[0]), float(q[1]), float(q[2])]


def shape_of(sapien, shape: tabletop.Shape, assets: Path):  # noqa: ANN001, ANN201
    """A SAPIEN render shape for one tabletop shape, placed in its body's frame."""
    r = sapien.render
    local = sapien.Pose(list(shape.pos), wxyz(shape.quat))
    if shape.kind == "model":
        out = r.RenderShapeTriangleMesh(str(assets / tabletop.MODELS[shape.model][0]), [shape.size[0]] * 3)
        out.set_local_pose(local)
        return out
    mat = r.RenderMaterial(base_color=list(shape.color), metallic=shape.metallic, roughness=shape.roughness)
    if shape.kind == "box":
        out = r.RenderShapeBox(list(shape.size), mat)
    elif shape.kind == "sphere":
        out = r.RenderShapeSphere(shape.size[0], mat)
    elif shape.kind == "capsule":
        out = r.RenderShapeCapsule(shape.size[0], shape.size[1], mat)
        local = local * sapien.Pose([0, 0, 0], list(X_TO_Z))
    else:  # the floor: a thin box (SAPIEN's plane faces +x)
        out = r.RenderShapeBox([shape.size[0], shape.size[1], 0.001], mat)
        local = local * sapien.Pose([0, 0, -0.001])
    out.set_local_pose(local)
    return out


def build_scene(sapien, world: tabletop.Tabletop, index: int, args: argparse.Namespace, assets: Path):  # noqa: ANN001, ANN201
    """One world: a sub-scene with the static bodies, the moving ones (their shapes read pose
    row index * N + n of the group's buffer), the lights and the camera."""
    scene = sapien.Scene([sapien.render.RenderSystem()])
    scene.set_ambient_light([0.3, 0.3, 0.3])
    scene.add_directional_light(list(world.light_direction), [1.0, 0.97, 0.92], shadow=args.shadows > 0,
                                shadow_scale=2.0, shadow_map_size=max(args.shadows, 64))
    n = 0
    moving = []
    for body in world.bodies:
        entity = sapien.Entity()
        entity.name = body.name
        render_body = sapien.render.RenderBodyComponent()
        shape = shape_of(sapien, body.shape, assets)
        render_body.attach(shape)
        entity.add_component(render_body)
        entity.set_pose(sapien.Pose(list(body.rest[:3]), wxyz(body.rest[3:])))
        scene.add_entity(entity)
        if body.moving:
            for s in render_body.render_shapes:
                s.set_gpu_pose_batch_index(index * len(tabletop.MOVING) + n)
            moving.append(entity)
            n += 1
    cam = sapien.render.RenderCameraComponent(args.width, args.height)
    cam.set_fovy(math.radians(world.yfov_deg), compute_x=True)
    cam.near, cam.far = 0.05, 20.0
    mount = sapien.Entity()
    mount.add_component(cam)
    mount.set_pose(sapien.Pose((world.camera @ GL_FROM_SAPIEN).astype(np.float32)))
    scene.add_entity(mount)
    scene.update_render()
    return scene, cam, moving


def main() -> None:
    args = c.parse_args("sapien_worlds", extra)
    try:
        import sapien
    except ImportError:
        c.fail("sapien", "sapien is not importable: carry .whl-sapien (benchmarks/peers/fetch_wheels.sh) "
               "and unpack it (run_worlds.sh STEP=sapien)")
    cuda = args.device != "cpu"
    torch = c.need_torch_cuda("sapien") if cuda else None
    try:
        sapien.render.set_picture_format("Color", "r8g8b8a8unorm")
        color_format = "r8g8b8a8unorm"
    except Exception:  # noqa: BLE001  (an older SAPIEN: its float32 default)
        color_format = "r32g32b32a32sfloat"
    world = c.world_of(args)
    assets = tabletop.assets_dir()
    t0 = time.perf_counter()
    try:
        built = [build_scene(sapien, world, i, args, assets) for i in range(args.worlds)]
    except RuntimeError as e:
        c.fail("sapien", f"sapien {sapien.__version__}: cannot build the worlds ({e})")
    scenes, cams, moving = (list(v) for v in zip(*built, strict=True))
    if not cuda:
        dry_run(sapien, args, world, scenes, cams, moving)
        return
    poses = c.pose_steps(args, world, "wxyz", "cuda")
    buffer = torch.zeros((args.worlds * len(tabletop.MOVING), 7), dtype=torch.float32, device="cuda")
    group = sapien.render.RenderSystemGroup([s.render_system for s in scenes])
    group.set_cuda_poses(sapien.CudaArray(buffer))
    group.set_cuda_stream(torch.cuda.current_stream().cuda_stream)
    cam_group = group.create_camera_group(cams, ["Color"])
    load_s = time.perf_counter() - t0

    def step(p) -> None:  # noqa: ANN001
        buffer.copy_(p.reshape(-1, 7))
        group.update_render()
        cam_group.take_picture()
        cam_group.get_picture_cuda("Color").torch()

    vps, host_us = c.time_steps(step, poses, args.reps, torch.cuda.synchronize)
    only, _ = c.time_steps(lambda _p: cam_group.take_picture(), poses, args.reps, torch.cuda.synchronize)
    image = cam_group.get_picture_cuda("Color").torch()[0].cpu().numpy()
    if image.dtype != np.uint8:
        image = (np.clip(image, 0, 1) * 255 + 0.5).astype(np.uint8)
    c.report(args, "sapien", sapien.__version__, world, vps, host_us, gpu_name(sapien),
             f"RenderCameraGroup, one sub-scene a world; ambient 0.3 + sun, shadow map {args.shadows}; "
             f"Color {color_format}", image,
             {"render_only_world_views_per_s": round(only, 1), "load_s": round(load_s, 2)})
    sys.stdout.flush()
    os._exit(0)  # SAPIEN 3.0.3 can crash in its teardown (sapien_bench.py): the row is out


def dry_run(sapien, args, world, scenes, cams, moving) -> None:  # noqa: ANN001
    """The CPU path: NumPy poses set per entity, each scene's camera rendered alone."""
    poses = c.pose_steps(args, world, "wxyz", "numpy")
    t = time.perf_counter()
    for p in poses:
        for w, (scene, cam) in enumerate(zip(scenes, cams, strict=True)):
            for entity, row in zip(moving[w], p[w], strict=True):
                entity.set_pose(sapien.Pose(row[:3].tolist(), row[3:].tolist()))
            scene.update_render()
            cam.take_picture()
    vps = args.worlds * len(poses) / (time.perf_counter() - t)
    image = np.asarray(cams[0].get_picture("Color"))
    if image.dtype != np.uint8:
        image = (np.clip(image, 0, 1) * 255 + 0.5).astype(np.uint8)
    c.report(args, "sapien", sapien.__version__, world, vps, float("nan"), gpu_name(sapien),
             "dry run: per-scene take_picture (no camera group)", image)
    sys.stdout.flush()
    os._exit(0)


def gpu_name(sapien) -> str | None:  # noqa: ANN001
    try:  # the summary's first line: "GPU: <name>" (informative only)
        first = sapien.render.get_device_summary().strip().splitlines()[0]
        return first.split(":", 1)[1].strip() if ":" in first else first
    except Exception:  # noqa: BLE001
        return None


if __name__ == "__main__":
    main()
