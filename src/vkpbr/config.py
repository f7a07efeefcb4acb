"""Settings shared by the library, the CLI and Ray jobs: where vkpbr keeps its caches and how
many views go into one GPU submission. No GPU and nothing of app/ here, so vkpbr.distributed
and the commands read the same values.

    VKPBR_CACHE_DIR   the folder `default_cache_dir` gives: the CLI and Ray's actors keep
                      baked scenes (`--cache`), the split-sum BRDF table and the measured
                      frame paths (frame-paths.json) there. A `Renderer` of your own uses
                      the `cache_dir` it is given (None: nothing on disk).
    XDG_CACHE_HOME    its parent when VKPBR_CACHE_DIR is not set (the XDG base directories)
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["BATCH_VIEWS", "default_cache_dir"]

# Views per GPU submission of `vkpbr render --cameras` (its --batch) and of Ray's actors
# (Renderer.render_many(batch=...): render/batch.py).
BATCH_VIEWS = 64


def default_cache_dir() -> Path:
    """The cache folder: $VKPBR_CACHE_DIR, else $XDG_CACHE_HOME/vkpbr, else ~/.cache/vkpbr.

    Read from the environment at each call (cheap; a test or a job may set it). The folder is
    not created here: whoever writes a file into it does.
    """
    env = os.environ.get("VKPBR_CACHE_DIR")
    if env:
        return Path(env)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "vkpbr"
