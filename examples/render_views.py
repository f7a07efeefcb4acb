"""Render four debug views of a scene side by side: the shaded image, the GGX
distribution D, the mapped normal and the base colour.

    python examples/render_views.py [SCENE.gltf] [--size 320x240] [--out views.png]
"""

import argparse

import numpy as np
from PIL import Image

from vkpbr import Renderer, RenderOptions, load_scene

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scene", nargs="?", help="default: the built-in chart")
parser.add_argument("--size", default="320x240", help="WIDTHxHEIGHT of each view")
parser.add_argument("--out", default="views.png")
args = parser.parse_args()
size = tuple(int(v) for v in args.size.split("x"))

views = ("final", "d", "mapped-normal", "base-color")
with Renderer(load_scene(args.scene) if args.scene else None) as renderer:
    images = [renderer.render(size=size, options=RenderOptions(view=v)) for v in views]
Image.fromarray(np.hstack(images)).save(args.out)  # (H, 4 W, 4) uint8
print(f"wrote {args.out}: {', '.join(views)}")
