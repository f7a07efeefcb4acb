"""Environment pre-filter cost (issue 12 target: <= 100 ms for a 2k x 1k HDR on the GPU).

    PYTHONPATH=src python benchmarks/bench_environment.py [--device NAME]

Prints the pre-filter time (source cube from the panorama, its mips, the GGX chain, the
irradiance cube; the BRDF table is made once beforehand) and the same with the upload.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vkpbr.gpu.device import Device
from vkpbr.render.environment import EnvironmentBaker, EnvironmentSpec


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--device", default=None)
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    pano = (np.random.default_rng(0).random((1024, 2048, 3)) * 4).astype(np.float32)
    with Device(args.device) as dev:
        baker = EnvironmentBaker(dev, EnvironmentSpec())
        baker.brdf_lut()
        for _ in range(args.runs):
            t = time.perf_counter()
            env = baker.from_panorama(pano)
            total = (time.perf_counter() - t) * 1e3
            print(f"{dev.info.name}: 2048x1024 pre-filter {env.bake_ms:.1f} ms "
                  f"(with upload {total:.1f} ms); source {env.source.image.width}^2, "
                  f"specular {env.specular.image.width}^2 x {env.max_lod + 1} levels")
            env.destroy()
        env = baker.from_sky()
        print(f"{dev.info.name}: sky {env.bake_ms:.1f} ms")
        env.destroy()
        baker.destroy()


if __name__ == "__main__":
    main()
