"""The readback copy's threads (gpu/target.py copy_out): a frame's bytes from (mapped)
memory into a fresh NumPy array, split over 1, 2, 4 or 8 threads, for the frame sizes users
read back. Where a fresh array's page faults bound the copy, threads take them in parallel;
below some size they cost more than they save: this prints where, for PARALLEL_BYTES.

    python3 benchmarks/bench_copy_out.py [--repeats 200]

Prints one Markdown table (median ms a copy). Not a test.
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

SIZES = {"640x480 rgba8": (480, 640, 4), "1280x720 rgba8": (720, 1280, 4),
         "1920x1080 rgba8": (1080, 1920, 4), "3840x2160 rgba8": (2160, 3840, 4),
         "1920x1080 rgba32f": (1080, 1920, 16)}


def copy(pool: ThreadPoolExecutor | None, src: np.ndarray, parts: int) -> np.ndarray:
    out = np.empty_like(src)
    if parts == 1:
        np.copyto(out, src)
        return out
    step = -(-len(src) // parts)
    for done in [pool.submit(np.copyto, out[i:i + step], src[i:i + step])  # type: ignore[union-attr]
                 for i in range(0, len(src), step)]:
        done.result()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=200)
    args = ap.parse_args()
    threads = [t for t in (1, 2, 4, 8) if t <= (os.cpu_count() or 1)]
    pool = ThreadPoolExecutor(max(threads))
    print(f"cores: {os.cpu_count()}")
    print("| frame | MiB | " + " | ".join(f"{t} thread{'s' * (t > 1)} ms" for t in threads) + " |")
    print("|---|---:|" + "---:|" * len(threads))
    for name, shape in SIZES.items():
        src = np.random.default_rng(0).integers(0, 256, shape, dtype=np.uint8)
        row = []
        for t in threads:
            for _ in range(5):
                copy(pool, src, t)
            times = []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                copy(pool, src, t)
                times.append(time.perf_counter() - t0)
            row.append(f"{1e3 * float(np.median(times)):.3f}")
        print(f"| {name} | {src.nbytes / 2**20:.1f} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
