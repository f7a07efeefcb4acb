"""Session 18's measurement: `add_instances` of 1,000 CesiumMan (a crowd's set-up), seconds.

    python benchmarks/results/lavapipe-2026-12-04-s18-addinst.py [ASSETS]
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene


def main() -> None:
    assets = Path(sys.argv[1] if len(sys.argv) > 1 else "/work/shared/assets")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(assets / "CesiumMan" / "glTF" / "CesiumMan.gltf")
    renderer = Renderer(scene)
    try:
        mesh = next(n.mesh for n in scene.nodes if n.mesh is not None and n.mesh >= 0)
        matrices = np.tile(np.eye(4), (1000, 1, 1))
        matrices[:, 0, 3] = np.arange(1000)
        t = time.perf_counter()
        renderer.add_instances(mesh, matrices)
        print(f"add_instances(1000 CesiumMan): {time.perf_counter() - t:.2f} s")
    finally:
        renderer.close()


if __name__ == "__main__":
    main()
