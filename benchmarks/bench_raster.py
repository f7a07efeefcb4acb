"""The compute rasteriser's work split, swept in one process (issue 13): GPU ms per raster step.

    python benchmarks/bench_raster.py [--scene Sponza.gltf] [--sizes 1920x1080,640x480]
        [--frames 40] [--variants 256/16384/256/4096,...] [--json OUT.json]

Each variant is a compute_path.RasterTuning (big_area/big_chunk/masked_area/masked_chunk: the
box pixels above which work groups take a triangle, and a listed band's box pixels, for
opaque and for masked draws), set before the frames' command buffers are recorded again.
The GPU first renders WARM_UP_FRAMES untimed frames (its clocks ramp up: a cold H200 read
twice the time on the first rows). Rows: the preset camera
of bench_paths, course lighting, the compute path with the compute rasteriser; GPU times
are timestamp medians over `--frames` after 10 warm-up frames. Prints a Markdown table. Not
a test.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

from bench_paths import CAMERA

from vkpbr.render import compute_path
from vkpbr.render.paths import RASTER_STEPS
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene

WARM_UP = 10
WARM_UP_FRAMES = 300


def measure(r: Renderer, size: tuple[int, int], frames: int) -> dict:
    steps, gpu = [], []
    for i, _ in enumerate(r.render_many([CAMERA] * (WARM_UP + frames), size=size, readback=False,
                                        lighting="course", pipeline="compute", raster="compute")):
        if i >= WARM_UP:
            steps.append(r.last_stats.pass_ms)
            gpu.append(r.last_stats.gpu_ms)
    row = {name: statistics.median(s.get(name, 0.0) for s in steps) for name in RASTER_STEPS}
    return {**row, "raster": sum(row.values()), "frame": statistics.median(gpu)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(Path(__file__).resolve().parents[1]
                                           / ".assets/models/Sponza/glTF/Sponza.gltf"))
    ap.add_argument("--sizes", default="1920x1080,640x480")
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--variants", default="256/16384/256/4096")
    ap.add_argument("--json")
    args = ap.parse_args()
    sizes = [tuple(int(x) for x in s.split("x")) for s in args.sizes.split(",")]
    variants = [compute_path.RasterTuning(*(int(x) for x in v.split("/")))
                for v in args.variants.split(",")]
    rows = []
    with Renderer(load_scene(args.scene)) as r:
        print(f"device: {r.device.info.name}; scene {Path(args.scene).name}; "
              f"{args.frames} frames a row")
        measure(r, sizes[0], WARM_UP_FRAMES)
        cols = ["size", *vars(variants[0]), *RASTER_STEPS, "raster", "frame"]
        print("| " + " | ".join(cols) + " |\n|" + "---|" * len(cols))
        for size in sizes:
            for tuning in variants:
                compute_path.RASTER_TUNING = tuning
                r.recorder.free()  # the push constants are recorded: record again
                row = {"size": f"{size[0]}x{size[1]}", **vars(tuning),
                       **measure(r, size, args.frames)}
                rows.append(row)
                print("| " + " | ".join(str(row[c]) if isinstance(row[c], (str, int))
                                        else f"{row[c]:.3f}" for c in cols) + " |", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
