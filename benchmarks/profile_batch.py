"""Where one render_batch call's wall time goes (issue 14): cProfile of warm calls of the
compute batch into NumPy and into torch, top functions by own time, beside the GPU time.

    python benchmarks/profile_batch.py [--scene helmet] [--size 128] [--views 4096]

Scenes and poses as benchmarks/bench_batch.py. Not a test.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from bench_batch import load, poses_for, torch_cuda

from vkpbr.render.renderer import Renderer
from vkpbr.scene.camera_batch import CameraBatch


def main() -> None:
    import common as peers

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="helmet")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--views", type=int, default=4096)
    ap.add_argument("--pipeline", default="auto")
    args = ap.parse_args()
    torch = torch_cuda()
    size = (args.size, args.size)
    with Renderer(load(args.scene)) as r:
        views = CameraBatch.from_poses(poses_for(args.scene, r, args.views), peers.YFOV_DEG)
        for device in ("cpu", "cuda") if torch is not None else ("cpu",):
            for _ in range(3):  # warm: targets, recordings, imports
                r.render_batch(views, size, device=device, pipeline=args.pipeline)
            if torch is not None:
                torch.cuda.synchronize()
            prof = cProfile.Profile()
            t = time.perf_counter()
            prof.enable()
            r.render_batch(views, size, device=device, pipeline=args.pipeline)
            if torch is not None:
                torch.cuda.synchronize()
            prof.disable()
            wall = (time.perf_counter() - t) * 1e3
            print(f"\n== {args.scene} {args.size}x{args.size} B={args.views} into {device}: "
                  f"{wall:.1f} ms wall, {r.last_stats.gpu_ms:.1f} ms GPU, "
                  f"passes {dict((k, round(v, 2)) for k, v in r.last_stats.pass_ms.items() if v > 0.01)}")
            pstats.Stats(prof).sort_stats("tottime").print_stats(14)


if __name__ == "__main__":
    main()
