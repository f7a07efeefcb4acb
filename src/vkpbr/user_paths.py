"""Checks of the paths a user gives (options, job files, API arguments), before any work.

A path the file system cannot take fails the same way whatever the command: one line (a
UsageError) naming the option and the path, before a scene is loaded or a frame rendered,
never an OSError or ValueError traceback after the work is done. What is checked:

- the name itself: a NUL byte, text that is no file name (a lone surrogate from JSON's
  "\\ud800"), a part longer than the file system's NAME_MAX (255 bytes on Linux file
  systems) or a whole path longer than PATH_MAX (4,096 bytes);
- for a path to write (`check_writable_file`, `check_writable_folder`): every existing
  ancestor is a folder (not a file such as /etc/hostname/x.png), and a file can really be
  made where the output goes: a probe file, the same kind of name vkpbr/atomic.py's
  temporary file has, is created and removed. os.access says yes to root on /proc, on a
  read-only mount and on a full disk; the probe does not. (A name that fits NAME_MAX but
  not with the temporary file's 22 more bytes is caught too.)

A write can still fail after the check (the disk fills, a folder is removed): the writers
raise OutputError then (vkpbr.errors), one line naming the file, an OSError too.
"""

from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path

from vkpbr.errors import UsageError, shown_path

__all__ = ["NAME_MAX", "PATH_MAX", "check_path", "check_writable_file", "check_writable_folder",
           "os_reason", "path_problem", "shown"]

NAME_MAX = 255  # bytes of one name on Linux file systems (ext4, xfs, btrfs, tmpfs)
PATH_MAX = 4096  # bytes of a whole path handed to the kernel (Linux PATH_MAX)


shown = shown_path  # how messages show a path (long ones cut in the middle)


_HINTS = {errno.EFBIG: "the file size limit (ulimit -f) is too low", errno.ENOSPC: "the disk is full",
          errno.EDQUOT: "the disk quota is full", errno.EACCES: "check the permissions",
          errno.EPERM: "check the permissions", errno.ENAMETOOLONG: "use a shorter path",
          errno.EROFS: "write elsewhere"}


def os_reason(exc: OSError) -> str:
    """The OS's reason for `exc` with what to do about it, for a message."""
    hint = _HINTS.get(exc.errno)  # type: ignore[arg-type]
    reason = exc.strerror or str(exc) or type(exc).__name__
    return f"{reason} ({hint})" if hint else reason


def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError):
        return NAME_MAX


def path_problem(path: str | os.PathLike[str]) -> str | None:
    """Why `path` cannot name a file on this system (a phrase for a message), or None."""
    text = os.fspath(path)
    if "\0" in text:
        return "holds a NUL byte, which no file name can"
    try:
        raw = os.fsencode(text)
    except UnicodeEncodeError as exc:
        return f"is not a file name (character {exc.object[exc.start:exc.end]!r} cannot be encoded)"
    if len(raw) > PATH_MAX:
        return f"is {len(raw):,} bytes long, more than the {PATH_MAX:,} a path may have"
    for part in raw.split(b"/"):
        if len(part) > NAME_MAX:
            return (f"has a name of {len(part):,} bytes ({os.fsdecode(part)[:24]}...), more "
                    f"than the {NAME_MAX} the file system allows")
    return None


def check_path(path: str | os.PathLike[str], what: str) -> Path:
    """`path` as a Path, or UsageError "WHAT PATH: PROBLEM" (`path_problem`)."""
    problem = path_problem(path)
    if problem is not None:
        raise UsageError(f"{what} {shown(path)}: {problem}")
    return Path(path)


def _existing_ancestor(folder: Path, what: str, path: object) -> Path:
    """The nearest ancestor of `folder` (itself included) that exists; UsageError when it
    is not a folder."""
    probe = folder
    while True:
        try:
            if probe.exists():
                break
        except OSError as exc:  # ELOOP, EACCES on a parent: the OS's reason
            raise UsageError(f"{what} {shown(path)}: {shown(probe)}: {exc.strerror or exc}") from None
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise UsageError(f"{what} {shown(path)}: {shown(probe)} is a file, not a folder")
    return probe


def _probe(folder: Path, name: str, what: str, path: object) -> None:
    """Create and remove a file named like atomic_writer's temporary of `name` in `folder`."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{name}.{os.getpid()}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            room = _name_max(folder) - len(f"..{os.getpid()}.12345678.tmp")
            raise UsageError(f"{what} {shown(path)}: the name is too long to write atomically "
                             f"(at most {room} bytes here)") from None
        raise UsageError(f"{what} {shown(path)}: cannot write in {shown(folder)}: "
                         f"{os_reason(exc)}") from None
    os.close(fd)
    os.unlink(tmp)


def check_writable_file(path: str | os.PathLike[str], what: str = "--out") -> Path:
    """Before any work: `path` can be written as a file (its folder exists, is a folder and
    takes a new file of this name). UsageError naming `what` and the path otherwise."""
    p = check_path(path, what)
    folder = p.parent if str(p.parent) else Path(".")
    if p.is_dir():
        raise UsageError(f"{what} {shown(p)}: is a directory; give a file name such as "
                         f"{shown(p / 'image.png')}")
    ancestor = _existing_ancestor(folder, what, p)
    if ancestor != folder:
        raise UsageError(f"{what} {shown(p)}: folder {shown(folder)} does not exist")
    _probe(folder, p.name, what, p)
    return p


def check_writable_folder(folder: str | os.PathLike[str], what: str = "--out",
                          file_name: str = "frame_00000.png") -> Path:
    """Before any work: `folder` exists as a folder, or can be made (its nearest existing
    ancestor is a folder that takes new entries), and files named like `file_name` fit in
    it. Nothing is created (check first, create last). UsageError otherwise."""
    f = check_path(folder, what)
    problem = path_problem(f / file_name)
    temporary = len(os.fsencode(file_name)) + len(f"..{os.getpid()}.12345678.tmp")
    if problem is None and temporary > NAME_MAX:
        problem = f"has a name too long to write atomically ({temporary} bytes with its temporary)"
    if problem is not None:
        raise UsageError(f"{what} {shown(f)}: its files would be too long: {shown(f / file_name)} "
                         f"{problem}")
    ancestor = _existing_ancestor(f, what, f)
    _probe(ancestor, file_name if ancestor == f else "folder", what, f)
    return f
