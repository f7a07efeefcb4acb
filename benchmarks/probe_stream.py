"""Where a streamed frame's GPU time goes. Prints Markdown tables. Not a test.

    python3 benchmarks/probe_stream.py --scene Sponza.gltf [--size 1920x1080] [--frames 300]

1. `render_many` with and without readback into NumPy (the same frames; a still camera and
   bench_paths' walk, the automatic sun or the scene's point light): GPU ms a frame, its
   "copy" step's (timestamps) and frames/s.
2. The walk with the sun, no readback, frames grouped by the shadow layers they redrew:
   frames, mean GPU ms and the mean of each step over 0.01 ms (the compute shadow kernels
   timed apart: shadow_raster.TIMED_STEPS).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_paths import CAMERA, walk  # noqa: E402

from vkpbr.render import shadow_raster  # noqa: E402
from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402


def row(r: Renderer, cams: list, size: tuple[int, int], readback: bool, lights: list | None) -> list[str]:
    """GPU ms (median, mean), the copy step's, frames/s, and where the host's time a frame
    went (means): the frame's draw (`cpu_ms`), its wait for the GPU, its readback, and the
    rest (the generator and this loop)."""
    gpu, copy, cpu, wait, read = [], [], [], [], []
    for _ in r.render_many(cams[:20], lights, size=size, readback=readback):  # warm-up
        pass
    recordings = len(r.parts.recorder._recorded)
    t = time.perf_counter()
    for _ in r.render_many(cams, lights, size=size, readback=readback):
        s = r.last_stats
        gpu.append(s.gpu_ms)
        copy.append(s.pass_ms.get("copy", 0.0))
        cpu.append(s.cpu_ms)
        wait.append(s.wait_ms)
        read.append(s.readback_ms)
    wall = time.perf_counter() - t
    recorded = len(r.parts.recorder._recorded) - recordings
    host = [statistics.fmean(x) for x in (cpu, wait, read)]
    rest = 1e3 * wall / len(cams) - sum(host)
    return [f"{statistics.median(gpu):.3f}", f"{statistics.fmean(gpu):.3f}",
            f"{statistics.median(copy):.3f}", f"{len(cams) / wall:.0f}",
            " / ".join(f"{x:.3f}" for x in (*host, rest)),
            f"{statistics.median(cpu):.3f} / {sorted(cpu)[int(0.95 * len(cpu))]:.3f} / {max(cpu):.1f}",
            str(recorded), f"{sum(c for c in cpu if c > 5):.0f}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--cameras", default="still,walk", help="part 1's cameras: still, walk or both")
    ap.add_argument("--profile", type=Path, metavar="FILE",
                    help="also write the walk + sun's frames into NumPy under cProfile (top 50 "
                         "by own time) into FILE")
    ap.add_argument("--shadow-raster", default="auto",
                    help="what draws part 2's shadow maps: auto, compute or hardware (lavapipe's "
                         "auto is hardware: compute to time the kernels there)")
    ap.add_argument("--redraws-only", action="store_true",
                    help="only part 2, the compute shadow kernels timed apart in every recording")
    args = ap.parse_args()
    if args.redraws_only:
        shadow_raster.TIMED_STEPS = True
    size = tuple(int(x) for x in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        print(f"device: {r.device.info.name}")
        if args.redraws_only:
            redraw_rows(r, args.frames, size, args.shadow_raster)
            return
        print("| camera | light | readback | GPU ms median | mean | copy ms | frames/s "
              "| host ms a frame: draw / wait / readback / rest | draw ms median / p95 / max "
              "| recordings made | ms in draws over 5 ms |")
        print("|---|---|---|---:|---:|---:|---:|---|---|---:|---:|")
        chosen = args.cameras.split(",")
        for camera, cams in (("still", [CAMERA] * args.frames), ("walk", walk(args.frames))):
            if camera not in chosen:
                continue
            for light, lights in (("sun", [r.automatic_sun()]), ("point", None)):
                for readback in (False, True):
                    print("| " + " | ".join([camera, light, str(readback),
                                             *row(r, cams, size, readback, lights)]) + " |")
        if args.profile:
            profile_walk(r, args.frames, size, args.profile)
        redraw_rows(r, args.frames, size, args.shadow_raster)


def profile_walk(r: Renderer, frames: int, size: tuple[int, int], into: Path) -> None:
    """The walk + sun into NumPy under cProfile: its top 50 functions by own time."""
    import cProfile
    import io
    import pstats

    cams, sun = walk(frames), [r.automatic_sun()]
    prof = cProfile.Profile()
    prof.enable()
    for _ in r.render_many(cams, sun, size=size):
        pass
    prof.disable()
    text = io.StringIO()
    pstats.Stats(prof, stream=text).sort_stats("tottime").print_stats(50)
    into.write_text(text.getvalue())


def redraw_rows(r: Renderer, frames: int, size: tuple[int, int], raster: str = "auto") -> None:
    """The walk with the sun, its frames grouped by the layers they redrew and of those the
    layers scrolled (moved by whole texels, their new strip drawn: ShadowMaps.last_scrolled)."""
    timed = shadow_raster.TIMED_STEPS
    shadow_raster.TIMED_STEPS = True  # (recordings made before keep their steps untimed)
    sun = [r.automatic_sun()]
    cams = walk(frames)
    drawn: list[tuple[int, int]] = []  # layers each frame redrew, scrolled: read as the next camera is asked for

    def redrawn() -> tuple[int, int]:
        return sum(n for _, n in r.shadows.last_redrawn_layers), len(getattr(r.shadows, "last_scrolled", ()))

    def cameras():  # noqa: ANN202 - render_many draws frame k before it asks for camera k+1
        for i, cam in enumerate(cams[:20] + cams):
            if i:
                drawn.append(redrawn())
            yield cam

    stats = [r.last_stats for _ in r.render_many(cameras(), sun, size=size, readback=False,
                                                 shadow_raster=raster)]
    drawn.append(redrawn())
    groups: dict[tuple[int, int], list] = {}
    for layers, s in list(zip(drawn, stats, strict=True))[20:]:
        groups.setdefault(layers, []).append(s)
    shadow_raster.TIMED_STEPS = timed
    print("\n| layers redrawn | of them scrolled | frames | GPU ms mean | steps over 0.01 ms (mean) |")
    print("|---:|---:|---:|---:|---|")
    for (layers, scrolled), stats in sorted(groups.items()):
        names = {k for s in stats for k in s.pass_ms}
        means = {k: statistics.fmean(s.pass_ms.get(k, 0.0) for s in stats) for k in names}
        steps = " ".join(f"{k} {v:.3f}" for k, v in sorted(means.items(), key=lambda kv: -kv[1])
                         if v > 0.01)
        print(f"| {layers} | {scrolled} | {len(stats)} | {statistics.fmean(s.gpu_ms for s in stats):.3f} "
              f"| {steps} |")


if __name__ == "__main__":
    main()
