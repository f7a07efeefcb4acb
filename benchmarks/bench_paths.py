"""Frame paths and lighting on one scene (issues 12 and 13): GPU time per step, frames/s.

    python benchmarks/bench_paths.py [--scene Sponza.gltf] [--frames 200]
                                     [--sizes 1920x1080,640x480,128x128] [--lights 1,16,64,256]
                                     [--rows course/scene/still,...] [--paths compute/compute,...]
                                     [--json OUT.json]

Rows: the course's lighting and the physically based one (the automatic sun's cascaded
shadows and the sky's image-based light; with the camera still, whose maps are drawn once,
and walking 2 cm a frame, whose cascades are redrawn as they cross their snapping grid), each
on the fragment path and on the compute path
(render/compute_path.py); then the cost per punctual light (N point lights spread over the
scene's floor, shadows off so the lights alone are measured). GPU times are timestamp
queries, median (and mean, max) over the frames after 10 warm-up frames, with the shadow-map
layers drawn per frame; frames/s is wall time over
`render_many` with readback into NumPy and without. "draw() ms" is the frame's Python call
(stats.cpu_ms, wall time), "of which driver" the thread CPU time inside the driver (fence
wait, timestamp read, submit: stats.driver_ms), "Python alone" their difference (an upper
bound: a driver wait that sleeps counts as Python). Prints Markdown tables. Not a test.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import time
from pathlib import Path

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.render.paths import STEP_NAMES
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Camera, Light

CAMERA = Camera(eye=(9.0, 1.8, -0.4), target=(-9.0, 3.5, -0.4), yfov_deg=45.0)  # the preset
# (frame path, what makes the compute path's visibility buffer): render/compute_raster's
# compute rasteriser beside the raster units.
PATHS = (("forward", "hardware"), ("compute", "hardware"), ("compute", "compute"))
# (lighting, light, camera): the scene's light (Sponza's preset point light: one cube map,
# drawn once while it stands still) or the automatic sun (four cascades fitted to the view:
# drawn once for a still camera, every frame for a walking one).
ROWS = (("course", "scene", "still"), ("pbr", "scene", "still"), ("pbr", "sun", "still"),
        ("pbr", "sun", "moving"))
# Every timed step of a frame (the compute rasteriser's kernels and the classification on
# the compute path; "opaque" is then the depths' write) and the copies after them.
STEPS = tuple(n for n in STEP_NAMES if n not in ("prepass_opaque_double", "cull", "views"))


def walk(frames: int) -> list[Camera]:
    """The preset camera walking 2 cm a frame along the nave (1.2 m/s at 60 frames/s): the
    sun's cascades are refitted every frame and redrawn when they cross their snapping grid
    (shadow_math.snap_texels), as in a fly-through; a still camera's maps are drawn once."""
    return [dataclasses.replace(CAMERA, eye=(CAMERA.eye[0] - 0.02 * i, *CAMERA.eye[1:]),
                                target=(CAMERA.target[0] - 0.02 * i, *CAMERA.target[1:]))
            for i in range(frames)]


def measure(r: Renderer, size: tuple[int, int], frames: int, lights=None,  # noqa: ANN001
            camera: str = "still", **options) -> dict:
    cams = walk(frames) if camera == "moving" else [CAMERA] * frames
    gpu, passes, cpu, driver, layers = [], [], [], [], []
    for i, _ in enumerate(r.render_many((cams * 10)[:10] + cams, lights, size=size,
                                        readback=False, driver_time=True, **options)):
        if i >= 10:
            gpu.append(r.last_stats.gpu_ms)
            passes.append(r.last_stats.pass_ms)
            cpu.append(r.last_stats.cpu_ms)
            driver.append(r.last_stats.driver_ms)
            layers.append(sum(n for _, n in r.shadows.last_redrawn_layers))
    t = time.perf_counter()
    for _ in r.render_many(cams, lights, size=size, **options):
        pass
    fps = frames / (time.perf_counter() - t)
    t = time.perf_counter()
    for _ in r.render_many(cams, lights, size=size, readback=False, **options):
        pass
    fps_render = frames / (time.perf_counter() - t)
    per_pass = {k: statistics.median(p.get(k, 0.0) for p in passes) for k in passes[0]}
    return {"size": f"{size[0]}x{size[1]}", "gpu_ms": statistics.median(gpu),
            "gpu_ms_mean": statistics.fmean(gpu), "gpu_ms_max": max(gpu),
            "shadow_layers": statistics.fmean(layers),
            "cpu_ms": statistics.median(cpu), "driver_ms": statistics.median(driver),
            "python_ms": statistics.median(c - d for c, d in zip(cpu, driver, strict=True)),
            "fps_readback": fps, "fps_render_only": fps_render,
            "pass_ms": per_pass, "camera": camera, **{k: str(v) for k, v in options.items()}}


def floor_lights(scene, n: int) -> list[Light]:  # noqa: ANN001
    lo, hi = scene.bounds()
    rng = np.random.default_rng(7)
    xz = rng.uniform(lo[[0, 2]], hi[[0, 2]], (n, 2))
    y = lo[1] + 0.1 * (hi[1] - lo[1])
    return [Light(kind="point", position=(float(x), float(y), float(z)), intensity=2.0,
                  color=tuple(float(c) for c in rng.uniform(0.3, 1.0, 3)),
                  falloff="inverse_square", range=float(0.25 * (hi[0] - lo[0])))
            for x, z in xz]


def scene_rows(scenes: list[tuple[str, object]], sizes: list[tuple[int, int]], frames: int,
               key: str, paths: tuple = PATHS) -> list[dict]:
    """`measure` of each (label, scene) at every size and frame path, lit by the automatic sun
    (bench_materials.py, bench_transmission.py: a scene with and without a material feature),
    each row labelled `key`: label."""
    rows = []
    for label, scene in scenes:
        with Renderer(scene) as r:
            print(f"device: {r.device.info.name}; {key}: {label}")
            for size in sizes:
                for pipeline, raster in paths:
                    row = measure(r, size, frames, [r.automatic_sun()], lighting="pbr",
                                  pipeline=pipeline, raster=raster)
                    rows.append({**row, key: label})
    return rows


def table(rows: list[dict], keys: tuple[str, ...]) -> None:
    head = ["size", *keys, "GPU ms", "mean", "max", "shadow layers drawn", *STEPS,
            "fps (NumPy)", "fps (GPU only)", "draw() ms", "of which driver", "Python alone"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        steps = [f"{row['pass_ms'].get(s, 0.0):.3f}" for s in STEPS]
        print("| " + " | ".join([row["size"], *(row.get(k, "") for k in keys),
                                 f"{row['gpu_ms']:.3f}", f"{row['gpu_ms_mean']:.3f}",
                                 f"{row['gpu_ms_max']:.3f}", f"{row['shadow_layers']:.2f}",
                                 *steps, f"{row['fps_readback']:.0f}",
                                 f"{row['fps_render_only']:.0f}", f"{row['cpu_ms']:.3f}",
                                 f"{row['driver_ms']:.3f}", f"{row['python_ms']:.3f}"]) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(Path(__file__).resolve().parents[1]
                                           / ".assets/models/Sponza/glTF/Sponza.gltf"))
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--sizes", default="1920x1080,640x480,128x128")
    ap.add_argument("--lights", default="1,16,64,256")
    ap.add_argument("--rows", default=",".join("/".join(r) for r in ROWS),
                    help="lighting/light/camera rows (default all)")
    ap.add_argument("--paths", default=",".join("/".join(p) for p in PATHS),
                    help="pipeline/raster pairs (default all)")
    ap.add_argument("--json")
    args = ap.parse_args()
    frame_rows = [tuple(r.split("/")) for r in args.rows.split(",")]
    paths = [tuple(p.split("/")) for p in args.paths.split(",")]
    scene = load_scene(args.scene)
    sizes = [tuple(int(x) for x in s.split("x")) for s in args.sizes.split(",")]
    rows, light_rows = [], []
    with Renderer(scene) as r:
        print(f"device: {r.device.info.name}; scene {Path(args.scene).name}, "
              f"{scene.triangle_count} triangles; {args.frames} frames a row")
        for size in sizes:
            for lighting, light, camera in frame_rows:
                for pipeline, raster in paths:
                    try:
                        row = measure(r, size, args.frames, [r.automatic_sun()] if light == "sun" else None,
                                      lighting=lighting, pipeline=pipeline, raster=raster, camera=camera)
                        rows.append({**row, "light": light})
                    except UsageError as exc:
                        print(f"skipped {pipeline} ({raster} raster): {exc}")
        table(rows, ("lighting", "light", "camera", "pipeline", "raster"))
        size = sizes[0]
        for n in (int(x) for x in args.lights.split(",") if x):
            lights = floor_lights(scene, n)
            for pipeline, raster in paths:
                try:
                    row = measure(r, size, max(args.frames // 2, 20), lights, lighting="pbr",
                                  pipeline=pipeline, raster=raster, shadows=False, env="none")
                except UsageError as exc:
                    print(f"skipped {pipeline}: {exc}")
                    continue
                row["lights"] = str(n)
                light_rows.append(row)
        if light_rows:
            print()
            table(light_rows, ("lights", "pipeline", "raster"))
    if args.json:
        Path(args.json).write_text(json.dumps({"paths": rows, "lights": light_rows}, indent=1))


if __name__ == "__main__":
    main()
