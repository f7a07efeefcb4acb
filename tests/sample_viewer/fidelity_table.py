"""Print the vkpbr-against-Sample-Viewer table of docs/fidelity-sample-viewer.md and save each
scenario's picture (viewer | vkpbr | 4 x difference):

    PYTHONPATH=src /work/main/.venv/bin/python tests/sample_viewer/fidelity_table.py \
        [--out DIR] [--bake ci|full] [--size N] [--viewer-roughness-floor F]
        [--viewer-fix sg] [NAME ...]

Needs the sample-viewer extra (sample_viewer_ref.missing() says what is not installed) and the
sample models ($VKPBR_ASSETS, else ../shared/assets).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent)]

from assets_path import assets_dir  # noqa: E402
from sample_viewer_ref import (  # noqa: E402
    SCENARIOS,
    VIEWER_FIXES,
    compare,
    missing,
    render_viewer,
    render_vkpbr,
    write_environment,
)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("out/sample-viewer"))
    parser.add_argument("--bake", choices=("ci", "full"), default="ci")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--viewer-roughness-floor", type=float, default=None,
                        help="clamp the viewer's roughness to at least this (vkpbr: 0.03)")
    parser.add_argument("--viewer-fix", action="append", default=[], choices=sorted(VIEWER_FIXES),
                        help="serve the viewer with a fix of sample_viewer_ref.VIEWER_FIXES")
    parser.add_argument("names", nargs="*")
    args = parser.parse_args()
    if (why := missing()) is not None:
        print(why, file=sys.stderr)
        return 2
    from PIL import Image

    from vkpbr import Renderer

    scenarios = [s for s in SCENARIOS if not args.names or s.name in args.names]
    scenarios = [s for s in scenarios if s.available(assets_dir())]
    assets = assets_dir()
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        env = write_environment(Path(tmp) / "studio.hdr")
        run = render_viewer(scenarios, assets, env, size=args.size, bake=args.bake,
                            roughness_floor=args.viewer_roughness_floor, fixes=args.viewer_fix)
        print(f"Sample Viewer ({args.bake} bake): {run.seconds:.0f} s", file=sys.stderr)
        print("| scenario | dB | covered pixels | vkpbr s |\n| --- | ---: | ---: | ---: |")
        for s in scenarios:
            t0 = time.perf_counter()
            with Renderer(s.load(assets, Path(tmp)), msaa=4) as r:
                rgb, covered = render_vkpbr(r, s, env, size=args.size)
            c = compare(s, run.images[s.name], rgb, covered)
            Image.fromarray(c.picture()).save(args.out / f"{s.name}.png")
            print(f"| {s.name} | {c.db:.1f} | {c.mask.mean():.0%} | "
                  f"{time.perf_counter() - t0:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
