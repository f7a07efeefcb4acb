"""Render vkpbr's built-in PBR chart (its own camera and light) to a PNG.

    python examples/render_default.py [--size 640x480] [--out default.png]
"""

import argparse

from PIL import Image

from vkpbr import Renderer

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--size", default="640x480", help="WIDTHxHEIGHT")
parser.add_argument("--out", default="default.png")
args = parser.parse_args()
size = tuple(int(v) for v in args.size.split("x"))

with Renderer() as renderer:  # no scene: the built-in chart
    rgba = renderer.render(size=size)  # (H, W, 4) uint8, sRGB-encoded
Image.fromarray(rgba).save(args.out)
print(f"wrote {args.out} ({renderer.last_stats.gpu_ms:.2f} ms on the GPU)")
