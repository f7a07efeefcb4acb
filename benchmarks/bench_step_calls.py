"""The Python calls of one replayed worlds step (issue 32, pystep3): every function a warm
`batch_step(worlds=poses)` call enters, with its calls and own microseconds a step
(cProfile), the calls in all, and the peak of a step's allocations (tracemalloc).

    python benchmarks/bench_step_calls.py [--variant tabletop|primitives|box|helmet]
        [--worlds 64] [--size 8] [--steps 20] [--expand gpu|auto] [--top 40]

The call count and the allocations do not depend on the machine (lavapipe's threads share
the CPU with the step's Python here: its microseconds are those of a cold cache, several
times what a quiet host gives; profile_worlds_step.py times the phases). NumPy poses (the
same array written in place each step, as a simulator does). Not a test.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from profile_worlds_step import scene_and_poses  # noqa: E402

from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.camera_batch import CameraBatch  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variant", default="tabletop")
    ap.add_argument("--worlds", type=int, default=64)
    ap.add_argument("--size", type=int, default=8)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--expand", default="gpu", help="world_expand (gpu: the kernel's path)")
    ap.add_argument("--top", type=int, default=40, help="functions listed")
    args = ap.parse_args()
    scene, slots, eye, yfov, poses, space = scene_and_poses(args.variant, args.worlds,
                                                            args.steps + 3)
    live = np.array(poses[0], np.float32)  # (the simulator's array, rewritten in place)
    with Renderer(scene) as r:
        r.world_slots(slots)
        cams = CameraBatch.from_poses(np.repeat(eye[None], args.worlds, 0), yfov)
        step = r.batch_step(cams, (args.size, args.size), quaternion="xyzw", space=space,
                            shadows=False, world_expand=args.expand)
        for s in range(3):  # warm: the ring's slots record their steps
            np.copyto(live, poses[s])
            step(worlds=live)
        replayed = r.batch_path.replays.replayed
        prof = cProfile.Profile()
        for s in range(3, 3 + args.steps):
            np.copyto(live, poses[s])
            prof.enable()
            step(worlds=live)
            prof.disable()
        tracemalloc.start()
        blocks = []
        for s in range(args.steps):
            np.copyto(live, poses[s])
            tracemalloc.reset_peak()
            base = tracemalloc.get_traced_memory()[0]
            step(worlds=live)
            blocks.append(tracemalloc.get_traced_memory()[1] - base)
        tracemalloc.stop()
        replayed = r.batch_path.replays.replayed - replayed
    st = pstats.Stats(prof)
    n = args.steps
    rows = sorted(st.stats.items(), key=lambda kv: -kv[1][2])  # (own time)
    calls = sum(v[1] for v in st.stats.values()) / n  # (all calls, recursive ones too)
    print(f"## {args.variant}, W={args.worlds}, {args.size}x{args.size}, world_expand="
          f"{args.expand}, {n} steps ({replayed} of {2 * n} replayed)")
    print(f"Python calls a step: {calls:.0f}; peak bytes allocated in a step (tracemalloc: "
          f"Python objects and NumPy arrays, the returned frames included), median: "
          f"{sorted(blocks)[n // 2]:,}")
    print("| function | calls a step | own us a step (cProfile, cold) |")
    print("|---|---:|---:|")
    for (file, line, name), v in rows[:args.top]:
        where = f"{Path(file).name}:{line}" if line else file
        print(f"| {name} ({where}) | {v[1] / n:g} | {1e6 * v[2] / n:.1f} |")


if __name__ == "__main__":
    main()
