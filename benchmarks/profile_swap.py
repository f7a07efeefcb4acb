"""Where a scene swap's CPU time goes (issue 32): `set_scene` and the first item's render call
on one Renderer, per model, at a tiny size (rendering negligible, so lavapipe measures the CPU
cost of changing scene).

    python benchmarks/profile_swap.py [--models DIR] [--names A,B,...] [--rounds 5]
                                      [--size 16x16] [--views 16] [--frames]
                                      [--pipeline auto|forward|compute] [--ahead] [--no-bake]
                                      [--profile OUT.txt]

Each model is loaded `--rounds` times beforehand (a Scene object of its own per swap, as a job
loads each entry: nothing a scene caches on itself carries over), through a bake cache made in
a temporary folder (a job's default; `--no-bake`: the glTF parsed), predecoded as the job's
actor does it (distributed/actor.py `predecode`), or with `--ahead` handed over as a finished
SceneAhead (bake/ahead.py: its decoded images). One Renderer renders the last model once (not
timed), then each round swaps through every model: set_scene, an item of --views orbit views
rendered as the job's actor renders one (render_many in batches of vkpbr.config.BATCH_VIEWS;
`--frames`: frame by frame; `--pipeline compute`: the path auto takes on GPUs), then the same
item again. The swap's cost is set_scene + the first item - the second (what a scene change
adds to rendering the views). Prints per model the medians over the rounds, wall clock and the
main thread's CPU time; with --profile, the cProfile of the swaps and first items (not the
loads, not the second items) sorted by cumulative and by own time.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

DEFAULT = ("DamagedHelmet", "CesiumMilkTruck", "BoxAnimated", "MetalRoughSpheresNoTextures",
           "CesiumMan", "2CylinderEngine")


def load(path: Path, max_size: int, ahead: bool, cache: Path | None) -> object:
    """One scene as a job's actor gets it: through the bake cache in `cache` (None: the glTF
    parsed), predecoded (or as a finished SceneAhead)."""
    from vkpbr.distributed.actor import predecode
    from vkpbr.scene.loader import load_scene

    if ahead:
        from vkpbr.bake.ahead import load_ahead

        got = load_ahead(path, cache)
        got.result()
        if got.decoded is not None:
            got.decoded.result()
        return got
    if cache is None:
        return predecode(load_scene(path), max_size)
    from vkpbr.bake.bake import cached_bake

    return predecode(load_scene(cached_bake(path, cache), root=path.parent), max_size)


def _row(name: str, m: list[float]) -> str:
    """A table row: (wall, CPU) of set_scene, first item, second item, swap."""
    return (f"| {name} | {m[0]:.1f} ({m[3]:.1f}) | {m[1]:.1f} ({m[4]:.1f}) | {m[2]:.1f} "
            f"({m[5]:.1f}) | **{m[6]:.1f}** ({m[7]:.1f}) |")


def main() -> None:
    from assets_path import ASSETS

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", type=Path, default=ASSETS)
    p.add_argument("--names", default=",".join(DEFAULT))
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--size", default="16x16")
    p.add_argument("--views", type=int, default=16)
    p.add_argument("--frames", action="store_true",
                   help="render an item frame by frame (render_many without batch) instead of"
                        " as the job's actor does (batches of vkpbr.config.BATCH_VIEWS)")
    p.add_argument("--pipeline", default="auto", choices=("auto", "forward", "compute"))
    p.add_argument("--ahead", action="store_true")
    p.add_argument("--no-bake", action="store_true",
                   help="parse the glTF files (a job's entry with cache false) instead of "
                        "loading through a bake cache (a job's default; made in a temp folder)")
    p.add_argument("--profile", type=Path)
    p.add_argument("--top", type=int, default=45)
    a = p.parse_args()
    size = tuple(int(v) for v in a.size.split("x"))
    names = a.names.split(",")
    paths = [next((a.models / n / "glTF").glob("*.gltf")) for n in names]

    from vkpbr.config import BATCH_VIEWS
    from vkpbr.render.options import RenderOptions
    from vkpbr.render.renderer import Renderer
    from vkpbr.scene.camera_batch import CameraBatch

    opts = RenderOptions() if a.pipeline == "auto" else RenderOptions(pipeline=a.pipeline)
    batch = None if a.frames else BATCH_VIEWS

    def item(r: Renderer, cams: list) -> None:
        """A job item's render call (distributed/actor.py render_views)."""
        for _ in r.render_many(cams, size=size, options=opts, batch=batch):
            pass

    cache = None if a.no_bake else Path(tempfile.mkdtemp(prefix="vkpbr-profile-swap-"))
    with Renderer(None) as r:
        max_size = int(r.device.limits.maxImageDimension2D)
        scenes = [[load(p, max_size, a.ahead, cache) for p in paths] for _ in range(a.rounds)]
        orbits = []
        for s in scenes[0]:
            sc = s.result() if hasattr(s, "result") else s
            b = CameraBatch.orbit(a.views, bounds=sc.bounds())
            orbits.append([b.camera(i) for i in range(len(b))])
        r.set_scene(load(paths[-1], max_size, False, cache))
        item(r, orbits[-1])
        times: dict[str, list[tuple[float, ...]]] = {n: [] for n in names}
        prof = cProfile.Profile() if a.profile else None
        for rnd in range(a.rounds):
            for name, scene, cams in zip(names, scenes[rnd], orbits, strict=True):
                if prof is not None:
                    prof.enable()
                c0, t0 = time.thread_time(), time.perf_counter()
                r.set_scene(scene)
                c1, t1 = time.thread_time(), time.perf_counter()
                item(r, cams)
                c2, t2 = time.thread_time(), time.perf_counter()
                if prof is not None:
                    prof.disable()
                item(r, cams)
                c3, t3 = time.thread_time(), time.perf_counter()
                times[name].append((t1 - t0, t2 - t1, t3 - t2, c1 - c0, c2 - c1, c3 - c2))
            scenes[rnd] = []
    if cache is not None:
        shutil.rmtree(cache, ignore_errors=True)
    how = "frame by frame" if a.frames else "batch"
    print(f"\n{a.rounds} rounds, {a.views} views at {a.size} an item ({how}, pipeline"
          f" {a.pipeline}), medians in ms: wall clock, and in brackets the"
          " main thread's CPU time (time.thread_time: lavapipe's own threads and the fence waits"
          " not counted). swap = set_scene + the first item - the second item\n")
    print("| model | set_scene | first item | second item | **swap** |")
    print("|---|---:|---:|---:|---:|")
    tot = [0.0] * 8
    for name, got in times.items():
        med = [statistics.median(t[k] for t in got) * 1e3 for k in range(6)]
        med += [med[0] + med[1] - med[2], med[3] + med[4] - med[5]]
        tot = [x + y for x, y in zip(tot, med, strict=True)]
        print(_row(name, med))
    print(_row("mean", [x / len(times) for x in tot]))
    if prof is not None:
        text = io.StringIO()
        st = pstats.Stats(prof, stream=text)
        st.sort_stats("cumulative").print_stats(a.top)
        st.sort_stats("tottime").print_stats(a.top)
        a.profile.write_text(text.getvalue())
        print(f"profile: {a.profile}")


if __name__ == "__main__":
    main()
