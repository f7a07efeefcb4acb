"""Run a benchmark with render_many's collector threads set (render/frame_path.py
COLLECTORS), for A/B runs of one tree: the count, then a script (or -m module) and its
arguments.

    python benchmarks/with_collectors.py 2 benchmarks/probe_stream.py --scene S --frames 600
    python benchmarks/with_collectors.py 1 -m vkpbr bench --scenario sponza-1080p
"""

from __future__ import annotations

import runpy
import sys

import vkpbr.render.frame_path as frame_path

if __name__ == "__main__":
    frame_path.COLLECTORS = int(sys.argv[1])
    if sys.argv[2] == "-m":
        sys.argv = sys.argv[3:]
        runpy.run_module(sys.argv[0], run_name="__main__", alter_sys=True)
    else:
        sys.argv = sys.argv[2:]
        runpy.run_path(sys.argv[0], run_name="__main__")
