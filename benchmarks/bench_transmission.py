"""The cost of screen-space transmission (render/transmission.py): Sponza as it is and with
some of its materials made clear glass, GPU ms per step on every frame path, the physically
based mode with the automatic sun and the sky.

    python benchmarks/bench_transmission.py [--scene Sponza.gltf] [--frames 100]
                                            [--sizes 1920x1080,640x480] [--materials 0,1,2]

The "transmission" step is the copy of the opaque scene (its draws, the environment behind,
the mip chain); the shading steps then also sample it. Prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from bench_paths import scene_rows, table

from vkpbr.scene.loader import load_scene


def with_glass(scene, indices: set[int]):  # noqa: ANN001, ANN201
    """`scene` with materials `indices` clear glass (transmission 1, roughness 0.1, not
    metallic; Sponza's materials have no names)."""
    mats = [dataclasses.replace(m, transmission_factor=1.0, roughness_factor=0.1, metallic_factor=0.0)
            if i in indices else m for i, m in enumerate(scene.materials)]
    return dataclasses.replace(scene, materials=mats)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(Path(__file__).resolve().parents[1]
                                           / ".assets/models/Sponza/glTF/Sponza.gltf"))
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--sizes", default="1920x1080,640x480")
    ap.add_argument("--materials", default="0,1,2", help="indices of the glass materials")
    args = ap.parse_args()
    plain = load_scene(args.scene)
    indices = {int(i) for i in args.materials.split(",")}
    glass = with_glass(plain, indices)
    sizes = [tuple(int(x) for x in s.split("x")) for s in args.sizes.split(",")]
    rows = scene_rows([("none", plain), ("materials " + args.materials, glass)], sizes, args.frames,
                      "transmissive")
    table(rows, ("transmissive", "pipeline", "raster"))


if __name__ == "__main__":
    main()
