"""Where a frame's recording goes (render/recorder.py FrameRecorder._record): a scene's frame
recorded anew N times (the recordings dropped before each), under cProfile. Not a test.

    python3 benchmarks/profile_record.py --scene Sponza.gltf [--size 1920x1080] [--times 10]
        [--sun] [--compute] [--sort tottime|cumtime]

Prints each recording's milliseconds and the top 40 functions of the recordings alone.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from vkpbr.render import recorder as recorder_module
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--times", type=int, default=10)
    ap.add_argument("--sun", action="store_true", help="lit by the automatic sun (its cascades)")
    ap.add_argument("--sort", default="tottime")
    ap.add_argument("--compute", action="store_true",
                    help="the compute path, its rasteriser and compute-drawn shadow maps (the "
                         "H200's auto; lavapipe's is the fragment path)")
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    opts = ({"pipeline": "compute", "raster": "compute", "shadow_raster": "compute"}
            if args.compute else {})
    with Renderer(load_scene(args.scene)) as r:
        lights = [r.automatic_sun()] if args.sun else None
        r.render(size=size, lights=lights, **opts)  # the kernels, the path's choice
        original = recorder_module.FrameRecorder._record
        prof, ms = cProfile.Profile(), []

        def timed(self, *a, **k):  # noqa: ANN001, ANN002, ANN003, ANN202
            t = time.perf_counter()
            prof.enable()
            try:
                return original(self, *a, **k)
            finally:
                prof.disable()
                ms.append(1e3 * (time.perf_counter() - t))

        recorder_module.FrameRecorder._record = timed
        try:
            for _ in range(args.times):
                r.parts.recorder.free()
                r.render(size=size, lights=lights, **opts)
        finally:
            recorder_module.FrameRecorder._record = original
        print(f"device: {r.device.info.name}; recordings (ms): " + " ".join(f"{m:.2f}" for m in ms))
        pstats.Stats(prof).sort_stats(args.sort).print_stats(40)


if __name__ == "__main__":
    main()
