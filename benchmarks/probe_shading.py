"""Where the compute path's shading time goes (issue 13): Sponza, compute path + compute
rasteriser, GPU ms of the shading and classification steps per debug view (the final image,
the base colour alone, the texture coordinates alone: no texture), per lighting (the
course's, physically based with the sun's cascades and the sky) and with the material
samplers' 16x anisotropic filtering on and off.

    python benchmarks/probe_shading.py --scene Sponza.gltf [--size 1920x1080] [--frames 60]

"anisotropy off" is a probe, not an option: it builds the renderer with
gpu.device.anisotropy_usable answering False (what llvmpipe gets), so every sampler
filters trilinearly. Views are chosen at run time (Settings.view), so all rows run the same
shader; the views skip work, not registers. Prints a Markdown table. Not a test.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_paths import measure  # noqa: E402

import vkpbr.gpu.device as gpu_device  # noqa: E402
from vkpbr.render.renderer import Renderer  # noqa: E402
from vkpbr.scene.loader import load_scene  # noqa: E402

VIEWS = ("final", "base_color", "texcoords")
STEPS = ("classify", "shading", "background")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--frames", type=int, default=60)
    args = ap.parse_args()
    size = tuple(int(x) for x in args.size.split("x"))
    scene = load_scene(args.scene)
    usable = gpu_device.anisotropy_usable
    print(f"| anisotropy | lighting | view | GPU ms | {' | '.join(STEPS)} |")
    print("|" + "---|" * (4 + len(STEPS)))
    for aniso in (True, False):
        gpu_device.anisotropy_usable = usable if aniso else (lambda info, supported: False)
        try:
            with Renderer(scene) as r:
                for lighting in ("course", "pbr"):
                    lights = [r.automatic_sun()] if lighting == "pbr" else None
                    for view in VIEWS:
                        row = measure(r, size, args.frames, lights, lighting=lighting,
                                      pipeline="compute", raster="compute", view=view)
                        steps = " | ".join(f"{row['pass_ms'].get(s, 0.0):.3f}" for s in STEPS)
                        print(f"| {'16x' if aniso and r.device.anisotropy else 'off'} | {lighting} "
                              f"| {view} | {row['gpu_ms']:.3f} | {steps} |", flush=True)
        finally:
            gpu_device.anisotropy_usable = usable


if __name__ == "__main__":
    main()
