"""Session 24: the Python of the shadow caches' alpha watch (GpuSceneState._touch_alpha_changes)
after a set_material, 10,000 draws (sphere_field), median of 200; run it at two commits to compare.

    python benchmarks/results/lavapipe-2026-12-05-s24-alpha.py
"""

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

from vkpbr import Renderer  # noqa: E402
from vkpbr.scene.synthetic import sphere_field  # noqa: E402

with Renderer(sphere_field(10_000, rings=4, segments=8)) as r:
    gs = r.parts.gpu_state
    ts = []
    for i in range(200):
        r.set_material(0, base_color=(0.5, 0.5, 0.5, 0.5 + (i % 2) * 0.1))
        t0 = time.perf_counter()
        gs._touch_alpha_changes()
        ts.append(time.perf_counter() - t0)
    print("draws", len(r.gpu_scene.draws), "alpha watch ms median", round(1e3 * statistics.median(ts), 3))
