"""Frame-path benchmark (issue 10): Sponza's GPU time per pass with and without the depth
pre-pass, and `render_many` throughput, at the sizes given. Prints a Markdown table.

    python benchmarks/bench_frame_path.py [--scene Sponza.gltf] [--frames 200]
                                          [--sizes 1920x1080,640x480] [--json OUT.json]

GPU times are timestamp queries (median over the frames, after 10 warm-up frames);
frames/s is wall time over `render_many` with readback into NumPy. Not a test.
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


def run(scene, size: tuple[int, int], frames: int, prepass: bool) -> dict:  # noqa: ANN001
    with Renderer(scene, depth_prepass=prepass) as r:
        cams = [CAMERA] * frames
        gpu, passes = [], []
        for i, _ in enumerate(r.render_many([CAMERA] * 10 + cams, size=size, readback=False)):
            if i >= 10:
                gpu.append(r.last_stats.gpu_ms)
                passes.append(r.last_stats.pass_ms)
        t = time.perf_counter()
        for _ in r.render_many(cams, size=size):
            pass
        fps = frames / (time.perf_counter() - t)
        t = time.perf_counter()
        for _ in r.render_many(cams, size=size, readback=False):
            pass
        fps_render = frames / (time.perf_counter() - t)
        per_pass = {k: statistics.median(p[k] for p in passes) for k in passes[0]}
        return {"size": f"{size[0]}x{size[1]}", "prepass": prepass, "gpu_ms": statistics.median(gpu),
                "fps_readback": fps, "fps_render_only": fps_render, "pass_ms": per_pass,
                "device": r.device.info.name}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(Path(__file__).resolve().parents[1]
                                           / ".assets/models/Sponza/glTF/Sponza.gltf"))
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--sizes", default="1920x1080,640x480")
    ap.add_argument("--json")
    args = ap.parse_args()
    scene = load_scene(args.scene)
    rows = []
    for text in args.sizes.split(","):
        w, h = (int(x) for x in text.split("x"))
        for prepass in (False, True):
            rows.append(run(scene, (w, h), args.frames, prepass))
    names = [k for k in rows[0]["pass_ms"] if any(r["pass_ms"][k] > 0.005 for r in rows)]
    print(f"device: {rows[0]['device']}, scene {Path(args.scene).name}, {args.frames} frames\n")
    print("| size | pre-pass | GPU ms | " + " | ".join(names) + " | frames/s readback | frames/s render only |")
    print("|---|---|---:|" + "---:|" * len(names) + "---:|---:|")
    for r in rows:
        cells = " | ".join(f"{r['pass_ms'][k]:.2f}" for k in names)
        print(f"| {r['size']} | {'on' if r['prepass'] else 'off'} | {r['gpu_ms']:.2f} | {cells} "
              f"| {r['fps_readback']:.1f} | {r['fps_render_only']:.1f} |")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
