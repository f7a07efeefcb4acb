"""Where a many-scene job's time goes (issue 32): bench_load.py's in-process job (one
Renderer, set_scene per change, the next scene loaded on a thread) under cProfile, after a
run that warms the bake cache, against the job's views rendered by a warm actor.

    python benchmarks/profile_job.py [--models DIR] [--names A,B,...] [--scenes 24]
                                     [--views 16] [--size 32x32] [--profile OUT.txt]

Runs the job once (cold bake cache, not profiled), then again warm (profiled when --profile:
the main thread's calls, sorted by cumulative and by own time), then each model's items on a
warm actor (bench_load.one_scene_rates). Prints the warm job's views/s, the one-scene rate
and the overhead per scene: (warm job seconds - one-scene seconds) / scenes.
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
    a = p.parse_args()
    from bench_load import job_doc, one_scene_rates, run_job

    models = [next((a.models / n / "glTF").glob("*.gltf")).resolve() for n in a.names.split(",")]
    work = Path(tempfile.mkdtemp(prefix="vkpbr-profile-job-"))
    os.environ["VKPBR_CACHE_DIR"] = str(work / "cache")
    try:
        doc = job_doc(models, a.scenes, a.views, a.size, work / "out")
        cold = run_job(doc, "in-process job (cold bake cache)")
        prof = cProfile.Profile() if a.profile else None
        t = time.perf_counter()
        warm = prof.runcall(run_job, doc, "in-process job (warm)") if prof else run_job(doc, "warm")
        wall = time.perf_counter() - t
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
    if prof is not None:
        text = io.StringIO()
        st = pstats.Stats(prof, stream=text)
        st.sort_stats("cumulative").print_stats(a.top)
        st.sort_stats("tottime").print_stats(a.top)
        a.profile.write_text(f"warm job wall {wall:.2f} s\n" + text.getvalue())
        print(f"profile: {a.profile}")


if __name__ == "__main__":
    main()
