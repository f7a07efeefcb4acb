"""Batched views (issue 14): views/s into NumPy through `Renderer.render_batch`, against
`render_many` frame by frame, the host-side cost per view and the GPU memory a batch holds.

    python benchmarks/bench_batch.py [--scenes default,helmet,sponza] [--sizes 64x64,128x128,512x512]
                                     [--batches 1,16,64,256,1024,4096] [--reps 3] [--json OUT.jsonl]

Scenes: "default" (the built-in chart scene, an orbit about its default camera's target),
"alphablend" (AlphaBlendModeTest: blended materials; the chart's orbit), "helmet"
(DamagedHelmet: one textured object) and "sponza", both with the poses of the peers'
batch scenario (benchmarks/peers/common.py `batch_poses`: a seeded orbit) and one point light
at (0, 4, 0); a scene whose glTF is not in the sample-models folder is skipped. Per scene, size
and B: four warm-up calls (every slot of the frame ring recorded, the shadow maps drawn), then
the median of `--reps` timed calls of `render_batch(CameraBatch.from_poses(poses), size)`:

- views/s: B / wall clock of the call (render + one readback into a new (B, H, W, 4) uint8
  array); "out=": the same into one array reused across calls (no fresh pages to fault in);
- GPU views/s: B / the batch's GPU time (`last_stats.gpu_ms`, timestamp queries, every
  submission's summed when the batch was split) = render only;
- host us/view: (wall - GPU time - the host copy of the result) / B: the Python and driver
  cost per view (the copy, copy_out as the readback makes it, timed separately on an
  array of the same size; the readback's source is mapped memory, so this is approximate);
- GPU MiB: device memory vkpbr holds beyond the scene's own after the row (Device.bytes_allocated:
  every live buffer and image, as allocated): the batch targets or atlases kept (two per path:
  the row's and the previous size's), their readback and CUDA-exported buffers, the views'
  records;
- render_many views/s (B <= `--many-max`, default 256): the same B cameras frame by frame;
- torch views/s (where torch sees CUDA and render_batch takes device="cuda"): B / wall clock
  of `render_batch(..., device="cuda")` + `torch.cuda.synchronize()`, the views a (B, H, W, 4)
  tensor on the GPU (no host copy).

`--pipeline` auto (the default: the compute batch, where the device has it),
forward (the layered batch: pbr.frag BATCH) or compute (render_batch(pipeline="compute"): one
atlas, rasterised and shaded in compute shaders; into torch too), rows "scene (PIPELINE)".

A B whose views would need more than `--max-mib` (default: a quarter of the free device or
host memory, whichever is less, as `batch="auto"` budgets a submission) is skipped. Not a test. Prints one Markdown table;
`--json FILE` appends one JSON line per row.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from vkpbr.app.bench_cmd import BATCH_WARM_UPS
from vkpbr.gpu.target import copy_out
from vkpbr.render.renderer import Renderer
from vkpbr.scene.camera_batch import CameraBatch
from vkpbr.scene.types import Light

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "peers"))
import common as peers  # noqa: E402  (the peers' scenario: poses, scene paths; NumPy only)

# Scenes of this benchmark's own (a ring about the default camera's target, as "default"):
# AlphaBlendModeTest's blended materials (the compute batch draws them since session 27).
OWN_SCENES = {"alphablend": "AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf"}


def load(key: str):  # noqa: ANN201
    """The scene of `key`, or None when its glTF is missing."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if key == "default":
            from vkpbr.scene.default import default_scene

            return default_scene()
        path = peers.ASSETS / OWN_SCENES.get(key, peers.BATCH_SCENES.get(key, key))
        if not path.exists():
            return None
        from vkpbr.scene.loader import load_scene

        scene = load_scene(path)
        scene.lights = [Light(position=peers.LIGHT_POS)]
        return scene


def poses_for(key: str, r: Renderer, count: int) -> np.ndarray:
    """(count, 4, 4) OpenGL world-from-camera poses: the peers' orbit, or (default scene) a
    seeded ring about the default camera's target at its distance (the other scenes too)."""
    if key in peers.BATCH_SCENES:
        return peers.batch_poses(key, count)
    cam = r.default_camera()
    eye, target = np.asarray(cam.eye, float), np.asarray(cam.target, float)
    rng = np.random.default_rng(peers.BATCH_SEED)
    a = 2 * np.pi * (np.arange(count) + rng.uniform(0, 1, count)) / count
    d = eye - target
    radius, height = math.hypot(d[0], d[2]), d[1]
    eyes = np.stack([target[0] + radius * np.cos(a),
                     target[1] + height * rng.uniform(0.5, 1.5, count),
                     target[2] + radius * np.sin(a)], 1)
    return np.stack([peers.look_at(e, target) for e in eyes])


def batch_gpu_bytes(r: Renderer, baseline: int) -> int:
    """Device memory vkpbr holds beyond `baseline` (the scene's, before any batch): every live
    buffer and image, as their memory requirements asked (Device.bytes_allocated), so the
    batch targets, atlases, view buffers and CUDA-exported buffers of the sizes rendered so far."""
    return r.device.bytes_allocated()[0] - baseline


def torch_cuda():  # noqa: ANN201
    """torch when it sees a CUDA device (render_batch(device="cuda")), else None."""
    try:
        import torch
    except ImportError:
        return None
    return torch if torch.cuda.is_available() else None


WARM_UP = BATCH_WARM_UPS


def copy_ms(shape: tuple[int, ...], reps: int = 3) -> float:
    """The readback's host copy of a result of `shape` into a fresh array, as render_batch
    makes it (gpu/target.py copy_out: threads for big ones), from ordinary memory."""
    a = np.ones(shape, np.uint8)
    out = []
    for _ in range(reps):
        t = time.perf_counter()
        copy_out(a)
        out.append((time.perf_counter() - t) * 1e3)
    return statistics.median(out)


def run_scene(key: str, sizes: list[tuple[int, int]], batches: list[int], reps: int,
              many_max: int, max_mib: float | None, pipeline: str = "auto") -> list[dict]:
    scene = load(key)
    if scene is None:
        print(f"skipped {key}: its glTF is not under {peers.ASSETS}", file=sys.stderr)
        return []
    rows = []
    torch = torch_cuda()
    opts = {"pipeline": pipeline}
    with Renderer(scene) as r:
        r.render(size=(64, 64))  # the scene's own buffers, pipelines and environment
        baseline = r.device.bytes_allocated()[0]
        if max_mib:
            budget = max_mib * 2**20
        else:  # free device and host memory (VK_EXT_memory_budget where the driver has it)
            local, host = r.device.memory_available()
            budget = min(local, host) / 4
        for size in sizes:
            w, h = size
            for b in batches:
                view_bytes = w * h * (2 * 4 + 4 + (25 if pipeline == "compute" else 0))
                if b * view_bytes > budget:
                    print(f"skipped {key} {w}x{h} B={b}: {b * view_bytes / 2**20:.0f} MiB > "
                          f"{budget / 2**20:.0f} MiB", file=sys.stderr)
                    continue
                views = CameraBatch.from_poses(poses_for(key, r, b), peers.YFOV_DEG)
                for _ in range(WARM_UP):  # targets, every ring slot's recordings, shadow maps
                    out = r.render_batch(views, size=size, **opts)
                assert out.shape == (b, h, w, 4) and out.dtype == np.uint8, out.shape
                wall, gpu, reused = [], [], []
                for _ in range(reps):
                    t = time.perf_counter()
                    r.render_batch(views, size=size, **opts)
                    wall.append((time.perf_counter() - t) * 1e3)
                    gpu.append(r.last_stats.gpu_ms)
                    t = time.perf_counter()
                    r.render_batch(views, size=size, out=out, **opts)
                    reused.append((time.perf_counter() - t) * 1e3)
                wall_ms, gpu_ms = statistics.median(wall), statistics.median(gpu)
                cp = copy_ms(out.shape)
                row = {"scene": key if pipeline == "auto" else f"{key} ({pipeline})",
                       "size": f"{w}x{h}", "B": b, "views_per_s": b / wall_ms * 1e3,
                       "reused_views_per_s": b / statistics.median(reused) * 1e3,
                       "ms_per_batch": wall_ms, "gpu_ms": gpu_ms,
                       "gpu_views_per_s": b / gpu_ms * 1e3 if gpu_ms > 0 else float("nan"),
                       "host_us_per_view": (wall_ms - (gpu_ms if math.isfinite(gpu_ms) else 0) - cp)
                       * 1e3 / b,
                       "copy_ms": cp, "gpu_mib": batch_gpu_bytes(r, baseline) / 2**20,
                       "device": r.device.info.name, "draws": len(r.gpu_scene.draws)}
                if torch is not None:
                    for _ in range(WARM_UP):
                        r.render_batch(views, size=size, device="cuda", **opts)
                    times = []
                    for _ in range(reps):
                        t = time.perf_counter()
                        r.render_batch(views, size=size, device="cuda", **opts)
                        torch.cuda.synchronize()
                        times.append(time.perf_counter() - t)
                    row["torch_views_per_s"] = b / statistics.median(times)
                    row["gpu_mib_with_torch_target"] = batch_gpu_bytes(r, baseline) / 2**20
                if b <= many_max:
                    cams = [views.camera(i) for i in range(b)]
                    list(r.render_many(cams[: min(b, 8)], size=size, **opts))
                    t = time.perf_counter()
                    for _ in r.render_many(cams, size=size, **opts):
                        pass
                    row["many_views_per_s"] = b / (time.perf_counter() - t)
                rows.append(row)
                print_row(row)
    return rows


HEADER = ("| scene | size | B | views/s into NumPy | into NumPy (out=) | views/s into torch "
          "| GPU views/s (render only) | ms per batch | host us/view | GPU MiB "
          "| render_many views/s | batch / many |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|")


def print_row(r: dict) -> None:
    many = r.get("many_views_per_s")
    many_s = f"{many:,.0f}" if many else "-"
    ratio = f"{r['views_per_s'] / many:.1f}x" if many else "-"
    gvps = f"{r['gpu_views_per_s']:,.0f}" if math.isfinite(r["gpu_views_per_s"]) else "n/a"
    tvps = f"{r['torch_views_per_s']:,.0f}" if "torch_views_per_s" in r else "-"
    print(f"| {r['scene']} | {r['size']} | {r['B']} | {r['views_per_s']:,.0f} "
          f"| {r['reused_views_per_s']:,.0f} | {tvps} | {gvps} "
          f"| {r['ms_per_batch']:.2f} | {r['host_us_per_view']:.1f} | {r['gpu_mib']:.2f} "
          f"| {many_s} | {ratio} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="default,helmet,sponza")
    ap.add_argument("--sizes", default="64x64,128x128,512x512")
    ap.add_argument("--batches", default="1,16,64,256,1024,4096")
    ap.add_argument("--reps", type=int, default=3, help="timed calls per row (median)")
    ap.add_argument("--many-max", type=int, default=256, help="largest B also run by render_many")
    ap.add_argument("--max-mib", type=float, default=None,
                    help="skip a B whose views need more (default: a quarter of device memory)")
    ap.add_argument("--json", default=None, help="append one JSON line per row to this file")
    ap.add_argument("--pipeline", default="auto", choices=("auto", "forward", "compute"),
                    help="compute: the compute batch (one atlas, raster.comp and shade.comp)")
    args = ap.parse_args()
    sizes = [tuple(int(v) for v in s.lower().split("x")) for s in args.sizes.split(",")]
    batches = [int(b) for b in args.batches.split(",")]
    print(HEADER, flush=True)
    rows = []
    for key in args.scenes.split(","):
        rows += run_scene(key, sizes, batches, args.reps, args.many_max, args.max_mib,
                          args.pipeline)
    if rows:
        print(f"\ndevice: {rows[0]['device']}; {args.reps} timed calls per row (median)")
    if args.json:
        with open(args.json, "a") as f:
            for row in rows:
                f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
