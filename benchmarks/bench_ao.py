"""What ambient occlusion costs (render/ao.py: GTAO, its denoise and at half resolution the
upsample: the "ao" step): Sponza on the compute path (compute rasteriser) as `vkpbr bench`
draws it, with `--ao off` and each GTAO preset (`gtao`: half resolution, the default;
`gtao-full`: full resolution, XeGTAO's High; `gtao-low`: half resolution, 2 slices of 2), at
1920x1080 and 640x480; and a compute batch of 4,096 views of 128x128 each way. Prints GPU ms
per frame (or per batch) and the "ao" step's own time (from the timestamps around it),
medians; `--profile` adds each kernel's (the depth prefilter, GTAO, the denoise passes, the
upsample: a timestamp after each). Targets (issue 33): the step <= 0.15 ms at 1080p on the
H200. `--fuse both` runs the half-resolution presets twice: the last denoise pass as its own kernel (off, the
default) and run by the upsample on the pixels it blends (on: render/ao.py AoImages.fuse).
`--mip-offsets 2.3,3.3` runs each at each MIP level offset (AoImages.mip_offset: which depth
MIP level GTAO's far samples read; 3.3, XeGTAO's, the default; 2.3 reads a level coarser).

    python3 benchmarks/bench_ao.py --scene Sponza.gltf [--frames 300] [--batches 5] \
        [--modes off,gtao,gtao-full,gtao-low] [--profile] [--fuse off|on|both] \
        [--batch-pipelines compute,forward] [--mip-offsets 2.3,3.3] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys

import numpy as np

from vkpbr.render.ao import MIP_OFFSET
from vkpbr.render.renderer import Renderer
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.loader import load_scene

BATCH_VIEWS, BATCH_SIZE = 4096, (128, 128)


# --profile: each timed apart (the depth prefilter, GTAO's main pass, the denoise passes, the
# last kernel: the upsample at half resolution)
KERNELS = ("ao_prefilter", "ao_gtao", "ao_denoise0", "ao_denoise1", "ao")


def ao_times(r: Renderer, into: dict[str, list[float]]) -> None:
    """The frame's "ao" step time (the sum of its kernels' where --profile times them
    apart) and each kernel's, appended to `into`."""
    ms = r.last_stats.pass_ms
    into.setdefault("ao_ms", []).append(sum(ms.get(k, 0.0) for k in KERNELS))
    for k in KERNELS:
        if k in ms and k != "ao":
            into.setdefault(f"{k}_ms", []).append(ms[k])
    if "ao" in ms and len(ms.keys() & set(KERNELS)) > 1:  # the last kernel, alone
        into.setdefault("ao_last_ms", []).append(ms["ao"])


def frames(r: Renderer, size: tuple[int, int], count: int, ao: str) -> dict:
    times: dict[str, list[float]] = {"gpu_ms": []}
    cams = [r.default_camera()] * (count + 20)
    for i, _ in enumerate(r.render_many(cams, size=size, readback=False, pipeline="compute",
                                        raster="compute", ao=ao)):
        if i >= 20:
            times["gpu_ms"].append(r.last_stats.gpu_ms)
            ao_times(r, times)
    return {k: statistics.median(v) for k, v in times.items()}


def ring_poses(r: Renderer, count: int) -> np.ndarray:
    """(count, 4, 4) OpenGL world-from-camera poses on a ring about the default camera's
    target, at its distance and height (seeded)."""
    cam = r.default_camera()
    eye, target = np.asarray(cam.eye, float), np.asarray(cam.target, float)
    rng = np.random.default_rng(33)
    a = 2 * np.pi * (np.arange(count) + rng.uniform(0, 1, count)) / count
    d = eye - target
    radius = math.hypot(d[0], d[2])
    poses = np.zeros((count, 4, 4))
    for i, angle in enumerate(a):
        e = target + np.array([radius * math.cos(angle), d[1], radius * math.sin(angle)])
        f = target - e
        f /= np.linalg.norm(f)
        s = np.cross(f, (0.0, 1.0, 0.0))
        s /= np.linalg.norm(s)
        u = np.cross(s, f)
        poses[i, :3, 0], poses[i, :3, 1], poses[i, :3, 2], poses[i, :3, 3] = s, u, -f, e
        poses[i, 3, 3] = 1.0
    return poses


def batch(r: Renderer, reps: int, ao: str, count: int, pipeline: str = "compute") -> dict:
    """`pipeline` "forward": the layered batch (its GTAO steps untimed apart: compare the
    GPU ms with and without)."""
    views = CameraBatch.from_poses(ring_poses(r, count), yfov_deg=60.0)
    times: dict[str, list[float]] = {"gpu_ms": []}
    for i in range(reps + 1):
        r.render_batch(views, size=BATCH_SIZE, pipeline=pipeline, ao=ao)
        if i:
            times["gpu_ms"].append(r.last_stats.gpu_ms)
            ao_times(r, times)
    return {k: statistics.median(v) for k, v in times.items()}


def set_fuse(r: Renderer, fuse: bool, mip_offset: float) -> None:
    """Fuse the last denoise pass into the upsample, or not, and the MIP level offset; the
    recordings made another way are dropped (their steps or push constants differ)."""
    r.device.wait_idle()
    r.parts.recorder.free()
    r.parts.ao.fuse, r.parts.ao.mip_offset = fuse, mip_offset


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--batches", type=int, default=5)
    ap.add_argument("--views", type=int, default=BATCH_VIEWS, help="views of the batch")
    ap.add_argument("--sizes", default="1920x1080,640x480")
    ap.add_argument("--modes", default="off,gtao,gtao-full,gtao-low", help="--ao values")
    ap.add_argument("--profile", action="store_true", help="time each GTAO kernel apart")
    ap.add_argument("--batch-pipelines", default="compute",
                    help="the batches' pipelines: compute (the compute batch), forward (the "
                    "layered batch), comma-separated")
    ap.add_argument("--fuse", choices=("off", "on", "both"), default="off",
                    help="the last denoise pass in the upsample (half resolution)")
    ap.add_argument("--mip-offsets", default=str(MIP_OFFSET),
                    help="GTAO's MIP level offsets to run, comma-separated (render/ao.py "
                    "MIP_OFFSET, XeGTAO's DepthMIPSamplingOffset: larger reads finer levels)")
    ap.add_argument("--json")
    args = ap.parse_args()
    sizes = [tuple(int(v) for v in s.split("x")) for s in args.sizes.split(",")]
    modes = args.modes.split(",")
    rows = []
    fuses = {"off": [False], "on": [True], "both": [False, True]}[args.fuse]
    with Renderer(load_scene(args.scene)) as r:
        r.parts.ao.profile = args.profile
        for fuse, offset in [(f, float(o)) for f in fuses for o in args.mip_offsets.split(",")]:
            set_fuse(r, fuse, offset)
            runs = [m for m in modes if not fuse or m in ("gtao", "gtao-low")]
            tag = ("" if offset == MIP_OFFSET else f" mip {offset:g}") + (" fused" if fuse else "")
            label = lambda ao, tag=tag: ao + tag  # noqa: E731
            for size in sizes:
                for ao in runs:
                    rows.append({"what": f"frame {size[0]}x{size[1]}", "ao": label(ao),
                                 **frames(r, size, args.frames, ao)})
            for pipeline in args.batch_pipelines.split(",") if args.views else ():
                what = f"batch {args.views} x {BATCH_SIZE[0]}x{BATCH_SIZE[1]} {pipeline}"
                for ao in runs:
                    rows.append({"what": what, "ao": label(ao),
                                 **batch(r, args.batches, ao, args.views, pipeline)})
    kernels = [f"{k}_ms" for k in KERNELS[:-1]] + ["ao_last_ms"]
    cols = [k for k in kernels if any(k in row for row in rows)]
    print("| what | --ao | GPU ms | ao step ms |" + "".join(f" {k[:-3]} |" for k in cols))
    print("|---|---|---:|---:|" + "---:|" * len(cols))
    for row in rows:
        print(f"| {row['what']} | {row['ao']} | {row['gpu_ms']:.3f} | {row.get('ao_ms', 0):.3f} |"
              + "".join(f" {row.get(k, 0.0):.3f} |" for k in cols))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    sys.exit(0)


if __name__ == "__main__":
    main()
