"""Where a walking camera's Python time goes: cProfile of render_many over Sponza's walk
(bench_paths.walk) with the automatic sun (or the scene's lights), three frames in flight,
into NumPy. Prints the 30 costliest functions by own time, then by cumulative time.

    python3 benchmarks/profile_walk.py --scene Sponza.gltf [--frames 300] [--size 1920x1080] [--still]
                                       [--light sun|scene] [--resolution 2048]

With --python instead: each frame's Python alone (draw()'s stats.cpu_ms less its driver_ms,
as bench_paths.py's "Python alone") through render() once a frame (the GPU idle while Python
runs), median and quartiles over --frames, for a still camera with the sun, the walk with the
sun and the walk with the scene's lights, each shadow_raster mode; and the recordings made
while measuring (a redraw set new to a frame slot records its command buffer). On a CPU:

    python3 benchmarks/profile_walk.py --scene Sponza.gltf --python --size 64x48 --resolution 128 --frames 300
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_paths import CAMERA, walk  # noqa: E402

from vkpbr.render import recorder  # noqa: E402
from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402


def python_rows(r: Renderer, frames: int, size: tuple[int, int], resolution: int) -> None:
    """--python: the median Python alone per frame of each row (see the docstring)."""
    made = [0]
    record = recorder.FrameRecorder._record

    def counted(self, *a, **k):  # noqa: ANN001, ANN002, ANN003, ANN202 - counts recordings
        made[0] += 1
        return record(self, *a, **k)

    recorder.FrameRecorder._record = counted
    print("| shadow_raster | row | Python alone ms (median) | q1 | q3 | mean | layers/frame | recordings |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for mode in ("hardware", "compute"):
        opts = {"size": size, "pipeline": "compute", "raster": "compute",
                "shadow_resolution": resolution, "shadow_raster": mode}
        for row in ("still + sun", "walk + sun", "walk + scene"):
            lights = [r.automatic_sun()] if row.endswith("sun") else None
            cams = walk(frames) if row.startswith("walk") else [CAMERA] * frames
            for _ in r.render_many(cams[:10], lights, **opts):  # warm-up
                pass
            made[0] = 0
            py, layers = [], []
            for cam in cams:
                for _ in r.render_many([cam], lights, driver_time=True, **opts):  # render()
                    py.append(r.last_stats.cpu_ms - r.last_stats.driver_ms)
                    layers.append(sum(n for _, n in r.shadows.last_redrawn_layers))
            q = statistics.quantiles(py, n=4)
            print(f"| {mode} | {row} | {statistics.median(py):.4f} | {q[0]:.4f} | {q[2]:.4f} | "
                  f"{statistics.fmean(py):.4f} | {statistics.fmean(layers):.3f} | {made[0]} |",
                  flush=True)
    recorder.FrameRecorder._record = record


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--still", action="store_true", help="the preset camera, not moving")
    ap.add_argument("--pipeline", default="compute")
    ap.add_argument("--light", choices=("sun", "scene"), default="sun",
                    help="the automatic sun, or the scene's lights (Sponza: its preset point light)")
    ap.add_argument("--resolution", type=int, default=2048, help="shadow-map texels a side")
    ap.add_argument("--python", action="store_true",
                    help="the median Python alone per frame of each row, no profile")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        if args.python:
            python_rows(r, args.frames, size, args.resolution)
            return
        lights = [r.automatic_sun()] if args.light == "sun" else None
        opts = {"size": size, "pipeline": args.pipeline, "shadow_resolution": args.resolution}
        cams = [CAMERA] * args.frames if args.still else walk(args.frames)
        for _ in r.render_many(cams[:20], lights, **opts):
            pass
        prof = cProfile.Profile()
        t = time.perf_counter()
        prof.enable()
        n = sum(1 for _ in r.render_many(cams, lights, **opts))
        prof.disable()
        dt = time.perf_counter() - t
    print(f"{n} frames in {dt:.3f} s: {n / dt:.1f} frames/s ({'still' if args.still else 'walk'}, "
          f"{args.size}, {args.light})")
    stats = pstats.Stats(prof).strip_dirs()
    stats.sort_stats("tottime").print_stats(30)
    stats.sort_stats("cumulative").print_stats(30)


if __name__ == "__main__":
    main()
