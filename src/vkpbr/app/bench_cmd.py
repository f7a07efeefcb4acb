"""`vkpbr bench`: named headless scenarios, frames/s with and without readback into NumPy.

    vkpbr bench [--scenario NAME ...] [--frames N] [--json] [--sponza PATH] [--peers]

Scenarios: sponza-1080p, sponza-480p, default-1080p, spheres-5k (5,000 draws, 5.1 M triangles)
and spheres-100 (100 draws), the last two showing how cost grows with draws and triangles;
Sponza on each frame path (sponza-*-forward, -compute, -compute-raster); and, only when named,
spheres-5k-20m[-instanced][-forward] (5,000 draws, 20.5 M triangles, as nodes or instanced:
issue 13's scale rows, minutes a frame on a CPU).
Each scenario renders an orbit of camera poses through `Renderer.render_many` (frames in
flight), then the same without copying into NumPy.

Worlds scenarios (issue 32): worlds-tabletop-{128,256} (4,096 worlds) and worlds-helmet-64
(8,192): benchmarks/bench_worlds.py, every world's poses anew each step (named to run them).
Batch scenarios (issue 14): batch-{sponza,helmet}-{128,512}: the peers' batch views
(benchmarks/peers/common.py: a seeded orbit of `--views` poses, written once as a .npy that
every peer reads) rendered through `Renderer.render_batch`, `--batch-views` views a call (the
poses repeated), views/s into NumPy and on the GPU alone (timestamps). They need a source
checkout (the poses come from benchmarks/peers/common.py); `--batch` runs them all, and
only they run when no --scenario is given with it.

`--peers` then runs benchmarks/peers/ (pyrender, pygfx; SAPIEN in the batch scenarios) on the
same scenes and poses and prints the ratios vkpbr / peer at equal pixels (pygfx also at its
default pixel_scale 2, which renders 4x the pixels).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import os
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
from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import decode_json

log = logging.getLogger(__name__)

REPO = Path(__file__).resolve().parents[3]
SPONZA_CANDIDATES = (
    REPO / ".assets" / "models" / "Sponza" / "glTF" / "Sponza.gltf",
    REPO / ".assets" / "Sponza" / "Sponza.gltf",
    REPO.parent / "shared" / "assets" / "Sponza" / "glTF" / "Sponza.gltf",
)


def sponza_path(args: argparse.Namespace) -> Path:
    """--sponza, else Sponza under $VKPBR_ASSETS (the sample models' folder the tests use:
    Sponza/glTF/Sponza.gltf), else the checkout's usual places. UsageError naming where it
    looked when none exists."""
    if getattr(args, "sponza", None):
        return Path(args.sponza)
    env = os.environ.get("VKPBR_ASSETS")
    if env:  # set: it wins, as for the tests, so that a wrong value is reported
        root = Path(env).expanduser()
        found = next((p for p in (root / "Sponza" / "glTF" / "Sponza.gltf",
                                  root / "Sponza" / "Sponza.gltf") if p.exists()), None)
        if found is None:
            raise UsageError(f"Sponza not found under $VKPBR_ASSETS={env} (Sponza/glTF/"
                             "Sponza.gltf): pass --sponza PATH/Sponza.gltf")
        return found
    path = next((p for p in SPONZA_CANDIDATES if p.exists()), None)
    if path is None:
        raise UsageError("Sponza not found: set $VKPBR_ASSETS or pass --sponza PATH/Sponza.gltf")
    return path
# The peers' scenario (shared/notes/peers.md): same camera, light and field of view.
SPONZA_CAMERA = dict(eye=(9.0, 1.8, -0.4), target=(-9.0, 3.5, -0.4), yfov_deg=45.0)


def _sponza(args: argparse.Namespace):  # noqa: ANN202
    from vkpbr.scene.loader import load_scene
    from vkpbr.scene.types import Light

    scene = load_scene(sponza_path(args), strict=args.strict, allow_outside_paths=args.allow_outside_paths,
                       variant=getattr(args, "variant", None))
    scene.cameras = [dataclasses.replace(scene.cameras[0], **SPONZA_CAMERA)]
    scene.lights = [Light(position=(0.0, 4.0, 0.0))]
    return scene


def _sponza_parts(args: argparse.Namespace):  # noqa: ANN202
    """Sponza with a node of its own for each of its 103 primitives (the file has one node
    holding them all), so that a scenario can move 100 of them."""
    scene = _sponza(args)
    scene.tree = None
    for node in scene.nodes:
        node.tree = -1
    return scene


def _moving(r: object, cams: list, count: int):  # noqa: ANN202
    """`cams`, each after moving `count` of the scene's nodes a little (set_poses: one call a
    frame, as a simulation's step writes them)."""
    import numpy as np

    nodes = np.arange(min(count, len(r.state)))  # type: ignore[attr-defined]
    rest = r.state.local[nodes].copy()  # type: ignore[attr-defined]
    for step, cam in enumerate(cams):
        m = rest.copy()
        m[:, 1, 3] += 0.01 * np.sin(0.1 * step + np.arange(len(m)))
        r.set_poses(nodes, m)  # type: ignore[attr-defined]
        yield cam


def _default(args: argparse.Namespace):  # noqa: ANN202
    from vkpbr.scene.default import default_scene

    return default_scene()


def _spheres(draws: int, rings: int = 16, segments: int = 32, instanced: bool = False) -> Callable:
    def make(args: argparse.Namespace):  # noqa: ANN202
        from vkpbr.scene.synthetic import sphere_field

        return sphere_field(draws, rings, segments, instanced=instanced)
    return make


# name -> (scene, (width, height)[, render options]): the default frame path (auto: on GPUs
# the compute path with the compute rasteriser), Sponza on the fragment path, and through the
# compute path with the raster units and with the compute rasteriser.
SCENARIOS: dict[str, tuple] = {
    "sponza-1080p": (_sponza, (1920, 1080)),
    "sponza-480p": (_sponza, (640, 480)),
    "default-1080p": (_default, (1920, 1080)),
    "spheres-100": (_spheres(100), (1920, 1080)),
    "spheres-5k": (_spheres(5000), (1920, 1080)),
    # Issue 13's scale: 5,000 draws, 20.5 M triangles, as separate nodes and instanced, on
    # the default path (compute on GPUs) and the fragment path.
    **{f"spheres-5k-20m{kind}{path}": (_spheres(5000, 32, 64, bool(kind)), (1920, 1080),
                                       *([{"pipeline": "forward"}] if path else []))
       for kind in ("", "-instanced") for path in ("", "-forward")},
    **{f"sponza-{label}-{path}": (_sponza, size, options)
       for label, size in (("1080p", (1920, 1080)), ("480p", (640, 480)))
       for path, options in (("forward", {"pipeline": "forward"}),
                             ("compute", {"pipeline": "compute", "raster": "hardware"}),
                             ("compute-raster", {"pipeline": "compute", "raster": "compute"}))},
    # Issue 31: 100 of Sponza's nodes moved every frame (its point light's cube map is then
    # redrawn every frame: the moved nodes cast shadows).
    "sponza-moving-1080p": (_sponza_parts, (1920, 1080), {"moving": 100}),
    "sponza-moving-480p": (_sponza_parts, (640, 480), {"moving": 100}),
    # 3 of them moved (an animated model in a still scene): compute-drawn maps copy the still
    # casters' kept maps and draw the 3 over them (render/shadow_frames.py split).
    "sponza-few-moving-1080p": (_sponza_parts, (1920, 1080), {"moving": 3}),
}


# What a plain `vkpbr bench` runs: all but the 20 M-triangle fields (named to run them).
DEFAULT_SCENARIOS = [name for name in SCENARIOS if "-20m" not in name]


# name -> (scene key of benchmarks/peers/common.py BATCH_SCENES, (width, height), frame path):
# the default (auto: the compute batch on GPUs), the layered batch (pipeline="forward") and
# the compute batch (pipeline="compute", docs/batch.md).
BATCH_SCENARIOS: dict[str, tuple[str, tuple[int, int], str]] = {
    f"batch-{key}-{n}{suffix}": (key, (n, n), pipeline) for key in ("sponza", "helmet")
    for n in (128, 512) for suffix, pipeline in (("", "auto"), ("-forward", "forward"),
                                                 ("-compute", "compute"))
}
PEERS_DIR = REPO / "benchmarks" / "peers"
# Batches of worlds (issue 32, docs/batch.md "Worlds"): name -> (benchmarks/bench_worlds.py
# variant, (width, height), worlds W); each step every world's poses anew from the GPU.
WORLD_SCENARIOS: dict[str, tuple[str, tuple[int, int], int]] = {
    "worlds-tabletop-128": ("tabletop", (128, 128), 4096),
    "worlds-tabletop-256": ("tabletop", (256, 256), 4096),
    "worlds-helmet-64": ("helmet", (64, 64), 8192),
}


def run_world_scenario(name: str, args: argparse.Namespace) -> None:
    """A worlds-* scenario through benchmarks/bench_worlds.py (a source checkout; it prints
    its own table, rows as the peers' in benchmarks/peers/worlds_common.py)."""
    import importlib.util

    path = REPO / "benchmarks" / "bench_worlds.py"
    if not path.exists():
        raise UsageError(f"worlds scenarios need {path} (a source checkout)")
    spec = importlib.util.spec_from_file_location("vkpbr_bench_worlds", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    variant, (w, h), worlds = WORLD_SCENARIOS[name]
    module.run(argparse.Namespace(variant=variant, worlds=str(worlds), sizes=f"{w}x{h}", steps=16,
                                  reps=max(1, math.ceil(args.frames / (16 * worlds))) + 1,
                                  scene_dir=None, json=None, png_dir=None, seed=None))


def peers_common():  # noqa: ANN201
    """benchmarks/peers/common.py as a module (the batch scenario's poses and scenes), or None
    outside a source checkout."""
    import importlib.util

    path = PEERS_DIR / "common.py"
    if not path.exists():
        return None
    spec = importlib.util.spec_from_file_location("vkpbr_peers_common", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def batch_poses_file(args: argparse.Namespace, key: str) -> Path:
    """The .npy of the batch poses of `key` in --poses-dir (written on first use)."""
    common = peers_common()
    if common is None:
        raise UsageError(f"batch scenarios need {PEERS_DIR / 'common.py'} (a source checkout)")
    from vkpbr.user_paths import check_writable_folder

    name = f"poses_{key}_{args.views}.npy"
    folder = check_writable_folder(args.poses_dir, "--poses-dir", name)  # before any work
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    common.load_poses(path, key, args.views)
    return path


# Calls before a batch scenario's timing: more than the frame ring's slots (each has its
# recording) and both of the compute batch's atlases (render/batch_path.py keeps two).
BATCH_WARM_UPS = 4


def run_batch_scenario(name: str, args: argparse.Namespace) -> dict:
    import numpy as np

    from vkpbr.render.renderer import Renderer
    from vkpbr.scene.camera_batch import CameraBatch
    from vkpbr.scene.loader import load_scene
    from vkpbr.scene.types import Light

    key, size, pipeline = BATCH_SCENARIOS[name]
    common = peers_common()
    poses_path = batch_poses_file(args, key)
    poses = np.load(poses_path)
    path = (Path(args.sponza) if key == "sponza" and args.sponza
            else common.ASSETS / common.BATCH_SCENES[key])
    if not path.exists():
        raise UsageError(f"{name}: {path} not found" + (" (pass --sponza PATH)" if key == "sponza" else ""))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(path, strict=args.strict, allow_outside_paths=args.allow_outside_paths)
    scene.lights = [Light(position=tuple(common.LIGHT_POS))]
    b = max(1, args.batch_views)
    views = CameraBatch.from_poses(np.resize(poses, (b, 4, 4)), common.YFOV_DEG)  # poses repeated
    reps = max(3, math.ceil(args.frames / b))  # a median of at least 3 calls
    with Renderer(scene, device=args.device) as r:
        load_s = time.perf_counter() - t0
        for _ in range(BATCH_WARM_UPS):
            r.render_batch(views, size=size, pipeline=pipeline)
        wall, gpu = [], []
        for _ in range(reps):
            t = time.perf_counter()
            r.render_batch(views, size=size, pipeline=pipeline)
            wall.append(time.perf_counter() - t)
            gpu.append(r.last_stats.gpu_ms)
        gpu_ms = statistics.median(gpu)
        return {"scenario": name, "scene": key, "size": f"{size[0]}x{size[1]}", "batch": b,
                "poses": len(poses), "reps": reps, "draws": len(r.gpu_scene.draws),
                "triangles": scene.triangle_count, "load_s": load_s, "device": r.device.info.name,
                "views_per_s_readback": b / statistics.median(wall),
                "views_per_s_render_only": b / gpu_ms * 1e3 if gpu_ms > 0 else float("nan"),
                "ms_per_batch": 1e3 * statistics.median(wall), "gpu_ms": gpu_ms,
                "poses_file": str(poses_path), "poses_sha1": common.poses_digest(poses)}


def print_batch_table(rows: list[dict]) -> None:
    print("| scenario | size | views a call | views/s (render + readback into NumPy) "
          "| views/s (GPU time only) | ms per call | GPU ms per call | draws | load s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scenario']} | {r['size']} | {r['batch']:,} | {r['views_per_s_readback']:,.0f} "
              f"| {r['views_per_s_render_only']:,.0f} | {r['ms_per_batch']:.2f} | {r['gpu_ms']:.2f} "
              f"| {r['draws']:,} | {r['load_s']:.2f} |")


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

    make, size, *rest = SCENARIOS[name]
    options = dict(rest[0]) if rest else {}
    moving = options.pop("moving", 0)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = make(args)
    with Renderer(scene, device=args.device) as r:
        load_s = time.perf_counter() - t0  # parse, decode, upload, mips
        cams = orbit(r.default_camera(), args.frames)
        list(r.render_many(cams[:10], size=size, **options))  # warm-up: record, compile, caches
        result = {"scenario": name, "size": f"{size[0]}x{size[1]}", "draws": len(r.gpu_scene.draws),
                  "triangles": scene.triangle_count, "load_s": load_s, "device": r.device.info.name}
        for readback in (True, False):
            cpu, gpu, rb = [], [], []
            t = time.perf_counter()
            views = _moving(r, cams, moving) if moving else cams
            for _ in r.render_many(views, size=size, readback=readback, **options):
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


def _run_peer(cmd: list[str], what: str, timeout: float = 300.0) -> None:
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        log.warning("%s: stopped after %.0f s", what, timeout)
        return
    if proc.returncode:
        tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
        log.warning("%s: failed (rc %s: %s)", what, proc.returncode, tail)


# The peers of the batch scenario: (script, label, extra arguments). pygfx twice: at
# pixel_scale 1 (the others' pixels) and at its default 2 (2x2 supersampling: 4x the pixels).
BATCH_PEERS = (
    ("pyrender", "pyrender", ()),
    ("pygfx", "pygfx", ("--pixel-scale", "1")),
    ("pygfx", "pygfx (pixel_scale 2)", ("--pixel-scale", "2")),
    ("sapien", "sapien", ("--mode", "cameras")),
    ("sapien", "sapien (group)", ("--mode", "group")),
)


def read_peer_rows(args: argparse.Namespace) -> list[dict]:
    """Peer results measured before (--peers-json: run_peers.sh's peers.json, e.g. SAPIEN from
    another device call when the carried files do not fit in one)."""
    rows = []
    for name in args.peers_json or ():
        path = Path(name)
        if not path.exists():
            raise UsageError(f"--peers-json {path}: no such file")
        try:
            lines = path.read_bytes().splitlines()
        except OSError as e:
            raise UsageError(f"--peers-json {path}: {e.strerror or e}") from None
        for i, line in enumerate(lines, 1):
            if line.strip():
                try:
                    row = decode_json(line, f"{path}:{i}")
                except JsonError as e:
                    raise UsageError(f"--peers-json {path}:{i}: not JSON ({e.problem})") from None
                if not isinstance(row, dict):
                    raise UsageError(f"--peers-json {path}:{i}: expected a JSON object, got "
                                     f"{type(row).__name__}")
                rows.append({**row, "source": path.name})
    return rows


def run_batch_peers(args: argparse.Namespace, rows: list[dict]) -> list[dict]:
    """The batch scenario's peers on the same poses files, scenes and sizes; prints the
    ratios vkpbr / peer (views/s into NumPy, and render only)."""
    import tempfile

    ours = {(r["scene"], r["size"]): r for r in rows if "batch" in r}
    if not ours:
        return []
    peers = []
    given = [p for p in read_peer_rows(args) if p.get("scenario") == "batch"]
    measured = {p.get("peer") for p in given}  # peers read back are not run again
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "peers.json"
        for (key, size), mine in ours.items():
            for script, label, extra in BATCH_PEERS:
                if script in measured:
                    continue
                cmd = [sys.executable, str(PEERS_DIR / f"{script}_bench.py"), "--batch",
                       "--scene", key if not (key == "sponza" and args.sponza) else str(args.sponza),
                       "--size", size, "--poses", mine["poses_file"], "--reps", "2",
                       "--json", str(out), *extra]
                _run_peer(cmd, f"{label} {key} {size}", args.peer_timeout)
        if out.exists():
            peers = [decode_json(line, out) for line in out.read_bytes().splitlines() if line.strip()]
    peers += given
    print("\n| peer | scene | size | pixels rendered per view | peer views/s (into NumPy) "
          "| vkpbr views/s | vkpbr / peer | render only: peer | vkpbr (GPU) | vkpbr / peer |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for p in peers:
        key = p["scene"]  # the peers name a glTF path by its stem: Sponza.gltf -> "sponza"
        mine = ours.get((key, p["size"]))
        if not mine:
            continue
        if p.get("poses_sha1") != mine["poses_sha1"]:
            log.warning("%s %s %s: not the poses vkpbr rendered (same --views and seed needed); "
                        "not compared", p["peer"], key, p["size"])
            continue
        w, h = (int(v) for v in p["size"].split("x"))
        scale = float(p.get("pixel_scale", 1.0))
        label = p["peer"] + (f" (pixel_scale {scale:g})" if scale != 1 else "")
        if p["peer"] == "sapien" and "group" in p.get("settings", ""):
            label = "sapien (RenderCameraGroup)"
        label += f" {p.get('version', '')}" + (f" (from {p['source']})" if "source" in p else "")
        mr, pr = mine["views_per_s_readback"], p["views_per_s_readback"]
        mo, po = mine["views_per_s_render_only"], p["views_per_s_render_only"]
        print(f"| {label} | {key} | {p['size']} | {int(w * h * scale * scale):,} "
              f"| {pr:,.0f} | {mr:,.0f} | {mr / pr:.1f}x | {po:,.0f} | {mo:,.0f} | {mo / po:.1f}x |")
    return peers


def run_peers(args: argparse.Namespace, rows: list[dict]) -> list[dict]:
    """Run benchmarks/peers/{pyrender,pygfx}_bench.py on the same Sponza scenario, in this
    environment (the peers are optional benchmark dependencies), and print the ratios; the
    batch scenarios' peers (with SAPIEN) through `run_batch_peers`."""
    import tempfile

    folder = PEERS_DIR
    if not folder.is_dir():
        raise UsageError(f"--peers needs {folder} (a source checkout with benchmarks/)")
    ours = {r["size"]: r for r in rows if r["scenario"].startswith("sponza")}
    if not ours and not any("batch" in r for r in rows):
        raise UsageError("--peers compares on Sponza: include a sponza-* or batch-* scenario")
    peers = run_batch_peers(args, rows)
    if not ours:
        return peers
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "peers.json"
        for peer in ("pyrender", "pygfx"):
            for size in ours:
                cmd = [sys.executable, str(folder / f"{peer}_bench.py"), "--size", size,
                       "--frames", str(args.frames), "--json", str(out)]
                if args.sponza:
                    cmd += ["--scene", str(args.sponza)]
                _run_peer(cmd, f"{peer} {size}", args.peer_timeout)
        if out.exists():
            peers += [decode_json(line, out) for line in out.read_bytes().splitlines() if line.strip()]
    peers += [p for p in read_peer_rows(args) if p.get("scenario") != "batch" and "fps_readback" in p]
    print("\n| peer | size | frames/s (render + readback) | vkpbr frames/s | vkpbr / peer "
          "| render only: peer | vkpbr |")
    print("|---|---|---|---|---|---|---|")
    for p in peers:
        mine = ours.get(p["size"]) if p.get("scenario") != "batch" else None
        if mine:
            print(f"| {p['peer']} {p.get('version', '')} | {p['size']} | {p['fps_readback']:.1f} "
                  f"| {mine['fps_readback']:.1f} | {mine['fps_readback'] / p['fps_readback']:.1f}x "
                  f"| {1e3 / p['ms_render_only']:.1f} | {mine['fps_render_only']:.1f} |")
    return peers


EPILOG = """\
examples:
  vkpbr bench                                        every frame scenario, 200 frames each
  vkpbr bench --scenario sponza-480p --frames 50     one scenario, shorter
  vkpbr bench --scenario spheres-5k --json           JSON rows for scripts
  vkpbr bench --scenario sponza-1080p --peers        and pyrender / pygfx on the same scene
  vkpbr bench --scenario batch-sponza-128 --peers    B views per call, beside SAPIEN, pygfx, pyrender
  vkpbr bench --batch --peers                        every batch scenario (Sponza, DamagedHelmet; 128, 512)
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
    p.add_argument("--scenario", action="append",
                   choices=[*SCENARIOS, *BATCH_SCENARIOS, *WORLD_SCENARIOS],
                   help="scenario to run (repeatable); default: every frame scenario but the "
                        "spheres-5k-20m* ones (not the batch-* ones: --batch)")
    p.add_argument("--batch", action="store_true",
                   help="run every batch-* scenario (besides any --scenario)")
    p.add_argument("--frames", type=int, default=200, metavar="N",
                   help="timed frames per scenario (default 200)")
    p.add_argument("--sponza", metavar="PATH", help="path to Sponza.gltf")
    p.add_argument("--device", metavar="NAME|INDEX", help="device name substring or index")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--peers", action="store_true",
                   help="also run pyrender and pygfx (and SAPIEN in the batch scenarios) and print ratios")
    p.add_argument("--peers-json", action="append", metavar="FILE",
                   help="with --peers: also compare against peer rows measured before "
                        "(run_peers.sh's peers.json; repeatable)")
    p.add_argument("--peer-timeout", type=float, default=300.0, metavar="S",
                   help="with --peers: stop a peer's run after S seconds (default 300)")
    p.add_argument("--views", type=int, default=256, metavar="B",
                   help="batch scenarios: camera poses generated (default 256)")
    p.add_argument("--batch-views", type=int, default=1024, metavar="N",
                   help="batch scenarios: views per render_batch call, the poses repeated (default 1024)")
    p.add_argument("--poses-dir", default="out/bench-poses", metavar="DIR",
                   help="batch scenarios: where the poses .npy files are read or written "
                        "(default out/bench-poses)")
    add_scene_loading_options(p)  # for --sponza: --strict, --allow-outside-paths, --variant
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.frames < 1:
        raise UsageError("--frames must be at least 1")
    if args.views < 1:
        raise UsageError("--views must be at least 1")
    names = list(args.scenario or ([] if args.batch else DEFAULT_SCENARIOS))
    if args.batch:
        names += [n for n in BATCH_SCENARIOS if n not in names]
    for n in (n for n in names if n in WORLD_SCENARIOS):  # (they print their own table)
        run_world_scenario(n, args)
    names = [n for n in names if n not in WORLD_SCENARIOS]
    rows = [run_batch_scenario(n, args) if n in BATCH_SCENARIOS else run_scenario(n, args)
            for n in names]
    if not rows:
        return 0
    frame_rows = [r for r in rows if "batch" not in r]
    batch_rows = [r for r in rows if "batch" in r]
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        if frame_rows:
            print(f"device: {rows[0]['device']}; {args.frames} frames per scenario, 3 frames in flight")
            print_table(frame_rows)
        if batch_rows:
            print(f"\ndevice: {rows[0]['device']}; batch scenarios: {args.views} poses, "
                  f"--batch-views per render_batch call, at least --frames views timed")
            print_batch_table(batch_rows)
    if args.peers:
        run_peers(args, rows)
    return 0
