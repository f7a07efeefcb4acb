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

__all__ = ["add_parser", "format_report", "run"]


def add_parser(subparsers: Any) -> None:
    """Add ``bake`` to an argparse subparsers object (from ``add_subparsers()``)."""
    p = subparsers.add_parser(
        "bake",
        help="bake a scene into a GPU-ready .vkpbr file",
        description="Clean, deduplicate and cache-optimise every mesh, compute tangent frames "
        "(float, quaternion and packed 32-bit), and write one checksummed .vkpbr file that "
        "loads without parsing.",
    )
    p.add_argument("scene", type=Path, help="source scene (.gltf, .glb, .obj, .comp5822mesh)")
    p.add_argument("--out", "-o", type=Path, required=True, help="output file (.vkpbr)")
    p.add_argument("--report", action="store_true",
                   help="print memory per vertex, frame precision and sizes")
    p.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    p.add_argument("--embed-textures", action="store_true",
                   help="store decoded RGBA8 mip chains in the file (larger, loads faster)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


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
        ("load / bake / write (s)",
         f"{report['load_seconds']:.2f} / {report['seconds']:.2f} / "
         f"{report['write_seconds']:.2f}"),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def run(args: argparse.Namespace) -> int:
    """Bake ``args.scene`` to ``args.out``; returns the exit status (0).

    Raises VkpbrError subclasses (SceneError for a bad source); the CLI reports them.
    """
    from vkpbr.bake.bake import bake_file  # lazily: keeps `vkpbr --help` fast

    start = time.perf_counter()
    report = bake_file(args.scene, args.out, embed_textures=args.embed_textures,
                       progress=not (args.no_progress or args.json))
    seconds = time.perf_counter() - start
    # Peak resident memory of this process (Linux reports ru_maxrss in KiB).
    report["peak_memory_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    n = report["vertices"]
    report["vertex_bytes_saved_packed_vs_vectors"] = n * (
        report["bytes_per_vertex"]["vectors"] - report["bytes_per_vertex"]["packed"])
    if args.json:
        print(json.dumps({**report, "total_seconds": seconds}, indent=2, sort_keys=True))
        return 0
    print(f"wrote {args.out} ({report['file_bytes'] / 2**20:.2f} MiB, "
          f"{report['meshes']} meshes, {report['vertices']:,} vertices, "
          f"{report['triangles']:,} triangles) in {seconds:.2f} s")
    if args.report:
        print(format_report(report))
    return 0
