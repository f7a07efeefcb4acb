"""Batched worlds (issue 32): vkpbr on the tabletop worlds (benchmarks/tabletop.py), the scenario
the peers run (benchmarks/peers/worlds_common.py: W worlds, one camera a world, the 17 moving
bodies posed anew every step, S distinct steps made before the clock starts).

    python benchmarks/bench_worlds.py [--variant tabletop|primitives] [--worlds 1024,4096]
        [--sizes 128x128,256x256] [--steps 16] [--reps 4] [--shadows N] [--json OUT.jsonl]
        [--png-dir DIR]

Rows (one per variant, size, W and mode; a Markdown table, and JSON lines as the peers'):

Variants: the tabletop (full, or primitives only) and "helmet": DamagedHelmet alone, its mesh
node turning per world (tabletop.Spin), the camera 3 units away (issue 32's worlds-helmet-64:
`--variant helmet --worlds 8192 --sizes 64x64`).

- "one state" (today's API): each step sets ONE world's poses (world 0's, from NumPy:
  `Renderer.set_poses(MOVING, poses, quaternion="xyzw")`, local to the glTF's z-up root, so the
  simulator's rows as they are) and renders the W views with `render_batch` (into NumPy, and
  into torch on the GPU where torch sees CUDA). Every view shows world 0: the ceiling of the
  pose upload of one world plus W views, not yet W different worlds.
- "worlds" (issue 32's API, `render_worlds`): each step hands the (W, N, 7) CUDA tensor of
  all W worlds to `render_batch(worlds=..., space="local")`, views into torch, shadows off.
- "worlds + shadows" (`--shadows N`): the same with each world's own shadow maps of N texels
  a side (render/world_shadows.py: the tabletop's sun, one scene-wide map per world), e.g.
  `--worlds 1024 --sizes 128x128 --shadows 256`.

Columns: world-views/s (W x steps / wall clock, the device synchronised at the end), host
us/step (Python time of a step's calls), GPU ms/step (`last_stats.gpu_ms`), vkpbr MiB (device
memory vkpbr holds beyond the scene's: Device.bytes_allocated) and MiB per 1,000 worlds. Not a
test. `--device cpu`-style dry runs need nothing: on lavapipe use small --worlds and --sizes.
"""

from __future__ import annotations

import argparse
import inspect
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from vkpbr.render.renderer import Renderer
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.loader import load_scene

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "peers"))
import worlds_common as c  # noqa: E402  (the worlds scenario; NumPy only)

tabletop = c.tabletop


def torch_cuda():  # noqa: ANN201
    """torch when it sees a CUDA device (render_batch(device="cuda")), else None."""
    try:
        import torch
    except ImportError:
        return None
    return torch if torch.cuda.is_available() else None


def has_worlds(r: Renderer) -> bool:
    return "worlds" in inspect.signature(r.render_batch).parameters


def render_worlds(r: Renderer, views: CameraBatch, size: tuple[int, int], poses, slots,  # noqa: ANN001, ANN201
                  shadow_resolution: int = 0):
    # `poses`: this step's (W, N, 7) float32 CUDA tensor, rows position + quaternion x, y, z, w
    # for tabletop.MOVING in order, local to the glTF's root (the simulator's z-up world:
    # space="local"); `slots`: what `r.world_slots(list(tabletop.MOVING))` named. View w sees
    # world w (B == W, so world_of_view is left out).
    # shadows off as SAPIEN's camera group draws none by default; `shadow_resolution` > 0
    # (--shadows): each world's own shadow maps of that size (render/world_shadows.py: the
    # sun's scene-wide map per world)
    if shadow_resolution:
        return r.render_batch(views, size=size, worlds=poses, quaternion="xyzw", space="local",
                              device="cuda", world_shadow_resolution=shadow_resolution)
    return r.render_batch(views, size=size, worlds=poses, quaternion="xyzw", space="local",
                          device="cuda", shadows=False)


def parse() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description="vkpbr on the tabletop worlds: world-views/s")
    ap.add_argument("--variant", choices=("tabletop", "primitives", "helmet"), default="tabletop",
                    help="helmet: DamagedHelmet alone, turning (tabletop.Spin), camera 3 units away")
    ap.add_argument("--worlds", default="1024,4096", help="comma-separated W values")
    ap.add_argument("--sizes", default="128x128,256x256", help="comma-separated WIDTHxHEIGHT")
    ap.add_argument("--steps", type=int, default=16, help="distinct pose steps made beforehand")
    ap.add_argument("--reps", type=int, default=4, help="timed passes over the steps")
    ap.add_argument("--scene-dir", default=None, help="where the glTF is written (default: a temp dir)")
    ap.add_argument("--json", default=None, help="append one JSON line a row")
    ap.add_argument("--shadows", type=int, default=0, metavar="N",
                    help="also a row 'worlds + shadows': each world's own shadow maps of N texels "
                         "a side (world_shadow_resolution, e.g. 256)")
    ap.add_argument("--png-dir", default=None, help="save world 0's view of each row there")
    return ap.parse_args()


def row_args(args: argparse.Namespace, size: tuple[int, int], worlds: int, mode: str) -> argparse.Namespace:
    """The Namespace worlds_common.report reads, for one row."""
    png = None
    if args.png_dir:
        tag = mode.replace(" -> ", "-into-").replace(" ", "-")
        png = str(Path(args.png_dir) / f"vkpbr-{args.variant}-{size[0]}x{size[1]}-{worlds}-{tag}.png")
    return argparse.Namespace(variant=args.variant, width=size[0], height=size[1], worlds=worlds,
                              steps=args.steps, reps=args.reps, device="cuda" if "torch" in mode or
                              mode.startswith("worlds") else "cpu", json=args.json, png=png)


def scene_of(args: argparse.Namespace):  # noqa: ANN201
    """(scene, slots, camera pose (4, 4) OpenGL, yfov degrees, motion(W), sha source(W)) of the
    variant: the tabletop's 17 moving nodes, or the helmet's mesh node."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if args.variant == "helmet":
            scene = load_scene(tabletop.assets_dir() / "DamagedHelmet/glTF/DamagedHelmet.gltf")
            tree = scene.node_tree()
            slots = [n.tree for n in scene.nodes if n.mesh is not None][:1]
            m = tree.local[slots[0]]
            rest = np.array([[*m[:3, 3], *tabletop.matrix_quat(m[:3, :3])]])
            eye = tabletop.look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
            spin = lambda w: tabletop.Spin(rest, w)  # noqa: E731
            return scene, slots, eye, 45.0, spin, spin
        world = c.world_of(args)
        folder = Path(args.scene_dir or tempfile.mkdtemp(prefix="tabletop-"))
        scene = load_scene(tabletop.write_gltf(world, folder))
        return (scene, list(tabletop.MOVING), tabletop.camera_gltf(world), world.yfov_deg,
                lambda w: tabletop.Motion(world, w), lambda w: world)


def run(args: argparse.Namespace) -> None:
    scene, names, eye, yfov, motion, sha = scene_of(args)
    torch = torch_cuda()
    print("| peer | variant | size | W | world-views/s | host us/step | GPU MiB | mode |")
    print("|---|---|---|---|---|---|---|---|")
    with Renderer(scene) as r:
        r.render(size=(64, 64))  # the scene's own buffers, pipelines and environment
        baseline = r.device.bytes_allocated()[0]
        slots = r.world_slots(names) if hasattr(r, "world_slots") else None
        for size in [tuple(int(v) for v in s.lower().split("x")) for s in args.sizes.split(",")]:
            for w in [int(v) for v in args.worlds.split(",")]:
                views = CameraBatch.from_poses(np.repeat(eye[None], w, 0), yfov)
                row = (r, args, sha(w), size, w)
                one_state(*row, views, names, motion(w), baseline, torch)
                if torch is None:
                    continue
                if not has_worlds(r):
                    print(f"skipped worlds {size[0]}x{size[1]} W={w}: render_batch has no worlds= yet "
                          "(render_worlds in this file)", file=sys.stderr)
                    continue
                poses = motion(w).steps(args.steps, "xyzw", "cuda")
                step = lambda p, v=views, s=size: render_worlds(r, v, s, p, slots)  # noqa: E731
                record(*row, "worlds", step, poses, torch.cuda.synchronize, baseline,
                       lambda out: out[0].cpu().numpy())
                if args.shadows:
                    lit = lambda p, v=views, s=size: render_worlds(r, v, s, p, slots, args.shadows)  # noqa: E731
                    record(*row, "worlds + shadows", lit, poses, torch.cuda.synchronize, baseline,
                           lambda out: out[0].cpu().numpy())


def one_state(r: Renderer, args, world, size, w, views, names, motion, baseline, torch) -> None:  # noqa: ANN001
    """Today's API: world 0's poses set from NumPy each step, W views of that one state."""
    poses = motion.steps(args.steps, "xyzw")[:, 0]
    modes = [("one state -> numpy", "cpu", lambda: None)]
    if torch is not None:
        modes.append(("one state -> torch", "cuda", torch.cuda.synchronize))
    for mode, device, sync in modes:
        def step(p, device=device):  # noqa: ANN001, ANN202
            r.set_poses(names, p, quaternion="xyzw")
            return r.render_batch(views, size=size, device=device)

        record(r, args, world, size, w, mode, step, poses, sync, baseline,
               lambda out: np.asarray(out[0].cpu() if hasattr(out, "cpu") else out[0]))


def record(r: Renderer, args, world, size, w, mode, step, poses, sync, baseline, first) -> None:  # noqa: ANN001
    """Time `step` over the pose steps (worlds_common.time_steps) and report one row."""
    gpu_ms: list[float] = []

    def timed(p):  # noqa: ANN001, ANN202
        out = step(p)
        gpu_ms.append(r.last_stats.gpu_ms)
        timed.out = out
        return out

    t = time.perf_counter()
    vps, host_us = c.time_steps(timed, poses, args.reps, sync, worlds=w)
    mib = (r.device.bytes_allocated()[0] - baseline) / 2**20
    a = row_args(args, size, w, mode)
    c.report(a, "vkpbr", "main", world, vps, host_us, r.device.info.name, mode, first(timed.out),
             {"gpu_ms_per_step": round(statistics.median(gpu_ms), 3), "vkpbr_mib": round(mib, 1),
              "mib_per_1000_worlds": round(mib * 1000 / w, 2), "wall_s": round(time.perf_counter() - t, 2)})


if __name__ == "__main__":
    run(parse())
