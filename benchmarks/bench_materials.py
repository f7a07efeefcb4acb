"""The cost of the material extensions of issue 34 (KHR_materials_anisotropy, _iridescence,
_diffuse_transmission, _dispersion, _pbrSpecularGlossiness): Sponza as it is, then with some
of its materials given one extension each, GPU ms per step on every frame path, the
physically based mode with the automatic sun and the sky.

    python benchmarks/bench_materials.py [--scene Sponza.gltf] [--frames 100]
                                         [--sizes 1920x1080,640x480] [--materials 0,1,2]
                                         [--extensions anisotropy,iridescence,...]

"none" is the scene's own materials: the frame every scene without the extensions pays
(benchmarks/gpu_regress.sh compares it with an earlier tree). A material with a layer
shades with the compute path's layered kernel (shade.glsl SHADE_LAYERS), so each row beside
"none" is that kernel plus the extension's own work. Prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from bench_paths import PATHS, scene_rows, table

from vkpbr.scene.loader import load_scene

# Each extension as Material fields (dispersion needs a volume that transmits).
EXTENSIONS = {
    "anisotropy": {"anisotropy_strength": 0.8, "anisotropy_rotation": 0.5},
    "iridescence": {"iridescence_factor": 1.0, "iridescence_thickness_maximum": 500.0},
    "diffuse-transmission": {"diffuse_transmission_factor": 0.5,
                             "diffuse_transmission_color_factor": (1.0, 0.6, 0.3)},
    "dispersion": {"transmission_factor": 1.0, "thickness_factor": 0.2, "dispersion": 3.0,
                   "metallic_factor": 0.0},
    # The archived extension after conversion: glossiness in the roughness slot, F0 = 0.04 x 25.
    "specular-glossiness": {"glossiness": True, "metallic_factor": 0.0, "metallic_texture": None,
                            "specular_color_factor": (12.5, 12.5, 12.5)},
}


def with_extension(scene, indices: set[int], fields: dict):  # noqa: ANN001, ANN201
    mats = [dataclasses.replace(m, **fields) if i in indices else m
            for i, m in enumerate(scene.materials)]
    return dataclasses.replace(scene, materials=mats)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(Path(__file__).resolve().parents[1]
                                           / ".assets/models/Sponza/glTF/Sponza.gltf"))
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--sizes", default="1920x1080,640x480")
    ap.add_argument("--materials", default="0,1,2", help="indices of the materials changed")
    ap.add_argument("--extensions", default=",".join(EXTENSIONS))
    ap.add_argument("--paths", default="all", help="'all' or 'compute' (compute + compute raster)")
    args = ap.parse_args()
    plain = load_scene(args.scene)
    indices = {int(i) for i in args.materials.split(",")}
    sizes = [tuple(int(x) for x in s.split("x")) for s in args.sizes.split(",")]
    paths = PATHS if args.paths == "all" else [p for p in PATHS if p[0] == "compute"]
    scenes = [("none", plain)] + [(name, with_extension(plain, indices, EXTENSIONS[name]))
                                  for name in args.extensions.split(",")]
    rows = scene_rows(scenes, sizes, args.frames, "extension", paths)
    table(rows, ("extension", "pipeline", "raster"))


if __name__ == "__main__":
    main()
