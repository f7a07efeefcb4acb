"""Render the built-in chart with its smoothest row of spheres made of glass
(KHR_materials_transmission + _volume: the floor seen through them, refracted and tinted).

    python examples/render_glass.py [--size 640x360] [--out glass.png]
"""

import argparse
import dataclasses

from PIL import Image

from vkpbr import Renderer
from vkpbr.scene.default import default_scene

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--size", default="640x360", help="WIDTHxHEIGHT")
parser.add_argument("--out", default="glass.png")
args = parser.parse_args()
size = tuple(int(v) for v in args.size.split("x"))

scene = default_scene()
tints = [(1.0, 1.0, 1.0), (0.9, 0.95, 1.0), (0.6, 0.85, 1.0), (1.0, 0.75, 0.4), (0.7, 1.0, 0.6)]
glass = 0
for i, m in enumerate(scene.materials):
    if m.name.startswith("sphere-") and m.name.endswith("-r0"):  # the smoothest row
        scene.materials[i] = dataclasses.replace(
            m, base_color_factor=(1.0, 1.0, 1.0, 1.0), metallic_factor=0.0, roughness_factor=0.05 * glass,
            transmission_factor=1.0, ior=1.5, thickness_factor=0.6, attenuation_distance=0.4,
            attenuation_color=tints[glass % len(tints)])
        glass += 1

with Renderer(scene) as renderer:
    rgba = renderer.render(size=size)  # (H, W, 4) uint8, sRGB-encoded
Image.fromarray(rgba).save(args.out)
print(f"wrote {args.out} ({glass} glass spheres, {renderer.last_stats.gpu_ms:.2f} ms on the GPU)")
