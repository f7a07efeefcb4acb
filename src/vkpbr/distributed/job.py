"""The job model of `vkpbr.distributed`: scenes, their poses and outputs, split into work items.
No Ray here: a job is read and checked in full before any actor starts.

A job is a list of scene entries; each renders one scene from many poses into its own `out`
folder, with the file names `vkpbr render SCENE --cameras POSES --out DIR` uses there
(frame_00000.png, frame_00000.depth.exr, ..., transforms.json). An entry's views are split
into work items of `views_per_item` poses: the unit Ray hands to an actor, the manifest
records and a retry repeats.

Job file (JSON), a list of entries or {"scenes": [entries], "views_per_item"?, "retries"?}:

    {"scene": "model.glb",           # null or absent: the built-in PBR chart
     "cameras": "poses.json",        # a poses file (docs/poses.md), or the poses inline
     "out": "frames/model",          # a folder, one per entry
     "size": "256x256",              # or [256, 256]; default: the poses' own (a NeRF file's
                                     # w/h), else 1280x720
     "outputs": ["depth", "normal"], # dataset outputs besides colour (docs/outputs.md)
     "linear": false, "msaa": 1, "colmap": false, "cache": true,
     "semantics": "mesh",            # or "material", "extras", a mapping file or {name: id}
     "batch": 64,                    # views per GPU submission (0: frame by frame; default 64)
     "worlds": {"nodes": ["cube"], "poses": "worlds.npy"},  # per-view world state
                                     # (vkpbr.distributed.worlds)
     "animation": "Walk",            # what the poses' "time"s play (name or index;
                                     # default: every animation of the file)
     "options": {"view": "final"}}   # RenderOptions fields (vkpbr.render.options)

Poses with a "time" (docs/poses.md) are rendered at that time of the file's animations, as
`vkpbr render --cameras` renders them (every view a time, or none); the time is part of the
poses' digest, so a folder resumes only the times it was rendered at.

Relative paths are relative to the job file's folder. The checks are plain Python, as in
vkpbr.scene.poses (no schema library is a dependency): each error is one UsageError line
"JOB.json: entry 2: size: ...".
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vkpbr.config import BATCH_VIEWS
from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import read_json

__all__ = ["Job", "SceneJob", "RenderSettings", "WorkItem", "load_job", "job_from_doc",
           "frame_files", "DEFAULT_VIEWS_PER_ITEM", "DEFAULT_RETRIES"]

DEFAULT_VIEWS_PER_ITEM = 16
DEFAULT_RETRIES = 2  # further attempts of a failed item, each on another actor where one is free
MAX_SIDE = 16384
_ENTRY_KEYS = frozenset({"animation", "scene", "cameras", "out", "size", "outputs", "linear", "msaa",
                         "colmap", "cache", "options", "strict", "allow_outside_paths",
                         "semantics", "batch", "worlds"})
_JOB_KEYS = frozenset({"scenes", "views_per_item", "retries"})


@dataclass(frozen=True)
class RenderSettings:
    """How an entry's views are rendered and written: everything but the poses.

    scene : the scene file (None: the built-in chart). size : (width, height).
    outputs : dataset output names besides colour, in order. options : a RenderOptions.
    cache : load the scene through the bake cache (vkpbr.bake.bake.cached_bake), in
        `cache_dir` (None: $VKPBR_CACHE_DIR, else ~/.cache/vkpbr, on the actor's machine).
    """

    scene: Path | None
    out: Path
    size: tuple[int, int]
    outputs: tuple[str, ...] = ()
    linear: bool = False
    msaa: int = 1
    cache: bool = True
    cache_dir: str | None = None
    options: Any = None  # RenderOptions; None: RenderOptions()
    strict: bool = False
    allow_outside_paths: bool = False
    # Renderer(semantics=...): "mesh", "material", "extras", a mapping file's path or the
    # mapping as sorted (name, id or label) pairs (hashable: it is part of the scene key).
    semantics: str | tuple[tuple[str, int | str], ...] = "mesh"
    # Views per GPU submission (render --cameras --batch): 0 renders frame by frame, each
    # view with its own shadow cascades; any other number gives the same pixels.
    batch: int = BATCH_VIEWS
    # The animation time of views whose pose gives none ("time" in a poses file: per view;
    # `vkpbr render --time`), and the animation(s) the times play (a name, an index, or
    # None: all; `Renderer.render_many(times=, animation=)`).
    time: float | None = None
    animation: str | int | None = None

    def semantic_source(self) -> Any:
        """What Renderer(semantics=...) takes."""
        return dict(self.semantics) if isinstance(self.semantics, tuple) else self.semantics

    @property
    def suffix(self) -> str:
        return ".npy" if self.linear else ".png"

    def render_options(self) -> Any:
        from vkpbr.render.options import RenderOptions

        return self.options if self.options is not None else RenderOptions()

    def scene_key(self) -> tuple:
        """What an actor loads once and keeps: one Renderer per distinct key."""
        return (str(self.scene) if self.scene else None, self.cache, self.strict,
                self.allow_outside_paths, self.msaa, self.semantics)


def frame_files(settings: RenderSettings, frame: int, stem: str | None = None) -> list[str]:
    """The files view `frame` writes into `settings.out`: the colour image first, then each
    dataset output beside it (the names `vkpbr render --cameras` gives). `stem`: the frame's
    name without suffix, relative to the folder (a NeRF frame's file_path); None:
    frame_NNNNN."""
    from vkpbr.io import output_path

    color = f"{stem or f'frame_{frame:05d}'}{settings.suffix}"
    return [color, *(output_path(Path(color), n).as_posix() for n in settings.outputs)]


def _sha256_of_file(path: Path | None) -> str | None:
    """The scene file's hash (its own bytes: a .gltf's JSON, a .glb whole): an edited scene
    is another run's."""
    if path is None:
        return None
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        raise UsageError(f"{path}: cannot read the scene file: {exc.strerror or exc}") from None
    return h.hexdigest()


@dataclass(frozen=True)
class SceneJob:
    """One entry: a scene, its poses and where they go. `poses` are vkpbr.scene.camera.Pose."""

    settings: RenderSettings
    poses: tuple[Any, ...]
    colmap: bool = False
    where: str = "entry 0"  # how messages name the entry ("job.json: entry 2")
    # What else the frames depend on (`vkpbr render --cameras` without --ray: --camera,
    # --light, ... as given), as sorted (name, value) pairs; empty for a job's entries.
    extra: tuple[tuple[str, str], ...] = ()
    worlds: Any = None  # JobWorlds (vkpbr.distributed.worlds): each view's world, or None

    def world_digest(self, view: int) -> str | None:
        """The digest of view `view`'s world (None without worlds): the manifest records it
        with the view, and a view whose world changed is not done."""
        return None if self.worlds is None else self.worlds.digest(view)

    def files(self, view: int) -> list[str]:
        """The files view `view` writes, relative to the out folder (`frame_files`)."""
        from vkpbr.scene.poses import frame_stem

        fp = getattr(self.poses[view], "file_path", None)
        return frame_files(self.settings, view, frame_stem(fp) if fp else None)

    def transforms_name(self, view: int) -> str:
        """The frame's file_path in the transforms.json written: the poses file's own where it
        named the frame without a suffix (NeRF's synthetic scenes), else the file written."""
        from vkpbr.scene.poses import frame_stem

        fp = getattr(self.poses[view], "file_path", None)
        return fp if fp and frame_stem(fp) == fp else self.files(view)[0]

    def fingerprint(self) -> dict[str, object]:
        """What the files depend on; a manifest written for another fingerprint is refused.
        The poses by value (not where they were read from), the scene by path and hash."""
        s = self.settings
        values = [(p.eye, p.target, p.up, p.yfov_deg, p.pixel_intrinsics, p.name,
                   *((p.time,) if getattr(p, "time", None) is not None else ()))
                  for p in self.poses]
        poses = hashlib.sha256(repr(values).encode()).hexdigest()
        names = [self.files(v)[0] for v in range(len(self.poses))]
        named = any(getattr(p, "file_path", None) for p in self.poses)
        return {"scene": str(s.scene.resolve()) if s.scene else None,
                "scene_sha256": _sha256_of_file(s.scene), "views": len(self.poses),
                "poses_sha256": poses, "size": list(s.size), "outputs": list(s.outputs),
                "linear": s.linear, "msaa": s.msaa, "options": repr(s.render_options()),
                **({} if s.semantics == "mesh" else {"semantics": repr(s.semantics)}),
                **({} if s.batch else {"batch": 0}),
                **({"names_sha256": hashlib.sha256("\n".join(names).encode()).hexdigest()}
                   if named else {}),
                **({"extra": dict(self.extra)} if self.extra else {})}


@dataclass(frozen=True)
class WorkItem:
    """What one actor call renders: views `frames` of entry `entry`, from `poses`."""

    entry: int
    frames: tuple[int, ...]
    poses: tuple[Any, ...]
    settings: RenderSettings
    files: tuple[tuple[str, ...], ...] = ()  # per frame, its files (SceneJob.files)
    worlds: Any = None  # ItemWorlds: the worlds its views see (vkpbr.distributed.worlds)
    where: str = ""  # how messages name its entry ("job.json: entry 2")

    def files_of(self, k: int) -> list[str]:
        """The files of the item's k-th frame."""
        return list(self.files[k]) if self.files else frame_files(self.settings, self.frames[k])

    def label(self) -> str:
        scene = self.settings.scene.name if self.settings.scene else "<built-in chart>"
        lo, hi = self.frames[0], self.frames[-1]
        return f"{scene} view{'s' if len(self.frames) > 1 else ''} {lo}" + (f"-{hi}" if hi != lo else "")


@dataclass(frozen=True)
class Job:
    """A checked job: its scene entries and how items are cut and retried."""

    scenes: tuple[SceneJob, ...]
    views_per_item: int = DEFAULT_VIEWS_PER_ITEM
    retries: int = DEFAULT_RETRIES
    source: str = "job"

    @property
    def views(self) -> int:
        return sum(len(s.poses) for s in self.scenes)

    def items(self, skip: Sequence[set[int]] | None = None) -> list[WorkItem]:
        """The work items, entry by entry (so an actor keeps its scene loaded), leaving out
        the views in `skip[entry]` (done in an earlier run)."""
        out = []
        for e, scene in enumerate(self.scenes):
            done = skip[e] if skip is not None else set()
            todo = [i for i in range(len(scene.poses)) if i not in done]
            for k in range(0, len(todo), self.views_per_item):
                frames = tuple(todo[k:k + self.views_per_item])
                worlds = scene.worlds.item(frames) if scene.worlds is not None else None
                out.append(WorkItem(e, frames, tuple(scene.poses[i] for i in frames), scene.settings,
                                    tuple(tuple(scene.files(i)) for i in frames), worlds,
                                    scene.where))
        return out


def _type(value: object) -> str:
    from vkpbr.scene.poses import _json_type

    return _json_type(value)


def _bool(entry: Mapping[str, object], key: str, where: str, default: bool) -> bool:
    value = entry.get(key, default)
    if not isinstance(value, bool):
        raise UsageError(f"{where}: {key}: expected true or false, got {_type(value)}")
    return value


def _path(value: object, key: str, where: str, base: Path) -> Path:
    from vkpbr.user_paths import check_path

    if not isinstance(value, str) or not value.strip():
        raise UsageError(f"{where}: {key}: expected a path, got {_type(value)}")
    check_path(value, f"{where}: {key}")  # a NUL byte, a name over NAME_MAX: one line, now
    p = Path(os.path.expanduser(value))
    return check_path(p if p.is_absolute() else base / p, f"{where}: {key}")


def _size(value: object, where: str) -> tuple[int, int]:
    from vkpbr.scene._checks import size_arg

    if isinstance(value, str):
        parts = value.lower().split("x")
        try:
            value = [int(p) for p in parts]
        except ValueError:
            raise UsageError(f'{where}: size: expected "WIDTHxHEIGHT" or [width, height], '
                             f"got {value!r}") from None
    size = size_arg(value, f"{where}: size")
    if max(size) > MAX_SIDE:
        raise UsageError(f"{where}: size: {size[0]}x{size[1]} is larger than {MAX_SIDE} a side")
    return size


def _outputs(value: object, where: str) -> tuple[str, ...]:
    from vkpbr.io import OUTPUT_KINDS

    if isinstance(value, str):
        value = [v.strip() for v in value.split(",") if v.strip()]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise UsageError(f"{where}: outputs: expected a list of output names, got {_type(value)}")
    for name in value:
        if name not in OUTPUT_KINDS:
            raise UsageError(f"{where}: outputs: unknown output {name!r} (known: "
                             f"{', '.join(OUTPUT_KINDS)})")
    if len(set(value)) != len(value):
        raise UsageError(f"{where}: outputs: {value} names an output twice")
    return tuple(n for n in value if n != "color")


def _options(value: object, where: str) -> Any:
    from vkpbr.render.options import RenderOptions

    if not isinstance(value, dict):
        raise UsageError(f"{where}: options: expected an object of render options, got {_type(value)}")
    known = {f.name for f in dataclasses.fields(RenderOptions)}
    unknown = sorted(set(value) - known)
    if unknown:
        raise UsageError(f"{where}: options: unknown option {unknown[0]!r} (known: "
                         f"{', '.join(sorted(known))})")
    try:
        return RenderOptions(**value)
    except UsageError as exc:
        raise UsageError(f"{where}: options: {exc}") from None


def _poses(value: object, where: str, base: Path) -> tuple[Any, ...]:
    from vkpbr.scene.poses import load_poses, parse_poses

    if isinstance(value, str):
        from vkpbr.scene._checks import context

        with context(f"{where}: cameras"):  # the poses file's own messages, after the entry
            return tuple(load_poses(_path(value, "cameras", where, base)))
    if isinstance(value, (list, dict)):
        return tuple(parse_poses(value, f"{where}: cameras"))
    raise UsageError(f"{where}: cameras: expected a poses file or a list of poses, got "
                     f"{_type(value)}")


def scene_entry(entry: object, where: str, base: Path) -> SceneJob:
    """One checked entry of a job file (see the module docstring)."""
    if not isinstance(entry, dict):
        raise UsageError(f"{where}: expected an object with scene, cameras and out, got {_type(entry)}")
    unknown = sorted(set(entry) - _ENTRY_KEYS)
    if unknown:
        raise UsageError(f"{where}: unknown key {unknown[0]!r} (known: {', '.join(sorted(_ENTRY_KEYS))})")
    for key in ("cameras", "out"):
        if key not in entry:
            raise UsageError(f'{where}: missing "{key}"')
    scene = entry.get("scene")
    scene_path = None if scene is None else _path(scene, "scene", where, base)
    if scene_path is not None and not scene_path.is_file():
        raise UsageError(f"{where}: scene {scene_path}: no such file")
    msaa = entry.get("msaa", 1)
    if msaa not in (1, 4) or isinstance(msaa, bool):
        raise UsageError(f"{where}: msaa: expected 1 or 4, got {msaa!r}")
    poses = _poses(entry["cameras"], where, base)
    from vkpbr.scene.poses import poses_size

    size = _size(entry["size"], where) if "size" in entry else None
    settings = RenderSettings(
        scene=scene_path, out=_path(entry["out"], "out", where, base),
        size=poses_size(list(poses), size, f"{where}: size"),
        outputs=_outputs(entry.get("outputs", []), where),
        linear=_bool(entry, "linear", where, False), msaa=int(msaa),
        cache=_bool(entry, "cache", where, True),
        options=_options(entry["options"], where) if "options" in entry else None,
        strict=_bool(entry, "strict", where, False),
        allow_outside_paths=_bool(entry, "allow_outside_paths", where, False),
        semantics=_semantics(entry.get("semantics", "mesh"), where, base),
        batch=_count(entry, "batch", where, BATCH_VIEWS, 0))
    animation = _animation(entry.get("animation"), where)
    if animation is not None:
        settings = dataclasses.replace(settings, animation=animation)
    view_times(poses, settings, f"{where}: cameras")  # every view a time, or none
    worlds = None
    if entry.get("worlds") is not None:
        from vkpbr.distributed.worlds import job_worlds

        worlds = job_worlds(entry["worlds"], len(poses), f"{where}: worlds", base,
                            settings.allow_outside_paths)
    if worlds is not None and view_times(poses, settings) is not None:
        raise UsageError(f'{where}: cameras with a "time" and worlds together are not rendered '
                         "yet: give the times or the worlds")
    return SceneJob(settings, poses, colmap=_bool(entry, "colmap", where, False), where=where,
                    worlds=worlds,
                    extra=() if animation is None else (("animation", repr(animation)),))


def view_times(poses: Sequence[Any], settings: RenderSettings, where: str = "cameras"
               ) -> list[float] | None:
    """The animation time of each view: its pose's "time", else `settings.time`; None when
    neither gives one. Some views with a time and others without is a one-line error."""
    given = [getattr(p, "time", None) for p in poses]
    if all(t is None for t in given):
        return None if settings.time is None else [settings.time] * len(given)
    if settings.time is None and any(t is None for t in given):
        missing = next(i for i, t in enumerate(given) if t is None)
        raise UsageError(f'{where}: entry {missing} has no "time" while others do (give every '
                         "view a time)")
    return [settings.time if t is None else float(t) for t in given]


def _animation(value: object, where: str) -> str | int | None:
    """An entry's "animation": the name or index of the animation its times play."""
    if value is None or (isinstance(value, str) and value) or (
            isinstance(value, int) and not isinstance(value, bool) and value >= 0):
        return value  # type: ignore[return-value]
    raise UsageError(f"{where}: animation: expected an animation's name or index, got {value!r}")


def _semantics(value: object, where: str, base: Path) -> str | tuple[tuple[str, int | str], ...]:
    """An entry's "semantics": a source name, a mapping file (checked now) or a mapping."""
    from vkpbr.scene.semantics import SEMANTIC_SOURCES, load_semantic_mapping

    with_where = f"{where}: semantics"
    try:
        if isinstance(value, Mapping):
            from vkpbr.scene.semantics import checked_mapping

            return tuple(sorted(checked_mapping(value, "(inline)").items()))
        if isinstance(value, str) and value in SEMANTIC_SOURCES:
            return value
        if isinstance(value, str) and value.lower().endswith(".json"):
            path = _path(value, "semantics", where, base)
            load_semantic_mapping(path)  # readable, a valid mapping: before any actor starts
            return str(path)
    except UsageError as e:
        raise UsageError(f"{with_where}: {str(e).removeprefix('semantic mapping ')}") from None
    raise UsageError(f"{with_where}: expected {', '.join(SEMANTIC_SOURCES)}, a .json mapping "
                     f"file or a {{name: id or label}} object, got {value!r}")


def _count(doc: Mapping[str, object], key: str, where: str, default: int, lo: int) -> int:
    value = doc.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise UsageError(f"{where}: {key}: expected an integer >= {lo}, got {value!r}")
    return value


def job_from_doc(doc: object, source: str = "job", base: str | os.PathLike[str] = ".") -> Job:
    """A checked Job from a decoded job document (a list of entries, or {"scenes": [...]});
    `source` starts every message, `base` resolves relative paths."""
    base = Path(base)
    settings: Mapping[str, object] = {}
    if isinstance(doc, dict):
        unknown = sorted(set(doc) - _JOB_KEYS)
        if unknown:
            raise UsageError(f"{source}: unknown key {unknown[0]!r} (known: {', '.join(sorted(_JOB_KEYS))})")
        if "scenes" not in doc:
            raise UsageError(f'{source}: missing "scenes" (the list of scene entries)')
        settings, doc = doc, doc["scenes"]
    if not isinstance(doc, list):
        raise UsageError(f"{source}: expected a list of scene entries, got {_type(doc)}")
    if not doc:
        raise UsageError(f"{source}: the list of scene entries is empty")
    scenes = tuple(scene_entry(e, f"{source}: entry {i}", base) for i, e in enumerate(doc))
    seen: dict[Path, str] = {}
    for s in scenes:  # two entries in one folder would write the same frame names
        key = Path(os.path.abspath(s.settings.out))
        if key in seen:
            raise UsageError(f"{s.where}: out {s.settings.out}: the same folder as {seen[key]}; "
                             "give each scene its own")
        seen[key] = s.where.removeprefix(f"{source}: ")
    return Job(scenes, views_per_item=_count(settings, "views_per_item", source,
                                             DEFAULT_VIEWS_PER_ITEM, 1),
               retries=_count(settings, "retries", source, DEFAULT_RETRIES, 0), source=source)


def load_job(path: str | os.PathLike[str]) -> Job:
    """Read and check a job file; relative paths in it are relative to its folder."""
    p = Path(path)
    try:
        doc = read_json(p)
    except OSError as exc:
        raise UsageError(f"{p}: cannot read the job file: {exc.strerror or exc}") from None
    except JsonError as exc:
        raise UsageError(f"{p}: not valid JSON ({exc.problem})") from None
    return job_from_doc(doc, str(p), p.parent)
