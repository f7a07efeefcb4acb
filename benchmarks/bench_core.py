"""Core benchmark (issue 2): import time, device creation, Python-side per-frame cost,
GPU time by timestamp queries, at 256x256 and 1920x1080. Prints a Markdown table.

    python benchmarks/bench_core.py [--frames N] [--sizes 256x256,1920x1080] [--scene PATH]
                                    [--json OUT.json]

The "static" scene is the default PBR chart with its sphere grid widened to 12 x 12 (>= 100
draws), so the per-draw recording cost would show if it were paid per frame. Python-side
cost is measured twice: the same camera every frame (uniforms unchanged: submit + wait
bookkeeping only) and a moving camera (uniform maths each frame). Not a test: no assertions.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import time
from dataclasses import replace
from datetime import date

import numpy as np


def import_time(runs: int = 5) -> float:
    """Median wall time of `python -c "import vkpbr"` in a fresh interpreter (s)."""
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import vkpbr"], check=True)
        times.append(time.perf_counter() - t)
    base = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        base.append(time.perf_counter() - t)
    return statistics.median(times) - statistics.median(base)


def many_draw_scene(grid: int = 12):
    """The default scene with grid x grid spheres (>= 100 draws)."""
    from vkpbr.scene.default import SPACING, default_scene
    from vkpbr.scene.types import Material, Mesh, Node

    scene = default_scene()
    sphere = scene.meshes[0]
    keep_nodes = scene.nodes[25:]  # floor, card, bulb
    meshes, materials, nodes = list(scene.meshes), list(scene.materials), []
    for i in range(grid * grid):
        row, col = divmod(i, grid)
        materials.append(Material(name=f"s{i}", base_color_factor=(0.9, 0.5, 0.3, 1),
                                  metallic_factor=col / (grid - 1), roughness_factor=0.05 + 0.95 * row / (grid - 1)))
        meshes.append(Mesh(name=f"s{i}", positions=sphere.positions, indices=sphere.indices,
                           normals=sphere.normals, texcoords=sphere.texcoords, tangents=sphere.tangents,
                           material=len(materials) - 1))
        m = np.eye(4, dtype=np.float32)
        s = 5.0 / grid
        m[:3, :3] *= s * 2
        m[:3, 3] = ((col - (grid - 1) / 2) * SPACING * s * 2, 0.5 + row * SPACING * s * 2, 0.0)
        nodes.append(Node(mesh=len(meshes) - 1, matrix=m))
    scene.meshes, scene.materials, scene.nodes = meshes, materials, nodes + keep_nodes
    return scene


def bench_frames(renderer, size, frames: int, moving: bool) -> dict[str, float]:
    cam = renderer.default_camera()
    renderer.render(cam, size=size)  # record, compile shaders, warm caches
    cpu, wait, gpu, total = [], [], [], []
    for i in range(frames):
        c = replace(cam, eye=(cam.eye[0] + 0.001 * i, cam.eye[1], cam.eye[2])) if moving else cam
        t = time.perf_counter()
        renderer.render(c, size=size)
        total.append((time.perf_counter() - t) * 1e3)
        s = renderer.last_stats
        cpu.append(s.cpu_ms)
        wait.append(s.wait_ms)
        gpu.append(s.gpu_ms)
    med = statistics.median
    return {"cpu_ms": med(cpu), "gpu_ms": med(gpu), "wait_ms": med(wait), "frame_ms": med(total),
            "readback_ms": renderer.last_stats.readback_ms}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--sizes", default="256x256,1920x1080")
    ap.add_argument("--device", default=None)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    sizes = [tuple(int(x) for x in s.split("x")) for s in args.sizes.split(",")]

    imp = import_time()
    from vkpbr.gpu.device import Device
    from vkpbr.render.renderer import Renderer

    t = time.perf_counter()
    Device(args.device).close()
    device_s = time.perf_counter() - t
    scene = many_draw_scene()
    t = time.perf_counter()
    renderer = Renderer(scene, device=args.device)
    setup_s = time.perf_counter() - t
    rows = []
    for size in sizes:
        for moving in (False, True):
            r = bench_frames(renderer, size, args.frames, moving)
            rows.append({"size": f"{size[0]}x{size[1]}", "camera": "moving" if moving else "static", **r})
    name = renderer.device.info.name
    draws = len(renderer.gpu_scene.draws)
    tris = renderer.scene.triangle_count
    renderer.close()

    print(f"device: {name}; {draws} draws, {tris:,} triangles; {platform.python_version()}; {date.today()}")
    print(f"import vkpbr: {imp * 1e3:.0f} ms; device creation: {device_s * 1e3:.0f} ms; "
          f"renderer set-up (scene upload, textures, mips): {setup_s * 1e3:.0f} ms")
    print()
    print("| size | camera | Python per frame (ms) | GPU (ms, timestamps) | wait (ms) | readback (ms) | frame (ms) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['size']} | {r['camera']} | {r['cpu_ms']:.3f} | {r['gpu_ms']:.2f} | {r['wait_ms']:.2f} "
              f"| {r['readback_ms']:.2f} | {r['frame_ms']:.2f} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"device": name, "draws": draws, "triangles": tris, "import_s": imp,
                       "device_s": device_s, "setup_s": setup_s, "rows": rows}, f, indent=2)


if __name__ == "__main__":
    main()
