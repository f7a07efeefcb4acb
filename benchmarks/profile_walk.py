"""Where a walking camera's Python time goes: cProfile of render_many over Sponza's walk
(bench_paths.walk) with the sun, three frames in flight, into NumPy. Prints the 30 costliest
functions by own time, then by cumulative time.

    python3 benchmarks/profile_walk.py --scene Sponza.gltf [--frames 300] [--size 1920x1080] [--still]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_paths import CAMERA, walk  # noqa: E402

from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--still", action="store_true", help="the preset camera, not moving")
    ap.add_argument("--pipeline", default="compute")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        cams = [CAMERA] * args.frames if args.still else walk(args.frames)
        for _ in r.render_many(cams[:20], size=size, pipeline=args.pipeline):
            pass
        prof = cProfile.Profile()
        t = time.perf_counter()
        prof.enable()
        n = sum(1 for _ in r.render_many(cams, size=size, pipeline=args.pipeline))
        prof.disable()
        dt = time.perf_counter() - t
    print(f"{n} frames in {dt:.3f} s: {n / dt:.1f} frames/s ({'still' if args.still else 'walk'}, {args.size})")
    stats = pstats.Stats(prof).strip_dirs()
    stats.sort_stats("tottime").print_stats(30)
    stats.sort_stats("cumulative").print_stats(30)


if __name__ == "__main__":
    main()
