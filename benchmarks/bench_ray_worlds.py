"""Job entries with per-view worlds (issue 32, must-have 6): what a world per view costs a Ray
actor, on each of its two routes, against the same views without worlds.

    python benchmarks/bench_ray_worlds.py [--scene SCENE --nodes 'PATTERN,...'] [--views 256]
                                          [--size 128x128] [--views-per-item 64]
                                          [--views-per-world 1] [--json OUT.json]

Each row runs the actor's own code (RendererActor.render: render, PNG encoding, atomic
writes) in this process on the same orbit of `--views` poses, after a warm-up item, so
the numbers are a Ray actor's steady rate (bench_ray.py measures Ray's own overhead):

- "plain": no worlds (the reference);
- "worlds, world by world": every view its own world (random poses of the nodes, every
  tenth node hidden), shadows on: each world set on the state, its views a plain batch;
- "worlds + materials": the same with a base colour and roughness per world and material;
- with --no-shadows as well: "plain", "worlds, batch of worlds" and the same with
  materials, with shadows and AO off (one render_batch(worlds=..., world_materials=...) per
  item).

`--views-per-world K` lets K views share each world (world_of_view): the world-by-world
route then submits K views at a time. Default scene: the built-in chart, its 25 spheres
moved. Prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_ray import orbit

from vkpbr.distributed import Job, RenderSettings, SceneJob, check_job
from vkpbr.distributed.actor import RendererActor
from vkpbr.distributed.worlds import job_worlds


def world_arrays(scene: Path | None, nodes: list[str], worlds: int, folder: Path) -> dict:
    """Random world matrices of `nodes` around their rest poses (jitter 5% of the scene's
    size, any rotation), saved as .npy in `folder`; the "worlds" object naming them."""
    from vkpbr.scene.default import default_scene
    from vkpbr.scene.loader import load_scene

    s = load_scene(scene) if scene else default_scene()
    tree = s.node_tree()
    idx = tree.indices(nodes)
    rest = tree.world()[idx]  # (N, 4, 4)
    lo, hi = s.bounds()
    rng = np.random.default_rng(0)
    q = rng.normal(size=(worlds, len(idx), 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q, -1, 0)
    rot = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                    2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                    2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
                   -1).reshape(worlds, len(idx), 3, 3)
    poses = np.broadcast_to(rest, (worlds, *rest.shape)).copy()
    poses[..., :3, :3] = rot @ rest[:, :3, :3]
    poses[..., :3, 3] += rng.normal(0, 0.05 * np.linalg.norm(np.subtract(hi, lo)), (worlds, len(idx), 3))
    np.save(folder / "poses.npy", poses)
    np.save(folder / "visible.npy", rng.uniform(size=(worlds, len(idx))) > 0.1)
    mats = [m.name for m in s.materials][:8]
    np.save(folder / "colors.npy", rng.uniform(size=(worlds, len(mats), 3)))
    np.save(folder / "rough.npy", rng.uniform(size=(worlds, len(mats))))
    return {"nodes": list(nodes), "poses": "poses.npy", "visible": "visible.npy",
            "materials": {"names": mats, "base_color": "colors.npy", "roughness": "rough.npy"}}


def run(job: Job) -> dict:
    """The actor's code in this process: one warm-up item, then every item timed."""
    check_job(job)
    actor = RendererActor()
    items = job.items()
    try:
        warm = actor.render(items[0])
        assert warm["ok"], warm
        t = time.perf_counter()
        for item in items:
            res = actor.render(item)
            assert res["ok"], res
        seconds = time.perf_counter() - t
    finally:
        actor.close()
    views = sum(len(i.frames) for i in items)
    return {"views": views, "seconds": seconds, "views_s": views / seconds}


def main() -> None:
    from vkpbr.app.parsing import parse_size
    from vkpbr.render.options import RenderOptions

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", type=Path, help="default: the built-in chart")
    p.add_argument("--nodes", default="sphere-*", help="comma-separated names or patterns")
    p.add_argument("--views", type=int, default=256)
    p.add_argument("--size", type=parse_size, default="128x128")
    p.add_argument("--views-per-item", type=int, default=64)
    p.add_argument("--views-per-world", type=int, default=1)
    p.add_argument("--no-shadows", action="store_true", help="also the rows with shadows off")
    p.add_argument("--json", type=Path)
    args = p.parse_args()

    work = Path(tempfile.mkdtemp(prefix="vkpbr-bench-worlds-"))
    rows: list[dict] = []
    try:
        poses = orbit(args.scene, args.views)
        n_worlds = -(-args.views // args.views_per_world)
        spec = world_arrays(args.scene, args.nodes.split(","), n_worlds, work)
        spec["world_of_view"] = (np.arange(args.views) // args.views_per_world).tolist()
        no_mats = {k: v for k, v in spec.items() if k != "materials"}
        off = RenderOptions(shadows=False, ao="off")
        cases = [("plain", None, None), ("worlds, world by world", no_mats, None),
                 ("worlds + materials", spec, None)]
        if args.no_shadows:
            cases += [("plain, no shadows/AO", None, off),
                      ("worlds, batch of worlds, no shadows/AO", no_mats, off),
                      ("worlds + materials, batch of worlds, no shadows/AO", spec, off)]
        for k, (name, worlds, options) in enumerate(cases):
            settings = RenderSettings(scene=args.scene, out=work / f"out{k}", size=args.size,
                                      cache=True, cache_dir=str(work / "cache"), options=options)
            jw = job_worlds(worlds, len(poses), name, work, False) if worlds else None
            job = Job((SceneJob(settings, poses, where=name, worlds=jw),),
                      views_per_item=args.views_per_item)
            rows.append({"route": name, **run(job)})
    finally:
        shutil.rmtree(work, ignore_errors=True)

    size = f"{args.size[0]}x{args.size[1]}"
    print(f"\n{args.views} views of {args.scene or 'the built-in chart'} at {size}, "
          f"{args.views_per_item} views per item, {args.views_per_world} view(s) per world, "
          f"nodes {args.nodes}\n")
    print("| route | views | s | views/s | vs plain |")
    print("|---|---|---|---|---|")
    for r in rows:
        base = rows[3] if "no shadows" in r["route"] and len(rows) > 3 else rows[0]
        print(f"| {r['route']} | {r['views']} | {r['seconds']:.2f} | {r['views_s']:.1f} | "
              f"{r['views_s'] / base['views_s']:.2f}x |")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
