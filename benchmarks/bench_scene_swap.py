"""A scene's set-up on a Renderer that changes scene (issue 32): `set_scene` over sample models
loaded beforehand (no parse in the timings), each scene's first frame, then its views.

    python benchmarks/bench_scene_swap.py [--models DIR] [--count 10] [--rounds 2]
                                          [--views 16] [--size 256x256] [--label NAME]

The models are every */glTF/*.gltf under --models (sorted; Sponza left out: it is no job's
small model), the first --count of them. One Renderer renders the first model once (not
timed), then --rounds times over all of them: set_scene, one frame (its first: pipelines,
the environment's pre-filter, recordings), --views more frames of an orbit (render_many at
--size). Prints one Markdown row: mean seconds per scene of set_scene (and of it the scene's
upload: geometry + textures + materials), of the first frame, of set_scene + first frame,
the views/s of the whole loop (set-ups included), and the pipelines built per scene after
the first round. Runs on any tree with `Renderer.set_scene` (a before/after pair runs the
same file against each tree's src/).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))


def models(folder: Path, count: int) -> list[Path]:
    found = sorted(p for p in folder.glob("*/glTF/*.gltf") if p.parents[1].name != "Sponza")
    if not found:
        raise SystemExit(f"no */glTF/*.gltf under {folder}")
    return found[:count]


def run(paths: list[Path], rounds: int, views: int, size: tuple[int, int]) -> dict[str, float]:
    from vkpbr.render.renderer import Renderer
    from vkpbr.scene.camera_batch import CameraBatch
    from vkpbr.scene.loader import load_scene

    scenes = [load_scene(p) for p in paths]
    batches = [CameraBatch.orbit(views, bounds=s.bounds()) for s in scenes]
    orbits = [[b.camera(i) for i in range(len(b))] for b in batches]
    sums = dict.fromkeys(("set_scene", "upload", "first", "views_s"), 0.0)
    n = built = 0
    with Renderer(scenes[0]) as r:
        r.render(size=size)
        t_loop = time.perf_counter()
        for rnd in range(rounds):
            before = r.timings.get("pipelines_built", 0)
            for scene, cams in zip(scenes, orbits, strict=True):
                t0 = time.perf_counter()
                r.set_scene(scene)
                t1 = time.perf_counter()
                r.render(size=size)
                t2 = time.perf_counter()
                for _ in r.render_many(cams, size=size):
                    pass
                sums["views_s"] += time.perf_counter() - t2
                sums["set_scene"] += t1 - t0
                sums["first"] += t2 - t1
                sums["upload"] += sum(r.timings.get(k, 0.0) for k in ("geometry", "textures",
                                                                      "materials"))
                n += 1
            if rnd == rounds - 1:
                built = (r.timings.get("pipelines_built", 0) - before) / len(scenes)
        loop = time.perf_counter() - t_loop
    out = {k: v / n for k, v in sums.items()}
    out.update(rate=n * (views + 1) / loop, built=built, scenes=n)
    return out


def main() -> None:
    from assets_path import ASSETS

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", type=Path, default=ASSETS)
    p.add_argument("--count", type=int, default=10)
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--views", type=int, default=16)
    p.add_argument("--size", default="256x256")
    p.add_argument("--label", default=str(REPO.name))
    p.add_argument("--header", action="store_true", help="print the table's header first")
    a = p.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    res = run(models(a.models, a.count), a.rounds, a.views, (w, h))
    if a.header:
        print("| tree | scenes | set_scene s | of which upload s | first frame s | "
              "set_scene + first frame s | loop views/s | pipelines built / scene (last round) |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
    print(f"| {a.label} | {res['scenes']} | {res['set_scene']:.4f} | {res['upload']:.4f} | "
          f"{res['first']:.4f} | {res['set_scene'] + res['first']:.4f} | {res['rate']:.1f} | "
          f"{res['built']:.1f} |")


if __name__ == "__main__":
    main()
