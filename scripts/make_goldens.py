"""Re-make the golden images under tests/gpu/golden on lavapipe (the CI device).

Run after a deliberate change to what the renderer draws, then look at the images before
committing them:  .venv/bin/python scripts/make_goldens.py
The tests that read them state their tolerances (tests/gpu/test_views.py, test_scenes.py).
"""

from __future__ import annotations

import sys
from pathlib import Path

from PIL import Image

from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "gpu" / "golden"
ASSETS = ROOT.parent / "shared" / "assets"

# name -> (scene file under ../shared/assets or None for the default scene, (width, height))
GOLDENS = {
    "default_160x120.png": (None, (160, 120)),
    "sponza_320x180.png": ("Sponza/glTF/Sponza.gltf", (320, 180)),
}


def main() -> int:
    for name, (rel, size) in GOLDENS.items():
        scene = load_scene(ASSETS / rel) if rel else None
        with Renderer(scene, validation=True) as r:
            if "llvmpipe" not in r.device.info.name:
                sys.exit(f"goldens are made on lavapipe, not {r.device.info.name}")
            img = r.render(size=size)
        Image.fromarray(img[..., :3]).save(GOLDEN / name)
        print(f"wrote {GOLDEN / name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
