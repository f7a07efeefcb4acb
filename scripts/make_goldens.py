"""Re-make the golden images under tests/gpu/golden on lavapipe (the CI device).

Run after a deliberate change to what the renderer draws, then look at the images before
committing them:  .venv/bin/python scripts/make_goldens.py [NAME ...]
NAME is a key of GOLDENS (e.g. damagedhelmet_160x120); none means all. What each golden is
rendered from, and the tolerances the tests apply, are defined once in tests/gpu/goldens.py
(checked by tests/gpu/test_goldens.py). Before overwriting, the script prints how far the
new render is from the old golden.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image

from vkpbr.render.renderer import Renderer

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests" / "gpu"), str(ROOT / "tests")]
import goldens  # noqa: E402  (tests/gpu/goldens.py: the one table of goldens)
from assets_path import ASSETS  # noqa: E402  (the sample models, as the tests find them)


def main(names: list[str]) -> int:
    unknown = sorted(set(names) - set(goldens.GOLDENS))
    if unknown:
        sys.exit(f"unknown golden(s) {unknown}; known: {sorted(goldens.GOLDENS)}")
    for key, golden in goldens.GOLDENS.items():
        if names and key not in names:
            continue
        scene = goldens.load(golden, ASSETS)
        with Renderer(scene, validation=True) as r:
            if "llvmpipe" not in r.device.info.name:
                sys.exit(f"goldens are made on lavapipe, not {r.device.info.name}")
            t0 = time.perf_counter()
            img = goldens.render(r, golden)
            ms = (time.perf_counter() - t0) * 1e3
        was = ""
        if golden.path.exists():
            old = np.asarray(Image.open(golden.path).convert("RGB"))
            if old.shape == img.shape:
                mean, diff = goldens.difference(img, old)
                was = f"; vs the old golden: mean {mean:.3f}, {(diff > 8).mean():.3%} > 8"
        Image.fromarray(img).save(golden.path)
        print(f"wrote {golden.path} ({ms:.0f} ms render{was})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
