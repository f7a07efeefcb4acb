"""What each dataset output costs (issue 15): frames/s and GPU ms with and without them.

    python benchmarks/bench_outputs.py [--scene Sponza.gltf] [--size 1920x1080] [--frames 50]
                                       [--json OUT.json]

Rows: colour alone (the fragment path, no visibility pass), then colour with each output
(depth, range, instance + semantic, normal, normal_camera, normal_geometric) and with all of
them: the outputs add the visibility pass (the fragment path's depth pre-pass) and one
compute kernel per material, then a readback per output. GPU times are timestamp queries
(median after 5 warm-up frames); frames/s is wall time of `render_many` with every array
copied into NumPy. Prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Camera

CAMERA = Camera(eye=(9.0, 1.8, -0.4), target=(-9.0, 3.5, -0.4), yfov_deg=45.0)  # the preset
ROWS = ((), ("depth",), ("range",), ("instance", "semantic"), ("normal",), ("normal_camera",),
        ("normal_geometric",),
        ("depth", "range", "instance", "semantic", "normal", "normal_camera", "normal_geometric"))


def measure(r: Renderer, size: tuple[int, int], frames: int, outputs: tuple[str, ...]) -> dict:
    wanted = ("color", *outputs) if outputs else None
    gpu = []
    for i, _ in enumerate(r.render_many([CAMERA] * (frames + 5), size=size, outputs=wanted)):
        if i >= 5:
            gpu.append(r.last_stats.gpu_ms)
    t = time.perf_counter()
    for _ in r.render_many([CAMERA] * frames, size=size, outputs=wanted):
        pass
    return {"outputs": "+".join(outputs) or "colour only", "gpu_ms": statistics.median(gpu),
            "fps": frames / (time.perf_counter() - t), "size": f"{size[0]}x{size[1]}"}


def main() -> None:
    here = Path(__file__).resolve().parent.parent
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(here / ".assets/models/Sponza/glTF/Sponza.gltf"))
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--frames", type=int, default=50)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        print(f"{r.device.info.name}, {Path(args.scene).name}, {args.size}, {args.frames} frames")
        print("| outputs | GPU ms | frames/s into NumPy | GPU ms over colour only |")
        print("|---|---|---|---|")
        rows, base = [], None
        for outputs in ROWS:
            row = measure(r, size, args.frames, outputs)
            base = row["gpu_ms"] if base is None else base
            rows.append(row)
            print(f"| {row['outputs']} | {row['gpu_ms']:.2f} | {row['fps']:.1f} | "
                  f"{row['gpu_ms'] - base:+.2f} |", flush=True)
    if args.json:
        with args.json.open("a") as f:
            for row in rows:
                f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
