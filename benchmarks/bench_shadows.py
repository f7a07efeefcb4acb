"""Shadow maps by the raster units against compute shaders (RenderOptions.shadow_raster,
render/shadow_raster.py): issue 31's shadow rows. Prints one Markdown table.

    python3 benchmarks/bench_shadows.py --scene .assets/models/Sponza/glTF/Sponza.gltf [--frames 300] [--json out.json]
    (on a CPU, to try it: --size 64x48 --resolution 128 --frames 3)

Rows, each with shadow_raster = hardware and = compute (the compute path with the compute
rasteriser, as `vkpbr bench` draws Sponza):
  maps: sun cascades   the automatic sun's 4 cascades (--resolution 2048) redrawn every frame (the
                       maps forgotten before each): the "shadows" step's GPU ms (timestamps,
                       median), 1920x1080, and the compute path's "shading" step's: with
                       compute-drawn maps it compares by hand from their buffer
                       (render/shadow_raster.py), with the raster units' by the sampler.
  maps: point cube     Sponza's preset point light's 6 faces (half the resolution), likewise.
  walk + sun           the preset camera walking 2 cm a frame (bench_paths.walk) lit by the
                       automatic sun, 1920x1080: frames/s through render_many (three frames in
                       flight, into NumPy), and through render() once a frame; the shadow
                       layers redrawn per frame (mean).
  walk + point         the same walk lit by the preset point light (its cube stays cached):
                       render() once a frame, what issue 31 compares the sun's walk with.
  still / N moving     Sponza with the sun, a still camera; still, and N of its nodes moved
                       every frame (--moving: 3 and 100; every moved node a caster: the
                       cascades redraw each frame): frames/s through render_many (no readback,
                       as bench_living.py). Compute-drawn maps keep the casters that did not
                       move apart (render/shadow_frames.py split); "one pass" rows draw every
                       caster each frame instead, as before session 23.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_paths import CAMERA, walk  # noqa: E402

from vkpbr.render import shadow_frames, shadow_raster  # noqa: E402
from vkpbr.render.renderer import Renderer  # noqa: E402

# Frames after which moved nodes settle (0 in a tree before session 23's kept maps: A/B runs).
SETTLED_FRAMES = getattr(shadow_frames, "SETTLED_FRAMES", 0)
from vkpbr.scene.loader import load_scene  # noqa: E402

MODES = ("hardware", "compute")
SIZE = (1920, 1080)
COMMON = {"pipeline": "compute", "raster": "compute", "shadow_resolution": 2048}


def _median(xs: list[float]) -> float:
    return statistics.median(xs) if xs else float("nan")


def _shadow_ms(r: Renderer) -> float:
    """The frame's shadow steps' GPU ms (with --steps, their parts summed)."""
    return sum(v for k, v in r.last_stats.pass_ms.items() if k.startswith("shadows"))


def map_rows(r: Renderer, frames: int) -> list[dict]:
    """Every layer redrawn each frame: the "shadows" step's GPU ms."""
    rows = []
    for label, lights in (("maps: sun cascades", [r.automatic_sun()]), ("maps: point cube", None)):
        for mode in MODES:
            def views() -> Iterator:
                for _ in range(frames + 10):
                    r.shadows.forget()  # every layer stale: drawn again
                    yield CAMERA
            ms, layers, parts, shading = [], [], [], []
            for i, _ in enumerate(r.render_many(views(), lights, size=SIZE, readback=False,
                                                shadow_raster=mode, **COMMON)):
                if i >= 10:
                    passes = r.last_stats.pass_ms
                    ms.append(_shadow_ms(r))
                    shading.append(passes.get("shading", float("nan")))
                    parts.append({k: v for k, v in passes.items() if k.startswith("shadows")})
                    layers.append(sum(n for _, n in r.shadows.last_redrawn_layers))
            steps = {k: _median([p.get(k, 0.0) for p in parts]) for k in parts[0]} if parts else {}
            rows.append({"row": label, "shadow_raster": mode, "shadows_ms": _median(ms),
                         "shading_ms": _median(shading), "layers": statistics.fmean(layers),
                         "steps": " ".join(f"{k} {v:.3f}" for k, v in steps.items())})
    return rows


def walk_rows(r: Renderer, frames: int) -> list[dict]:
    rows = []
    cams = walk(frames)
    for label, lights in (("walk + sun", [r.automatic_sun()]), ("walk + point", None)):
        for mode in MODES:
            opts = {"size": SIZE, "shadow_raster": mode, **COMMON}
            ms, layers = [], []
            for _ in r.render_many(cams[:10], lights, **opts):  # warm-up: pipelines, recordings
                pass
            t = time.perf_counter()
            for _ in r.render_many(cams, lights, **opts):
                ms.append(_shadow_ms(r))
                layers.append(sum(n for _, n in r.shadows.last_redrawn_layers))
            fps_many = frames / (time.perf_counter() - t)
            t = time.perf_counter()
            for cam in cams:
                r.render(cam, lights, **opts)
            fps_render = frames / (time.perf_counter() - t)
            rows.append({"row": label, "shadow_raster": mode, "fps_render_many": fps_many,
                         "fps_render": fps_render, "shadows_ms": _median(ms),
                         "layers": statistics.fmean(layers)})
    return rows


def moving_rows(scene_path: Path, frames: int, counts: tuple[int, ...] = (3, 100),
                size: tuple[int, int] = SIZE) -> list[dict]:
    """bench_living.py's Sponza rows with the sun: still, and `counts` nodes moved each frame
    (with compute-drawn maps, also in one pass over every caster)."""
    scene = load_scene(scene_path)
    scene.tree = None  # one node holds all 103 primitives: a node each, so that 100 can move
    for node in scene.nodes:
        node.tree = -1
    rows = []
    with Renderer(scene) as r:
        sun = [r.automatic_sun()]
        rest = r.state.local.copy()
        runs = [("still", 0, False)] + [(f"{n} moving{' one pass' if one else ''}", n, one)
                                        for n in counts for one in (False, True)]
        for mode in MODES:
            for label, count, one_pass in runs:
                if one_pass and mode != "compute":
                    continue
                frames_ = r.parts.shadow_frames
                if one_pass:
                    frames_.split = lambda moved: None  # (every caster each frame, one pass)
                rows.append({"row": f"sponza sun {label}", "shadow_raster": mode,
                             **_moving_run(r, sun, rest, count, frames, mode, size)})
                if one_pass:
                    del frames_.split
    return rows


def _moving_run(r: Renderer, sun: list, rest: np.ndarray, count: int, frames: int, mode: str,
                size: tuple[int, int]) -> dict:
    """frames/s, GPU ms and shadow ms of `frames` frames whose first `count` nodes move a
    little each frame (after 30 frames of warm-up), then every node back at rest, settled."""
    moving = np.arange(min(count, len(r.state)))

    def views() -> Iterator:
        for step in range(frames + 30):
            if count:
                m = rest[moving].copy()
                m[:, 1, 3] += 0.01 * np.sin(step * 0.1 + np.arange(len(m)))
                r.set_poses(moving, m)
            yield CAMERA
    t0, gpu, ms = 0.0, [], []
    for i, _ in enumerate(r.render_many(views(), sun, size=size, readback=False,
                                        shadow_raster=mode, **COMMON)):
        if i == 30:
            t0 = time.perf_counter()
        if i >= 30:
            gpu.append(r.last_stats.gpu_ms)
            ms.append(_shadow_ms(r))
    fps = frames / (time.perf_counter() - t0)
    r.set_poses(np.arange(len(r.state)), rest)
    for _ in r.render_many([CAMERA] * (SETTLED_FRAMES + 1), sun, size=size, readback=False,
                           shadow_raster=mode, **COMMON):
        pass  # (the moved nodes settle: the next run's split is its own)
    return {"fps_render_many": fps, "gpu_ms": _median(gpu), "shadows_ms": _median(ms)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=Path(__file__).resolve().parents[1]
                    / ".assets/models/Sponza/glTF/Sponza.gltf")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--only", default="maps,walk,moving")
    ap.add_argument("--size", default="1920x1080", help="WxH (a small one to try it on a CPU)")
    ap.add_argument("--resolution", type=int, default=2048, help="shadow-map texels a side")
    ap.add_argument("--steps", action="store_true",
                    help="time the compute kernels apart (the maps rows' small/big/masked ms; "
                    "'shadows' is then the last kernel's end to the barrier that hands the maps "
                    "to the shading: ~0, there is no copy)")
    ap.add_argument("--moving", default="3,100", help="the moving rows' numbers of moved nodes")
    ap.add_argument("--json")
    args = ap.parse_args()
    global SIZE
    SIZE = tuple(int(x) for x in args.size.split("x"))
    COMMON["shadow_resolution"] = args.resolution
    shadow_raster.TIMED_STEPS = args.steps
    rows: list[dict] = []
    if "maps" in args.only or "walk" in args.only:
        with Renderer(load_scene(args.scene)) as r:
            print(f"device: {r.device.info.name}; {args.frames} frames a row, {SIZE[0]}x{SIZE[1]}")
            if "maps" in args.only:
                rows += map_rows(r, min(args.frames, 100))
            if "walk" in args.only:
                rows += walk_rows(r, args.frames)
    if "moving" in args.only:
        rows += moving_rows(args.scene, args.frames, tuple(int(n) for n in args.moving.split(",")),
                            SIZE)
    keys = ("shadows_ms", "shading_ms", "layers", "fps_render_many", "fps_render", "gpu_ms")
    print("| row | shadow_raster | " + " | ".join(keys) + " | steps (ms) |\n|---|---|"
          + "---:|" * len(keys) + "---|")
    for row in rows:
        cells = [f"{row[k]:.3f}" if isinstance(row.get(k), float) else "" for k in keys]
        print(f"| {row['row']} | {row['shadow_raster']} | " + " | ".join(cells)
              + f" | {row.get('steps', '')} |")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
