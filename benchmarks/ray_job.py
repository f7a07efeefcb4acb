"""Write a `vkpbr batch` job file (docs/distributed.md) for a many-scenes benchmark (issue 16):
every scene found under MODELS (the sample models' glTF files) with an orbit of N poses
around it (benchmarks/bench_ray.py's `orbit`), colour plus OUTPUTS at SIZE.

    python benchmarks/ray_job.py MODELS JOB.json [--views 64] [--size 256x256] [--outputs depth]

Prints how many scenes and views it wrote. Not a test.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bench_ray import orbit


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("models", type=Path)
    p.add_argument("job", type=Path)
    p.add_argument("--views", type=int, default=64)
    p.add_argument("--size", default="256x256")
    p.add_argument("--outputs", default="")
    args = p.parse_args()
    scenes = sorted(f for f in args.models.glob("*/glTF/*.gltf"))
    entries = []
    for i, scene in enumerate(scenes):
        poses = [{"eye": list(map(float, pose.eye)), "target": list(map(float, pose.target))}
                 for pose in orbit(scene, args.views)]
        entries.append({"scene": str(scene.resolve()), "cameras": poses, "out": f"out/{i:02d}-{scene.stem}",
                        "size": args.size, "outputs": [o for o in args.outputs.split(",") if o]})
    args.job.write_text(json.dumps({"views_per_item": 16, "scenes": entries}))
    print(f"{args.job}: {len(entries)} scenes x {args.views} views = {len(entries) * args.views} views")


if __name__ == "__main__":
    main()
