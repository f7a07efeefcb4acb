# `vkpbr bake`: turn a scene file into a GPU-ready .vkpbr baked file.
#
# References: bake/bake.py (bake_file, bake_report), docs/baked-format.md. The CLI (app/cli.py)
# registers this subcommand with add_parser and turns VkpbrErrors into one line on stderr.
"""The ``bake`` subcommand: ``vkpbr bake SCENE --out FILE.vkpbr [--report] [--json]``."""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path
from typing import Any

from vkpbr.app.log import say
from vkpbr.app.options import add_scene_loading_options
from vkpbr.errors import UsageError

__all__ = ["EPILOG", "add_parser", "check_out", "format_report", "run"]

DESCRIPTION = """\
Bake a scene into one GPU-ready .vkpbr file: every mesh cleaned (non-finite
data repaired, exact duplicate vertices merged, degenerate triangles dropped)
and reordered for the vertex cache, tangent frames computed (float vectors, a
quaternion and a packed 32-bit form), and all of it written as checksummed,
aligned sections that load without parsing. Textures are stored inside as their
source files' bytes (PNG, JPEG, KTX2 as they are: the .vkpbr is self-contained and
about as large as its sources); --textures decoded stores decoded mip chains
(larger, loads faster), --textures external keeps references to the files. A
texture that cannot be stored or reached is an error, never a file that renders
untextured. The file format: docs/baked-format.md."""

EPILOG = """\
examples:
  vkpbr bake Sponza/glTF/Sponza.gltf --out sponza.vkpbr
  vkpbr bake model.glb -o model.vkpbr --embed-textures --report
  vkpbr bake scene.obj -o scene.vkpbr --strict --json > bake-report.json"""


def add_parser(subparsers: Any) -> None:
    """Add ``bake`` to an argparse subparsers object (from ``add_subparsers()``)."""
    p = subparsers.add_parser(
        "bake",
        help="bake a scene into a GPU-ready .vkpbr file",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", type=Path,
                   help="source scene (.gltf, .glb, .obj, .comp5822mesh, or a .vkpbr to re-bake)")
    p.add_argument("--out", "-o", type=Path, required=True,
                   help="output file, ending in .vkpbr, in an existing folder")
    p.add_argument("--report", action="store_true",
                   help="print memory per vertex, frame precision and sizes")
    p.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    p.add_argument("--textures", choices=("source", "decoded", "external"), default=None,
                   help="source (default): the texture files' bytes inside, as they are; "
                        "decoded: RGBA8 mip chains inside (larger, loads faster); external: "
                        "references to the files, which must stay where they are")
    p.add_argument("--embed-textures", action="store_true",
                   help="the same as --textures decoded (its earlier name)")
    add_scene_loading_options(p)  # --strict, --allow-outside-paths, --variant: app/options.py
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def check_out(out: Path) -> Path:
    """Check an output path before any work is done: the .vkpbr suffix, not a folder, a
    name a file can have, an existing folder that takes a new file (vkpbr.user_paths).

    Raises
    ------
    UsageError : one line naming the path and the problem.
    """
    out = Path(out)
    if out.suffix.lower() != ".vkpbr":
        raise UsageError(f"--out {out}: the output must be a .vkpbr file "
                         f"(got {out.suffix or 'no extension'!r})")
    from vkpbr.user_paths import check_path, check_writable_file

    if check_path(out, "--out").is_dir():
        raise UsageError(f"--out {out}: is a folder; name the .vkpbr file to write")

    return check_writable_file(out, "--out")  # the folder takes a new file (/proc does not)


def format_report(report: dict[str, Any]) -> str:
    """The report as an aligned two-column table."""
    bpv, err, qerr = report["bytes_per_vertex"], report["tbn_error_deg"], report["quat_error_deg"]
    rows = [
        ("meshes", f"{report['meshes']}"),
        ("vertices (source -> baked)", f"{report['source_vertices']:,} -> {report['vertices']:,}"),
        ("triangles (source -> baked)",
         f"{report['source_triangles']:,} -> {report['triangles']:,}"),
        ("triangle order", report.get("vertex_cache_order", "?")),
        ("bytes/vertex: normal+tangent", f"{bpv['vectors']}"),
        ("bytes/vertex: quaternion", f"{bpv['quat']}"),
        ("bytes/vertex: packed u32", f"{bpv['packed']}"),
        ("packed frame error (deg)",
         f"mean {err['mean']:.3f}  p99 {err['p99']:.3f}  max {err['max']:.3f}"),
        ("quaternion frame error (deg)", f"max {qerr['max']:.5f}"),
        ("file size", f"{report['file_bytes'] / 2**20:.2f} MiB"),
        ("vertex memory saved (packed)",
         f"{report.get('vertex_bytes_saved_packed_vs_vectors', 0) / 2**20:.2f} MiB"),
        ("peak memory", f"{report.get('peak_memory_mib', float('nan')):.0f} MiB"),
        ("load / bake / textures / write (s)",
         f"{report['load_seconds']:.2f} / {report['seconds']:.2f} / "
         f"{report.get('embed_seconds', 0.0):.2f} / {report['write_seconds']:.2f}"),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def run(args: argparse.Namespace) -> int:
    """Bake ``args.scene`` to ``args.out``; returns the exit status (0).

    Raises VkpbrError subclasses (UsageError for a bad --out, found before any work; SceneError
    for a bad source); the CLI reports them.
    """
    check_out(args.out)
    from vkpbr.bake.bake import bake_file  # lazily: keeps `vkpbr --help` fast

    start = time.perf_counter()
    if args.embed_textures and args.textures not in (None, "decoded"):
        raise UsageError(f"--embed-textures is --textures decoded: not with --textures {args.textures}")
    report = bake_file(args.scene, args.out, embed_textures=args.embed_textures,
                       textures=args.textures,
                       progress=not (args.no_progress or args.json),
                       strict=args.strict, allow_outside_paths=args.allow_outside_paths,
                       variant=getattr(args, "variant", None))
    seconds = time.perf_counter() - start
    # Peak resident memory of this process (Linux reports ru_maxrss in KiB).
    report["peak_memory_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    n = report["vertices"]
    report["vertex_bytes_saved_packed_vs_vectors"] = n * (
        report["bytes_per_vertex"]["vectors"] - report["bytes_per_vertex"]["packed"])
    if args.json:
        print(json.dumps({**report, "total_seconds": seconds}, indent=2, sort_keys=True))
        return 0
    textures = ""
    for kind in ("embedded", "external"):
        n = report.get(f"{kind}_textures")
        if n:
            textures += f", {n} texture{'s' if n != 1 else ''} {kind}"
    if report.get("outside_textures"):
        textures += (f" ({report['outside_textures']} outside the .vkpbr's folder: loading it "
                     "needs --allow-outside-paths)")
    elif report.get("external_textures"):
        textures += " (they must stay where they are, relative to the .vkpbr)"
    say(f"wrote {args.out} ({report['file_bytes'] / 2**20:.2f} MiB, "
          f"{report['meshes']} meshes, {report['vertices']:,} vertices, "
          f"{report['triangles']:,} triangles{textures}) in {seconds:.2f} s")
    if args.report:
        print(format_report(report))
    return 0
