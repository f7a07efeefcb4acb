"""Dataset outputs in batches: views/s into NumPy of `render_batch(outputs=...)` through the
compute batch's own outputs pass (pipeline "auto", or "compute"), against the way without it
in the same run (pipeline "forward": the layered batch's colour, then every view drawn again
through render_many for the outputs, as every batch with outputs rendered before session 26),
and against the colour alone. Not a test; prints one Markdown table.

    python benchmarks/bench_batch_outputs.py [--scenes helmet,sponza] [--sizes 128x128]
        [--batches 64,1024] [--outputs color,depth,instance,normal] [--reps 3]

The scenes and poses are bench_batch.py's (the peers' orbit, one point light); each row: two
warm-up calls, then the median of `--reps` timed calls.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE / "peers")]
import common as peers  # noqa: E402  (the peers' scenario: poses, scene paths)
from bench_batch import load, poses_for  # noqa: E402

from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.camera_batch import CameraBatch  # noqa: E402


def views_per_s(r: Renderer, views: CameraBatch, size: tuple[int, int], reps: int,
                **kwargs: object) -> float:
    """B / the median wall clock of `reps` render_batch calls (after two warm-ups)."""
    for _ in range(2):
        r.render_batch(views, size=size, **kwargs)
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        r.render_batch(views, size=size, **kwargs)
        times.append(time.perf_counter() - t)
    return len(views) / statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="helmet,sponza")
    ap.add_argument("--sizes", default="128x128")
    ap.add_argument("--batches", default="64,1024")
    ap.add_argument("--outputs", default="color,depth,instance,normal")
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    outputs = tuple(args.outputs.split(","))
    print(f"outputs: {', '.join(outputs)}")
    print("| scene | size | B | colour only (auto) | outputs, compute batch (auto) "
          "| outputs, layered + view by view (forward) | outputs: auto / forward | device |")
    print("|---|---|---:|---:|---:|---:|---:|---|")
    for key in args.scenes.split(","):
        scene = load(key)
        if scene is None:
            print(f"skipped {key}: {peers.ASSETS / peers.BATCH_SCENES[key]} not found",
                  file=sys.stderr)
            continue
        with Renderer(scene) as r:
            for size_text in args.sizes.split(","):
                w, h = (int(v) for v in size_text.split("x"))
                for b in (int(v) for v in args.batches.split(",")):
                    views = CameraBatch.from_poses(poses_for(key, r, b), peers.YFOV_DEG)
                    colour = views_per_s(r, views, (w, h), args.reps)
                    auto = views_per_s(r, views, (w, h), args.reps, outputs=outputs)
                    forward = views_per_s(r, views, (w, h), args.reps, outputs=outputs,
                                          pipeline="forward")
                    print(f"| {key} | {w}x{h} | {b} | {colour:,.0f} | {auto:,.0f} "
                          f"| {forward:,.0f} | {auto / forward:.1f}x | {r.device.info.name} |",
                          flush=True)


if __name__ == "__main__":
    main()
