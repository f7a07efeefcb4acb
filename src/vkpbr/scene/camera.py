"""Cameras as users bring them: OpenCV's K and world-from-camera, OpenGL/NeRF/Blender 4x4
poses, "ex,ey,ez,tx,ty,tz" strings and pose dicts. NumPy only (no Vulkan).

Conventions (see docs/poses.md):

- "opencv" camera axes: x right, y down, z forward (OpenCV, COLMAP).
- "opengl" camera axes: x right, y up, z backward (OpenGL, NeRF's transforms.json, Blender).
- Pixel coordinates follow OpenCV: the centre of the top-left pixel is (0, 0), so an image of
  width W spans x in [-0.5, W - 0.5] and its centre is at (W - 1) / 2.
- A pose is world-from-camera (camera-to-world): its columns are the camera's axes in world
  space and its translation is the camera's position.

Everything a user can get wrong raises a one-line `UsageError`, never a NumPy error.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from vkpbr.errors import UsageError
from vkpbr.scene._checks import (
    Vec3,
    context,
    convention_arg,
    describe,
    matrix,
    real,
    rigid_pose,
    shown,
    size_arg,
    vec3,
)
from vkpbr.scene.lens import check_model

# The narrowest field of view: 1 / tan(fov / 2) stays far inside float32 (~1e6 here).
MIN_YFOV_DEG = 1e-4


@dataclass
class Camera:
    """A perspective camera by eye/target/up; yfov in degrees.

    Nothing is clipped beyond the near plane (reversed-Z, infinite far plane). `znear` None:
    chosen per render in front of the scene's bounds; `zfar` only normalises the depth debug
    view (None: the far side of the scene's bounds).
    pixel_intrinsics: (fx, fy, cx, cy, width, height) in pixels, OpenCV's convention (the
        centre of the top-left pixel is (0, 0); x right, y down). When set, it defines the
        projection (`intrinsics(size)` scales it to the image size) and `yfov_deg` must be
        its vertical field of view, 2 atan(height / (2 fy)); `validate_camera` checks the two
        agree. To change the field of view, set pixel_intrinsics to None.
    model: "pinhole" (default), "opencv" (lens distortion), "opencv_fisheye" or
        "equidistant" (fisheye lenses, up to 150 degrees across); `distortion` its
        coefficients in OpenCV's order: (k1, k2, p1, p2[, k3[, k4, k5, k6]]) for "opencv",
        (k1, k2, k3, k4) for "opencv_fisheye", none for the others (vkpbr.scene.lens,
        docs/cameras.md). A model other than the pinhole needs pixel_intrinsics; it is
        rendered as a wider pinhole and resampled on the GPU (render/post.py Lens).

    Conversions from and to the poses other tools use (OpenCV's K and world-from-camera,
    OpenGL/NeRF/Blender 4x4 poses) live in `vkpbr.scene.camera`; the methods below delegate.
    """

    eye: tuple[float, float, float] = (0.0, 0.0, 3.0)
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    yfov_deg: float = 60.0
    znear: float | None = None
    zfar: float | None = None
    name: str = ""
    pixel_intrinsics: tuple[float, float, float, float, int, int] | None = None
    model: str = "pinhole"
    distortion: tuple[float, ...] = ()

    # The imports are deferred: vkpbr.scene.camera builds Cameras, so it imports this module.
    def intrinsics(self, size: tuple[int, int]) -> np.ndarray:
        """The (3, 3) float64 pinhole matrix K for an image of `size` (width, height), in
        OpenCV's pixel convention. See `vkpbr.scene.camera.intrinsics`."""

        return intrinsics(self, size)

    def world_from_camera(self, convention: Literal["opencv", "opengl"] = "opencv") -> np.ndarray:
        """The (4, 4) float64 camera-to-world pose with "opencv" axes (x right, y down,
        z forward) or "opengl" axes (x right, y up, z backward: NeRF, Blender). See
        `vkpbr.scene.camera.world_from_camera`."""

        return world_from_camera(self, convention)

    @classmethod
    def from_opencv(cls, K: object, world_from_camera: object, size: object,
                    name: str = "", model: str = "pinhole",
                    distortion: object = ()) -> Camera:
        """A camera from OpenCV's K (3, 3), world-from-camera (4, 4) and image size (W, H),
        with a lens `model` and its `distortion` coefficients (OpenCV's distCoeffs or the
        fisheye D). See `vkpbr.scene.camera.from_opencv`."""

        return from_opencv(K, world_from_camera, size, name=name, model=model,
                           distortion=distortion)

    @classmethod
    def from_pose(cls, matrix: object, convention: Literal["opengl", "opencv"] = "opengl",
                  yfov_deg: float | None = None, base: Camera | None = None,
                  name: str = "") -> Camera:
        """A camera from a (4, 4) world-from-camera pose, OpenGL axes by default (NeRF's
        transforms.json, Blender). See `vkpbr.scene.camera.from_pose`."""

        return from_pose(matrix, convention, yfov_deg=yfov_deg, base=base, name=name)

__all__ = [
    "Convention",
    "Intrinsics",
    "PIXEL_CENTRE",
    "Pose",
    "as_camera",
    "as_pose",
    "corner_from_opencv",
    "format_camera",
    "from_opencv",
    "from_pose",
    "intrinsics",
    "opencv_from_corner",
    "parse_camera",
    "validate_camera",
    "world_from_camera",
]

Convention = Literal["opencv", "opengl"]
Intrinsics = tuple[float, float, float, float, int, int]  # (fx, fy, cx, cy, width, height)

# OpenCV camera axes -> OpenGL camera axes (and back): y and z flip.
_FLIP = np.diag([1.0, -1.0, -1.0, 1.0])

# The one pixel-convention shift, each way: NeRF's and COLMAP's K put the centre of the top-left
# pixel at (0.5, 0.5), OpenCV's (and vkpbr's) at (0, 0).
PIXEL_CENTRE = 0.5


def corner_from_opencv(K: np.ndarray) -> np.ndarray:
    """OpenCV's K (top-left pixel centre at (0, 0)) as NeRF's and COLMAP's ((0.5, 0.5)).

    K : (3, 3) float64. Returns a new (3, 3) float64 with cx, cy + 0.5.
    """
    out = np.array(K, dtype=np.float64)
    out[0, 2] += PIXEL_CENTRE
    out[1, 2] += PIXEL_CENTRE
    return out


def opencv_from_corner(K: np.ndarray) -> np.ndarray:
    """The inverse of `corner_from_opencv`: cx, cy - 0.5. (3, 3) float64."""
    out = np.array(K, dtype=np.float64)
    out[0, 2] -= PIXEL_CENTRE
    out[1, 2] -= PIXEL_CENTRE
    return out


# -- validation, parsing and printing ---------------------------------------------------------


# Largest coordinate accepted anywhere (positions after transforms, cameras, lights): far
# beyond any real scene, far below float32's 3.4e38, so squared distances and the projection
# stay finite. (scene/validate.py checks scenes against it.)
MAX_COORDINATE = 1e15


def _camera_problem(camera: Camera) -> str | None:
    """What is wrong with `camera`, or None. Plain floats: the renderer calls this per frame."""
    try:
        ex, ey, ez = (float(v) for v in camera.eye)
        tx, ty, tz = (float(v) for v in camera.target)
        ux, uy, uz = (float(v) for v in camera.up)
    except (TypeError, ValueError):
        return "eye, target and up must be three numbers each"
    if not all(map(math.isfinite, (ex, ey, ez, tx, ty, tz, ux, uy, uz))):
        return "eye, target and up must be finite numbers"
    if max(map(abs, (ex, ey, ez, tx, ty, tz, ux, uy, uz))) > MAX_COORDINATE:
        return f"eye, target and up must lie within +-{MAX_COORDINATE:g}"
    fx, fy, fz = tx - ex, ty - ey, tz - ez
    f_len = math.sqrt(fx * fx + fy * fy + fz * fz)
    if f_len < 1e-9:
        return "eye and target coincide"
    cx, cy, cz = fy * uz - fz * uy, fz * ux - fx * uz, fx * uy - fy * ux
    u_len = math.sqrt(ux * ux + uy * uy + uz * uz)
    if math.sqrt(cx * cx + cy * cy + cz * cz) < 1e-9 * f_len * max(u_len, 1e-30):
        return "up is parallel to the viewing direction (or zero)"
    yfov = camera.yfov_deg
    if isinstance(yfov, bool) or not isinstance(yfov, (int, float)) or not 0.0 < yfov < 180.0:
        return f"field of view {shown(yfov)} must be in (0, 180) degrees"
    if yfov < MIN_YFOV_DEG:
        return (f"field of view {shown(yfov)} is narrower than {MIN_YFOV_DEG:g} degrees: its "
                "projection overflows 32-bit floats")
    near, far = camera.znear, camera.zfar
    for label, z in (("near", near), ("far", far)):
        if z is not None and (isinstance(z, bool) or not isinstance(z, (int, float)) or z != z):
            return f"{label} plane {shown(z)} must be a number or None"
    if near is not None and not 0.0 < near < math.inf:
        return f"near plane {near} must be a finite number > 0 (or None: automatic)"
    if far is not None and not far > (near if near is not None else 0.0):
        return f"far plane {far} must be beyond the near plane {near} (or None: automatic)"
    if camera.model != "pinhole" or camera.distortion:
        problem = check_model(camera.model, camera.distortion)
        if problem is None and camera.pixel_intrinsics is None:
            problem = (f"model {camera.model!r} needs pixel_intrinsics (fx, fy, cx, cy, width, "
                       "height): make it with Camera.from_opencv(K, pose, size, model=...)")
        if problem is not None:
            return problem
    if camera.pixel_intrinsics is not None:
        return _intrinsics_problem(camera.pixel_intrinsics, yfov)
    return None


def _intrinsics_problem(k: object, yfov_deg: float) -> str | None:
    try:
        fx, fy, cx, cy, w, h = k  # type: ignore[misc]
    except (TypeError, ValueError):
        return f"pixel_intrinsics must be (fx, fy, cx, cy, width, height), got {describe(k)}"
    try:
        with context("pixel_intrinsics"):
            fx, fy = real(fx, "fx"), real(fy, "fy")
            real(cx, "cx")
            real(cy, "cy")
            size_arg((w, h), "(width, height)")
    except UsageError as exc:
        return str(exc)
    if not (fx > 0.0 and fy > 0.0):
        return f"pixel_intrinsics: fx ({fx}) and fy ({fy}) must be > 0"
    implied = math.degrees(2.0 * math.atan(h / (2.0 * fy)))
    if abs(implied - yfov_deg) > 1e-6:
        return (f"field of view {yfov_deg:g} disagrees with pixel_intrinsics (fy {fy:g} for "
                f"height {h} gives {implied:.6g} degrees); set pixel_intrinsics=None to use yfov_deg")
    return None


def validate_camera(camera: Camera) -> None:
    """Raise a one-line UsageError when `camera` cannot be rendered.

    znear None (derived per render) and zfar None (infinite) are valid; a given znear must be
    > 0 and a given zfar > znear. With pixel_intrinsics set, yfov_deg must be their vertical
    field of view.
    """
    problem = _camera_problem(camera)
    if problem is not None:
        raise UsageError(f"camera: {problem}")


def _numbers(text: str, label: str) -> list[float]:
    try:
        values = [float(x) for x in text.replace(" ", "").split(",")]
    except ValueError:
        raise UsageError(f"{label}: expected 6 or 9 comma-separated numbers") from None
    if len(values) not in (6, 9):
        raise UsageError(f"{label}: expected 6 or 9 numbers, got {len(values)}")
    if not all(map(math.isfinite, values)):
        raise UsageError(f"{label}: the numbers must be finite")
    return values


def parse_camera(text: str, base: Camera | None = None) -> Camera:
    """Parse "ex,ey,ez,tx,ty,tz[,ux,uy,uz]" (the format `format_camera` prints).

    Everything not in the string (up when only 6 numbers are given, the field of view, the
    planes, the intrinsics) comes from `base` (default: `Camera()`).
    """
    values = _numbers(text, f"--camera {text!r}")
    cam = dataclasses.replace(
        base or Camera(),
        eye=tuple(values[0:3]),
        target=tuple(values[3:6]),
        up=tuple(values[6:9]) if len(values) == 9 else (base or Camera()).up,
    )
    validate_camera(cam)
    return cam


def format_camera(camera: Camera) -> str:
    """"ex,ey,ez,tx,ty,tz,ux,uy,uz", what `parse_camera` and `--camera` read."""
    vals = [*camera.eye, *camera.target, *camera.up]
    return ",".join(f"{v:.6g}" for v in vals)


# -- OpenCV / OpenGL conversions --------------------------------------------------------------


def intrinsics(camera: Camera, size: tuple[int, int]) -> np.ndarray:
    """The pinhole matrix K, (3, 3) float64, for an image of `size` (width W, height H).

    Pixel coordinates follow OpenCV: u = K @ x_cam (x right, y down, z forward) divided by
    its z, with the centre of the top-left pixel at (0, 0). With `camera.pixel_intrinsics`
    (fx, fy, cx, cy, w0, h0), K is scaled to `size`: fx W/w0, fy H/h0, and the principal point
    as a position on the image, (cx + 0.5) W/w0 - 0.5 (a different aspect ratio stretches).
    Without, fx = fy = (H/2) / tan(yfov/2) (square pixels) and the principal point is the
    image centre ((W-1)/2, (H-1)/2).
    """
    validate_camera(camera)
    W, H = size_arg(size, "intrinsics: size")
    if camera.pixel_intrinsics is not None:
        fx, fy, cx, cy, w0, h0 = (float(v) for v in camera.pixel_intrinsics)
        sx, sy = W / w0, H / h0
        fx, fy, cx, cy = fx * sx, fy * sy, (cx + 0.5) * sx - 0.5, (cy + 0.5) * sy - 0.5
    else:
        fx = fy = (H / 2.0) / math.tan(math.radians(camera.yfov_deg) / 2.0)
        cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def world_from_camera(camera: Camera, convention: Convention = "opencv") -> np.ndarray:
    """The camera-to-world pose, (4, 4) float64.

    "opencv": columns are the camera's right, down and forward axes in world space (x right,
    y down, z forward); "opengl": right, up and backward (x right, y up, z backward, as in
    NeRF's transforms.json and Blender). The last column is the eye. The up column is `up`
    made orthogonal to the viewing direction, so a camera made by `from_opencv` or
    `from_pose` gives its matrix back.
    """
    convention = convention_arg(convention, "world_from_camera: convention")
    validate_camera(camera)
    eye = np.array(camera.eye, dtype=np.float64)
    f = np.array(camera.target, dtype=np.float64) - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, np.array(camera.up, dtype=np.float64))
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = s, -u, f, eye
    return m @ _FLIP if convention == "opengl" else m


def _opencv_pose(m: np.ndarray) -> tuple[Vec3, Vec3, Vec3]:
    """eye, target (eye + forward) and up (-y) of an OpenCV world-from-camera matrix."""
    eye = m[:3, 3]
    return (tuple(map(float, eye)), tuple(map(float, eye + m[:3, 2])),  # type: ignore[return-value]
            tuple(map(float, -m[:3, 1])))


def _opencv_fields(K: object, pose: object, size: object) -> dict[str, object]:
    """Camera fields from OpenCV's K, world-from-camera and image size (raises UsageError)."""
    k = matrix(K, (3, 3), "K")
    m = rigid_pose(pose, "world_from_camera")
    w, h = size_arg(size, "size")
    fx, fy = float(k[0, 0]), float(k[1, 1])
    if abs(k[0, 1]) > 1e-12 * max(abs(fx), 1.0):
        raise UsageError(f"K: skewed intrinsics are not supported (K[0, 1] = {k[0, 1]:g})")
    if k[1, 0] != 0.0 or k[2, 0] != 0.0 or k[2, 1] != 0.0 or k[2, 2] != 1.0:
        raise UsageError(f"K: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], got {k.tolist()}")
    if not (fx > 0.0 and fy > 0.0):
        raise UsageError(f"K: fx ({fx:g}) and fy ({fy:g}) must be > 0")
    eye, target, up = _opencv_pose(m)
    return {"eye": eye, "target": target, "up": up,
            "yfov_deg": math.degrees(2.0 * math.atan(h / (2.0 * fy))),
            "pixel_intrinsics": (fx, fy, float(k[0, 2]), float(k[1, 2]), w, h)}


def _pose_fields(pose: object, convention: object, what: str = "world_from_camera") -> dict[str, Vec3]:
    convention = convention_arg(convention, "convention")
    m = rigid_pose(pose, what)
    eye, target, up = _opencv_pose(m @ _FLIP if convention == "opengl" else m)
    return {"eye": eye, "target": target, "up": up}


def from_opencv(K: object, world_from_camera: object, size: object, name: str = "",
                model: str = "pinhole", distortion: object = ()) -> Camera:
    """A camera from OpenCV's calibration and pose.

    K: (3, 3) intrinsics [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] in pixels, centre of the
        top-left pixel at (0, 0); no skew.
    world_from_camera: (4, 4) camera-to-world, OpenCV axes (x right, y down, z forward); the
        rotation must be orthonormal to 1e-4 with determinant +1. (OpenCV's solvePnP gives
        camera-from-world: invert it.)
    size: (W, H) of the image K belongs to.

    model, distortion: the lens (vkpbr.scene.lens): "pinhole", "opencv" with
        cv2.projectPoints' distCoeffs (k1, k2, p1, p2[, k3[, k4, k5, k6]]), "opencv_fisheye"
        with cv2.fisheye's D (k1, k2, k3, k4), or "equidistant".

    Returns a Camera with eye = the translation, target = eye + forward (z), up = -y,
    yfov_deg = 2 atan(H / (2 fy)) and pixel_intrinsics = (fx, fy, cx, cy, W, H); znear and
    zfar None (derived per render, infinite).
    """
    with context("from_opencv"):
        fields = _opencv_fields(K, world_from_camera, size)
        fields.update(_lens_fields(model, distortion))
        return Camera(**fields, name=name)  # type: ignore[arg-type]


def _lens_fields(model: object, distortion: object) -> dict[str, object]:
    """Camera fields `model` and `distortion` (a tuple of floats), checked (UsageError)."""
    if isinstance(distortion, np.ndarray):
        distortion = distortion.ravel().tolist()
    problem = check_model(model, distortion)
    if problem is not None:
        raise UsageError(problem)
    return {"model": model, "distortion": tuple(float(v) for v in distortion)}  # type: ignore[attr-defined]


def from_pose(matrix: object, convention: Convention = "opengl", yfov_deg: float | None = None,
              base: Camera | None = None, name: str = "") -> Camera:
    """A camera from a (4, 4) world-from-camera pose (NumPy array or nested lists).

    convention: "opengl" (default: x right, y up, z backward, as NeRF's transforms.json and
        Blender write them) or "opencv" (x right, y down, z forward).
    yfov_deg: the vertical field of view; None keeps `base`'s (and its pixel_intrinsics).
    base: where everything but the pose comes from (default `Camera()`).
    """
    with context("from_pose"):
        fields: dict[str, object] = dict(_pose_fields(matrix, convention, "matrix"))
        if yfov_deg is not None:
            fields["yfov_deg"] = real(yfov_deg, "yfov_deg")
            fields["pixel_intrinsics"] = None
        cam = dataclasses.replace(base or Camera(), name=name, **fields)  # type: ignore[arg-type]
        validate_camera(cam)
        return cam


# -- poses: a camera without the scene's defaults ---------------------------------------------


@dataclasses.dataclass(frozen=True)
class Pose:
    """A validated camera pose waiting for the scene's default camera (`camera(base)`).

    up None: the base camera's up; yfov_deg None: the base's field of view (and intrinsics);
    pixel_intrinsics: the pose's own calibration (then yfov_deg is its field of view).
    `where` prefixes the errors `camera` raises ("poses.json: entry 3").
    """

    eye: Vec3
    target: Vec3
    up: Vec3 | None = None
    yfov_deg: float | None = None
    pixel_intrinsics: Intrinsics | None = None
    name: str = ""
    where: str = "camera"
    time: float | None = None  # the scene's animation time of this view ("time"), if given
    model: str = "pinhole"
    distortion: tuple[float, ...] = ()
    # A NeRF frame's "file_path" (relative, as the file wrote it): the rendered frame's name.
    file_path: str | None = None

    def camera(self, base: Camera) -> Camera:
        """`base` with this pose applied. Only a pose without `up` can fail here (the base's up
        may be parallel to its viewing direction): the error names `where`."""
        fields: dict[str, object] = {"eye": self.eye, "target": self.target, "name": self.name,
                                     "up": self.up if self.up is not None else base.up}
        if self.pixel_intrinsics is not None or self.yfov_deg is not None:
            fields["yfov_deg"] = self.yfov_deg
            fields["pixel_intrinsics"] = self.pixel_intrinsics
            fields["model"], fields["distortion"] = self.model, self.distortion
        cam = dataclasses.replace(base, **fields)  # type: ignore[arg-type]
        problem = _camera_problem(cam)
        if problem is not None:
            raise UsageError(f"{self.where}: {problem}")
        return cam


_EYE_KEYS = ("eye", "target", "up", "fov", "name", "time")
_MATRIX_KEYS = ("world_from_camera", "convention", "fov", "name", "time")
_K_KEYS = ("K", "world_from_camera", "size", "convention", "name", "model", "distortion", "time")


def _pose_from_dict(d: Mapping[str, object]) -> dict[str, object]:
    keys = [k for k in d if not isinstance(k, str)]
    if keys:
        raise UsageError(f"keys must be strings, got {describe(keys[0])}")
    if "K" in d:
        form, allowed, required = "a K pose", _K_KEYS, ("world_from_camera", "size")
    elif "world_from_camera" in d:
        form, allowed, required = "a world_from_camera pose", _MATRIX_KEYS, ("convention",)
    elif "eye" in d or "target" in d:
        form, allowed, required = "an eye/target pose", _EYE_KEYS, ("eye", "target")
    else:
        raise UsageError('expected "eye" and "target", or "world_from_camera" (with "convention"'
                         f' or "K" and "size"), got keys {sorted(d)}')
    for key in d:
        if key not in allowed:
            raise UsageError(f"unknown key {key!r} in {form} (expected: {', '.join(allowed)})")
    for key in required:
        if key not in d:
            raise UsageError(f"missing {key!r} in {form}")
    name = d.get("name", "")
    if not isinstance(name, str):
        raise UsageError(f'"name": expected a string, got {describe(name)}')
    fields: dict[str, object] = {"name": name}
    if "time" in d:  # the animation time of the view (docs/living-scenes.md)
        t = d["time"]
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
            raise UsageError(f'"time": expected a finite number of seconds, got {describe(t)}')
        fields["time"] = float(t)
    if "K" in d:
        fields.update(_opencv_fields(d["K"], _pose_from_convention(d), d["size"]))
        fields.update(_lens_fields(d.get("model", "pinhole"), d.get("distortion", ())))
        return fields
    if "world_from_camera" in d:
        fields.update(_pose_fields(d["world_from_camera"], d["convention"]))
    else:
        fields["eye"], fields["target"] = vec3(d["eye"], '"eye"'), vec3(d["target"], '"target"')
        if "up" in d:
            fields["up"] = vec3(d["up"], '"up"')
    if "fov" in d:
        fov = real(d["fov"], '"fov"')
        if not 0.0 < fov < 180.0:
            raise UsageError(f'"fov": {fov:g} must be in (0, 180) degrees')
        fields["yfov_deg"] = fov
    return fields


def _pose_from_convention(d: Mapping[str, object]) -> np.ndarray:
    """The K form's world_from_camera as OpenCV axes (its convention defaults to "opencv")."""
    m = rigid_pose(d["world_from_camera"], "world_from_camera")
    return m @ _FLIP if convention_arg(d.get("convention", "opencv"), "convention") == "opengl" else m


def as_pose(value: object, where: str = "camera", convention: Convention = "opengl") -> Pose:
    """Validate a pose given as an "ex,ey,ez,tx,ty,tz[,ux,uy,uz]" string, a dict or a (4, 4)
    world-from-camera array-like (in `convention`, OpenGL axes by default).

    Dicts (the entries of a poses file, see docs/poses.md):
    {"eye", "target", "up"?, "fov"?}, {"world_from_camera", "convention", "fov"?} or
    {"K", "world_from_camera", "size", "convention"? (default "opencv")}, each with "name"?.
    Errors are one UsageError line starting with `where`.
    """
    with context(where):
        if isinstance(value, str):
            v = _numbers(value, repr(value))
            fields: dict[str, object] = {"eye": tuple(v[0:3]), "target": tuple(v[3:6])}
            if len(v) == 9:
                fields["up"] = tuple(v[6:9])
        elif isinstance(value, Mapping):
            fields = _pose_from_dict(value)
        elif _is_4x4(value):
            fields = dict(_pose_fields(value, convention, "pose"))
        else:
            raise UsageError("expected a Camera, a 4x4 pose, a pose dict or an "
                             f"'ex,ey,ez,tx,ty,tz' string, got {describe(value)}")
    pose = Pose(where=where, **fields)  # type: ignore[arg-type]
    # Check all that does not depend on the base camera now: any up that is not parallel to
    # the viewing direction stands in for the base's.
    pose.camera(Camera(up=pose.up or _perpendicular(pose.eye, pose.target)))
    return pose


def _perpendicular(eye: Vec3, target: Vec3) -> Vec3:
    f = [t - e for t, e in zip(target, eye, strict=True)]
    i = min(range(3), key=lambda j: abs(f[j]))  # the axis least aligned with f
    return tuple(1.0 if j == i else 0.0 for j in range(3))  # type: ignore[return-value]


def _is_4x4(value: object) -> bool:
    """Whether `value` looks like a 4x4 matrix (its contents are checked later)."""
    if isinstance(value, (list, tuple)):
        return len(value) == 4 and all(isinstance(r, (list, tuple)) and len(r) == 4 for r in value)
    return getattr(value, "shape", None) == (4, 4) and hasattr(value, "__array__")


def as_camera(value: object, base: Camera, convention: Convention = "opengl") -> Camera:
    """Whatever a user passed as a camera, as a Camera.

    value: a Camera (returned as is); a (4, 4) world-from-camera array-like, in OpenGL axes
        (x right, y up, z backward, as NeRF and Blender) unless `convention="opencv"`; an
        "ex,ey,ez,tx,ty,tz[,ux,uy,uz]" string (as `--camera`); or a pose dict (the entries
        of a poses file, see `as_pose`).
    base: what the pose does not give (up, field of view, planes) comes from it.

    Anything else raises a UsageError naming the type received.
    """
    if isinstance(value, Camera):
        return value
    return as_pose(value, "camera", convention).camera(base)
