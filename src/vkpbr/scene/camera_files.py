"""Camera files for dataset tools: NeRF / instant-ngp `transforms.json` and COLMAP's text
model (cameras.txt, images.txt, points3D.txt). NumPy only (no Vulkan).

Conventions (docs/camera-files.md has the diagram):

- vkpbr's Camera API (vkpbr.scene.camera) owns the axes: `world_from_camera("opengl")` is
  NeRF's `transform_matrix` (x right, y up, z backward, camera-to-world) and
  `world_from_camera("opencv")` inverted is COLMAP's pose (x right, y down, z forward,
  world-to-camera). Nothing here flips an axis itself.
- Pixels: vkpbr's K follows OpenCV (the centre of the top-left pixel is (0, 0)); NeRF and
  COLMAP put that centre at (0.5, 0.5), so their cx, cy are larger by 0.5. The shift is
  made in `vkpbr.scene.camera.corner_from_opencv` and undone in `opencv_from_corner`.
- COLMAP's quaternion is Hamilton (qw, qx, qy, qz) of the world-to-camera rotation, qw >= 0.

References: instant-ngp docs/nerf_dataset_tips.md; nerfstudio's data conventions; COLMAP's
"Output format" page and scripts/python/read_write_model.py.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from vkpbr.atomic import atomic_writer
from vkpbr.errors import UsageError
from vkpbr.scene._checks import context, size_arg
from vkpbr.scene.camera import Camera, corner_from_opencv, from_opencv, opencv_from_corner
from vkpbr.scene.lens import COEFFICIENTS, distortion_vector
from vkpbr.scene.poses import load_poses

__all__ = [
    "colmap_text",
    "quaternion_from_rotation",
    "read_colmap",
    "read_transforms",
    "rotation_from_quaternion",
    "transforms_dict",
    "write_colmap",
    "write_transforms",
]

# -- quaternions (COLMAP) ----------------------------------------------------------------------


def quaternion_from_rotation(R: np.ndarray) -> np.ndarray:
    """The unit Hamilton quaternion (w, x, y, z), w >= 0, of a (3, 3) rotation matrix.

    Shepperd's method: divide by the largest of the four candidate magnitudes, so no branch
    loses precision (S. W. Shepperd, "Quaternion from rotation matrix", J. Guidance 1978).
    """
    r = np.asarray(R, dtype=np.float64)
    t = np.trace(r)
    candidates = (t, r[0, 0], r[1, 1], r[2, 2])
    i = int(np.argmax(candidates))
    if i == 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    elif i == 1:
        s = 2.0 * math.sqrt(max(1.0 + r[0, 0] - r[1, 1] - r[2, 2], 0.0))
        q = ((r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s)
    elif i == 2:
        s = 2.0 * math.sqrt(max(1.0 + r[1, 1] - r[0, 0] - r[2, 2], 0.0))
        q = ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s)
    else:
        s = 2.0 * math.sqrt(max(1.0 + r[2, 2] - r[0, 0] - r[1, 1], 0.0))
        q = ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s)
    qa = np.array(q, dtype=np.float64)
    qa /= np.linalg.norm(qa)
    return -qa if qa[0] < 0.0 else qa


def rotation_from_quaternion(q: Sequence[float]) -> np.ndarray:
    """The (3, 3) float64 rotation of a Hamilton quaternion (w, x, y, z), normalised first."""
    w, x, y, z = np.asarray(q, dtype=np.float64) / np.linalg.norm(np.asarray(q, dtype=np.float64))
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


# -- NeRF / instant-ngp transforms.json --------------------------------------------------------


def _names(names: Sequence[str] | None, n: int, what: str, default: str) -> list[str]:
    if names is None:
        return [default.format(i) for i in range(n)]
    names = list(names)
    if len(names) != n:
        raise UsageError(f"{what}: {len(names)} names for {n} cameras")
    for name in names:
        if not isinstance(name, str) or not name or "\n" in name:
            raise UsageError(f"{what}: every name must be a non-empty one-line string, "
                             f"got {name!r}")
    return names


def _cameras(cameras: Sequence[Camera], what: str) -> list[Camera]:
    cams = list(cameras)
    if not cams:
        raise UsageError(f"{what}: no cameras")
    for c in cams:
        if not isinstance(c, Camera):
            raise UsageError(f"{what}: expected Cameras, got {type(c).__name__}")
    return cams


def _nerf_intrinsics(K: np.ndarray, w: int, h: int, cam: Camera) -> dict[str, object]:
    k = corner_from_opencv(K)
    fl_x, fl_y = float(k[0, 0]), float(k[1, 1])
    return {"camera_angle_x": 2.0 * math.atan(w / (2.0 * fl_x)),
            "camera_angle_y": 2.0 * math.atan(h / (2.0 * fl_y)),
            "fl_x": fl_x, "fl_y": fl_y, "cx": float(k[0, 2]), "cy": float(k[1, 2]),
            "w": w, "h": h, **_nerf_lens(cam)}


def _nerf_lens(cam: Camera) -> dict[str, object]:
    """nerfstudio's lens keys: "camera_model" OPENCV with k1, k2, p1, p2 (k3..k6 where
    given) or OPENCV_FISHEYE with k1..k4 (an equidistant lens: all 0); none for a pinhole."""
    if cam.model == "pinhole":
        return {}
    if cam.model == "opencv":
        names = COEFFICIENTS["opencv"][: len(cam.distortion)]
        return {"camera_model": "OPENCV", **dict(zip(names, cam.distortion, strict=True))}
    values = distortion_vector(cam.model, cam.distortion) if cam.model == "opencv_fisheye" else (0.0,) * 4
    return {"camera_model": "OPENCV_FISHEYE",
            **{k: float(v) for k, v in zip(("k1", "k2", "k3", "k4"), values, strict=True)}}


def transforms_dict(cameras: Sequence[Camera], size: tuple[int, int],
                    file_paths: Sequence[str] | None = None,
                    times: Sequence[float] | None = None) -> dict[str, object]:
    """The NeRF / instant-ngp transforms.json of `cameras` rendered at `size` (W, H).

    The intrinsics (camera_angle_x, camera_angle_y in radians; fl_x, fl_y, cx, cy in pixels
    with the top-left pixel's centre at (0.5, 0.5); w, h) are written once at the top when
    every camera has the same K at `size`, else in each frame (instant-ngp and nerfstudio
    read both). Each frame has `file_path` (default "frame_00000.png", ..., the names
    `vkpbr render --cameras` writes; relative to the JSON file's folder) and
    `transform_matrix`, the (4, 4) world-from-camera pose in OpenGL axes; with `times`,
    each frame's animation "time" in seconds (what `--cameras` reads back). A lens is written
    as nerfstudio writes it: "camera_model" OPENCV with k1, k2, p1, p2 (and k3..k6 where the
    camera has them), OPENCV_FISHEYE with k1..k4 (an equidistant lens as OPENCV_FISHEYE with
    zeros).
    """
    w, h = size_arg(size, "transforms.json: size")
    cams = _cameras(cameras, "transforms.json")
    paths = _names(file_paths, len(cams), "transforms.json: file_paths", "frame_{:05d}.png")
    intrinsics = [_nerf_intrinsics(c.intrinsics((w, h)), w, h, c) for c in cams]
    shared = all(k == intrinsics[0] for k in intrinsics)
    doc: dict[str, object] = dict(intrinsics[0]) if shared else {}
    frames = []
    for cam, k, path in zip(cams, intrinsics, paths, strict=True):
        frame: dict[str, object] = {"file_path": path}
        if not shared:
            frame.update(k)
        frame["transform_matrix"] = cam.world_from_camera("opengl").tolist()
        if times is not None:
            frame["time"] = float(times[len(frames)])
        frames.append(frame)
    doc["frames"] = frames
    return doc


def write_transforms(path: str | os.PathLike[str], cameras: Sequence[Camera],
                     size: tuple[int, int], file_paths: Sequence[str] | None = None, *,
                     extra: Mapping[str, object] | None = None,
                     times: Sequence[float] | None = None) -> dict[str, object]:
    """Write `transforms_dict(cameras, size, file_paths)` to `path` atomically; returns it.

    extra : more top-level keys ("aabb_scale", "scale", ...), written as given; they may not
        replace the ones vkpbr writes.
    """
    doc = transforms_dict(cameras, size, file_paths, times)
    if extra:
        clash = sorted(set(extra) & set(doc))
        if clash:
            raise UsageError(f"{path}: extra keys {clash} would replace vkpbr's")
        doc = {**doc, **extra}
    text = json.dumps(doc, indent=2, allow_nan=False)  # floats as repr: exact round trips
    Path(path).parent.mkdir(parents=True, exist_ok=True)  # as write_colmap makes its folder
    with atomic_writer(path) as f:
        f.write(text.encode() + b"\n")
    return doc


def read_transforms(path: str | os.PathLike[str]) -> list[Camera]:
    """The cameras of a NeRF transforms.json, one per frame, named by `file_path`.

    Through `vkpbr.scene.poses.load_poses` (the reader `vkpbr render --cameras` uses), so the
    file is checked the same way (one UsageError line naming the file and the frame). A file
    with `w` and `h` gives calibrated cameras (`pixel_intrinsics` set).
    """
    return [pose.camera(Camera()) for pose in load_poses(path)]


# -- COLMAP text model -------------------------------------------------------------------------


def _colmap_params(K: np.ndarray, cam: Camera) -> tuple[str, tuple[float, ...]]:
    """COLMAP's camera model and PARAMS of `cam` with `K`: PINHOLE, OPENCV (k1 k2 p1 p2),
    FULL_OPENCV (k1 k2 p1 p2 k3 k4 k5 k6) or OPENCV_FISHEYE (k1 k2 k3 k4)."""
    k = corner_from_opencv(K)
    base = (float(k[0, 0]), float(k[1, 1]), float(k[0, 2]), float(k[1, 2]))
    if cam.model == "pinhole":
        return "PINHOLE", base
    if cam.model == "opencv":
        full = distortion_vector("opencv", cam.distortion)
        if len(cam.distortion) == 4:
            return "OPENCV", (*base, *map(float, full[:4]))
        return "FULL_OPENCV", (*base, *map(float, full))
    return "OPENCV_FISHEYE", (*base, *map(float, distortion_vector("opencv_fisheye", cam.distortion
                                                                     if cam.model == "opencv_fisheye" else ())))


def colmap_text(cameras: Sequence[Camera], size: tuple[int, int],
                image_names: Sequence[str] | None = None) -> dict[str, str]:
    """COLMAP's text model of `cameras` rendered at `size`: {"cameras.txt": ...,
    "images.txt": ..., "points3D.txt": ...}.

    cameras.txt has one camera per distinct K and lens: PINHOLE (fx fy cx cy, top-left pixel
    centre at (0.5, 0.5)), OPENCV (... k1 k2 p1 p2), FULL_OPENCV (... k1 k2 p1 p2 k3 k4 k5 k6)
    or OPENCV_FISHEYE (... k1 k2 k3 k4; an equidistant lens with zeros); images.txt one image per camera, "IMAGE_ID QW QX QY QZ TX TY TZ
    CAMERA_ID NAME" with the world-to-camera pose in OpenCV axes, then an empty 2D-points
    line; points3D.txt no points.
    """
    w, h = size_arg(size, "COLMAP: size")
    cams = _cameras(cameras, "COLMAP")
    names = _names(image_names, len(cams), "COLMAP: image_names", "frame_{:05d}.png")
    for name in names:
        if name != name.strip() or " " in name:
            raise UsageError(f"COLMAP: image name {name!r} has spaces (images.txt splits on them)")
    camera_ids: dict[tuple[str, tuple[float, ...]], int] = {}
    image_lines = []
    for i, (cam, name) in enumerate(zip(cams, names, strict=True), start=1):
        params = _colmap_params(cam.intrinsics((w, h)), cam)
        cid = camera_ids.setdefault(params, len(camera_ids) + 1)
        camera_from_world = np.linalg.inv(cam.world_from_camera("opencv"))
        q = quaternion_from_rotation(camera_from_world[:3, :3])
        t = camera_from_world[:3, 3]
        numbers = " ".join(repr(float(v)) for v in (*q, *t))
        image_lines += [f"{i} {numbers} {cid} {name}", ""]
    camera_lines = [f"{cid} {model} {w} {h} " + " ".join(repr(p) for p in params)
                    for (model, params), cid in camera_ids.items()]
    return {
        "cameras.txt": "\n".join([
            "# Camera list with one line of data per camera:",
            "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]",
            f"# Number of cameras: {len(camera_ids)}", *camera_lines]) + "\n",
        "images.txt": "\n".join([
            "# Image list with two lines of data per image:",
            "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
            "#   POINTS2D[] as (X, Y, POINT3D_ID)",
            f"# Number of images: {len(cams)}, mean observations per image: 0",
            *image_lines]) + "\n",
        "points3D.txt": "\n".join([
            "# 3D point list with one line of data per point:",
            "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)",
            "# Number of points: 0, mean track length: 0"]) + "\n",
    }


def write_colmap(folder: str | os.PathLike[str], cameras: Sequence[Camera],
                 size: tuple[int, int], image_names: Sequence[str] | None = None) -> list[Path]:
    """Write `colmap_text(...)` into `folder` (made if missing), each file atomically.

    Everything is checked and formatted before the first file is written. Returns the paths.
    """
    from vkpbr.errors import OutputError
    from vkpbr.user_paths import check_writable_folder, os_reason

    texts = colmap_text(cameras, size, image_names)
    out = check_writable_folder(folder, "write_colmap: folder", "cameras.txt")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # made between the check and here, or the disk filled
        raise OutputError(out, os_reason(exc), exc.errno) from exc
    paths = []
    for name, text in texts.items():
        with atomic_writer(out / name) as f:
            f.write(text.encode())
        paths.append(out / name)
    return paths


def _data_lines(path: Path) -> list[tuple[int, str]]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise UsageError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise UsageError(f"{path}: not a COLMAP text file (not UTF-8)") from None
    return [(n, line.strip()) for n, line in enumerate(text.splitlines(), start=1)
            if not line.startswith("#")]


def _floats(fields: list[str], where: str) -> list[float]:
    try:
        values = [float(v) for v in fields]
    except ValueError:
        raise UsageError(f"{where}: expected numbers, got {' '.join(fields)!r}") from None
    if not all(map(math.isfinite, values)):
        raise UsageError(f"{where}: the numbers must be finite")
    return values


# COLMAP camera model -> (number of PARAMS, vkpbr model, indices of fx fy cx cy (fy = fx for
# one focal), the distortion's positions in OpenCV's order).
_COLMAP_MODELS: dict[str, tuple[int, str, tuple[int, int, int, int], tuple[int, ...]]] = {
    "SIMPLE_PINHOLE": (3, "pinhole", (0, 0, 1, 2), ()),
    "PINHOLE": (4, "pinhole", (0, 1, 2, 3), ()),
    "SIMPLE_RADIAL": (4, "opencv", (0, 0, 1, 2), (3, -1, -1, -1)),
    "RADIAL": (5, "opencv", (0, 0, 1, 2), (3, 4, -1, -1)),
    "OPENCV": (8, "opencv", (0, 1, 2, 3), (4, 5, 6, 7)),
    "FULL_OPENCV": (12, "opencv", (0, 1, 2, 3), tuple(range(4, 12))),
    "OPENCV_FISHEYE": (8, "opencv_fisheye", (0, 1, 2, 3), (4, 5, 6, 7)),
}


def _read_colmap_cameras(path: Path) -> dict[int, tuple[np.ndarray, tuple[int, int], str, tuple[float, ...]]]:
    cams = {}
    for n, line in _data_lines(path):
        if not line:
            continue
        where = f"{path}: line {n}"
        parts = line.split()
        if len(parts) < 4:
            raise UsageError(f"{where}: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS...")
        cid, model, w, h, params = parts[0], parts[1], parts[2], parts[3], parts[4:]
        try:
            cid_i, size = int(cid), size_arg((int(w), int(h)), "size")
        except (ValueError, UsageError):
            raise UsageError(f"{where}: bad camera id or size {' '.join(parts[:4])!r}") from None
        p = _floats(params, where)
        if model not in _COLMAP_MODELS or len(p) != _COLMAP_MODELS[model][0]:
            raise UsageError(f"{where}: camera model {model} with {len(p)} parameters is not "
                             f"supported ({', '.join(_COLMAP_MODELS)} with their parameters)")
        _, lens, (ifx, ify, icx, icy), positions = _COLMAP_MODELS[model]
        K = np.array([[p[ifx], 0.0, p[icx]], [0.0, p[ify], p[icy]], [0.0, 0.0, 1.0]])
        distortion = tuple(p[i] if i >= 0 else 0.0 for i in positions)
        cams[cid_i] = (opencv_from_corner(K), size, lens, distortion)
    return cams


def read_colmap(folder: str | os.PathLike[str]) -> list[Camera]:
    """The cameras of a COLMAP text model (cameras.txt and images.txt in `folder`), in the
    order of images.txt, each named by its image NAME and calibrated (`pixel_intrinsics`).

    Raises a one-line UsageError naming the file and line for anything malformed.
    """
    folder = Path(folder)
    intrinsics = _read_colmap_cameras(folder / "cameras.txt")
    path = folder / "images.txt"
    lines = _data_lines(path)
    cameras = []
    i = 0
    while i < len(lines):
        n, line = lines[i]
        i += 1
        if not line:
            continue
        i += 1  # the 2D points line that follows every image line (often empty)
        where = f"{path}: line {n}"
        parts = line.split(maxsplit=9)
        if len(parts) != 10:
            raise UsageError(f"{where}: expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME")
        values = _floats(parts[1:8], where)
        q, t = np.array(values[:4]), np.array(values[4:])
        if not np.linalg.norm(q) > 1e-12:
            raise UsageError(f"{where}: the quaternion is zero")
        try:
            cid = int(parts[8])
        except ValueError:
            raise UsageError(f"{where}: bad camera id {parts[8]!r}") from None
        if cid not in intrinsics:
            raise UsageError(f"{where}: camera {cid} is not in {folder / 'cameras.txt'}")
        R = rotation_from_quaternion(q)
        world_from_camera = np.eye(4)
        world_from_camera[:3, :3] = R.T
        world_from_camera[:3, 3] = -R.T @ t
        K, size, lens, distortion = intrinsics[cid]
        with context(where):
            cameras.append(from_opencv(K, world_from_camera, size, name=parts[9], model=lens,
                                       distortion=distortion))
    if not cameras:
        raise UsageError(f"{path}: no images")
    return cameras

