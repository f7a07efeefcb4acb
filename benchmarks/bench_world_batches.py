"""Batches of worlds (issue 32): world-views/s with every world's poses changed every step,
from CUDA tensors (a simulator's GPU buffer) or NumPy, into torch or NumPy.

    python benchmarks/bench_world_batches.py --assets MODELS [--rows helmet-64,analytic-128]
        [--worlds 1024,8192] [--steps 30] [--json OUT.jsonl]

Rows "SCENE-SIZE": helmet = DamagedHelmet (its one node spun per world), analytic = the
tests' four-object scene (box and small sphere posed per world). Per row and W: a (W, N, 7)
position + quaternion tensor rewritten on the GPU each step (torch ops, as a simulator
writes poses), then `render_batch(cams, size, worlds=poses, device=...)`; the first
`WARM` steps record, the next `--steps` are timed:

- world-views/s: W / wall clock of a step (the pose write, the render, the frames as a
  torch tensor on the GPU for "torch", or a NumPy array for "numpy"), torch.cuda.synchronize()
  after each step so that nothing is left queued;
- Python ms: the call's host time up to its submission (last_stats.cpu_ms);
- GPU ms: the submission's GPU time (timestamps), with the worlds kernel's share;
- MiB/1k worlds: device memory vkpbr holds for the row per 1,000 worlds (records, inputs,
  frames), from Device.bytes_allocated.

Where torch has no CUDA, the poses are NumPy and only "numpy" rows run. Not a test; prints
one Markdown table.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "gpu"))
sys.path.insert(0, str(HERE.parent / "tests"))

from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.camera_batch import CameraBatch  # noqa: E402
from vkpbr.scene.gltf import load_gltf  # noqa: E402

WARM = 5


def _torch():  # noqa: ANN202
    try:
        import torch

        return torch if torch.cuda.is_available() else None
    except ImportError:
        return None


def scene_for(name: str, assets: Path):  # noqa: ANN201
    if name == "helmet":
        return load_gltf(assets / "DamagedHelmet" / "glTF" / "DamagedHelmet.gltf"), ["*"], 3.0
    from test_outputs import analytic_scene

    return analytic_scene(), ["box", "small sphere"], 6.0


def cameras(count: int, distance: float) -> CameraBatch:
    a = np.linspace(0, 2 * np.pi, count, endpoint=False)
    eye = np.stack([distance * np.sin(a), 0.6 * np.ones_like(a), distance * np.cos(a)], 1)
    return CameraBatch.from_look_at(eye, np.zeros_like(eye))


def step_poses(rows: object, step: int, torch: object) -> None:
    """Rewrite (W, N, 7) position + x,y,z,w quaternion rows in place: a spin about y."""
    if torch is None:
        w = rows.shape[0]  # type: ignore[attr-defined]
        a = 0.05 * step + np.arange(w)[:, None] * 0.01
        rows[..., 4] = np.sin(a / 2)  # type: ignore[index]
        rows[..., 6] = np.cos(a / 2)  # type: ignore[index]
        return
    w = rows.shape[0]  # type: ignore[attr-defined]
    a = 0.05 * step + torch.arange(w, device="cuda")[:, None] * 0.01  # type: ignore[attr-defined]
    rows[..., 4] = torch.sin(a / 2)  # type: ignore[index, attr-defined]
    rows[..., 6] = torch.cos(a / 2)  # type: ignore[index, attr-defined]


def row(r: Renderer, name: str, size: int, worlds: int, into: str, steps: int, distance: float,
        slots: int, torch: object, shadows: bool = True) -> dict:
    cams = cameras(worlds, distance)
    if torch is not None:
        rows = torch.zeros((worlds, slots, 7), device="cuda")  # type: ignore[attr-defined]
    else:
        rows = np.zeros((worlds, slots, 7))
    rows[..., 6] = 1.0
    before = r.device.bytes_allocated()[0]
    walls, py, gpu, kernel, per_step = [], [], [], [], []
    for s in range(WARM + steps):
        t0 = time.perf_counter()
        step_poses(rows, s, torch)
        out = r.render_batch(cams, (size, size), worlds=rows, device="cuda" if into == "torch" else "cpu",
                             shadows=shadows)
        if torch is not None:
            torch.cuda.synchronize()  # type: ignore[attr-defined]
        wall = time.perf_counter() - t0
        if s >= WARM:
            st = r.last_stats
            walls.append(wall)
            py.append(st.cpu_ms)
            gpu.append(st.gpu_ms)
            kernel.append(st.pass_ms.get("worlds", 0.0))
            per_step.append(dict(st.pass_ms))
    del out
    held = r.device.bytes_allocated()[0] - before
    med = statistics.median(walls)
    return {"row": f"{name}-{size}" + ("" if shadows else " no shadows"), "worlds": worlds, "into": into,
            "world_views_per_s": worlds / med, "python_ms": statistics.median(py),
            "gpu_ms": statistics.median(gpu), "worlds_kernel_ms": statistics.median(kernel),
            "mib_per_1k_worlds": held / 2**20 / worlds * 1000,
            "gpu_ordered": r.batch_path.cuda_order is not None and into == "torch",
            "steps_ms": {k: statistics.median(x.get(k, 0.0) for x in per_step) for k in per_step[0]}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--assets", type=Path, required=True)
    ap.add_argument("--rows", default="helmet-64,analytic-128")
    ap.add_argument("--worlds", default="1024,8192")
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--shadows", choices=("on", "off", "both"), default="on",
                    help="shadow maps (a batch of worlds draws each world's own)")
    ap.add_argument("--json")
    args = ap.parse_args()
    torch = _torch()
    shadow_modes = {"on": (True,), "off": (False,), "both": (True, False)}[args.shadows]
    results = []
    for spec in args.rows.split(","):
        name, size = spec.rsplit("-", 1)
        scene, nodes, distance = scene_for(name, args.assets)
        with Renderer(scene) as r:
            slots = len(r.world_slots(nodes))
            for w in (int(x) for x in args.worlds.split(",")):
                for into, shadows in ((i, m) for i in (("torch", "numpy") if torch is not None else ("numpy",))
                                      for m in shadow_modes):
                    results.append(row(r, name, int(size), w, into, args.steps, distance, slots, torch,
                                       shadows))
                    print(json.dumps(results[-1]), file=sys.stderr)
    print("| row | worlds | into | world-views/s | Python ms | GPU ms | worlds kernel ms | MiB/1k worlds | steps (GPU ms) |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---|")
    for x in results:
        print(f"| {x['row']} | {x['worlds']:,} | {x['into']} | {x['world_views_per_s']:,.0f} | "
              f"{x['python_ms']:.3f} | {x['gpu_ms']:.3f} | {x['worlds_kernel_ms']:.3f} | "
              f"{x['mib_per_1k_worlds']:.2f} | "
              + " ".join(f"{k} {v:.2f}" for k, v in x["steps_ms"].items() if v > 0.05) + " |")
    if args.json:
        with open(args.json, "a", encoding="utf-8") as f:
            for x in results:
                f.write(json.dumps(x) + "\n")


if __name__ == "__main__":
    main()
