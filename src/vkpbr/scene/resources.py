# The path policy for every file a scene file names (glTF buffers and images, OBJ mtllib and
# map_* files, .comp5822mesh textures, .vkpbr external images), in one place. A scene file from
# the internet must not make vkpbr read /etc/passwd, /proc/self/environ or a FIFO: by default a
# reference resolves only inside the scene's folder tree (the folder of the scene file and its
# subfolders, after resolving symlinks and `..`), and only regular files are ever opened.
# `allow_outside_paths` lifts the folder rule (never the regular-file rule). Readers read at most
# the bytes the file declares (a glTF buffer's byteLength), never a whole file to slice it.
# Details and the reasons: docs/security.md.

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

from vkpbr.errors import SceneError
from vkpbr.scene.types import Image

__all__ = [
    "OUTSIDE_HINT",
    "ResourcePolicy",
    "ResourceRefused",
    "is_regular_file",
    "policy_image",
    "read_error",
    "read_resource",
    "resolve_resource",
]

OUTSIDE_HINT = "pass --allow-outside-paths (allow_outside_paths=True) to read it"


class ResourceRefused(SceneError):
    """A file named by a scene that the path policy will not read.

    `reason` is the short form the texture summary groups by ("outside the scene's folder",
    "not a regular file"); `reference` is the name as the scene file wrote it.
    """

    def __init__(self, scene: object, reference: str, reason: str, problem: str,
                 path: Path | None = None) -> None:
        self.reference = reference
        self.reason = reason
        self.file = path  # the path it would have read
        super().__init__(scene, problem)


def _real(path: Path, folders: dict[str, str] | None = None) -> Path:
    """os.path.realpath of `path`; with `folders` (a cache of one scene's load: folder ->
    its realpath) the folder's resolution is reused and only the last name is looked at (one
    lstat instead of one per component: Sponza's 69 textures named 300 paths a load, each
    a dozen system calls, which a job's loading thread paid for again and again in waits for
    the GIL)."""
    # realpath (not Path.resolve) because it never raises for a missing or overlong name in
    # non-strict mode: the containment decision must not depend on whether the file exists.
    if folders is None:
        return Path(os.path.realpath(path))
    parent, name = os.path.split(os.fspath(path))
    if name in ("", ".", "..") or not parent:
        return Path(os.path.realpath(path))
    folder = folders.get(parent)
    if folder is None:
        folder = folders[parent] = os.path.realpath(parent)
    joined = os.path.join(folder, name)
    try:
        link = stat.S_ISLNK(os.lstat(joined).st_mode)
    except (OSError, ValueError):  # missing or unusable: realpath keeps such a name as it is
        link = False
    return Path(os.path.realpath(joined) if link else joined)


@dataclass(frozen=True)
class ResourcePolicy:
    """Where the files named by one scene file may lie.

    Parameters
    ----------
    scene : the scene file; references resolve relative to its folder, messages name it.
    allow_outside : read references outside `root` too (still only regular files).
    root : the folder tree references must lie in; default the scene file's folder. A bake
        cache file lies in the cache, so its loader passes the source scene's folder here.
    """

    scene: Path
    allow_outside: bool = False
    root: Path | None = None
    # The realpaths of the folders it has resolved in: a policy serves one load
    folders: dict[str, str] = field(default_factory=dict, compare=False, repr=False)

    def resolve(self, reference: str, what: str = "file", base: Path | None = None) -> Path:
        """`reference` (a decoded relative or absolute path, relative to `base`, default the
        scene's folder) -> the Path to read, or ResourceRefused (outside the tree without
        `allow_outside`, not a regular file)."""
        return resolve_resource(self.scene, reference, self.allow_outside, what=what,
                                root=self.root if self.root is not None else self.scene.parent,
                                base=base, folders=self.folders)


def resolve_resource(scene_path: str | os.PathLike[str], reference: str,
                     allow_outside: bool = False, *, what: str = "file",
                     root: str | os.PathLike[str] | None = None,
                     base: str | os.PathLike[str] | None = None,
                     folders: dict[str, str] | None = None) -> Path:
    """Resolve a file a scene names, applying the path policy.

    Parameters
    ----------
    scene_path : the scene file; `reference` is relative to its folder.
    reference : the path as the scene file gives it, already percent-decoded (glTF URIs).
    allow_outside : accept a file outside the folder tree.
    what : what the file is, for messages ("buffer 0", "image", "material library").
    root : the folder tree (default: the scene file's folder).
    base : the folder `reference` is relative to (default: the scene file's folder; an MTL
        file's folder for its maps).
    folders : a cache of folders' realpaths, kept for one scene's load (ResourcePolicy's).

    Returns
    -------
    The path to open: the scene's folder joined with `reference` (not symlink-resolved, so
    messages show the name the user knows). It may not exist: a missing texture is the
    caller's business (the missing-texture fallback), as is a read error.

    Raises
    ------
    ResourceRefused : one line naming the scene file and `reference`: outside the folder tree
        (unless `allow_outside`), not a regular file (a FIFO, a device, a folder), or a name
        no file can have (a NUL byte).
    """
    scene_path = Path(scene_path)
    folder = scene_path.parent
    path = (Path(base) if base is not None else folder) / reference
    if "\0" in reference:
        raise ResourceRefused(scene_path, reference, "not valid file names",
                              f"{what} {reference!r} is not a valid file name (NUL byte)", path)
    if not allow_outside:
        tree = _real(Path(root) if root is not None else folder, folders)
        if not _real(path, folders).is_relative_to(tree):
            # Inside by name but not in fact: a symlink (or a folder symlink) leads out.
            via = (", which resolves" if Path(os.path.normpath(path)).is_relative_to(
                os.path.normpath(Path(root) if root is not None else folder)) else "")
            raise ResourceRefused(
                scene_path, reference, "outside the scene's folder",
                f"{what} refers to {reference}{via} outside the scene's folder; {OUTSIDE_HINT}",
                path)
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return path  # missing, overlong, unreadable: reported where it is read
    if not stat.S_ISREG(mode):
        raise ResourceRefused(scene_path, reference, "not regular files",
                              f"{what} {reference} is not a regular file; vkpbr reads only "
                              "regular files", path)
    return path


def is_regular_file(path: str | os.PathLike[str]) -> bool:
    """Whether `path` is a regular file; False (never an exception) for a missing, overlong
    (ENAMETOOLONG), unreadable or otherwise unusable name."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


def read_resource(path: str | os.PathLike[str], max_bytes: int | None = None,
                  exact: bool = False) -> bytes:
    """Read a regular file, at most `max_bytes` of it.

    Parameters
    ----------
    path : the file (already through `resolve_resource`).
    max_bytes : read no more than this (a glTF buffer's byteLength); None: the whole file.
    exact : the file must hold at least `max_bytes` bytes.

    Returns
    -------
    The bytes read: min(file size, max_bytes).

    Raises
    ------
    OSError : the file cannot be opened or read, is not a regular file (EINVAL; a FIFO is
        opened non-blocking and refused after fstat, so it never blocks), or is shorter than
        `max_bytes` with `exact` (EIO, "file is shorter than declared"). Its `filename` is
        `path`; callers turn it into a SceneError naming the scene file.
    """
    path = os.fspath(path)
    # stat first, so a device is never opened (opening one can have effects); fstat after the
    # non-blocking open closes the race with a file swapped for a FIFO in between.
    if not stat.S_ISREG(os.stat(path).st_mode):
        raise OSError(22, "not a regular file", path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0) \
        | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_BINARY", 0)
    fd = os.open(path, flags)
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise OSError(22, "not a regular file", path)
        size = info.st_size
        want = size if max_bytes is None else min(size, max_bytes)
        if exact and max_bytes is not None and size < max_bytes:
            raise OSError(5, f"file is shorter than declared ({size} bytes, {max_bytes} "
                             "expected)", path)
        chunks, got = [], 0
        while got < want:
            chunk = os.read(fd, min(want - got, 1 << 24))
            if not chunk:
                break
            chunks.append(chunk)
            got += len(chunk)
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if exact and max_bytes is not None and len(data) < max_bytes:
        raise OSError(5, f"file is shorter than declared ({len(data)} bytes, {max_bytes} "
                         "expected)", path)
    return data


def read_error(scene: object, what: str, reference: str, exc: OSError) -> SceneError:
    """The SceneError for an OSError reading `reference`: names the scene file, the resource,
    the OS's reason and what to do."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    return SceneError(scene, f"{what} {reference}: cannot read ({reason}); check that the file "
                             "exists next to the scene and is readable")


def policy_image(policy: ResourcePolicy, reference: str, name: str | None = None,
                 mime_type: str | None = None, base: Path | None = None) -> Image:
    """The Image of a texture file a scene names. One the policy refuses keeps its path and
    the reason (`Image.refused`): never opened, reported and replaced like a missing file."""
    try:
        return Image(name=name or reference, path=policy.resolve(reference, "texture", base),
                     mime_type=mime_type)
    except ResourceRefused as exc:
        return Image(name=name or reference, mime_type=mime_type, refused=exc.reason,
                     path=exc.file)
