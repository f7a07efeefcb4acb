"""One pool of threads for big memory copies: readbacks into NumPy (gpu/target.py copy_out)
and uploads into staging memory (gpu/image.py TextureUploader). NumPy releases the GIL while
it copies, so a big copy split over threads goes as fast as the memory lets it. The pool is
made on first use and kept: making and joining a pool per upload batch had cost Sponza's scene
change 38 thread starts and joins on the H200's host (benchmarks/results/h200-2026-12-04s17.md,
run g). A forked child (multiprocessing, Ray's workers) has none of its parent's threads and
makes its own."""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

__all__ = ["THREADS", "pool"]

THREADS = max(1, min(8, os.cpu_count() or 1))
_pool: ThreadPoolExecutor | None = None
_making = threading.Lock()


def pool() -> ThreadPoolExecutor:
    """The process's copy threads (THREADS of them)."""
    global _pool
    if _pool is None:
        with _making:  # (a stream's collector thread may ask first, beside the caller's)
            if _pool is None:
                _pool = ThreadPoolExecutor(THREADS, thread_name_prefix="vkpbr-copy")
    return _pool


def _forget() -> None:
    global _pool, _making
    _pool, _making = None, threading.Lock()


os.register_at_fork(after_in_child=_forget)
