"""Where a many-scene job's time goes (issue 32): bench_load.py's in-process job (one
Renderer, set_scene per change, the next scene loaded on a thread) under cProfile, after a
run that warms the bake cache, against the job's views rendered by a warm actor.

    python benchmarks/profile_job.py [--models DIR] [--names A,B,...] [--scenes 24]
                                     [--views 16] [--size 32x32] [--profile OUT.txt]

Runs the job once (cold bake cache, not profiled), then again warm (profiled when --profile:
the main thread's calls, sorted by cumulative and by own time), then each model's items on a
warm actor (bench_load.one_scene_rates). Prints the warm job's views/s, the one-scene rate
and the overhead per scene: (warm job seconds - one-scene seconds) / scenes.

`--phases`: the warm job's main thread by phase instead of cProfile (whose accounting of
the job's other threads misleads): wall-clock ms per scene inside each wrapped function
(nested phases indented, counted in their parents too), and the rest of an item (its
files' encoding waited for, the manifest) by difference.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import shutil
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "benchmarks"))

DEFAULT = ("DamagedHelmet", "CesiumMilkTruck", "BoxAnimated", "MetalRoughSpheresNoTextures",
           "CesiumMan", "2CylinderEngine")


# (depth, label, module, owner, attribute): the job's main thread, as Timers takes them
JOB_PHASES: tuple[tuple[int, str, str, str, str], ...] = (
    (0, "an item (RendererActor.render)", "vkpbr.distributed.actor", "RendererActor", "render"),
    (1, "its scene (_renderer_for)", "vkpbr.distributed.actor", "RendererActor", "_renderer_for"),
    (2, "the scene loaded ahead, waited for (_scene)", "vkpbr.distributed.actor", "RendererActor",
     "_scene"),
    (2, "set_scene", "vkpbr.render.renderer", "Renderer", "set_scene"),
    (3, "textures' upload (_upload_textures)", "vkpbr.render.gpu_scene", "GpuScene",
     "_upload_textures"),
    (1, "next scene's load started (prefetch)", "vkpbr.distributed.actor", "RendererActor",
     "prefetch"),
    # (render_many's frames come from a generator: its phases are the item's own)
    (1, "pipelines built (build_pipelines)", "vkpbr.render.recorder", "FrameRecorder",
     "build_pipelines"),
    (1, "commands recorded (command_buffer)", "vkpbr.render.recorder", "FrameRecorder",
     "command_buffer"),
    (1, "GPU waits (Frame.wait)", "vkpbr.gpu.frames", "Frame", "wait"),
    (1, "readback (read_tiles)", "vkpbr.gpu.target", "OffscreenTarget", "read_tiles"),
    (1, "pipeline cache saved (PipelineCache.save)", "vkpbr.gpu.pipeline_cache",
     "PipelineCache", "save"),
    (0, "manifest (driver._record)", "vkpbr.distributed.driver", "", "_record"),
)


# The loads ahead, on the actor's loader thread
LOADER_PHASES: tuple[tuple[int, str, str, str, str], ...] = (
    (0, "a scene's load ahead (RendererActor._load)", "vkpbr.distributed.actor", "RendererActor",
     "_load"),
    (1, "read (load_scene_for: the bake cache's file, or a bake)", "vkpbr.distributed.actor", "",
     "load_scene_for"),
    (1, "textures decoded (predecode)", "vkpbr.distributed.actor", "", "predecode"),
)


def phase_timers() -> tuple[object, object]:
    """profile_worlds_step.Timers over JOB_PHASES (main thread only) and LOADER_PHASES (any
    thread), switched on."""
    from profile_worlds_step import Timers

    timers = Timers(JOB_PHASES, main_only=True), Timers(LOADER_PHASES)
    for t in timers:
        t.install()
        t.on = True
    return timers


def print_phases(both: tuple[object, object], wall: float, scenes: int) -> None:
    timers, loader = both
    print(f"\n| warm job, main thread | ms a scene | calls |  (wall {wall:.2f} s, {scenes} scenes)")
    print("|---|---:|---:|")
    items = timers.total.get(JOB_PHASES[0][1], 0.0)  # type: ignore[attr-defined]
    inner = sum(timers.total.get(label, 0.0) for depth, label in timers.found  # type: ignore[attr-defined]
                if depth == 1)
    rest = (f"| &nbsp;&nbsp;the rest of the items (their files' encoding waited for, other "
            f"Python) | {(items - inner) / scenes * 1e3:.1f} | |")
    for i, (depth, label) in enumerate(timers.found):  # type: ignore[attr-defined]
        if depth == 0 and i:  # the item's own rows end here
            print(rest)
        total = timers.total.get(label, 0.0)  # type: ignore[attr-defined]
        calls = timers.calls.get(label, 0)  # type: ignore[attr-defined]
        print(f"| {'&nbsp;&nbsp;' * depth}{label} | {total / scenes * 1e3:.1f} | {calls} |")
    print(f"| outside items (the driver, manifests, folders) | {(wall - items) / scenes * 1e3:.1f} | |")
    print("\n| the loader thread | ms a scene | calls |\n|---|---:|---:|")
    for depth, label in loader.found:  # type: ignore[attr-defined]
        total = loader.total.get(label, 0.0)  # type: ignore[attr-defined]
        print(f"| {'&nbsp;&nbsp;' * depth}{label} | {total / scenes * 1e3:.1f} | "
              f"{loader.calls.get(label, 0)} |")  # type: ignore[attr-defined]


def main() -> None:
    from assets_path import ASSETS

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", type=Path, default=ASSETS)
    p.add_argument("--names", default=",".join(DEFAULT))
    p.add_argument("--scenes", type=int, default=24)
    p.add_argument("--views", type=int, default=16)
    p.add_argument("--size", default="32x32")
    p.add_argument("--profile", type=Path)
    p.add_argument("--top", type=int, default=50)
    p.add_argument("--phases", action="store_true",
                   help="time the warm job's main thread by phase (no cProfile)")
    a = p.parse_args()
    from bench_load import job_doc, one_scene_rates, run_job

    models = [next((a.models / n / "glTF").glob("*.gltf")).resolve() for n in a.names.split(",")]
    work = Path(tempfile.mkdtemp(prefix="vkpbr-profile-job-"))
    os.environ["VKPBR_CACHE_DIR"] = str(work / "cache")
    try:
        doc = job_doc(models, a.scenes, a.views, a.size, work / "out")
        cold = run_job(doc, "in-process job (cold bake cache)")
        prof = cProfile.Profile() if a.profile else None
        timers = phase_timers() if a.phases else None
        t = time.perf_counter()
        warm = prof.runcall(run_job, doc, "in-process job (warm)") if prof else run_job(
            doc, "in-process job (warm)")
        wall = time.perf_counter() - t
        for t in timers or ():
            t.on = False
        rates = one_scene_rates(doc, work / "one")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    ideal = sum(a.views / rates[str(m)] for m in (models * a.scenes)[:a.scenes])
    print(f"| run | views | s | views/s | of one scene | overhead ms a scene |  ({a.scenes} scenes,"
          f" {a.views} views at {a.size})")
    print("|---|---:|---:|---:|---:|---:|")
    print(f"| one scene in-process | {a.views * a.scenes} | {ideal:.2f} | "
          f"{a.views * a.scenes / ideal:.1f} | 100% | - |")
    for name, r in (("cold bake cache", cold), ("warm", warm)):
        rate = r["views"] / r["seconds"]
        print(f"| {name} | {r['views']} | {r['seconds']:.2f} | {rate:.1f} | "
              f"{rate * ideal / (a.views * a.scenes):.0%} | "
              f"{(r['seconds'] - ideal) / a.scenes * 1e3:.0f} |")
    print("per model views/s: " + ", ".join(f"{Path(k).stem} {v:.0f}" for k, v in rates.items()))
    if timers is not None:
        print_phases(timers, wall, a.scenes)
    if prof is not None:
        text = io.StringIO()
        st = pstats.Stats(prof, stream=text)
        st.sort_stats("cumulative").print_stats(a.top)
        st.sort_stats("tottime").print_stats(a.top)
        a.profile.write_text(f"warm job wall {wall:.2f} s\n" + text.getvalue())
        print(f"profile: {a.profile}")


if __name__ == "__main__":
    main()
