"""Where a renderer's device's making goes (render/parts.py open_device: the instance, the
logical device, the pipeline cache's file), under cProfile, with the pipeline cache file a
first run left (the warm start). Not a test.

    python3 benchmarks/profile_device.py [--cache DIR]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import threading
import time

from vkpbr.config import default_cache_dir
from vkpbr.render.parts import open_device


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", default=None, help="the cache folder (default: vkpbr's)")
    args = ap.parse_args()
    cache = args.cache or default_cache_dir()
    prof = cProfile.Profile()
    t = time.perf_counter()
    prof.enable()
    dev = open_device(None, False, False, None, cache)
    prof.disable()
    made = time.perf_counter() - t
    t = time.perf_counter()
    handle = dev.pipeline_cache.handle  # (its opening thread joined)
    print(f"open_device {made:.3f} s; the cache's handle {time.perf_counter() - t:.3f} s later "
          f"({dev.pipeline_cache.loaded_bytes} bytes; {handle is not None}); timings "
          + ", ".join(f"{k} {v:.3f}" for k, v in dev.timings.items())
          + f"; threads {[th.name for th in threading.enumerate()]}")
    pstats.Stats(prof).sort_stats("cumtime").print_stats(30)
    dev.close()


if __name__ == "__main__":
    main()
