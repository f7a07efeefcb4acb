"""Poses files: many cameras in one JSON file (`vkpbr render --cameras FILE`). NumPy only.

`load_poses` reads and validates the whole file before any scene loads, so a typo in entry 900
fails at once, not after the scene loaded and 899 frames rendered; `Pose.camera(base)` later
applies each pose to the scene's default camera. Accepted forms (docs/poses.md):

- a JSON list whose entries are "ex,ey,ez,tx,ty,tz[,ux,uy,uz]" strings (as `--camera`) or
  objects {"eye", "target", "up"?, "fov"?}, {"world_from_camera", "convention", "fov"?} or
  {"K", "world_from_camera", "size", "convention"? (default "opencv")}, each with "name"?;
- a NeRF transforms.json object {"camera_angle_x", "frames": [{"transform_matrix"}, ...]}
  (OpenGL axes), with fl_x/fl_y/cx/cy/w/h honoured, per frame or for all, and nerfstudio's
  lenses: "camera_model" OPENCV (k1, k2, p1, p2, k3..k6) or OPENCV_FISHEYE (k1..k4).
  A K entry may also carry "model" and "distortion" (vkpbr.scene.lens).

The checks are plain Python: neither pydantic nor jsonschema is installed, and a schema would
not check what matters here (a 4x4 rotation is orthonormal, a focal length positive) nor word
its errors as "FILE: entry 3: ..." lines. Every error is one UsageError line naming the file,
the entry and the problem; no other exception escapes.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import read_json
from vkpbr.scene._checks import context, real, rigid_pose, shown, size_arg
from vkpbr.scene.camera import Pose, as_pose, opencv_from_corner

__all__ = ["Pose", "load_poses", "parse_poses", "poses_size", "frame_stem", "DEFAULT_SIZE"]

# Intrinsics keys of NeRF-style transforms.json (instant-ngp, nerfstudio), per frame or global.
_NERF_KEYS = ("camera_angle_x", "camera_angle_y", "fl_x", "fl_y", "cx", "cy", "w", "h",
              "camera_model", "k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2")
_DISTORTION = ("k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2")


def _json_type(value: object) -> str:
    names = {dict: "an object", list: "a list", str: "a string", bool: "true/false",
             type(None): "null", int: "a number", float: "a number"}
    return names.get(type(value), type(value).__name__)


def load_poses(path: str | os.PathLike[str]) -> list[Pose]:
    """Read and validate a poses file: a JSON list of poses or a NeRF transforms.json.

    Returns one `Pose` per entry (per frame), in order; `pose.camera(base)` gives the Camera.
    Raises a one-line UsageError naming the file, the entry and the problem.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise UsageError(f"poses file: expected a path, got {type(path).__name__}")
    p = Path(path)
    try:
        doc = read_json(p)
    except OSError as exc:
        raise UsageError(f"{p}: cannot read the poses file: {exc.strerror or exc}") from None
    except JsonError as exc:  # malformed, not text, too big, too deep, a 5000-digit integer
        raise UsageError(f"{p}: not valid JSON ({exc.problem})") from None
    return parse_poses(doc, p)


def parse_poses(doc: object, p: str | os.PathLike[str]) -> list[Pose]:
    """`load_poses` for a document already decoded from JSON (a job file's inline poses);
    `p` is what the messages start with ("job.json: entry 2: cameras")."""
    if isinstance(doc, list):
        if not doc:
            raise UsageError(f"{p}: the list of poses is empty")
        poses = []
        for i, entry in enumerate(doc):
            where = f"{p}: entry {i}"
            if not isinstance(entry, (str, dict)):
                raise UsageError(f'{where}: expected a "ex,ey,ez,tx,ty,tz" string or an object, '
                                 f"got {_json_type(entry)}")
            poses.append(as_pose(entry, where))
        return poses
    if isinstance(doc, dict) and "frames" in doc:
        return _nerf_poses(doc, p)
    got = f"an object with keys {sorted(doc)[:8]}" if isinstance(doc, dict) else _json_type(doc)
    raise UsageError(f'{p}: expected a JSON list of poses or a NeRF transforms.json object with '
                     f'"frames", got {got}')


def _nerf_poses(doc: Mapping[str, object], p: Path) -> list[Pose]:
    frames = doc["frames"]
    if not isinstance(frames, list) or not frames:
        what = "an empty list" if frames == [] else _json_type(frames)
        raise UsageError(f'{p}: "frames" must be a non-empty list of frames, got {what}')
    shared = {k: doc[k] for k in _NERF_KEYS if k in doc}
    try:  # the file's own intrinsics, checked once (frames may override them)
        if not any(k in f for f in frames if isinstance(f, dict) for k in _NERF_KEYS):
            _nerf_camera(shared)
    except UsageError as exc:
        raise UsageError(f"{p}: {exc}") from None
    poses = []
    for i, frame in enumerate(frames):
        where = f"{p}: frame {i}"
        if not isinstance(frame, dict):
            raise UsageError(f"{where}: expected an object, got {_json_type(frame)}")
        if "transform_matrix" not in frame:
            raise UsageError(f'{where}: missing "transform_matrix"')
        with context(where):
            pose = rigid_pose(frame["transform_matrix"], '"transform_matrix"').tolist()
            camera = _nerf_camera({**shared, **{k: frame[k] for k in _NERF_KEYS if k in frame}})
        name = frame.get("file_path")
        entry = {"world_from_camera": pose, "convention": "opengl", **camera,
                 "name": name if isinstance(name, str) else f"frame {i}",
                 **({"time": frame["time"]} if "time" in frame else {})}
        file_path = _file_path(name, where) if "file_path" in frame else None
        poses.append(dataclasses.replace(as_pose(entry, where), file_path=file_path))
    seen: dict[str, int] = {}
    for i, pose in enumerate(poses):
        if pose.file_path is not None:
            key = frame_stem(pose.file_path)
            if key in seen:
                raise UsageError(f'{p}: frame {i}: "file_path" {pose.file_path!r} names the same '
                                 f"frame as frame {seen[key]}")
            seen[key] = i
    return poses


# The image suffixes a frame's file_path may carry: the rendered frame takes its own.
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".exr", ".npy", ".bmp", ".tif", ".tiff", ".webp")


def _file_path(value: object, where: str) -> str:
    """A frame's "file_path", checked: a relative path inside the output folder ("./" and
    absolute prefixes are dropped as NeRF tools write both; ".." is refused)."""
    if not isinstance(value, str) or not value.strip():
        raise UsageError(f'{where}: "file_path": expected a relative file name, got {shown(value)}')
    if "\0" in value or "\\" in value or len(value) > 1024:
        raise UsageError(f'{where}: "file_path": {shown(value)} is not a usable file name')
    parts = [x for x in value.split("/") if x not in ("", ".")]
    if not parts or ".." in parts or any(x.startswith(".") or len(x.encode()) > 200 for x in parts):
        raise UsageError(f'{where}: "file_path" {shown(value)}: give a relative path inside the '
                         "output folder (no .., no hidden names)")
    if value.startswith("/"):  # an absolute path: the file's name, in the output folder
        parts = parts[-1:]
    return "/".join(parts)


def frame_stem(file_path: str) -> str:
    """A checked file_path without its image suffix: the rendered frame's name less its own."""
    lower = file_path.lower()
    for suffix in _IMAGE_SUFFIXES:
        if lower.endswith(suffix) and len(file_path) > len(suffix):
            return file_path[: -len(suffix)]
    return file_path


DEFAULT_SIZE = (1280, 720)


def poses_size(poses: list[Pose], size: tuple[int, int] | None, where: str = "--size"
               ) -> tuple[int, int]:
    """The image size to render `poses` at: the size their calibrations state (a NeRF
    file's w/h, a K pose's size), else `size`, else 1280x720. A `size` of the calibrations'
    aspect ratio rescales them (within half a pixel); another aspect ratio would stretch the
    intrinsics (fx and fy scaled differently) and is a UsageError, as are poses of different
    image sizes."""
    sizes = sorted({(int(p.pixel_intrinsics[4]), int(p.pixel_intrinsics[5]))
                    for p in poses if p.pixel_intrinsics is not None})
    if not sizes:
        return size if size is not None else DEFAULT_SIZE
    if len(sizes) > 1:
        (a, b), (c, d) = sizes[:2]
        raise UsageError(f"{where}: the poses are of images of different sizes ({a}x{b}, "
                         f"{c}x{d}): render each size into its own folder")
    w0, h0 = sizes[0]
    if size is None:
        return (w0, h0)
    w, h = size
    if abs(w * h0 - h * w0) > (w0 + h0) / 2:
        raise UsageError(f"{where} {w}x{h}: the poses' cameras are calibrated for {w0}x{h0} "
                         "images, another aspect ratio (their intrinsics would stretch); give "
                         f"a size of the same aspect ratio, or leave it out to render {w0}x{h0}")
    return (w, h)


def _nerf_camera(keys: Mapping[str, object]) -> dict[str, object]:
    """NeRF intrinsics as the keys of a pose entry: {"K", "size"} with "w" and "h", else
    {"fov"} (then the images are taken to be square, as in NeRF's synthetic scenes)."""
    lens = _nerf_lens(keys)
    angles = {}
    for k in ("camera_angle_x", "camera_angle_y"):
        if k in keys:
            angles[k] = real(keys[k], f'"{k}"')
            if not 0.0 < angles[k] < math.pi:
                raise UsageError(f'"{k}": {angles[k]:g} must be in (0, pi) radians')
    if "w" not in keys and "h" not in keys:
        for k in ("fl_x", "fl_y", "cx", "cy"):
            if k in keys:
                raise UsageError(f'"{k}" needs the image size "w" and "h"')
        if "camera_angle_x" not in angles:
            raise UsageError('missing "camera_angle_x" (or "fl_x" with "w" and "h")')
        if lens:
            raise UsageError(f'a {lens["model"]} lens needs the image size "w" and "h"')
        return {"fov": math.degrees(angles.get("camera_angle_y", angles["camera_angle_x"]))}
    for k in ("w", "h"):
        if k not in keys:
            raise UsageError(f'"w" and "h" go together: missing "{k}"')
    # colmap2nerf writes the size as floats (1920.0): take whole numbers of either type.
    wh = [keys["w"], keys["h"]]
    wh = [int(v) if isinstance(v, float) and v.is_integer() and v > 0 else v for v in wh]
    w, h = size_arg(wh, '"w", "h"')
    if "fl_x" in keys:
        fx = real(keys["fl_x"], '"fl_x"')
    elif "camera_angle_x" in angles:
        fx = 0.5 * w / math.tan(0.5 * angles["camera_angle_x"])
    else:
        raise UsageError('missing "fl_x" or "camera_angle_x"')
    if "fl_y" in keys:
        fy = real(keys["fl_y"], '"fl_y"')
    elif "camera_angle_y" in angles:
        fy = 0.5 * h / math.tan(0.5 * angles["camera_angle_y"])
    else:
        fy = fx
    if not (fx > 0.0 and fy > 0.0):
        raise UsageError(f"the focal lengths ({fx:g}, {fy:g}) must be > 0")
    # NeRF and COLMAP put the centre of the top-left pixel at (0.5, 0.5); OpenCV at (0, 0).
    cx = real(keys["cx"], '"cx"') if "cx" in keys else w / 2.0
    cy = real(keys["cy"], '"cy"') if "cy" in keys else h / 2.0
    K = opencv_from_corner(np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]))
    return {"K": K.tolist(), "size": [w, h], **lens}


def _nerf_lens(keys: Mapping[str, object]) -> dict[str, object]:
    """The lens of NeRF intrinsics as pose-entry keys ({} for a pinhole): "camera_model"
    OPENCV (or FULL_OPENCV) with k1, k2, p1, p2 and optionally k3..k6 (OpenCV's meaning: k4..k6
    the rational denominator), OPENCV_FISHEYE with k1..k4, as nerfstudio writes them."""
    model = keys.get("camera_model", "OPENCV")
    coefficients = {k: real(keys[k], f'"{k}"') for k in _DISTORTION if k in keys}
    if model in ("OPENCV", "FULL_OPENCV"):
        order = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
        values = [coefficients.get(k, 0.0) for k in order]
        if not any(values):
            return {}
        n = 8 if any(values[5:]) else 5 if values[4] else 4
        return {"model": "opencv", "distortion": values[:n]}
    if model == "OPENCV_FISHEYE":
        extra = sorted(k for k in coefficients if k not in ("k1", "k2", "k3", "k4") and coefficients[k])
        if extra:
            raise UsageError(f'"camera_model" OPENCV_FISHEYE takes k1..k4, not {extra[0]}')
        return {"model": "opencv_fisheye",
                "distortion": [coefficients.get(k, 0.0) for k in ("k1", "k2", "k3", "k4")]}
    if model in ("PINHOLE", "SIMPLE_PINHOLE"):
        if any(coefficients.values()):
            raise UsageError(f'"camera_model" {model} has no distortion coefficients')
        return {}
    raise UsageError(f'"camera_model" {shown(model)} is not supported (OPENCV, FULL_OPENCV, '
                     "OPENCV_FISHEYE, PINHOLE)")
