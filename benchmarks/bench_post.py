"""What the post stage costs: Sponza's frame on the compute path (compute rasteriser) as
`vkpbr bench` draws it, three ways: tone mapped in the shading (the default), through the HDR
target with only the encode (VKPBR_HDR_FRAMES=1: what an always-on post stage would cost),
and with a bloom. Prints GPU ms per frame and per step (medians).

    python3 benchmarks/bench_post.py --scene Sponza.gltf [--frames 300] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys

from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene

SIZES = ((1920, 1080), (640, 480))


def measure(r: Renderer, size: tuple[int, int], frames: int, **options: object) -> dict:
    gpu, steps = [], []
    cams = [r.default_camera()] * (frames + 20)
    for i, _ in enumerate(r.render_many(cams, size=size, readback=False, pipeline="compute",
                                        raster="compute", **options)):
        if i >= 20:
            gpu.append(r.last_stats.gpu_ms)
            steps.append(r.last_stats.pass_ms)
    names = {n for s in steps for n in s}
    return {"gpu_ms": statistics.median(gpu),
            "steps": {n: statistics.median(s.get(n, 0.0) for s in steps) for n in sorted(names)}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--json")
    args = ap.parse_args()
    rows = []
    with Renderer(load_scene(args.scene)) as r:
        for size in SIZES:
            for label, env, options in (("shading tone maps", "0", {}),
                                        ("HDR target + encode", "1", {}),
                                        ("bloom 0.3", "0", {"bloom": 0.3})):
                os.environ["VKPBR_HDR_FRAMES"] = env
                r._last_post = None  # the renderer keeps an options object's post steps
                row = measure(r, size, args.frames, **options)
                rows.append({"size": f"{size[0]}x{size[1]}", "frame": label, **row})
    print("| size | frame | GPU ms | encode | bloom |\n|---|---|---:|---:|---:|")
    for row in rows:
        st = row["steps"]
        print(f"| {row['size']} | {row['frame']} | {row['gpu_ms']:.3f} | "
              f"{st.get('encode', 0.0):.3f} | {st.get('bloom', 0.0):.3f} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    sys.exit(0)


if __name__ == "__main__":
    main()
