"""A batch of worlds' own shadow maps with and without the kept map of the casters no world
moves (render/world_shadows.py: WorldShadows.keep_still), alternating in one process: the
shadow steps' GPU ms a step and the step's wall ms (medians). Not a test.

    python3 benchmarks/probe_world_kept.py [--worlds 64] [--size 64x64] [--resolution 256]
        [--steps 6] [--rounds 2] [--steps-apart] [--sponza PATH/Sponza.gltf]

The tabletop (benchmarks/tabletop.py: its 17 moving bodies are the world slots; the table,
the floor and the arm's base are no world's), NumPy poses (on any machine); or, with
--sponza, Sponza with a node a primitive, one of which each world moves (a robot's part in a
detailed still environment), lit by a point light. The scene's lights are given to every
call, so that no step is replayed (a replay draws as its recording did) and each takes
`keep_still` as set.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import tabletop  # noqa: E402

from vkpbr.render import shadow_raster  # noqa: E402
from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.camera_batch import CameraBatch  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402
from vkpbr.scene.types import Light  # noqa: E402


def tabletop_worlds(worlds: int, steps: int):  # noqa: ANN201
    """(scene, slot names, views, poses a step, lights) of the tabletop."""
    world = tabletop.make_tabletop()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(tabletop.write_gltf(world, tempfile.mkdtemp(prefix="tabletop-")))
    views = CameraBatch.from_poses(tabletop.camera_gltf(world)[None].repeat(worlds, 0),
                                   world.yfov_deg)
    return (scene, list(tabletop.MOVING), views,
            tabletop.Motion(world, worlds).steps(steps, "xyzw"), list(scene.lights))


def sponza_worlds(path: str, worlds: int, steps: int):  # noqa: ANN201
    """(scene, slots, views, poses a step, lights): Sponza's part 5 raised a little more in
    each world, step by step (4x4 local matrices)."""
    scene = load_scene(path)
    scene.tree = None  # one node holds all 103 primitives: a node each
    for node in scene.nodes:
        node.tree = -1
    rest = scene.node_tree().local[5]
    poses = np.repeat(rest[None, None, None], steps, 0).repeat(worlds, 1).copy()
    poses[..., 0, 1, 3] += 0.05 * np.arange(steps)[:, None] + np.linspace(0, 0.5, worlds)[None]
    return scene, [5], None, poses, [Light(kind="point", position=(0.0, 4.0, 0.0), intensity=50.0)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--worlds", type=int, default=64)
    ap.add_argument("--size", default="64x64")
    ap.add_argument("--resolution", type=int, default=256, help="world_shadow_resolution")
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--steps-apart", action="store_true", help="time the shadow kernels apart")
    ap.add_argument("--sponza", help="Sponza.gltf: a part of it moved per world instead")
    args = ap.parse_args()
    shadow_raster.TIMED_STEPS = args.steps_apart
    size = tuple(int(v) for v in args.size.split("x"))
    scene, names, views, poses, lights = (sponza_worlds(args.sponza, args.worlds, args.steps)
                                          if args.sponza else tabletop_worlds(args.worlds, args.steps))
    rows: dict[bool, tuple[list, list, list]] = {True: ([], [], []), False: ([], [], [])}
    with Renderer(scene) as r:
        r.world_slots(names)
        views = views if views is not None else [r.default_camera()] * args.worlds
        print(f"device: {r.device.info.name}; {args.worlds} worlds of {size[0]}x{size[1]}, "
              f"maps {args.resolution}^2; {len(names)} world slots")
        for _ in range(args.rounds):
            for keep in (True, False):
                for step in range(args.steps):
                    call = dict(lights=lights, worlds=poses[step], space="local",
                                world_shadow_resolution=args.resolution)
                    r.render_batch(views, size, **call)
                    r.batch_path.world_shadows.keep_still = keep
                    t = time.perf_counter()
                    r.render_batch(views, size, **call)
                    gpu, wall, parts = rows[keep]
                    wall.append(1e3 * (time.perf_counter() - t))
                    shadows = {k: v for k, v in r.last_stats.pass_ms.items() if k.startswith("shadows")}
                    gpu.append(sum(shadows.values()))
                    parts.append(shadows)
    print("| world maps | shadow steps GPU ms | step ms | steps |\n|---|---:|---:|---|")
    for keep, (gpu, wall, parts) in rows.items():
        label = "kept map copied, own casters drawn" if keep else "every caster in every world"
        names_ = sorted({k for d in parts for k in d})
        apart = " ".join(f"{k} {statistics.median(d.get(k, 0.0) for d in parts):.2f}" for k in names_)
        print(f"| {label} | {statistics.median(gpu):.2f} | {statistics.median(wall):.1f} | {apart} |")


if __name__ == "__main__":
    main()
