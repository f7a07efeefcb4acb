"""Test helper: what a frames folder promises (vkpbr.distributed.manifest), checked from its
files alone, for tests/gpu/test_frames_folder.py and tests/distributed/test_ray_job.py."""

from __future__ import annotations

import json
from pathlib import Path

from vkpbr.distributed.manifest import MANIFEST_NAME


def check_consistent(folder: Path, strict: bool = True) -> set[int]:
    """The folder's promise: every view its manifest lists as done has its files with the
    recorded sizes (`strict`; else such views do not count as done: the user deleted or
    cut them), and transforms.json is there only when every view is. Returns the done
    views."""
    lines = (folder / MANIFEST_NAME).read_bytes().split(b"\n")
    header = json.loads(lines[0])
    latest: dict[int, list[tuple[str, int]]] = {}  # a view rendered again: its last record
    for line in lines[1:-1]:  # the part after the last newline: a line a kill cut short
        rec = json.loads(line)
        if rec["type"] == "done":
            per = len(rec["files"]) // len(rec["views"])
            for k, view in enumerate(rec["views"]):
                latest[view] = list(zip(rec["files"][k * per:(k + 1) * per],
                                        rec["sizes"][k * per:(k + 1) * per], strict=True))
    done: set[int] = set()
    for view, files in latest.items():
        there = [(folder / f).is_file() and (folder / f).stat().st_size == size for f, size in files]
        assert all(there) or not strict, files
        done |= {view} if all(there) else set()
    if (folder / "transforms.json").exists():
        assert done == set(range(header["views"]))
        frames = json.loads((folder / "transforms.json").read_text())["frames"]
        assert all((folder / f["file_path"]).is_file() for f in frames)
    return done


def done_lines(folder: Path) -> int:
    """Complete "done" lines of the folder's manifest (0 when it has none yet)."""
    try:
        text = (folder / MANIFEST_NAME).read_text()
    except FileNotFoundError:
        return 0
    return sum('"type": "done"' in line for line in text.split("\n")[:-1])
