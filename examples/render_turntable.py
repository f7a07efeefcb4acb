"""Render 8 cameras around a scene with `render_many` (frames in flight on the GPU) and
save them as one 4 x 2 contact sheet.

    python examples/render_turntable.py [SCENE.gltf] [--size 320x240] [--out turntable.png]
"""

import argparse
import dataclasses
import math

import numpy as np
from PIL import Image

from vkpbr import Camera, Renderer, load_scene

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scene", nargs="?", help="default: the built-in chart")
parser.add_argument("--size", default="320x240", help="WIDTHxHEIGHT of each frame")
parser.add_argument("--out", default="turntable.png")
args = parser.parse_args()
size = tuple(int(v) for v in args.size.split("x"))

with Renderer(load_scene(args.scene) if args.scene else None) as renderer:
    start: Camera = renderer.default_camera()  # frames the scene; we orbit its target
    (ex, ey, ez), (tx, _, tz) = start.eye, start.target
    radius, angle0 = math.hypot(ex - tx, ez - tz), math.atan2(ex - tx, ez - tz)
    cameras = [dataclasses.replace(start, eye=(tx + radius * math.sin(a), ey, tz + radius * math.cos(a)))
               for a in (angle0 + i * math.pi / 4 for i in range(8))]
    # The scene's own lights (none: the automatic sun and the sky), the same for every view.
    frames = list(renderer.render_many(cameras, size=size))  # 8 x (H, W, 4) uint8
sheet = np.vstack([np.hstack(frames[:4]), np.hstack(frames[4:])])
Image.fromarray(sheet).save(args.out)
print(f"wrote {args.out}: 8 views, 45 degrees apart")
