"""A Renderer's scene change and its first frame, timed (and its Vulkan objects counted).

    python benchmarks/time_scene_change.py [--assets DIR] [--rounds 4] [--count]

Six sample models from the bake cache, decoded ahead as a job's loading thread leaves them;
each change is `set_scene` and 4 views at 64x64 through `render_many`; after one round to
warm up, `--rounds` rounds are timed (median and mean a change). `--count`: the Vulkan calls
that make, allocate, destroy or free objects (and the device waits and submissions) a
change, by name, instead of the timing.
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics
import time
from pathlib import Path

MODELS = ("DamagedHelmet", "CesiumMilkTruck", "BoxAnimated", "2CylinderEngine",
          "TextureCoordinateTest", "MetalRoughSpheresNoTextures")
COUNTED = ("vkCreate", "vkAllocate", "vkDestroy", "vkFree", "vkDeviceWaitIdle", "vkQueueSubmit")


def count_calls() -> collections.Counter:
    """Wrap the vulkan binding's object calls (before vkpbr imports them) to count them."""
    import vulkan

    counts: collections.Counter = collections.Counter()
    for name in dir(vulkan):
        fn = getattr(vulkan, name)
        if name.startswith(COUNTED) and callable(fn):
            def counted(*args, _fn=fn, _name=name, **kwargs):  # noqa: ANN002, ANN003, ANN202
                counts[_name] += 1
                return _fn(*args, **kwargs)
            setattr(vulkan, name, counted)
    return counts


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--assets", type=Path, default=Path(os.environ.get("VKPBR_ASSETS", "../shared/assets")))
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--count", action="store_true")
    args = p.parse_args()
    counts = count_calls() if args.count else None
    from vkpbr import Renderer
    from vkpbr.distributed import job_from_doc
    from vkpbr.distributed.actor import load_scene_for, predecode

    settings = [job_from_doc([{"scene": str(args.assets / m / "glTF" / f"{m}.gltf"),
                               "cameras": ["3,1,3,0,0,0"], "out": "unused", "size": "64x64"}]
                             ).items()[0].settings for m in MODELS]
    scenes = [predecode(load_scene_for(s), 16384) for s in settings]
    order = scenes[1:] + scenes[:1]
    with Renderer(scenes[0]) as r:
        def change(scene: object) -> None:
            r.set_scene(scene)
            list(r.render_many([r.default_camera()] * 4, size=(64, 64)))

        for scene in order:  # (warm: pipelines, kept handles, the AO images)
            change(scene)
        if counts is not None:
            counts.clear()
            for scene in order:
                change(scene)
            print(f"Vulkan object calls a change: {sum(counts.values()) / len(order):.1f}")
            for name, n in counts.most_common():
                print(f"  {name:32s} {n / len(order):6.1f}")
            return
        times = []
        for _ in range(args.rounds):
            for scene in order:
                t = time.perf_counter()
                change(scene)
                times.append(time.perf_counter() - t)
    print(f"a change + 4 views at 64x64: median {1000 * statistics.median(times):.1f} ms, "
          f"mean {1000 * statistics.mean(times):.1f} (n={len(times)})")


if __name__ == "__main__":
    main()
