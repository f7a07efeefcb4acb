"""Sum cProfile files (a renderer process's each: bench_load.py --profile-workers) and print
the functions that took the most time of their own, per item rendered.

    python benchmarks/profile_summary.py DIR [--items N] [--top 25]
"""

from __future__ import annotations

import argparse
import io
import pstats
from pathlib import Path


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folder", type=Path)
    p.add_argument("--items", type=int, default=1, help="divide by this many items")
    p.add_argument("--top", type=int, default=25)
    p.add_argument("--sort", default="tottime", choices=["tottime", "cumulative"])
    args = p.parse_args()
    files = sorted(args.folder.glob("*.prof"))
    if not files:
        raise SystemExit(f"{args.folder}: no .prof files")
    stats = pstats.Stats(str(files[0]), stream=io.StringIO())
    for f in files[1:]:
        stats.add(str(f))
    total = sum(v[2] for v in stats.stats.values())  # (tottime over all functions)
    print(f"{len(files)} processes, {total:.2f} s of their main threads' own time; "
          f"ms an item ({args.items} items):\n")
    print(f"| {args.sort} ms | calls | function |\n|---:|---:|---|")
    key = 2 if args.sort == "tottime" else 3
    rows = sorted(stats.stats.items(), key=lambda kv: -kv[1][key])[:args.top]
    for (file, line, name), (_cc, calls, tt, ct, _callers) in rows:
        where = f"{Path(file).name}:{line}({name})" if line else name
        value = tt if key == 2 else ct
        print(f"| {1000 * value / args.items:.2f} | {calls / args.items:.1f} | {where} |")


if __name__ == "__main__":
    main()
