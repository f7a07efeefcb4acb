"""What ambient occlusion costs (render/ao.py: GTAO and its denoise, the "ao" step): Sponza on
the compute path (compute rasteriser) as `vkpbr bench` draws it, with `--ao gtao` and
`--ao off`, at 1920x1080 and 640x480; and a compute batch of 4,096 views of 128x128 both ways.
Prints GPU ms per frame (or per batch) and the "ao" step's own time (the GTAO kernel and the
denoise passes, from the timestamps around them), medians. Targets (issue 33): the step
<= 0.15 ms at 1080p on the H200.

    python3 benchmarks/bench_ao.py --scene Sponza.gltf [--frames 300] [--batches 5] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys

import numpy as np

from vkpbr.render.renderer import Renderer
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.loader import load_scene

BATCH_VIEWS, BATCH_SIZE = 4096, (128, 128)


def frames(r: Renderer, size: tuple[int, int], count: int, ao: str) -> dict:
    gpu, step = [], []
    cams = [r.default_camera()] * (count + 20)
    for i, _ in enumerate(r.render_many(cams, size=size, readback=False, pipeline="compute",
                                        raster="compute", ao=ao)):
        if i >= 20:
            gpu.append(r.last_stats.gpu_ms)
            step.append(r.last_stats.pass_ms.get("ao", 0.0))
    return {"gpu_ms": statistics.median(gpu), "ao_ms": statistics.median(step)}


def ring_poses(r: Renderer, count: int) -> np.ndarray:
    """(count, 4, 4) OpenGL world-from-camera poses on a ring about the default camera's
    target, at its distance and height (seeded)."""
    cam = r.default_camera()
    eye, target = np.asarray(cam.eye, float), np.asarray(cam.target, float)
    rng = np.random.default_rng(33)
    a = 2 * np.pi * (np.arange(count) + rng.uniform(0, 1, count)) / count
    d = eye - target
    radius = math.hypot(d[0], d[2])
    poses = np.zeros((count, 4, 4))
    for i, angle in enumerate(a):
        e = target + np.array([radius * math.cos(angle), d[1], radius * math.sin(angle)])
        f = target - e
        f /= np.linalg.norm(f)
        s = np.cross(f, (0.0, 1.0, 0.0))
        s /= np.linalg.norm(s)
        u = np.cross(s, f)
        poses[i, :3, 0], poses[i, :3, 1], poses[i, :3, 2], poses[i, :3, 3] = s, u, -f, e
        poses[i, 3, 3] = 1.0
    return poses


def batch(r: Renderer, reps: int, ao: str, count: int) -> dict:
    views = CameraBatch.from_poses(ring_poses(r, count), yfov_deg=60.0)
    gpu, step = [], []
    for i in range(reps + 1):
        r.render_batch(views, size=BATCH_SIZE, pipeline="compute", ao=ao)
        if i:
            gpu.append(r.last_stats.gpu_ms)
            step.append(r.last_stats.pass_ms.get("ao", 0.0))
    return {"gpu_ms": statistics.median(gpu), "ao_ms": statistics.median(step)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--batches", type=int, default=5)
    ap.add_argument("--views", type=int, default=BATCH_VIEWS, help="views of the batch")
    ap.add_argument("--sizes", default="1920x1080,640x480")
    ap.add_argument("--json")
    args = ap.parse_args()
    sizes = [tuple(int(v) for v in s.split("x")) for s in args.sizes.split(",")]
    rows = []
    with Renderer(load_scene(args.scene)) as r:
        for size in sizes:
            for ao in ("off", "gtao"):
                rows.append({"what": f"frame {size[0]}x{size[1]}", "ao": ao,
                             **frames(r, size, args.frames, ao)})
        for ao in ("off", "gtao"):
            rows.append({"what": f"batch {args.views} x {BATCH_SIZE[0]}x{BATCH_SIZE[1]}",
                         "ao": ao, **batch(r, args.batches, ao, args.views)})
    print("| what | --ao | GPU ms | ao step ms |\n|---|---|---:|---:|")
    for row in rows:
        print(f"| {row['what']} | {row['ao']} | {row['gpu_ms']:.3f} | {row['ao_ms']:.3f} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    sys.exit(0)


if __name__ == "__main__":
    main()
