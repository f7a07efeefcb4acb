"""What the post stage costs: Sponza's frame on the compute path (compute rasteriser) as
`vkpbr bench` draws it: tone mapped in the shading (the default), through the HDR target
with only the encode (VKPBR_HDR_FRAMES=1: what an always-on post stage would cost), with a
bloom, with sensor noise (colour alone, and with the depth output's noise), and through a
camera model (an OpenCV fisheye of 120 degrees: the resample "lens", with and without the
dataset outputs it also maps; the frame's own cost includes its larger source pinhole).
Prints GPU ms per frame and per step (medians): lens is the resample (both kernels with
outputs), noise the colour noise, noise_depth the depth noise (with its copy back). And a
compute batch of 4,096 views of 128x128 without and with colour noise or a bloom (each
step one dispatch over the atlas; the batch then draws into an HDR atlas and encodes after:
"encode"), and through
a 100-degree fisheye (each view's wider source drawn as its tile, then one resample
dispatch: "lens"). The "cube" rows: a 200-degree OpenCV fisheye, drawn as 5 cube faces (a
frame each, render/lens_cube.py) and resampled from them: its GPU ms and steps are the last
face frame's (that face, the resample "lens", the encode), its "wall ms" (the median time
between frames of render_many, every column has it) the whole frame's, its 5 faces included.

    python3 benchmarks/bench_post.py --scene Sponza.gltf [--frames 300] [--json out.json]
    python3 benchmarks/bench_post.py --scene Sponza.gltf --only lens,noise   # those rows
    python3 benchmarks/bench_post.py --scene Sponza.gltf --only batch [--views 4096]
    python3 benchmarks/bench_post.py --scene Sponza.gltf --only cube --frames 100
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time

import numpy as np

from vkpbr.render.renderer import Renderer
from vkpbr.scene.camera import Camera
from vkpbr.scene.loader import load_scene

SIZES = ((1920, 1080), (640, 480))
BATCH_SIZE = (128, 128)
OUTPUTS = ("depth", "instance", "normal")


def fisheye(base: Camera, size: tuple[int, int], degrees: float = 120.0) -> Camera:
    """`base`'s pose through an OpenCV fisheye whose image is `degrees` across."""
    w, h = size
    f = (w / 2) / math.radians(degrees / 2)
    K = np.array([[f, 0.0, (w - 1) / 2], [0.0, f, (h - 1) / 2], [0.0, 0.0, 1.0]])
    return Camera.from_opencv(K, base.world_from_camera("opencv"), size, model="opencv_fisheye",
                              distortion=(0.02, -0.005, 0.001, 0.0))


def measure(r: Renderer, size: tuple[int, int], frames: int, camera: Camera | None = None,
            outputs: tuple[str, ...] | None = None, **options: object) -> dict:
    gpu, steps, wall = [], [], []
    cams = [camera or r.default_camera()] * (frames + 20)
    readback = outputs is not None  # (the dataset outputs are made only when read back)
    t = time.perf_counter()
    for i, _ in enumerate(r.render_many(cams, size=size, readback=readback, pipeline="compute",
                                        raster="compute", outputs=outputs, **options)):
        now = time.perf_counter()
        if i >= 20:
            gpu.append(r.last_stats.gpu_ms)
            steps.append(r.last_stats.pass_ms)
            wall.append((now - t) * 1e3)
        t = now
    names = {n for s in steps for n in s}
    return {"gpu_ms": statistics.median(gpu), "wall_ms": statistics.median(wall),
            "steps": {n: statistics.median(s.get(n, 0.0) for s in steps) for n in sorted(names)}}


def measure_batch(r: Renderer, views: int, reps: int, lens: bool = False,
                  **options: object) -> dict:
    """A compute batch of `views` views of BATCH_SIZE on a ring about the default camera's
    target (bench_ao.py ring_poses; `lens`: each through a 100-degree fisheye, 141 across the
    diagonal of the square): medians of
    its GPU ms and steps."""
    from bench_ao import ring_poses

    from vkpbr.scene.camera_batch import CameraBatch

    cams = CameraBatch.from_poses(ring_poses(r, views), yfov_deg=60.0)
    if lens:
        cams = CameraBatch.from_cameras([fisheye(cams.camera(i), BATCH_SIZE, 100.0)
                                         for i in range(views)], r.default_camera())
    gpu, steps = [], []
    for i in range(reps + 1):
        r.render_batch(cams, size=BATCH_SIZE, pipeline="compute", **options)
        if i:
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
    ap.add_argument("--only", default="", help="comma-separated words: rows whose label has one")
    ap.add_argument("--views", type=int, default=4096, help="views of the batch rows")
    ap.add_argument("--batches", type=int, default=5)
    args = ap.parse_args()
    rows = []
    only = [w for w in args.only.split(",") if w]
    with Renderer(load_scene(args.scene)) as r:
        for size in SIZES:
            lens = fisheye(r.default_camera(), size)
            cube = fisheye(r.default_camera(), size, 200.0)  # (5 cube faces)
            for label, env, options in (
                    ("shading tone maps", "0", {}),
                    ("HDR target + encode", "1", {}),
                    ("bloom 0.3", "0", {"bloom": 0.3}),
                    ("outputs (no post step)", "0", {"outputs": OUTPUTS}),
                    ("noise realsense-d435 colour", "0", {"noise": "realsense-d435"}),
                    ("noise realsense-d435 + depth", "0", {"noise": "realsense-d435",
                                                          "outputs": OUTPUTS}),
                    ("lens fisheye 120", "0", {"camera": lens}),
                    ("lens fisheye 120 + outputs", "0", {"camera": lens, "outputs": OUTPUTS}),
                    ("cube fisheye 200", "0", {"camera": cube}),
                    ("cube fisheye 200 + outputs", "0", {"camera": cube, "outputs": OUTPUTS})):
                if only and not any(w in label for w in only):
                    continue
                os.environ["VKPBR_HDR_FRAMES"] = env
                r._last_post = None  # the renderer keeps an options object's post steps
                row = measure(r, size, args.frames, **options)
                rows.append({"size": f"{size[0]}x{size[1]}", "frame": label, **row})
        os.environ["VKPBR_HDR_FRAMES"] = "0"
        for label, options in (("batch", {}), ("batch noise realsense-d435 colour",
                                               {"noise": "realsense-d435"}),
                               ("batch bloom 0.3", {"bloom": 0.3}),
                               ("batch lens fisheye 100", {"lens": True})):
            if only and not any(w in label for w in only):
                continue
            row = measure_batch(r, args.views, args.batches, **options)
            rows.append({"size": f"{args.views} x {BATCH_SIZE[0]}x{BATCH_SIZE[1]}",
                         "frame": label, **row})
    print("| size | frame | GPU ms | encode | bloom | lens | noise | noise_depth | wall ms |\n"
          "|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for row in rows:
        st = row["steps"]
        print(f"| {row['size']} | {row['frame']} | {row['gpu_ms']:.3f} | "
              f"{st.get('encode', 0.0):.3f} | {st.get('bloom', 0.0):.3f} | "
              f"{st.get('lens', 0.0):.3f} | {st.get('noise', 0.0):.3f} | "
              f"{st.get('noise_depth_copy', 0.0):.3f} | {row.get('wall_ms', math.nan):.2f} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    sys.exit(0)


if __name__ == "__main__":
    main()
