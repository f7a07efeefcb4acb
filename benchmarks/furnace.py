"""The white furnace (issue 34; docs/fidelity.md): does every material keep its energy?

    python benchmarks/furnace.py [--cell 24] [--image OUT.png] [--before SRC] [--json OUT.json]

White spheres (vkpbr.scene.synthetic.furnace_spheres: metallic 0, 0.25, ..., 1 by row,
roughness 0, 0.1, ..., 1 by column) in a uniform environment of radiance 1 (an EXR), no
punctual light, rendered into linear float32 by the forward and the compute path. Prints,
per path, each sphere's mean radiance over its pixels (1 = energy conserved) and the worst
pixel's |radiance - 1| per metallic row.

`--image` writes the picture of docs/fidelity.md: the spheres over a black background (the
environment lights them but is not drawn), sRGB; with `--before SRC` (a `src` folder of
another commit, e.g. `git archive 800eec9 src | tar -x -C /tmp/before`) the same spheres
rendered by that commit beside them, labelled, and its table printed first. Not a test
(tests/gpu/test_fidelity.py is).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
PIPELINES = ("forward", "compute")


def synthetic():  # noqa: ANN201
    """This checkout's vkpbr.scene.synthetic, also under an older vkpbr (`--before`) that
    lacks the furnace: loaded from its file (NumPy and vkpbr.scene.types only)."""
    path = HERE.parent / "src" / "vkpbr" / "scene" / "synthetic.py"
    spec = importlib.util.spec_from_file_location("furnace_synthetic", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def render(cell: int) -> dict[str, np.ndarray]:
    """{"<path>": (H, W, 3) linear radiance, "<path>_picture": the same without the
    backdrop, "depth": (H, W)} of the furnace with this process's vkpbr."""
    import OpenEXR

    from vkpbr.render.renderer import Renderer

    syn = synthetic()
    scene = syn.furnace_spheres()
    size = syn.furnace_size(cell)
    out: dict[str, np.ndarray] = {}
    with tempfile.TemporaryDirectory() as tmp:
        env = Path(tmp) / "white.exr"
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        with OpenEXR.File(header, {"RGB": np.ones((16, 32, 3), np.float32)}) as f:
            f.write(str(env))
        with Renderer(scene, cache_dir=Path(tmp) / "cache") as r:
            for pipeline in PIPELINES:
                if pipeline == "compute" and not r.device.compute_path:
                    continue
                common = {"lights": [], "size": size, "linear": True, "env": str(env),
                          "pipeline": pipeline}
                image, out["depth"] = r.render(depth=True, **common)
                out[pipeline] = image[..., :3]
                out[f"{pipeline}_picture"] = r.render(env_background=False, **common)[..., :3]
    return out


def table(frames: dict[str, np.ndarray], cell: int, title: str) -> dict:
    syn = synthetic()
    scene = syn.furnace_spheres()
    size = syn.furnace_size(cell)
    cells = syn.furnace_cells(scene.cameras[0], size)
    on = np.isfinite(frames["depth"])
    rows, cols = len(syn.FURNACE_METALLIC), len(syn.FURNACE_ROUGHNESS)
    result = {}
    for pipeline in (p for p in PIPELINES if p in frames):
        v = frames[pipeline]
        mean = np.array([[v[on & (cells == i * cols + j)].mean() for j in range(cols)]
                         for i in range(rows)])
        worst = np.array([np.abs(v[on & (cells // cols == i)] - 1.0).max() for i in range(rows)])
        result[pipeline] = {"mean": mean.tolist(), "worst": worst.tolist()}
        print(f"\n{title}, {pipeline} path: mean radiance per sphere (1 = energy kept)\n")
        print("| metallic \\ roughness | " + " | ".join(f"{r:.1f}" for r in syn.FURNACE_ROUGHNESS)
              + " | worst pixel |")
        print("|---" * (cols + 2) + "|")
        for i, m in enumerate(syn.FURNACE_METALLIC):
            print(f"| {m:.2f} | " + " | ".join(f"{x:.3f}" for x in mean[i])
                  + f" | {worst[i]:.4f} |")
    return result


def picture(panels: list[tuple[str, np.ndarray]], path: Path) -> None:
    """The panels side by side (sRGB, clipped), each with its title, metallic by row and
    roughness by column."""
    from PIL import Image, ImageDraw

    from vkpbr.scene.color import linear_to_srgb

    syn = synthetic()
    h, w = panels[0][1].shape[:2]
    left, top, gap = 44, 34, 16
    canvas = Image.new("RGB", (left + len(panels) * (w + gap), top + h + 22), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    rows, cols = len(syn.FURNACE_METALLIC), len(syn.FURNACE_ROUGHNESS)
    for k, (title, linear) in enumerate(panels):
        x0 = left + k * (w + gap)
        rgb = np.round(linear_to_srgb(np.clip(linear, 0.0, 1.0)) * 255).astype(np.uint8)
        canvas.paste(Image.fromarray(rgb), (x0, top))
        draw.text((x0, 4), title, fill=(0, 0, 0))
        draw.text((x0, 18), "roughness 0 ... 1 ->", fill=(90, 90, 90))
        for j in (0, cols - 1):
            draw.text((x0 + (j + 0.35) * w / cols, top + h + 4),
                      f"{syn.FURNACE_ROUGHNESS[j]:.1f}", fill=(90, 90, 90))
    draw.text((2, top - 14), "metallic", fill=(90, 90, 90))
    for i, m in enumerate(syn.FURNACE_METALLIC):
        draw.text((4, top + (i + 0.4) * h / rows), f"{m:.2f}", fill=(0, 0, 0))
    canvas.save(path)
    print(f"\nwrote {path}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cell", type=int, default=24, help="pixels a side per sphere's cell")
    ap.add_argument("--image", type=Path)
    ap.add_argument("--before", type=Path, help="another commit's src folder, rendered beside")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--dump", type=Path, help=argparse.SUPPRESS)  # the --before subprocess
    args = ap.parse_args()
    if args.dump:
        np.savez(args.dump, **render(args.cell))
        return
    results, panels = {}, []
    if args.before:
        with tempfile.TemporaryDirectory() as tmp:
            dump = Path(tmp) / "before.npz"
            env = {**os.environ, "PYTHONPATH": str(args.before.resolve())}
            subprocess.run([sys.executable, __file__, "--cell", str(args.cell), "--dump",
                            str(dump)], env=env, check=True)
            before = dict(np.load(dump))
        results["before"] = table(before, args.cell, f"before ({args.before})")
        panels.append(("before: one lobe of mixed F0", before["forward_picture"]))
    now = render(args.cell)
    results["now"] = table(now, args.cell, "this checkout")
    panels.append(("now: Appendix B's mix, each lobe compensated", now["forward_picture"]))
    if args.image:
        picture(panels, args.image)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
