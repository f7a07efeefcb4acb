"""The tabletop worlds (issue 32) in MuJoCo Warp's own batch renderer and in mujoco-warp-pbr.

    python benchmarks/peers/mujoco_worlds.py --renderer mjwarp|pbr [--worlds 4096] [--size 128x128]
        [--render-order tiled|world] [--json OUT.jsonl] [--png world0.png] [--device cpu]

The primitives-only world (tabletop.write_mjcf: boxes, spheres and capsules on MuJoCo's own
geom types, a plane floor, one directional light with shadows, a gradient skybox), W worlds
of one MjModel (`mujoco_warp.put_data(nworld=W)`), the camera "view". Each moving body is a free
body, so a step writes the (W, N, 7) poses (w, x, y, z quaternions, MuJoCo's order) into the
worlds' qpos, as MuJoCo Warp's own integrator would have:

    qpos.copy_(poses.view(W, -1))        # torch view of d.qpos: no host copy
    mujoco_warp.kinematics(m, d)         # body -> geom poses (what a simulator step ends with)
    mujoco_warp.refit_bvh(m, d, rc)      # the renderers' scene BVH follows the geoms
    render(m, d, rc)                     # mujoco_warp.render / mujoco_warp_pbr.render

all on torch's current CUDA stream (warp.ScopedStream(warp.stream_from_torch())), frames left in
the render context's (W, pixels) uint32 buffer (wp.to_torch views it without a copy). Timed as
worlds_common says; "render only" repeats the render call alone on unchanged poses.

- mjwarp: `mujoco_warp.create_render_context(render_rgb, use_shadows=True, render_skybox=True)`:
  ray-cast primitives, MuJoCo's Phong-style lighting (no PBR, no image-based light).
- pbr: `mujoco_warp_pbr.create_render_context(render_rgb)` with its defaults: the real-time
  tier (Filament's BRDF, ray-traced shadows, the skybox as environment light, PBR Neutral tone
  map), `--render-order` tiled (its default) or world (faster when every world shows nearly
  the same image).

`--device cpu` runs both on Warp's CPU device (needs warp-clang.so, which the carried tree
drops) with NumPy poses: a dry run that the scene loads and renders, not a benchmark.
"""

from __future__ import annotations

import argparse
import importlib.metadata
from pathlib import Path

import numpy as np
import worlds_common as c


def extra(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--renderer", choices=("mjwarp", "pbr"), required=True)
    ap.add_argument("--render-order", choices=("tiled", "world"), default="tiled",
                    help="mujoco-warp-pbr's RenderOrder (pbr only)")


def version(name: str) -> str:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "?"


def main() -> None:
    args = c.parse_args("mujoco_worlds", extra)
    peer = "mujoco-warp" if args.renderer == "mjwarp" else "mujoco-warp-pbr"
    if args.variant != "primitives":
        args.variant = "primitives"  # the MJCF holds the primitives-only world
    try:
        import mujoco
        import mujoco_warp as mjw
        import warp as wp

        mjpbr = None
        if args.renderer == "pbr":
            import mujoco_warp_pbr as mjpbr
    except ImportError as e:
        c.fail(peer, f"{e.name} is not importable: carry .whl-worlds "
               "(benchmarks/peers/fetch_worlds_wheels.sh) and unpack it (run_worlds.sh STEP=mujoco)")
    cuda = args.device != "cpu"
    torch = c.need_torch_cuda(peer) if cuda else None
    world = c.world_of(args)
    xml = c.tabletop.write_mjcf(world, Path(args.scene_dir) / "tabletop.xml")
    mjm = mujoco.MjModel.from_xml_path(str(xml))
    mjd = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, mjd)
    wp.init()
    device = "cuda:0" if cuda else "cpu"
    poses = c.pose_steps(args, world, "wxyz", "cuda:0" if cuda else "numpy")
    stream = wp.stream_from_torch(torch.cuda.current_stream()) if cuda else None
    with wp.ScopedDevice(device), wp.ScopedStream(stream) if cuda else _Null():
        m = mjw.put_model(mjm)
        d = mjw.put_data(mjm, mjd, nworld=args.worlds)
        if mjpbr is None:
            rc = mjw.create_render_context(mjm, nworld=args.worlds, cam_res=(args.width, args.height),
                                           render_rgb=True, render_depth=False, use_shadows=True,
                                           render_skybox=True)
            base, render, settings = rc, mjw.render, "MuJoCo Warp renderer: shadows, skybox, Phong lighting"
        else:
            order = mjpbr.RenderOrder.WORLD if args.render_order == "world" else mjpbr.RenderOrder.TILED
            rc = mjpbr.create_render_context(mjm, nworld=args.worlds, cam_res=(args.width, args.height),
                                             render_rgb=True, render_depth=False, render_order=order)
            base, render = rc.base, mjpbr.render
            settings = f"real-time tier: shadows, skybox IBL, PBR Neutral; order {args.render_order}"
        mjw.camlight(m, d)
        qpos = wp.to_torch(d.qpos) if cuda else None

        def step(p) -> None:  # noqa: ANN001
            if cuda:
                qpos.copy_(p.reshape(args.worlds, -1))
            else:
                d.qpos.assign(np.ascontiguousarray(p.reshape(args.worlds, -1)))
            mjw.kinematics(m, d)
            mjw.refit_bvh(m, d, base)
            render(m, d, rc)

        def sync() -> None:
            if cuda:
                torch.cuda.synchronize()
            else:
                wp.synchronize()

        vps, host_us = c.time_steps(step, poses, args.reps, sync)
        only, _ = c.time_steps(lambda _p: render(m, d, rc), poses, args.reps, sync)
        rgb = wp.zeros((args.worlds, args.height, args.width), dtype=wp.vec3)
        (mjpbr or mjw).get_rgb(rc, 0, rgb)
        image = (np.clip(rgb.numpy()[0], 0, 1) * 255 + 0.5).astype(np.uint8)
    gpu = wp.get_device(device).name
    ver = version("mujoco-warp") if mjpbr is None else version("mujoco-warp-pbr")
    c.report(args, peer, ver, world, vps, host_us, gpu,
             settings + f"; mujoco {mujoco.__version__}, warp {wp.__version__}", image,
             {"render_only_world_views_per_s": round(only, 1),
              "frames": "rc.rgb_data: (W, H*W) uint32 packed RGB, on the GPU"})


class _Null:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


if __name__ == "__main__":
    main()
