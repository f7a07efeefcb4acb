#!/usr/bin/env python3
"""Soak test (issue 11, long tier): CYCLES load/render/close cycles, then FRAMES frames of
one renderer, with host memory and the live Vulkan object count sampled along the way.

    PYTHONPATH=src python scripts/soak.py 1000 100000
    PYTHONPATH=src python scripts/soak.py 300 20000 --scene path/to/DamagedHelmet.gltf

Each cycle loads the scene (from its file, or builds the built-in one), makes a Renderer,
renders one frame of --size and closes it. The frames are `render_many` batches of --batch
cameras on one Renderer, with readback. RSS is read from /proc/self/statm (Linux).

What is bounded, and why. Raw RSS is not a leak measure: glibc keeps freed heap memory
mapped, and lavapipe allocates and frees ~13 MiB around its submits, so the heap's size moves
up in steps of that order whenever a fresh block lands above a fragmented one, while the
memory in use does not move (BENCHMARKS.md, "Memory over time": tracemalloc flat to the byte
over 20,000 frames, glibc's in-use bytes flat, malloc_trim(0) returning the steps). So each
sample first calls glibc's malloc_trim(0), which hands the free heap back, and the bounds
apply to that *trimmed* RSS. Even trimmed, a sample sometimes holds a ~13 MiB block of
lavapipe's that is gone at the next (glibc's in-use bytes jump by it and back), so the frame
bounds use the lower envelope of the samples after the warm-up (`floor_trend`: the minimum of
each quarter of them): its growth (--max-frame-mib) and its least-squares slope
(--max-frame-slope, KiB per 1,000 frames; the default 20 is 0.02 KiB a frame, a few Python
objects a frame would exceed it). The cycles' bound (--max-cycle-mib) is on the trimmed RSS
after the warm-up. Raw RSS and glibc's in-use bytes (mallinfo2) are printed beside it. Where
there is no glibc, trimmed equals raw. Exits 1
when a bound is exceeded or when the Vulkan object count is not back at its start after a
close (or changes during the frames).
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import gc
import os
import sys
import time
from pathlib import Path

MIB = 2**20


def rss() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
        "fordblks", "keepcost")]


def _libc():  # noqa: ANN202 - ctypes.CDLL or None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.malloc_trim.argtypes = [ctypes.c_size_t]
        libc.mallinfo2.restype = _MallInfo2  # glibc >= 2.33
        return libc
    except (OSError, AttributeError):
        return None


LIBC = _libc()


def sample() -> tuple[int, int, int | None]:
    """(raw RSS, RSS after gc and malloc_trim(0), glibc heap bytes in use or None)."""
    gc.collect()
    raw = rss()
    if LIBC is None:
        return raw, raw, None
    LIBC.malloc_trim(0)
    info = LIBC.mallinfo2()
    return raw, rss(), info.uordblks + info.hblkhd


def slope(xs: list[float], ys: list[float]) -> float:
    """Least-squares slope of ys over xs (0 with fewer than two points)."""
    n = len(xs)
    if n < 2:
        return 0.0
    mx, my = sum(xs) / n, sum(ys) / n
    var = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / var if var else 0.0


def floor_trend(xs: list[float], ys: list[float], windows: int = 4) -> tuple[float, float]:
    """(growth, slope) of the lower envelope of ys: the samples split into `windows` runs,
    each run's minimum placed at its mean x; growth is last minimum - first, slope the
    least-squares slope of the minima. Robust to a transient block that is alive at some
    samples and not at others (lavapipe's ~13 MiB), which only ever adds."""
    if not xs:
        return 0.0, 0.0
    k = max(1, -(-len(xs) // windows))
    mx = [sum(xs[i:i + k]) / len(xs[i:i + k]) for i in range(0, len(xs), k)]
    my = [min(ys[i:i + k]) for i in range(0, len(xs), k)]
    return my[-1] - my[0], slope(mx, my)


def parse_size(text: str) -> tuple[int, int]:
    w, _, h = text.lower().partition("x")
    return int(w), int(h)


def _line(i: int, s: tuple[int, int, int | None], objects: int, seconds: float) -> str:
    heap = f"{s[2] / MIB:>8.1f}" if s[2] is not None else f"{'-':>8}"
    return f"{i:>7} {s[0] / MIB:>8.1f} {s[1] / MIB:>8.1f} {heap} {objects:>8} {seconds:>7.1f}"


HEADER = f"{'RSS MiB':>8} {'trimmed':>8} {'in use':>8} {'objects':>8} {'s':>7}"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("cycles", type=int, help="load/render/close cycles")
    p.add_argument("frames", type=int, help="frames of one renderer after the cycles")
    p.add_argument("--scene", type=Path, help="scene file (default: the built-in scene)")
    p.add_argument("--size", type=parse_size, default=(64, 64), help="WxH (default 64x64)")
    p.add_argument("--batch", type=int, default=100, help="cameras per render_many call")
    p.add_argument("--lighting", choices=("pbr", "course"), default="pbr",
                   help="lighting mode of the frames (default pbr: shadows, sky light)")
    p.add_argument("--warmup", type=int, default=20, help="cycles before the RSS baseline")
    p.add_argument("--frame-warmup", type=int, default=1000,
                   help="frames before the frame baseline (default 1000)")
    p.add_argument("--samples", type=int, default=20, help="lines printed per phase")
    p.add_argument("--validation", action="store_true", help="with the validation layer")
    p.add_argument("--max-cycle-mib", type=float, default=16.0,
                   help="allowed trimmed-RSS growth over all cycles after the warm-up (MiB)")
    p.add_argument("--max-frame-mib", type=float, default=8.0,
                   help="allowed trimmed-RSS growth over all frames after the warm-up (MiB)")
    p.add_argument("--max-frame-slope", type=float, default=20.0,
                   help="allowed trimmed-RSS slope after the frame warm-up, KiB per 1,000 "
                        "frames (default 20: 2 MiB per 100,000 frames)")
    args = p.parse_args(argv)

    from vkpbr import Renderer, load_scene
    from vkpbr.gpu.device import live_objects, live_objects_by_kind
    from vkpbr.scene.default import default_scene

    def scene():  # noqa: ANN202
        return load_scene(args.scene) if args.scene else default_scene()

    if LIBC is None:
        print("no glibc malloc_trim/mallinfo2: trimmed RSS is raw RSS")
    failed = False
    start_objects = live_objects()
    t0 = time.perf_counter()
    every = max(1, args.cycles // args.samples)
    base = None
    if args.cycles:
        print(f"{'cycle':>7} {HEADER}")
    for i in range(args.cycles):
        with Renderer(scene(), validation=args.validation) as r:
            r.render(size=args.size)
        if live_objects() != start_objects:
            print(f"cycle {i}: {live_objects() - start_objects} Vulkan objects left after "
                  f"close: {live_objects_by_kind()}")
            failed = True
            break
        if i + 1 == min(args.warmup, args.cycles):
            base = sample()
        if i % every == 0 or i == args.cycles - 1:
            print(_line(i, sample(), live_objects(), time.perf_counter() - t0), flush=True)
    if args.cycles:
        end = sample()
        base = base or end
        grown, raw = (end[1] - base[1]) / MIB, (end[0] - base[0]) / MIB
        n = max(args.cycles - args.warmup, 0)
        ok = grown <= args.max_cycle_mib
        failed |= not ok
        print(f"cycles: {args.cycles}, trimmed RSS after warm-up {grown:+.1f} MiB over {n} "
              f"cycles ({grown * 1024 / max(n, 1):+.1f} KiB/cycle; raw RSS {raw:+.1f} MiB), "
              f"bound {args.max_cycle_mib} MiB: {'ok' if ok else 'FAIL'}")

    if args.frames:
        with Renderer(scene(), validation=args.validation) as r:
            batches = max(1, -(-args.frames // args.batch))
            every = max(1, batches // args.samples)
            done, first, objects = 0, None, None
            xs: list[float] = []
            ys: list[float] = []
            print(f"{'frame':>7} {HEADER}")
            t0 = time.perf_counter()
            for b in range(batches):
                n = min(args.batch, args.frames - done)
                for _ in r.render_many([None] * n, size=args.size, lighting=args.lighting):
                    pass
                done += n
                if objects is None:
                    objects = live_objects()
                elif live_objects() != objects:
                    print(f"frame {done}: the Vulkan object count changed "
                          f"({objects} -> {live_objects()})")
                    failed = True
                    break
                if first is None and (done >= args.frame_warmup or b == batches - 1):
                    first = (done, sample())
                if b % every == 0 or b == batches - 1:
                    s = sample()
                    if first is not None:
                        xs.append(done)
                        ys.append(s[1])
                    print(_line(done, s, live_objects(), time.perf_counter() - t0), flush=True)
            end = sample()
            assert first is not None
            frames = done - first[0]
            grown, raw = (end[1] - first[1][1]) / MIB, (end[0] - first[1][0]) / MIB
            heap = (f", in use {(end[2] - first[1][2]) / MIB:+.2f} MiB"
                    if end[2] is not None and first[1][2] is not None else "")
            floor_grown, floor_slope = floor_trend(xs, ys)
            floor_grown /= MIB
            per_k = floor_slope / 1024 * 1000  # KiB per 1,000 frames
            ok_total = floor_grown <= args.max_frame_mib
            ok_slope = per_k <= args.max_frame_slope
            failed |= not (ok_total and ok_slope)
            print(f"frames: {done}, after the first {first[0]}: trimmed RSS {grown:+.2f} MiB "
                  f"over {frames} frames (raw RSS {raw:+.2f} MiB{heap}); its floor "
                  f"{floor_grown:+.2f} MiB, bound {args.max_frame_mib} MiB: "
                  f"{'ok' if ok_total else 'FAIL'}; floor slope {per_k:+.2f} KiB per 1,000 "
                  f"frames over {len(xs)} samples, bound {args.max_frame_slope}: "
                  f"{'ok' if ok_slope else 'FAIL'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
