#!/usr/bin/env python3
"""Soak test (issue 11, long tier): CYCLES load/render/close cycles, then FRAMES frames of
one renderer, with host RSS and the live Vulkan object count sampled along the way.

    PYTHONPATH=src python scripts/soak.py 1000 100000
    PYTHONPATH=src python scripts/soak.py 300 20000 --scene path/to/DamagedHelmet.gltf

Each cycle loads the scene (from its file, or builds the built-in one), makes a Renderer,
renders one frame of --size and closes it. The frames are `render_many` batches of --batch
cameras on one Renderer, with readback. Prints one line per sample and a summary; exits 1
when the growth after the warm-up exceeds the bounds (--max-cycle-mib over all cycles,
--max-frame-mib over all frames: totals, as the heap moves in steps of a few MiB) or when the Vulkan object count is not back at its start after
a close. RSS is read from /proc/self/statm (Linux).
"""

from __future__ import annotations

import argparse
import gc
import os
import sys
import time
from pathlib import Path

MIB = 2**20


def rss() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def parse_size(text: str) -> tuple[int, int]:
    w, _, h = text.lower().partition("x")
    return int(w), int(h)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("cycles", type=int, help="load/render/close cycles")
    p.add_argument("frames", type=int, help="frames of one renderer after the cycles")
    p.add_argument("--scene", type=Path, help="scene file (default: the built-in scene)")
    p.add_argument("--size", type=parse_size, default=(64, 64), help="WxH (default 64x64)")
    p.add_argument("--batch", type=int, default=100, help="cameras per render_many call")
    p.add_argument("--warmup", type=int, default=20, help="cycles before the RSS baseline")
    p.add_argument("--samples", type=int, default=20, help="lines printed per phase")
    p.add_argument("--validation", action="store_true", help="with the validation layer")
    p.add_argument("--max-cycle-mib", type=float, default=16.0,
                   help="allowed RSS growth over all cycles after the warm-up (MiB)")
    p.add_argument("--max-frame-mib", type=float, default=8.0,
                   help="allowed RSS growth over all frames after the first batch (MiB)")
    args = p.parse_args(argv)

    from vkpbr import Renderer, load_scene
    from vkpbr.gpu.device import live_objects, live_objects_by_kind
    from vkpbr.scene.default import default_scene

    def scene():  # noqa: ANN202
        return load_scene(args.scene) if args.scene else default_scene()

    failed = False
    start_objects = live_objects()
    t0 = time.perf_counter()
    every = max(1, args.cycles // args.samples)
    base = None
    print(f"{'cycle':>7} {'RSS MiB':>8} {'objects':>8} {'s':>7}")
    for i in range(args.cycles):
        with Renderer(scene(), validation=args.validation) as r:
            r.render(size=args.size)
        if live_objects() != start_objects:
            print(f"cycle {i}: {live_objects() - start_objects} Vulkan objects left after "
                  f"close: {live_objects_by_kind()}")
            failed = True
            break
        if i + 1 == min(args.warmup, args.cycles):
            gc.collect()
            base = rss()
        if i % every == 0 or i == args.cycles - 1:
            gc.collect()
            print(f"{i:>7} {rss() / MIB:>8.1f} {live_objects():>8} {time.perf_counter() - t0:>7.1f}",
                  flush=True)
    if args.cycles:
        gc.collect()
        grown = (rss() - (base or rss())) / MIB
        n = max(args.cycles - args.warmup, 0)
        per = grown / n if n else 0.0
        ok = grown <= args.max_cycle_mib
        failed |= not ok
        print(f"cycles: {args.cycles}, RSS after warm-up {grown:+.1f} MiB over {n} cycles "
              f"({per * 1024:+.1f} KiB/cycle), bound {args.max_cycle_mib} MiB: "
              f"{'ok' if ok else 'FAIL'}")

    if args.frames:
        with Renderer(scene(), validation=args.validation) as r:
            batches = max(1, -(-args.frames // args.batch))
            every = max(1, batches // args.samples)
            done, frame_base, objects = 0, None, None
            print(f"{'frame':>7} {'RSS MiB':>8} {'objects':>8} {'s':>7}")
            t0 = time.perf_counter()
            for b in range(batches):
                n = min(args.batch, args.frames - done)
                for _ in r.render_many([None] * n, size=args.size):
                    pass
                done += n
                if b == 0:
                    gc.collect()
                    frame_base, objects, first = rss(), live_objects(), done
                elif live_objects() != objects:
                    print(f"frame {done}: the Vulkan object count changed "
                          f"({objects} -> {live_objects()})")
                    failed = True
                    break
                if b % every == 0 or b == batches - 1:
                    print(f"{done:>7} {rss() / MIB:>8.1f} {live_objects():>8} "
                          f"{time.perf_counter() - t0:>7.1f}", flush=True)
            gc.collect()
            frames = done - first
            grown = (rss() - frame_base) / 1024
            per = grown / frames if frames else 0.0
            ok = grown / 1024 <= args.max_frame_mib
            failed |= not ok
            print(f"frames: {done}, RSS after the first batch {grown / 1024:+.2f} MiB over "
                  f"{frames} frames ({per:+.3f} KiB/frame), bound {args.max_frame_mib} "
                  f"MiB: {'ok' if ok else 'FAIL'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
