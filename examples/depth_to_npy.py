"""Render linear colour and depth (view-space distance along the camera axis) and save
both as NumPy files.

    python examples/depth_to_npy.py [SCENE.gltf] [--size 640x480] [--out render]
    -> render_color.npy (H, W, 4) float32 linear, render_depth.npy (H, W) float32
"""

import argparse

import numpy as np

from vkpbr import Renderer, load_scene

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scene", nargs="?", help="default: the built-in chart")
parser.add_argument("--size", default="640x480", help="WIDTHxHEIGHT")
parser.add_argument("--out", default="render", help="prefix of the two .npy files")
args = parser.parse_args()
size = tuple(int(v) for v in args.size.split("x"))

with Renderer(load_scene(args.scene) if args.scene else None) as renderer:
    color, depth = renderer.render(size=size, linear=True, depth=True)
np.save(f"{args.out}_color.npy", color)
np.save(f"{args.out}_depth.npy", depth)  # inf where nothing was drawn
hit = np.isfinite(depth)
print(f"wrote {args.out}_color.npy, {args.out}_depth.npy: {hit.mean():.0%} of pixels hit, "
      f"depth {depth[hit].min():.3g}..{depth[hit].max():.3g}")
