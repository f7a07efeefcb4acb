"""Write files atomically: a temporary file in the target's folder, then one rename.

An interrupted or failed write never leaves a truncated file under the final name, and a
reader never sees a half-written one. The result gets the permissions a plain `open(path,
"wb")` would give (0666 less the umask), not mkstemp's private 0600.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

__all__ = ["atomic_writer"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_writer(path: str | Path, fsync: bool = False) -> Iterator[BinaryIO]:
    """`with atomic_writer(path) as f: f.write(...)`: `path` appears only when the block
    succeeds; on an exception the temporary file is removed and `path` is untouched. An
    OSError from writing (or from creating or renaming the temporary file) is re-raised with
    `path` as its filename, so messages name the user's file."""
    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:  # name the user's path, not the temporary one mkstemp tried
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            if fsync:
                os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        if exc.filename is None or exc.filename == tmp:
            # A failed write names the user's path, never the temporary file (which is gone)
            # and never nothing ("File too large" from a write has no filename).
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
        raise
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
