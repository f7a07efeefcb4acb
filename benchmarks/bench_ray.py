"""vkpbr.distributed on one machine (issue 16): views/s with 1, 2 and 4 renderer actors sharing
one device, the Ray path's per-view overhead against the same renders and writes in-process,
and (with --scenes) a many-scenes job in views/s including the scene loads.

    python benchmarks/bench_ray.py [--scene SCENE] [--views 64] [--size 256x256]
                                   [--actors 1,2,4] [--views-per-item 8] [--outputs depth]
                                   [--scenes A.glb,B.gltf,...] [--address HOST:PORT]
                                   [--json OUT.json]

Every row renders the same orbit of `--views` poses around the scene into a fresh folder
(PNG colour plus `--outputs`). "in-process" runs the actor's own code (RendererActor.render)
in this process after a warm-up, so it is the floor the Ray path is measured against. A Ray
row's "views/s" is the whole `vkpbr.distributed.render` call (actor start-up and scene load
included); "steady views/s" leaves out each actor's first item (its start-up and scene
load): per actor, the views of its later items over the time from its first result to its
last, summed over the actors: the throughput of a long job. Actors share the machine's one device: num_gpus = 1/N where Ray sees a GPU, else
num_cpus = CPUs/N (lavapipe). Prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import tempfile
import time
from pathlib import Path

from vkpbr.distributed import Job, RenderSettings, SceneJob, check_job, render
from vkpbr.distributed.actor import RendererActor
from vkpbr.scene.camera import as_pose


def orbit(scene_path: Path | None, n: int) -> tuple:
    """`n` poses on a circle around the scene's automatic camera target, at its distance."""
    import numpy as np

    from vkpbr.scene.default import default_scene
    from vkpbr.scene.geometry import auto_camera
    from vkpbr.scene.loader import load_scene

    scene = load_scene(scene_path) if scene_path else default_scene()
    cam = auto_camera(scene)
    eye, target = np.asarray(cam.eye), np.asarray(cam.target)
    d = eye - target
    r, h = math.hypot(d[0], d[2]), d[1]
    poses = []
    for i in range(n):
        a = 2 * math.pi * i / n
        e = target + (r * math.cos(a), h, r * math.sin(a))
        poses.append(as_pose({"eye": e.tolist(), "target": target.tolist()}, f"pose {i}"))
    return tuple(poses)


def scene_job(scene: Path | None, out: Path, args: argparse.Namespace) -> SceneJob:
    settings = RenderSettings(scene=scene, out=out, size=args.size, outputs=args.outputs,
                              cache=True)
    return SceneJob(settings, orbit(scene, args.views), where=str(scene or "chart"))


def in_process(job: Job) -> dict:
    """The actor's code in this process: warm-up (scene load, first renders), then timed."""
    check_job(job)  # creates the out folder, as render() does
    actor = RendererActor()
    items = job.items()
    try:
        warm = actor.render(items[0])
        assert warm["ok"], warm
        t = time.perf_counter()
        views = 0
        for item in items:
            res = actor.render(item)
            assert res["ok"], res
            views += len(item.frames)
        seconds = time.perf_counter() - t
    finally:
        actor.close()
    return {"views": views, "seconds": seconds, "views_s": views / seconds}


def on_ray(job: Job, actors: int, address: str | None) -> dict:
    import ray

    gpus = float(ray.cluster_resources().get("GPU", 0))
    cpus = float(ray.cluster_resources().get("CPU", 1))
    share = {"num_gpus": 1.0 / actors, "num_cpus": 0.0} if gpus >= 1 else \
        {"num_cpus": cpus / actors}
    results: list[tuple[float, int, int]] = []  # (time, pid, views)

    def note(item, res) -> None:  # noqa: ANN001
        results.append((time.perf_counter(), res.get("pid", 0), len(item.frames)))

    t = time.perf_counter()
    result = render(job, address, actors=actors, progress=False, on_result=note, **share)
    total = time.perf_counter() - t
    assert result.ok, result.summary()
    # Each actor has one item at a time, so the items an actor returns after its first were
    # all rendered after it: its steady rate is their views over that span; the actors run
    # side by side, so the job's is the sum.
    per_actor: dict[int, list[tuple[float, int]]] = {}
    for when, pid, views in results:
        per_actor.setdefault(pid, []).append((when, views))
    rates = [sum(v for _, v in r[1:]) / (r[-1][0] - r[0][0]) for r in per_actor.values()
             if len(r) > 1]
    steady = sum(rates) if len(rates) == len(per_actor) else float("nan")
    return {"actors": actors, "views": result.rendered, "seconds": total,
            "views_s": result.rendered / total, "steady_views_s": steady, **share}


def main() -> None:
    from vkpbr.app.parsing import parse_size

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", type=Path, help="default: the built-in chart")
    p.add_argument("--views", type=int, default=64)
    p.add_argument("--size", type=parse_size, default="256x256")
    p.add_argument("--actors", default="1,2,4")
    p.add_argument("--views-per-item", type=int, default=8)
    p.add_argument("--outputs", type=lambda s: tuple(x for x in s.split(",") if x), default=())
    p.add_argument("--scenes", help="comma-separated scene files for the many-scenes row")
    p.add_argument("--address", help="a Ray cluster (default: a local Ray instance)")
    p.add_argument("--json", type=Path)
    args = p.parse_args()

    import ray

    work = Path(tempfile.mkdtemp(prefix="vkpbr-bench-ray-"))
    os.environ.setdefault("VKPBR_CACHE_DIR", str(work / "cache"))
    rows: list[dict] = []
    try:
        def job(name: str) -> Job:
            return Job((scene_job(args.scene, work / name, args),),
                       views_per_item=args.views_per_item)

        base = in_process(job("in-process"))
        rows.append({"path": "in-process", "actors": 1, **base, "steady_views_s": base["views_s"]})
        ray.init(address=args.address, include_dashboard=False, log_to_driver=False,
                 logging_level="WARNING")
        for n in (int(x) for x in args.actors.split(",")):
            rows.append({"path": "ray", **on_ray(job(f"ray-{n}"), n, args.address)})
        if args.scenes:
            scenes = tuple(scene_job(Path(s), work / f"many-{i}", args)
                           for i, s in enumerate(args.scenes.split(",")))
            many = Job(scenes, views_per_item=args.views_per_item)
            t = time.perf_counter()
            result = render(many, args.address, progress=False)
            total = time.perf_counter() - t
            rows.append({"path": f"ray, {len(scenes)} scenes", "actors": result.actors,
                         "views": result.rendered, "seconds": total,
                         "views_s": result.rendered / total, "steady_views_s": float("nan")})
        ray.shutdown()
    finally:
        shutil.rmtree(work, ignore_errors=True)

    size = f"{args.size[0]}x{args.size[1]}"
    print(f"\n{args.views} views of {args.scene or 'the built-in chart'} at {size}, "
          f"{args.views_per_item} views per item, outputs: colour{''.join(', ' + o for o in args.outputs)}\n")
    print("| path | actors | views | s | views/s | steady views/s | per view ms (steady) | overhead vs in-process |")
    print("|---|---|---|---|---|---|---|---|")
    floor = rows[0]["views_s"]
    for r in rows:
        steady = r["steady_views_s"]
        over = (floor / steady - 1) * 100 if r["actors"] == 1 and steady == steady else None
        shown = (f"{steady:.1f} | {1e3 / steady:.2f}" if steady == steady  # not NaN
                 else "- (too few items) | -")
        print(f"| {r['path']} | {r['actors']} | {r['views']} | {r['seconds']:.2f} | "
              f"{r['views_s']:.1f} | {shown} | "
              + (f"{over:+.1f}% |" if over is not None else "- |"))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
