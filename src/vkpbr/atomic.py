"""Write files atomically: a temporary file in the target's folder, then one rename.

An interrupted or failed write never leaves a truncated file under the final name, and a
reader never sees a half-written one. The result gets the permissions a plain `open(path,
"wb")` would give (0666 less the umask), not mkstemp's private 0600.

A killed process (SIGKILL, a power cut) cannot remove its temporary file, so the name says
whose it is: `.NAME.PID.XXXXXXXX.tmp`. Each write first removes the leftovers next to its
target: temporary files of the same target whose process is gone, and any (older ones
without a PID too) left unwritten for `STALE_SECONDS`. A live writer's file is kept: it
is written to as it grows, so its modification time stays recent. The CLI turns SIGTERM
into an exception (app/cli.py), so a terminated write cleans up after itself.
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

__all__ = ["atomic_writer", "remove_stale_temporaries", "STALE_SECONDS"]

STALE_SECONDS = 600.0  # a temporary file not written for this long is a leftover
_RANDOM = r"[a-z0-9_]{8}"  # tempfile's random part


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    except OSError:  # pid out of range and the like: nothing of ours
        return False
    return True


def remove_stale_temporaries(path: str | Path, now: float | None = None) -> list[Path]:
    """Remove the temporary files that killed writes of `path` left next to it; returns them.

    A `.NAME.PID.XXXXXXXX.tmp` goes when process PID is gone, or when it was last written
    `STALE_SECONDS` ago (a PID reused since); a `.NAME.XXXXXXXX.tmp` of an older vkpbr
    only by its age. This process's own files stay (another thread may be writing one).
    """
    path = Path(path)
    now = time.time() if now is None else now
    name = re.escape(path.name)
    with_pid = re.compile(rf"\.{name}\.(\d+)\.{_RANDOM}\.tmp")
    without_pid = re.compile(rf"\.{name}\.{_RANDOM}\.tmp")
    removed = []
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return removed
    for entry in entries:
        m = with_pid.fullmatch(entry.name)
        if m is None and without_pid.fullmatch(entry.name) is None:
            continue
        try:
            st = entry.stat(follow_symlinks=False)
        except OSError:
            continue
        if not stat.S_ISREG(st.st_mode):
            continue
        old = now - st.st_mtime > STALE_SECONDS
        if m is not None:
            pid = int(m.group(1))
            stale = pid != os.getpid() and (old or not _pid_alive(pid))
        else:
            stale = old
        if stale:
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


@contextlib.contextmanager
def atomic_writer(path: str | Path, fsync: bool = False) -> Iterator[BinaryIO]:
    """`with atomic_writer(path) as f: f.write(...)`: `path` appears only when the block
    succeeds; on an exception the temporary file is removed and `path` is untouched.
    Leftovers of killed writes of `path` are removed first (`remove_stale_temporaries`).
    A path no file can have (a NUL byte, a name over NAME_MAX) and an OSError from writing
    (or from creating or renaming the temporary file) are OutputError (vkpbr.errors: one
    line naming `path`, never the temporary file; an OSError too, with its errno)."""
    from vkpbr.errors import OutputError
    from vkpbr.user_paths import os_reason, path_problem

    path = Path(path)
    problem = path_problem(path)
    if problem is not None:
        raise OutputError(path, f"the path {problem}")
    remove_stale_temporaries(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp",
                                   dir=path.parent)
    except OSError as exc:  # name the user's path, not the temporary one mkstemp tried
        raise OutputError(path, os_reason(exc), exc.errno) from exc
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
        if isinstance(exc, OutputError) or exc.filename not in (None, tmp):
            raise  # another file's error (a nested writer's, a source's): it names its file
        # A failed write names the user's path, never the temporary file (which is gone)
        # and never nothing ("File too large" from a write has no filename).
        raise OutputError(path, os_reason(exc), exc.errno) from exc
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
