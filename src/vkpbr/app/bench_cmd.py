"""`vkpbr bench`: named headless scenarios, frames/s with and without readback into NumPy.

    vkpbr bench [--scenario NAME ...] [--frames N] [--json] [--sponza PATH] [--peers]

Scenarios: sponza-1080p, sponza-480p, default-1080p, spheres-5k (5,000 draws, 5.1 M triangles)
and spheres-100 (100 draws), the last two showing how cost grows with draws and triangles.
Each scenario renders an orbit of camera poses through `Renderer.render_many` (frames in
flight), then the same without copying into NumPy. `--peers` then runs
benchmarks/peers/ (pyrender, pygfx) on the same scene and prints the ratios.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import statistics
import subprocess
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from vkpbr.app.options import add_scene_loading_options
from vkpbr.app.parsing import EPILOG_FORMATTER
from vkpbr.errors import UsageError

log = logging.getLogger(__name__)

REPO = Path(__file__).resolve().parents[3]
SPONZA_CANDIDATES = (
    REPO / ".assets" / "Sponza" / "Sponza.gltf",
    REPO.parent / "shared" / "assets" / "Sponza" / "glTF" / "Sponza.gltf",
)
# The peers' scenario (shared/notes/peers.md): same camera, light and field of view.
SPONZA_CAMERA = dict(eye=(9.0, 1.8, -0.4), target=(-9.0, 3.5, -0.4), yfov_deg=45.0)


def _sponza(args: argparse.Namespace):  # noqa: ANN202
    from vkpbr.scene.loader import load_scene
    from vkpbr.scene.types import Light

    path = args.sponza or next((p for p in SPONZA_CANDIDATES if p.exists()), None)
    if path is None:
        raise UsageError("Sponza not found: pass --sponza PATH/Sponza.gltf")
    scene = load_scene(path, strict=args.strict, allow_outside_paths=args.allow_outside_paths,
                       variant=getattr(args, "variant", None))
    scene.cameras = [dataclasses.replace(scene.cameras[0], **SPONZA_CAMERA)]
    scene.lights = [Light(position=(0.0, 4.0, 0.0))]
    return scene


def _default(args: argparse.Namespace):  # noqa: ANN202
    from vkpbr.scene.default import default_scene

    return default_scene()


def _spheres(draws: int) -> Callable:
    def make(args: argparse.Namespace):  # noqa: ANN202
        from vkpbr.scene.synthetic import sphere_field

        return sphere_field(draws)
    return make


SCENARIOS: dict[str, tuple[Callable, tuple[int, int]]] = {
    "sponza-1080p": (_sponza, (1920, 1080)),
    "sponza-480p": (_sponza, (640, 480)),
    "default-1080p": (_default, (1920, 1080)),
    "spheres-100": (_spheres(100), (1920, 1080)),
    "spheres-5k": (_spheres(5000), (1920, 1080)),
}


def orbit(camera, n: int, degrees: float = 0.2) -> list:  # noqa: ANN001
    """n poses turning the eye slightly about the target (distinct frames, same content)."""
    ex, ey, ez = camera.eye
    tx, _, tz = camera.target
    out = []
    for i in range(n):
        a = math.radians(degrees * i)
        dx, dz = ex - tx, ez - tz
        eye = (tx + dx * math.cos(a) + dz * math.sin(a), ey, tz - dx * math.sin(a) + dz * math.cos(a))
        out.append(dataclasses.replace(camera, eye=eye))
    return out


def run_scenario(name: str, args: argparse.Namespace) -> dict:
    from vkpbr.render.renderer import Renderer

    make, size = SCENARIOS[name]
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = make(args)
    with Renderer(scene, device=args.device) as r:
        load_s = time.perf_counter() - t0  # parse, decode, upload, mips
        cams = orbit(r.default_camera(), args.frames)
        list(r.render_many(cams[:10], size=size))  # warm-up: record, compile, caches
        result = {"scenario": name, "size": f"{size[0]}x{size[1]}", "draws": len(r.gpu_scene.draws),
                  "triangles": scene.triangle_count, "load_s": load_s, "device": r.device.info.name}
        for readback in (True, False):
            cpu, gpu, rb = [], [], []
            t = time.perf_counter()
            for _ in r.render_many(cams, size=size, readback=readback):
                s = r.last_stats
                cpu.append(s.cpu_ms)
                gpu.append(s.gpu_ms)
                rb.append(s.readback_ms)
            elapsed = time.perf_counter() - t
            key = "readback" if readback else "render_only"
            result[f"fps_{key}"] = len(cams) / elapsed
            result[f"ms_{key}"] = 1e3 * elapsed / len(cams)
            if readback:
                result["python_ms"] = statistics.median(cpu)
                result["gpu_ms"] = statistics.median(gpu)
                result["readback_ms"] = statistics.median(rb)
    return result


def print_table(rows: list[dict]) -> None:
    print("| scenario | size | draws | triangles | frames/s (render + readback) | frames/s (render only) "
          "| Python ms/frame | GPU ms/frame | readback ms | load s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scenario']} | {r['size']} | {r['draws']:,} | {r['triangles']:,} | {r['fps_readback']:.1f} "
              f"| {r['fps_render_only']:.1f} | {r['python_ms']:.3f} | {r['gpu_ms']:.2f} | {r['readback_ms']:.2f} "
              f"| {r['load_s']:.2f} |")


def run_peers(args: argparse.Namespace, rows: list[dict]) -> list[dict]:
    """Run benchmarks/peers/{pyrender,pygfx}_bench.py on the same Sponza scenario, in this
    environment (the peers are optional benchmark dependencies), and print the ratios."""
    import tempfile

    folder = REPO / "benchmarks" / "peers"
    if not folder.is_dir():
        raise UsageError(f"--peers needs {folder} (a source checkout with benchmarks/)")
    ours = {r["size"]: r for r in rows if r["scenario"].startswith("sponza")}
    if not ours:
        raise UsageError("--peers compares on Sponza: include a sponza-* scenario")
    peers = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "peers.json"
        for peer in ("pyrender", "pygfx"):
            for size in ours:
                cmd = [sys.executable, str(folder / f"{peer}_bench.py"), "--size", size,
                       "--frames", str(args.frames), "--json", str(out)]
                if args.sponza:
                    cmd += ["--scene", str(args.sponza)]
                proc = subprocess.run(cmd, capture_output=True, text=True)
                if proc.returncode:
                    tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
                    log.warning("%s %s: failed (%s)", peer, size, tail)
        if out.exists():
            peers = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]
    print("\n| peer | size | frames/s (render + readback) | vkpbr frames/s | vkpbr / peer "
          "| render only: peer | vkpbr |")
    print("|---|---|---|---|---|---|---|")
    for p in peers:
        mine = ours.get(p["size"])
        if mine:
            print(f"| {p['peer']} {p.get('version', '')} | {p['size']} | {p['fps_readback']:.1f} "
                  f"| {mine['fps_readback']:.1f} | {mine['fps_readback'] / p['fps_readback']:.1f}x "
                  f"| {1e3 / p['ms_render_only']:.1f} | {mine['fps_render_only']:.1f} |")
    return peers


EPILOG = """\
examples:
  vkpbr bench                                        every scenario, 200 frames each
  vkpbr bench --scenario sponza-480p --frames 50     one scenario, shorter
  vkpbr bench --scenario spheres-5k --json           JSON rows for scripts
  vkpbr bench --scenario sponza-1080p --peers        and pyrender / pygfx on the same scene
"""


def add_parser(sub: Any) -> None:
    p = sub.add_parser(
        "bench", help="benchmark headless rendering (frames/s, GPU and Python time)",
        description="Render named scenarios headless through Renderer.render_many (3 frames in "
                    "flight) and print, per scenario: frames/s with readback into NumPy and "
                    "without, the median Python and GPU milliseconds per frame, the readback "
                    "time and the load time. Scenarios: " + ", ".join(SCENARIOS) + " (the "
                    "sphere fields show how cost grows with draws and triangles).",
        epilog=EPILOG, formatter_class=EPILOG_FORMATTER)
    p.add_argument("--scenario", action="append", choices=list(SCENARIOS),
                   help="scenario to run (repeatable); default: all")
    p.add_argument("--frames", type=int, default=200, metavar="N",
                   help="timed frames per scenario (default 200)")
    p.add_argument("--sponza", metavar="PATH", help="path to Sponza.gltf")
    p.add_argument("--device", metavar="NAME|INDEX", help="device name substring or index")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--peers", action="store_true", help="also run pyrender and pygfx and print ratios")
    add_scene_loading_options(p)  # for --sponza: --strict, --allow-outside-paths, --variant
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.frames < 1:
        raise UsageError("--frames must be at least 1")
    rows = [run_scenario(name, args) for name in (args.scenario or list(SCENARIOS))]
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"device: {rows[0]['device']}; {args.frames} frames per scenario, 3 frames in flight")
        print_table(rows)
    if args.peers:
        run_peers(args, rows)
    return 0
