"""Where a streamed frame's readback goes on the GPU: `render_many` with and without
readback into NumPy (the same frames), GPU ms a frame and its "copy" step's (timestamps),
frames/s. Prints one Markdown table. Not a test.

    python3 benchmarks/probe_readback.py --scene Sponza.gltf [--size 1920x1080] [--frames 300]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_paths import CAMERA, walk  # noqa: E402

from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402


def row(r: Renderer, cams: list, size: tuple[int, int], readback: bool, lights: list | None) -> list[str]:
    gpu, copy = [], []
    for _ in r.render_many(cams[:20], lights, size=size, readback=readback):  # warm-up
        pass
    t = time.perf_counter()
    for _ in r.render_many(cams, lights, size=size, readback=readback):
        gpu.append(r.last_stats.gpu_ms)
        copy.append(r.last_stats.pass_ms.get("copy", 0.0))
    fps = len(cams) / (time.perf_counter() - t)
    return [f"{statistics.median(gpu):.3f}", f"{statistics.fmean(gpu):.3f}",
            f"{statistics.median(copy):.3f}", f"{fps:.0f}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--frames", type=int, default=300)
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    with Renderer(load_scene(args.scene)) as r:
        print(f"device: {r.device.info.name}; async readback: {getattr(r.device, 'transfer_queue', None) is not None}")
        print("| camera | light | readback | GPU ms median | mean | copy ms | frames/s |")
        print("|---|---|---|---:|---:|---:|---:|")
        for camera, cams in (("still", [CAMERA] * args.frames), ("walk", walk(args.frames))):
            for light, lights in (("sun", [r.automatic_sun()]), ("point", None)):
                for readback in (False, True):
                    print("| " + " | ".join([camera, light, str(readback),
                                             *row(r, cams, size, readback, lights)]) + " |")


if __name__ == "__main__":
    main()
