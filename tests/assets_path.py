# Where the sample models are: defined once for the tests (conftest's ASSETS and `assets`
# fixture), the benchmarks and scripts/make_goldens.py. Standard library only, so that the peer
# benchmarks, which run without vkpbr installed, can import it too.
"""The sample-models folder: ``$VKPBR_ASSETS`` if set, else ``.assets/models`` in the checkout,
else ``../shared/assets`` next to it. The folder holds the Khronos glTF sample models in their
usual layout (``Sponza/glTF/Sponza.gltf``, ``DamagedHelmet/glTF/DamagedHelmet.gltf``...)."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["ASSETS", "REPO", "assets_dir"]

REPO = Path(__file__).resolve().parents[1]


def assets_dir() -> Path:
    """The sample-models folder (which may not exist: callers skip or fail with its name).

    ``$VKPBR_ASSETS`` wins when set, existing or not, so that a wrong value is reported rather
    than silently replaced; otherwise the first existing of ``REPO/.assets/models`` (a copy
    made for a GPU machine, git-ignored) and ``REPO/../shared/assets``, else the latter.
    """
    env = os.environ.get("VKPBR_ASSETS")
    if env:
        return Path(env).expanduser().resolve()
    candidates = (REPO / ".assets" / "models", REPO.parent / "shared" / "assets")
    return next((c for c in candidates if c.is_dir()), candidates[-1]).resolve()


ASSETS = assets_dir()
