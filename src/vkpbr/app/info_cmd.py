"""`vkpbr info`: the Vulkan devices, which one vkpbr picks, and the features it relies on."""

from __future__ import annotations

import argparse
import json
from typing import Any

from vkpbr.app.parsing import EPILOG_FORMATTER

__all__ = ["add_parser", "run"]

EPILOG = """\
examples:
  vkpbr info                  one block per device; * marks the one vkpbr picks
  vkpbr info --json           the same as JSON (for scripts and bug reports)
  vkpbr render --device 1     render on device [1] of the list instead
"""


def add_parser(sub: Any) -> None:
    p = sub.add_parser(
        "info", help="list Vulkan devices and the features vkpbr uses",
        description="List every Vulkan device the loader reports: name, kind (discrete, "
                    "integrated, CPU), Vulkan version, and the features and limits vkpbr "
                    "uses (dynamic rendering, synchronization2, anisotropy, memory). The "
                    "device marked * is chosen by default; --device NAME|INDEX picks another.",
        epilog=EPILOG, formatter_class=EPILOG_FORMATTER)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(run=run)


def _frame_paths(device: dict) -> str:
    """What auto takes on `device`: its record (path_choice.recorded: checked), or why none."""
    record = device["frame_paths"]
    if record is None:
        return ("forward (CPUs are not measured)" if device["kind"] == "cpu" else
                "not measured yet (the rule until a renderer has drawn 10 s)")
    times = ", ".join(f"{k} {v:.3f} ms" for k, v in record["gpu_ms"].items())
    return f"{record['choice']} ({times} at {record['size'][0]}x{record['size'][1]})"


def run(args: argparse.Namespace) -> int:
    from vkpbr.config import default_cache_dir
    from vkpbr.render.info import device_report
    from vkpbr.render.path_choice import recorded

    report = device_report()
    for d in report["devices"]:  # what --pipeline auto measured here (render/path_choice.py)
        d["frame_paths"] = recorded(default_cache_dir(), d)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    for d in report["devices"]:
        mark = "*" if d["chosen"] else " "
        print(f"{mark} [{d['index']}] {d['name']} ({d['kind']}, Vulkan {d['api_version']})")
        for key, value in d["features"].items():
            print(f"      {key:28s} {value}")
        print(f"      {'autoFramePath':28s} {_frame_paths(d)}")
    print("* = chosen by default (discrete > integrated > CPU); pick another with --device")
    return 0
