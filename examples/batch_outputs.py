"""Render a batch of views with their dataset outputs in one call, and save a contact sheet:
a row per view, its colour, depth (near bright), instance ids (a colour each) and normals in
camera axes.

    python examples/batch_outputs.py [SCENE.gltf] [--views 4] [--size 128x128] [--out sheet.png]
"""

import argparse

import numpy as np
from PIL import Image

from vkpbr import Renderer, load_scene
from vkpbr.scene.camera_batch import CameraBatch

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scene", nargs="?", help="default: the built-in chart")
parser.add_argument("--views", type=int, default=4)
parser.add_argument("--size", default="128x128", help="WIDTHxHEIGHT of each view")
parser.add_argument("--out", default="sheet.png")
args = parser.parse_args()
size = tuple(int(v) for v in args.size.split("x"))

with Renderer(load_scene(args.scene) if args.scene else None) as renderer:
    cameras = CameraBatch.orbit(args.views, bounds=renderer.scene.bounds())
    out = renderer.render_batch(cameras, size, outputs=("color", "depth", "instance",
                                                         "normal_camera"))

depth = out["depth"]
finite = np.isfinite(depth)
near, far = depth[finite].min(), depth[finite].max()
grey = np.where(finite, 255 * (far - depth) / max(far - near, 1e-6), 0).astype(np.uint8)
palette = np.random.default_rng(0).integers(64, 256, (int(out["instance"].max()) + 1, 3))
palette[0] = 0  # the background
ids = palette[out["instance"]].astype(np.uint8)
covered = out["instance"][..., None] > 0
normals = np.where(covered, (out["normal_camera"] + 1) * 127.5, 0).astype(np.uint8)
alpha = np.full(grey.shape, 255, np.uint8)
columns = [out["color"],
           np.stack([grey, grey, grey, alpha], -1),
           np.concatenate([ids, alpha[..., None]], -1),
           np.concatenate([normals, alpha[..., None]], -1)]
sheet = np.concatenate([np.concatenate(list(c), 0) for c in columns], 1)  # views down, outputs across
Image.fromarray(sheet).save(args.out)
print(f"wrote {args.out}: {args.views} views x (colour, depth, instance, normal_camera)")
