"""Animation sampling on the CPU (issue 31): vkpbr.scene.animation.sample at B times at once,
world matrices and joint matrices, per sample model, as a table of milliseconds.

    python benchmarks/bench_animation.py [--times 1,100,1000] [--repeat 5]

Not a test: prints, asserts nothing. The best of `--repeat` runs is shown (the machine's
other work only ever adds time).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
from assets_path import ASSETS  # noqa: E402

MODELS = ("CesiumMan", "RiggedFigure", "InterpolationTest", "AnimatedMorphCube", "BoxAnimated")


def best(fn, repeat: int) -> float:  # noqa: ANN001 - a zero-argument callable
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times) * 1e3


def main() -> None:
    from vkpbr.scene.animation import joint_matrices, sample
    from vkpbr.scene.loader import load_scene

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--times", default="1,100,1000", help="batch sizes B, comma-separated")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    sizes = [int(x) for x in args.times.split(",")]
    print(f"{'model':<20} {'nodes':>5} {'chan':>5} {'B':>6} {'sample ms':>10} "
          f"{'world ms':>9} {'joints ms':>10}")
    for name in MODELS:
        path = ASSETS / name / "glTF" / f"{name}.gltf"
        if not path.is_file():
            print(f"{name:<20} (not in {ASSETS})")
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_scene(path)
        channels = sum(len(a.channels) for a in scene.animations)
        duration = max(a.duration for a in scene.animations)
        for b in sizes:
            t = np.linspace(0.0, duration, b)
            pose = sample(scene, t)
            world = pose.world(scene.tree)
            ms_sample = best(lambda s=scene, t=t: sample(s, t), args.repeat)
            ms_world = best(lambda p=pose, s=scene: p.world(s.tree), args.repeat)
            ms_joints = (best(lambda w=world, k=scene.skins[0]: joint_matrices(w, k), args.repeat)
                         if scene.skins else float("nan"))
            print(f"{name:<20} {len(scene.tree):>5} {channels:>5} {b:>6} {ms_sample:>10.2f} "
                  f"{ms_world:>9.2f} {ms_joints:>10.2f}")


if __name__ == "__main__":
    main()
