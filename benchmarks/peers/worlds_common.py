"""The worlds scenario (issue 32, must-have 4) every peer and vkpbr run: W tabletop worlds
(benchmarks/tabletop.py), one camera a world, every world's 17 moving bodies posed anew each
step from a CUDA tensor as a simulator writes them, the frames kept on the GPU (a torch tensor
or the peer's own CUDA buffer seen as one: no host copy).

Timing: `--steps` distinct steps of poses are made on the GPU before the clock starts
((S, W, N, 7) float32, position + quaternion; tabletop.Motion, the same seed for every peer, so
every peer renders the same worlds), then 3 untimed steps, then `--reps` passes over the S
steps; each step hands that step's (W, N, 7) tensor to the renderer, which takes it however it
must (its copy into the peer's own pose buffer is timed) and renders all W views. The clock
stops after a device synchronise: world-views/s = W x steps / wall clock. Host us/step: the
Python time a step's calls take to return (the GPU may still be busy), the cost a training
loop pays on its thread.

One JSON line a run (`--json FILE`, appended): peer, version, variant ("tabletop": primitives
and two sample models; "primitives": boxes, spheres and capsules only), size, worlds, steps,
world_views_per_s, host_us_per_step, gpu_mib (device memory the process holds after the run,
through NVML when nvidia-ml-py is importable), gpu, settings, poses_sha1 (of the first step's
poses: rows are compared only between equal worlds). `--png FILE`: world 0's view.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import tabletop  # noqa: E402  (NumPy only)

WARM_UP = 3
QUATERNION = {"vkpbr": "xyzw"}  # the others take MuJoCo's / SAPIEN's w, x, y, z


def fail(peer: str, message: str) -> None:
    """One line on stderr and exit status 2: what is missing and where it comes from."""
    print(f"{peer}: {message}", file=sys.stderr)
    raise SystemExit(2)


def need_torch_cuda(peer: str):  # noqa: ANN201
    try:
        import torch
    except ImportError:
        fail(peer, "needs torch (the worlds' poses are CUDA tensors): not importable")
    if not torch.cuda.is_available():
        fail(peer, "needs a CUDA GPU (torch.cuda.is_available() is False); "
             "--device cpu runs the CPU dry run where the peer has one")
    return torch


def parse_args(peer: str, extra: Callable[[argparse.ArgumentParser], object] | None = None
               ) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=f"the tabletop worlds with {peer}: world-views/s")
    ap.add_argument("--worlds", type=int, default=1024, help="W (default 1024)")
    ap.add_argument("--size", default="128x128", help="WIDTHxHEIGHT of every view (default 128x128)")
    ap.add_argument("--variant", choices=("tabletop", "primitives"), default="tabletop",
                    help="tabletop: primitives + DamagedHelmet + CesiumMilkTruck; primitives: "
                    "boxes, spheres, capsules (what the MJCF holds)")
    ap.add_argument("--steps", type=int, default=16, help="distinct pose steps made beforehand")
    ap.add_argument("--reps", type=int, default=4, help="timed passes over the steps")
    ap.add_argument("--scene-dir", default="/tmp/tabletop", help="where the scene files are written")
    ap.add_argument("--device", default="cuda", help="cuda (the benchmark) or cpu (a dry run, "
                    "where the peer can run on the CPU: timings mean nothing)")
    ap.add_argument("--json", default=None, help="append the result as one JSON line")
    ap.add_argument("--png", default=None, help="save world 0's view (Pillow)")
    if extra:
        extra(ap)
    args = ap.parse_args()
    args.width, args.height = (int(v) for v in args.size.lower().split("x"))
    return args


def world_of(args: argparse.Namespace) -> tabletop.Tabletop:
    return tabletop.make_tabletop(models=tuple(tabletop.MODELS) if args.variant == "tabletop" else ())


def pose_steps(args: argparse.Namespace, world: tabletop.Tabletop, quaternion: str, device: str):  # noqa: ANN201
    """(S, W, N, 7) float32 poses, on `device` (torch) or as NumPy for device=None."""
    motion = tabletop.Motion(world, args.worlds)
    return motion.steps(args.steps, quaternion, None if device == "numpy" else device)


def poses_sha1(world: tabletop.Tabletop | tabletop.Spin, worlds: int) -> str:
    """SHA-1 of step 0's poses (x, y, z, qx, qy, qz, qw as little-endian float32) of the
    tabletop's Motion, or of a motion given as is."""
    motion = world if isinstance(world, tabletop.Spin) else tabletop.Motion(world, worlds)
    first = motion.poses(0, "xyzw")
    return hashlib.sha1(np.ascontiguousarray(first, "<f4").tobytes()).hexdigest()


def time_steps(step: Callable[[object], object], poses, reps: int, sync: Callable[[], None],  # noqa: ANN001
               worlds: int | None = None) -> tuple[float, float]:
    """(world-views/s, host us/step) of `step(poses[s])` over `reps` passes of the S steps,
    after WARM_UP untimed steps; `sync` waits for the device. A step renders `worlds` views
    (default: poses.shape[1], the W of (S, W, N, 7) poses)."""
    count = len(poses)
    for s in range(WARM_UP):
        step(poses[s % count])
    sync()
    host = 0.0
    t0 = time.perf_counter()
    for _ in range(reps):
        for s in range(count):
            t = time.perf_counter()
            step(poses[s])
            host += time.perf_counter() - t
    sync()
    wall = time.perf_counter() - t0
    worlds = poses.shape[1] if worlds is None else worlds
    return worlds * count * reps / wall, host / (count * reps) * 1e6


def gpu_mib() -> float | None:
    """Device memory in use on GPU 0 (NVML), MiB; None without nvidia-ml-py."""
    try:
        import pynvml
    except ImportError:
        return None
    try:
        pynvml.nvmlInit()
        used = pynvml.nvmlDeviceGetMemoryInfo(pynvml.nvmlDeviceGetHandleByIndex(0)).used
        return round(used / 2**20, 1)
    except Exception:  # noqa: BLE001  (no driver: informative only)
        return None


def report(args: argparse.Namespace, peer: str, version: str, world: tabletop.Tabletop | tabletop.Spin,
           views_per_s: float, host_us: float, gpu: str | None, settings: str,
           image: np.ndarray | None = None, extra: dict | None = None) -> dict:
    """Print one Markdown row, append the JSON line to --json, save --png."""
    row = {"scenario": "worlds", "peer": peer, "version": version, "variant": args.variant,
           "size": f"{args.width}x{args.height}", "worlds": args.worlds, "steps": args.steps * args.reps,
           "world_views_per_s": round(views_per_s, 1), "host_us_per_step": round(host_us, 1),
           "gpu_mib": gpu_mib(), "gpu": gpu, "device": args.device, "settings": settings,
           "poses_sha1": poses_sha1(world, args.worlds), **(extra or {})}
    print(f"| {peer} {version} | {args.variant} | {row['size']} | {args.worlds} | {views_per_s:,.0f} "
          f"| {host_us:,.0f} | {row['gpu_mib']} | {settings} |", flush=True)
    if args.json:
        with open(args.json, "a") as f:
            f.write(json.dumps(row) + "\n")
    if args.png and image is not None:
        from PIL import Image

        Image.fromarray(np.ascontiguousarray(np.asarray(image)[..., :3])).save(args.png)
    return row


def unpack_abgr(packed: np.ndarray, width: int, height: int) -> np.ndarray:
    """MuJoCo Warp's packed pixels (uint32: 0xAARRGGBB read as B = low byte) of one view as
    (H, W, 3) uint8."""
    v = np.asarray(packed, np.uint32).reshape(height, width)
    return np.stack([(v >> 16) & 255, (v >> 8) & 255, v & 255], -1).astype(np.uint8)
