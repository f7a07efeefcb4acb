"""The manifest of a scene entry: an append-only JSON-lines file in its output folder, written
only by the driver, that makes a job resumable and exactly once.

`vkpbr-manifest.jsonl`, one JSON object a line:

- first, {"type": "job", "version": 1, ...}: the entry's fingerprint (scene, poses hash, size,
  outputs, options). A re-run with another fingerprint is refused: its files would be stale.
- {"type": "done", "views": [...], "files": [...], "cameras": [...], ...} per finished item:
  the views, the files they wrote (relative to the folder) and the cameras as rendered
  (fields of vkpbr.scene.camera.Camera), from which transforms.json is written at the end.
- {"type": "failed", "views": [...], "error": "...", "attempts": n} per item that failed
  after its retries. A re-run renders it again.

A view is done when a "done" line lists it and its files exist; a re-run renders the rest.
Each line is written with one write, flushed and fsync'ed; a driver killed mid-line leaves a
partial last line, which the next run drops before appending.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import decode_json

__all__ = ["MANIFEST_NAME", "Manifest", "camera_from_record", "camera_record"]

MANIFEST_NAME = "vkpbr-manifest.jsonl"
VERSION = 1


def camera_record(camera: Any) -> dict[str, object]:
    """A Camera as JSON values (floats round-trip exactly through json)."""
    return dataclasses.asdict(camera)


def camera_from_record(record: dict[str, Any]) -> Any:
    from vkpbr.scene.camera import Camera

    return Camera(**{k: tuple(v) if isinstance(v, list) else v for k, v in record.items()})


class Manifest:
    """The manifest of one output folder. `open` reads what an earlier run recorded;
    `done` / `failed` append; `cameras()` gives every done view's camera."""

    def __init__(self, path: Path, header: dict[str, object]) -> None:
        self.path = path
        self.header = header
        self.records: dict[int, dict[str, Any]] = {}  # view -> its latest "done" record
        self.failures: dict[int, str] = {}  # view -> error of its latest "failed" record
        self._file = None
        self._tail = 0  # the length of the file's complete lines when it was read

    @classmethod
    def open(cls, folder: Path, fingerprint: dict[str, object], where: str) -> Manifest:
        """Read the manifest in `folder` (none yet: an empty one). UsageError when it was
        written for another job, or is not a manifest."""
        path = Path(folder) / MANIFEST_NAME
        header = {"type": "job", "version": VERSION, **fingerprint}
        m = cls(path, header)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return m
        except OSError as exc:
            raise UsageError(f"{where}: {path}: cannot read the manifest: {exc.strerror or exc}") from None
        lines = data.split(b"\n")
        complete = lines[:-1]  # the part after the last newline is a line cut short
        for i, line in enumerate(complete):
            try:
                rec = decode_json(line, path)
            except JsonError:
                raise UsageError(f"{where}: {path}: line {i + 1} is not JSON; the manifest is "
                                 "damaged (delete it to render everything again)") from None
            if i == 0:
                m._check_header(rec, where)
            elif isinstance(rec, dict) and rec.get("type") == "done":
                for v in rec["views"]:
                    m.records[v] = rec
                    m.failures.pop(v, None)
            elif isinstance(rec, dict) and rec.get("type") == "failed":
                for v in rec["views"]:
                    m.failures[v] = rec.get("error", "")
        m._tail = len(data) - len(lines[-1])  # where a cut-short last line (if any) begins
        return m

    def _check_header(self, rec: object, where: str) -> None:
        if not isinstance(rec, dict) or rec.get("type") != "job":
            raise UsageError(f"{where}: {self.path}: not a vkpbr manifest")
        for key, value in self.header.items():
            if rec.get(key) != value:
                raise UsageError(f"{where}: {self.path}: written by a job with another {key} "
                                 f"({_short(rec.get(key))}, now {_short(value)}); use another "
                                 "out folder, or delete the manifest to render everything again")

    def done_views(self, files_exist: bool = True) -> set[int]:
        """Views recorded done (and, with `files_exist`, whose files are all there)."""
        if not files_exist:
            return set(self.records)
        folder = self.path.parent
        ok: dict[int, bool] = {}
        out = set()
        for view, rec in self.records.items():
            key = id(rec)
            if key not in ok:
                ok[key] = all((folder / f).is_file() for f in rec["files"])
            if ok[key]:
                out.add(view)
        return out

    def cameras(self, views: int) -> list[Any] | None:
        """The cameras of views 0..views-1 as rendered, or None while one is not done."""
        out = []
        for v in range(views):
            rec = self.records.get(v)
            if rec is None:
                return None
            out.append(camera_from_record(rec["cameras"][rec["views"].index(v)]))
        return out

    def _append(self, record: dict[str, object]) -> None:
        if self._file is None:
            # Drop a line a killed driver cut short (a cut-short header: the whole file).
            self._file = open(self.path, "r+b" if self.path.exists() else "wb")  # noqa: SIM115
            self._file.truncate(self._tail)
            self._file.seek(0, os.SEEK_END)
            if self._tail == 0:
                self._write(self.header)
        self._write(record)

    def _write(self, record: dict[str, object]) -> None:
        assert self._file is not None
        self._file.write(json.dumps(record, allow_nan=False).encode() + b"\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def done(self, views: Sequence[int], files: Sequence[str], cameras: Sequence[dict],
             **info: object) -> None:
        rec = {"type": "done", "views": list(views), "files": list(files),
               "cameras": list(cameras), "time": time.time(), **info}
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


def _short(value: object) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."
