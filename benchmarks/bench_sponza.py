"""Sponza benchmark (issues 3 and 4): load-to-first-frame breakdown, GPU frame time and GPU
memory at 1920x1080, vertex memory per TBN path, and the quat-vs-packed image difference.

    python benchmarks/bench_sponza.py [--scene PATH] [--frames N] [--size 1920x1080] [--json OUT]

Not a test: prints a table, asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
from assets_path import ASSETS  # noqa: E402  ($VKPBR_ASSETS, .assets/models or ../shared/assets)

CANDIDATES = [ASSETS / "Sponza" / "glTF" / "Sponza.gltf"]


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(((a.astype(np.float64) - b.astype(np.float64)) ** 2).mean())
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default=next((str(p) for p in CANDIDATES if p.exists()), None))
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    warnings.simplefilter("ignore")

    t0 = time.perf_counter()
    from vkpbr.render.renderer import Renderer
    from vkpbr.scene.loader import load_scene
    from vkpbr.scene.textures import decode_images

    t_import = time.perf_counter()
    scene = load_scene(args.scene)
    t_parse = time.perf_counter()
    # Decode once on its own to show its share; the renderer decodes again inside set-up.
    decode_images(scene.images)
    t_decode = time.perf_counter()
    renderer = Renderer(scene)
    t_setup = time.perf_counter()
    renderer.render(size=(640, 360))
    t_first = time.perf_counter()
    timings = renderer.timings

    gpu = []
    for tbn in ("vectors", "packed"):
        renderer.render(size=size, tbn=tbn)
        for _ in range(args.frames):
            renderer.render(size=size, tbn=tbn)
            gpu.append((tbn, renderer.last_stats.gpu_ms, renderer.last_stats.wait_ms))
    quat = renderer.render(size=size, tbn="quat")
    packed = renderer.render(size=size, tbn="packed")
    gs = renderer.gpu_scene
    name = renderer.device.info.name
    renderer.close()

    med = {t: statistics.median(g for k, g, _ in gpu if k == t) for t in ("vectors", "packed")}
    rows = {
        "device": name,
        "import_s": t_import - t0,
        "parse_s": t_parse - t_import,
        "decode_alone_s": t_decode - t_parse,
        "setup_s": t_setup - t_decode,
        "setup_geometry_s": timings["geometry"],
        "setup_textures_s (decode+upload+mips)": timings["textures"],
        "first_frame_640x360_s": t_first - t_setup,
        "load_to_first_frame_s (parse+setup+first frame)": (t_parse - t_import) + (t_first - t_decode),
        f"gpu_ms_{args.size}_vectors": med["vectors"],
        f"gpu_ms_{args.size}_packed": med["packed"],
        "gpu_memory_MiB": gs.gpu_bytes / 2**20,
        "texture_memory_MiB": gs.texture_bytes / 2**20,
        "vertex_MiB_per_path": {
            path: bpv * gs.vertex_count / 2**20 for path, bpv in gs.bytes_per_vertex().items()
        },
        "bytes_per_vertex": gs.bytes_per_vertex(),
        "psnr_quat_vs_packed_dB": psnr(quat[..., :3], packed[..., :3]),
        "max_diff_quat_vs_packed": int(np.abs(quat.astype(int) - packed.astype(int)).max()),
    }
    width = max(len(k) for k in rows)
    for k, v in rows.items():
        print(f"{k:<{width}}  {v:.3f}" if isinstance(v, float) else f"{k:<{width}}  {v}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
