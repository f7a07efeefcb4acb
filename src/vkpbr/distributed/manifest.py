"""The manifest of a frames folder: an append-only JSON-lines file that every writer into the
folder keeps (`vkpbr render --cameras`, `vkpbr render --cameras --ray`, `vkpbr batch`), so
that a folder never holds files of two different runs and a run resumes only what is really
there.

`vkpbr-manifest.jsonl`, one JSON object a line:

- first, {"type": "job", "version": 2, ...}: the folder's fingerprint (scene and a hash of
  its file, poses hash, size, outputs, options, frame names). A run with another fingerprint
  is refused in one line: its files would be mixed with stale ones.
- {"type": "done", "views": [...], "files": [...], "sizes": [...], "cameras": [...], ...}
  per finished group of views: the views, the files they wrote (relative to the folder), each
  file's size in bytes and the cameras as rendered (fields of vkpbr.scene.camera.Camera),
  from which transforms.json is written once every view is done; for an entry with
  per-view worlds, "worlds": each view's world digest (vkpbr.distributed.worlds).
- {"type": "failed", "views": [...], "error": "...", "attempts": n} per item that failed
  after its retries. A re-run renders it again.

A view is done when a "done" line lists it and each of its files exists with the recorded
size (a deleted or truncated file is rendered again), and its recorded world digest is the
one its world has now (none without worlds): a view whose world changed is rendered again. transforms.json is removed when a run
starts that has views to render and written when all are done, so it is there exactly when
the folder is complete. A folder that holds frame files or a transforms.json but no manifest
was made by something else (an older vkpbr, another tool): it is refused, not overwritten.

An existing manifest is read with validation, never trusted: every line is checked for its
keys and their types (views in range, file names that are the expected frame files, cameras
with Camera's fields), and anything else is one UsageError line naming the file and line.
Each line is written with one write, flushed and fsync'ed; a run killed mid-line leaves a
partial last line, which the next run drops before appending.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import json
import math
import os
import re
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import decode_json

__all__ = ["MANIFEST_NAME", "Manifest", "camera_from_record", "camera_record", "foreign_files",
           "create_folder", "check_folder_creatable", "open_frames_folder", "start_frames_folder",
           "abandon_frames_folder", "remove_leftovers"]

MANIFEST_NAME = "vkpbr-manifest.jsonl"
VERSION = 2
_DONE_KEYS = frozenset({"type", "views", "files", "sizes", "cameras", "time", "attempts", "pid",
                        "seconds", "worlds"})
_DIGEST = re.compile(r"[0-9a-f]{32}")  # a view's world digest (vkpbr.distributed.worlds)
_FAILED_KEYS = frozenset({"type", "views", "error", "attempts", "time"})
_CAMERA_FIELDS = ("eye", "target", "up", "yfov_deg", "znear", "zfar", "name", "pixel_intrinsics",
                  "model", "distortion")


def camera_record(camera: Any) -> dict[str, object]:
    """A Camera as JSON values (floats round-trip exactly through json)."""
    return dataclasses.asdict(camera)


def camera_from_record(record: dict[str, Any]) -> Any:
    from vkpbr.scene.camera import Camera

    return Camera(**{k: tuple(v) if isinstance(v, list) else v for k, v in record.items()})


class _Bad(Exception):
    """A manifest line that is not what the manifest writer writes."""


def _number(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _numbers(v: object, n: int) -> bool:
    return isinstance(v, list) and len(v) == n and all(_number(x) for x in v)


def _check_camera(rec: object) -> Any:
    if not isinstance(rec, dict):
        raise _Bad("a camera is not an object")
    unknown = sorted(set(rec) - set(_CAMERA_FIELDS))
    if unknown:
        raise _Bad(f"unknown camera key {unknown[0]!r}")
    for key in ("eye", "target", "up"):
        if key in rec and not _numbers(rec[key], 3):
            raise _Bad(f"camera {key}: expected 3 numbers")
    for key in ("yfov_deg", "znear", "zfar"):
        if key in rec and not (_number(rec[key]) or (key != "yfov_deg" and rec[key] is None)):
            raise _Bad(f"camera {key}: expected a number")
    if "name" in rec and not isinstance(rec["name"], str):
        raise _Bad("camera name: expected a string")
    if "model" in rec and not isinstance(rec["model"], str):
        raise _Bad("camera model: expected a string")
    if "distortion" in rec and not (isinstance(rec["distortion"], list)
                                    and len(rec["distortion"]) <= 8
                                    and all(_number(x) for x in rec["distortion"])):
        raise _Bad("camera distortion: expected at most 8 numbers")
    if rec.get("pixel_intrinsics") is not None and not _numbers(rec["pixel_intrinsics"], 6):
        raise _Bad("camera pixel_intrinsics: expected 6 numbers")
    try:
        from vkpbr.scene.camera import validate_camera

        camera = camera_from_record(rec)
        validate_camera(camera)  # a field of view, up vector, intrinsics that render
        return camera
    except (UsageError, ValueError, TypeError) as exc:
        raise _Bad(f"not a valid camera ({str(exc).splitlines()[0] if str(exc) else exc})") from None


def _views(rec: dict[str, Any], count: int) -> list[int]:
    views = rec.get("views")
    if not isinstance(views, list) or not views or not all(
            isinstance(v, int) and not isinstance(v, bool) and 0 <= v < count for v in views):
        raise _Bad(f"views: expected a list of view numbers 0..{count - 1}")
    return views


def _check_done(rec: dict[str, Any], count: int, files_of: Callable[[int], list[str]]) -> None:
    views = _views(rec, count)
    files, sizes, cameras = rec.get("files"), rec.get("sizes"), rec.get("cameras")
    expected = [f for v in views for f in files_of(v)]
    if files != expected:
        raise _Bad("files: not the frame files of its views")
    if not isinstance(sizes, list) or len(sizes) != len(expected) or not all(
            isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in sizes):
        raise _Bad("sizes: expected one byte count per file")
    if not isinstance(cameras, list) or len(cameras) != len(views):
        raise _Bad("cameras: expected one camera per view")
    worlds = rec.get("worlds")
    if worlds is not None and not (isinstance(worlds, list) and len(worlds) == len(views) and all(
            isinstance(d, str) and _DIGEST.fullmatch(d) for d in worlds)):
        raise _Bad("worlds: expected one world digest (32 hex digits) per view")
    for c in cameras:
        _check_camera(c)


def _check_line(rec: object, count: int, files_of: Callable[[int], list[str]]) -> dict[str, Any]:
    if not isinstance(rec, dict):
        raise _Bad("not an object")
    kind = rec.get("type")
    keys = {"done": _DONE_KEYS, "failed": _FAILED_KEYS}.get(kind) if isinstance(kind, str) else None
    if keys is None:
        raise _Bad(f"unknown type {_short(kind)}")
    unknown = sorted(set(rec) - keys)
    if unknown:
        raise _Bad(f"unknown key {_short(unknown[0])}")
    if kind == "done":
        _check_done(rec, count, files_of)
    else:
        _views(rec, count)
        if not isinstance(rec.get("error", ""), str):
            raise _Bad("error: expected a string")
    return rec


def foreign_files(folder: Path) -> list[str]:
    """What in `folder` a frames run writes (frame files, transforms.json, COLMAP text),
    sorted; used to refuse a folder that holds them without a manifest."""
    try:
        names = [e.name for e in os.scandir(folder)]
    except OSError:
        return []
    ours = ("transforms.json", "cameras.txt", "images.txt", "points3D.txt")
    return sorted(n for n in names if n in ours or (n.startswith("frame_") and not n.endswith(".tmp")))


def check_folder_creatable(folder: Path, where: str) -> None:
    """UsageError unless `folder` is a writable folder or can be made (its first missing
    ancestor can be created in a writable folder); nothing is created or left behind."""
    folder = Path(folder)
    if "\0" in str(folder):
        raise UsageError(f"{where} {str(folder)!r}: a path with a NUL byte")
    try:
        os.stat(folder)
    except OSError as exc:  # too long a name, a loop of links, ...: not only "missing"
        if exc.errno not in (errno.ENOENT, errno.ENOTDIR):
            raise UsageError(f"{where} {folder}: {exc.strerror or exc}") from None
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{where} {folder}: not writable (it is a file, not a folder)")
    existing = folder
    while not existing.exists():
        if existing.parent == existing:
            break
        existing = existing.parent
    if not existing.is_dir():
        raise UsageError(f"{where} {folder}: not writable ({existing} is a file, not a folder)")
    probe = existing / f".vkpbr-probe.{os.getpid()}"
    try:  # os.access says yes to root on a read-only mount and to anyone on a full disk
        probe.mkdir()
        probe.rmdir()
    except OSError as exc:
        raise UsageError(f"{where} {folder}: not writable ({exc.strerror or exc})") from None


def create_folder(folder: Path, where: str) -> bool:
    """Make `folder` (and its parents); True when it did not exist before."""
    folder = Path(folder)
    if folder.is_dir():
        return False
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"{where} {folder}: cannot create the folder ({exc.strerror or exc})") from None
    return True


class Manifest:
    """The manifest of one frames folder. `open` reads (and checks) what an earlier run
    recorded; `begin` makes the folder ready to write; `done` / `failed` append;
    `cameras()` gives every done view's camera."""

    def __init__(self, path: Path, header: dict[str, object], views: int,
                 files_of: Callable[[int], list[str]],
                 digest_of: Callable[[int], str | None] | None = None) -> None:
        self.path = path
        self.header = header
        self.views = views
        self.files_of = files_of
        self.digest_of = digest_of  # view -> its world's digest (None: no worlds)
        self.records: dict[int, dict[str, Any]] = {}  # view -> its latest "done" record
        self.failures: dict[int, str] = {}  # view -> error of its latest "failed" record
        self._file: Any = None
        self._tail = 0  # the length of the file's complete lines when it was read
        self.existed = False  # the folder held a manifest when it was opened
        self.created = False  # this run made the folder (start_frames_folder)

    @classmethod
    def open(cls, folder: Path, fingerprint: dict[str, object], where: str,
             views: int | None = None,
             files_of: Callable[[int], list[str]] | None = None,
             digest_of: Callable[[int], str | None] | None = None) -> Manifest:
        """Read the manifest in `folder` (none yet: an empty one). UsageError in one line when
        it was written for another run, is not a manifest or is damaged, or when the folder
        holds frame files without one. `views`: how many (None: the fingerprint's "views");
        `files_of(view)` names a view's files (None: frame_NNNNN.png); `digest_of(view)` its
        world's digest (None: the entry has no worlds)."""
        path = Path(folder) / MANIFEST_NAME
        if views is None:
            count = fingerprint.get("views")
            views = count if isinstance(count, int) else 0
        if files_of is None:
            files_of = _default_files
        header = {"type": "job", "version": VERSION, **fingerprint}
        m = cls(path, header, views, files_of, digest_of)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            data = None
        except OSError as exc:
            raise UsageError(f"{where}: {path}: cannot read the manifest: {exc.strerror or exc}") from None
        if not data:  # none, or empty: a run killed before it wrote the header
            found = foreign_files(Path(folder))
            if found:
                more = f" and {len(found) - 1} more file(s)" if len(found) > 1 else ""
                raise UsageError(f"{where} {folder}: holds {found[0]}{more} of another run but "
                                 "no vkpbr manifest; use another folder or empty this one")
            return m
        m.existed = True
        m._read(data, where)
        return m

    def _read(self, data: bytes, where: str) -> None:
        lines = data.split(b"\n")
        complete = lines[:-1]  # the part after the last newline is a line cut short
        damaged = "the manifest is damaged (delete the folder's files to render everything again)"
        for i, line in enumerate(complete):
            try:
                rec = decode_json(line, self.path)
            except JsonError:
                raise UsageError(f"{where}: {self.path}: line {i + 1} is not JSON; {damaged}") from None
            if i == 0:
                self._check_header(rec, where)
                continue
            try:
                rec = _check_line(rec, self.views, self.files_of)
            except _Bad as exc:
                raise UsageError(f"{where}: {self.path}: line {i + 1}: {exc}; {damaged}") from None
            if rec["type"] == "done":
                for v in rec["views"]:
                    self.records[v] = rec
                    self.failures.pop(v, None)
            else:
                for v in rec["views"]:
                    self.failures[v] = rec.get("error", "")
        self._tail = len(data) - len(lines[-1])  # where a cut-short last line (if any) begins

    def _check_header(self, rec: object, where: str) -> None:
        if not isinstance(rec, dict) or rec.get("type") != "job":
            raise UsageError(f"{where}: {self.path}: not a vkpbr manifest")
        for key, value in self.header.items():
            if rec.get(key) != value:
                raise UsageError(f"{where}: {self.path}: written by a run with another {key} "
                                 f"({_short(rec.get(key))}, now {_short(value)}); use another "
                                 "out folder, or empty this one to render everything again")
        unknown = sorted(set(rec) - set(self.header))
        if unknown:
            raise UsageError(f"{where}: {self.path}: written by a run with another "
                             f"{_short(unknown[0])}; use another out folder")

    def done_views(self, files_exist: bool = True) -> set[int]:
        """Views recorded done with the world they have now (see `digest_of`), and, with
        `files_exist`, whose own files are all there with the recorded sizes: a deleted or
        truncated file makes only its view undone."""
        folder = self.path.parent
        out = set()
        for view, rec in self.records.items():
            i = rec["views"].index(view)
            if _digest(rec, i) != (self.digest_of(view) if self.digest_of else None):
                continue  # rendered in another world
            if not files_exist:
                out.add(view)
                continue
            per = len(rec["files"]) // len(rec["views"])  # every view writes as many files
            k = i * per
            if all(_size(folder / f) == s
                   for f, s in zip(rec["files"][k:k + per], rec["sizes"][k:k + per], strict=True)):
                out.add(view)
        return out

    def cameras(self, views: int | None = None) -> list[Any] | None:
        """The cameras of views 0..views-1 as rendered, or None while one is not done (in
        the world it has now)."""
        out = []
        for v in range(self.views if views is None else views):
            rec = self.records.get(v)
            if rec is None:
                return None
            k = rec["views"].index(v)
            if _digest(rec, k) != (self.digest_of(v) if self.digest_of else None):
                return None
            out.append(camera_from_record(rec["cameras"][k]))
        return out

    def begin(self, complete: Sequence[str] = ("transforms.json",)) -> None:
        """Open the manifest for appending, writing the header first when there is none, and
        remove `complete` (the files written when the folder is complete): a run that renders
        anything leaves them only once it finished. The folder must exist."""
        if self._file is not None:
            return
        # Drop a line a killed run cut short (a cut-short header: the whole file).
        self._file = open(self.path, "r+b" if self.path.exists() else "wb")  # noqa: SIM115
        self._file.truncate(self._tail)
        self._file.seek(0, os.SEEK_END)
        if self._tail == 0:
            self._write(self.header)
        for name in complete:
            (self.path.parent / name).unlink(missing_ok=True)

    def _append(self, record: dict[str, object]) -> None:
        self.begin()
        self._write(record)

    def _write(self, record: dict[str, object]) -> None:
        assert self._file is not None
        self._file.write(json.dumps(record, allow_nan=False).encode() + b"\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def done(self, views: Sequence[int], files: Sequence[str], cameras: Sequence[dict],
             sizes: Sequence[int] | None = None, **info: object) -> None:
        """Record `views` done: their `files` (as `files_of` names them), each file's size
        (None: read from the folder now) and the cameras as rendered."""
        if sizes is None:
            sizes = [_size(self.path.parent / f) for f in files]
        rec = {"type": "done", "views": list(views), "files": list(files),
               "sizes": [int(s) for s in sizes], "cameras": list(cameras), "time": time.time(),
               **info}
        if self.digest_of is not None:  # the worlds the views were rendered in
            rec["worlds"] = [self.digest_of(v) for v in views]
        self._append(rec)
        for v in views:
            self.records[v] = rec
            self.failures.pop(v, None)

    def failed(self, views: Sequence[int], error: str, attempts: int) -> None:
        self._append({"type": "failed", "views": list(views), "error": error,
                      "attempts": attempts, "time": time.time()})
        for v in views:
            self.failures[v] = error

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def _digest(rec: dict[str, Any], k: int) -> str | None:
    """The world digest a "done" record gives its k-th view (None: rendered without worlds)."""
    worlds = rec.get("worlds")
    return None if worlds is None else worlds[k]


def _default_files(view: int) -> list[str]:
    return [f"frame_{view:05d}.png"]


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return -1


def _short(value: object) -> str:
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def open_frames_folder(scene: Any) -> Manifest:
    """Everything about a frames folder that can fail before any work, for one SceneJob
    (vkpbr.distributed.job): the folder is writable or can be made (nothing is created),
    each output format can be written (OpenEXR for .exr), and the folder is this run's or
    new. Returns its manifest (read and checked)."""
    from vkpbr.io import check_output_path, output_kind

    s = scene.settings
    out = Path(s.out)
    where = f"{scene.where}: out" if scene.where != "--out" else "--out"
    check_folder_creatable(out, where)
    existing = out
    while not existing.is_dir():  # check the formats in the folder that exists now
        existing = existing.parent
    names = [Path(f).name for f in scene.files(0)]
    check_output_path(existing / names[0], "color", where)
    for name, file in zip(s.outputs, names[1:], strict=True):
        check_output_path(existing / file, output_kind(name), where.replace("out", "outputs"))
    digest_of = scene.world_digest if getattr(scene, "worlds", None) is not None else None
    return Manifest.open(out, scene.fingerprint(), scene.where, len(scene.poses), scene.files,
                         digest_of)


def start_frames_folder(scene: Any, manifest: Manifest) -> bool:
    """Make the folder (and the subfolders its frame names need) and open the manifest for
    appending (`Manifest.begin`): right before the first file is written. True when the
    folder was made now."""
    s = scene.settings
    out = Path(s.out)
    where = f"{scene.where}: out" if scene.where != "--out" else "--out"
    created = create_folder(out, where)
    subfolders = {str(Path(f).parent) for v in range(len(scene.poses)) for f in scene.files(v)}
    for sub in sorted(subfolders - {"."}):
        create_folder(out / sub, where)
    colmap = ("cameras.txt", "images.txt", "points3D.txt") if getattr(scene, "colmap", False) else ()
    manifest.begin(complete=("transforms.json", *colmap))
    manifest.created = manifest.created or created
    return created


def abandon_frames_folder(scene: Any, manifest: Manifest, created: bool) -> None:
    """After a run that failed before recording anything: remove what it made (its manifest
    header and, when the run made it, the folder if nothing else is in it), so that a failed
    run leaves no empty --out folder behind."""
    manifest.close()
    if manifest.existed or manifest.records or manifest.failures:
        return
    out = Path(scene.settings.out)
    for sub in sorted({str(Path(f).parent) for v in range(len(scene.poses))
                       for f in scene.files(v)} - {"."}, key=len, reverse=True):
        with contextlib.suppress(OSError):
            (out / sub).rmdir()  # only when empty
    try:
        left = os.listdir(out)
    except OSError:
        return
    if left == [MANIFEST_NAME]:  # nothing but this run's header: the folder is as before
        manifest.path.unlink(missing_ok=True)
        if created:
            with contextlib.suppress(OSError):
                out.rmdir()


def remove_leftovers(scene: Any) -> None:
    """Remove the temporary files of writes that a killed run left beside the frame files
    (atomic.py names them .NAME.PID.RANDOM.tmp). Called when a run ends: nothing of it
    writes there any more."""
    pattern = re.compile(r"\.(.+)\.\d+\.[a-z0-9_]{8}\.tmp")
    folder = Path(scene.settings.out)
    by_dir: dict[Path, set[str]] = {}
    for view in range(len(scene.poses)):
        for name in scene.files(view):
            by_dir.setdefault((folder / name).parent, set()).add(Path(name).name)
    for d, names in by_dir.items():
        try:
            entries = list(os.scandir(d))
        except OSError:
            continue
        for entry in entries:
            m = pattern.fullmatch(entry.name)
            if m and m.group(1) in names:
                Path(entry.path).unlink(missing_ok=True)
