"""Checks of user-given numbers, vectors and matrices for the camera API and poses files.

Each check raises a one-line UsageError ("K[1][2]: expected a number, got str") and never lets
a NumPy error (truth value of an array, ragged sequences, overflow) escape. They accept NumPy
arrays and scalars as well as the nested lists and numbers that JSON gives.
"""

from __future__ import annotations

import contextlib
import math
import numbers
from collections.abc import Iterator

import numpy as np

from vkpbr.errors import UsageError

__all__ = ["Vec3", "context", "convention_arg", "describe", "frame_size", "matrix", "real",
           "rigid_pose", "shown", "size_arg", "vec3"]

Vec3 = tuple[float, float, float]

ORTHONORMAL_TOL = 1e-4  # max |R^T R - I|: float32 poses from other tools pass, scaled ones fail


@contextlib.contextmanager
def context(where: str) -> Iterator[None]:
    """Prefix the UsageErrors raised inside with `where` ("poses.json: entry 3: ...")."""
    try:
        yield
    except UsageError as exc:
        raise UsageError(f"{where}: {exc}") from None


def describe(value: object) -> str:
    """A short name for what the user gave: "ndarray of shape (3, 3)", "list of length 2"."""
    shape = getattr(value, "shape", None)
    if isinstance(shape, tuple):
        return f"{type(value).__name__} of shape {shape}"
    if isinstance(value, (list, tuple)):
        return f"{type(value).__name__} of length {len(value)}"
    if value is None:
        return "None"
    return type(value).__name__


def shown(value: object, sequences: bool = False) -> str:
    """`value` for a one-line message: the repr of a short scalar (with `sequences`, of a
    short list or tuple too: "(1.2, 0.5, 0.5)"), else `describe`."""
    if sequences and isinstance(value, (list, tuple)):
        text = repr(value)
        if len(text) <= 60 and "\n" not in text:
            return text
    if value is None or isinstance(value, (bool, int, float, str, np.generic)):
        text = repr(value.item() if isinstance(value, np.generic) else value)
        if len(text) <= 40:
            return text
    return describe(value)


def real(value: object, what: str) -> float:
    """A finite number (int or float, NumPy's included; not a bool or a string)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise UsageError(f"{what}: expected a number, got {describe(value)}")
    try:
        x = float(value)
    except (OverflowError, ValueError, TypeError):
        raise UsageError(f"{what}: the number is too large") from None
    if not math.isfinite(x):
        raise UsageError(f"{what}: {x} is not finite")
    return x


def _nested(value: object, shape: tuple[int, ...], what: str) -> list:
    if not shape:
        return real(value, what)  # type: ignore[return-value]
    if not isinstance(value, (list, tuple)):
        raise UsageError(f"{what}: expected a list of {shape[0]}, got {describe(value)}")
    if len(value) != shape[0]:
        raise UsageError(f"{what}: expected {shape[0]} items, got {len(value)}")
    return [_nested(v, shape[1:], f"{what}[{i}]") for i, v in enumerate(value)]


def matrix(value: object, shape: tuple[int, ...], what: str) -> np.ndarray:
    """`value` (nested lists/tuples or an array-like) as a finite float64 array of `shape`."""
    if isinstance(value, (list, tuple)):
        return np.array(_nested(value, shape, what), dtype=np.float64)
    dims = "x".join(map(str, shape))
    if isinstance(value, (str, bytes, bool, numbers.Number)) or not (
            isinstance(value, np.ndarray) or hasattr(value, "__array__")):
        raise UsageError(f"{what}: expected a {dims} matrix, got {describe(value)}")
    try:
        a = np.asarray(value)
    except (TypeError, ValueError, OverflowError, RuntimeError):
        raise UsageError(f"{what}: expected a {dims} matrix, got {describe(value)}") from None
    if a.shape != shape:
        raise UsageError(f"{what}: expected shape {shape}, got {a.shape}")
    if a.dtype.kind not in "iuf":
        raise UsageError(f"{what}: expected numbers, got an array of {a.dtype}")
    a = a.astype(np.float64)
    if not np.isfinite(a).all():
        raise UsageError(f"{what}: the numbers must be finite")
    return a


def vec3(value: object, what: str) -> Vec3:
    return tuple(float(x) for x in matrix(value, (3,), what))  # type: ignore[return-value]


def size_arg(value: object, what: str) -> tuple[int, int]:
    """(width, height): two positive integers."""
    # The renderer's per-frame case first, without the slow numbers.Integral checks.
    if (type(value) is tuple and len(value) == 2 and type(value[0]) is type(value[1]) is int
            and value[0] > 0 and value[1] > 0):
        return value  # type: ignore[return-value]
    if isinstance(value, np.ndarray):
        value = value.tolist() if value.ndim == 1 else value
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise UsageError(f"{what}: expected (width, height), got {describe(value)}")
    out = []
    for label, v in zip(("width", "height"), value, strict=True):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral) or v <= 0:
            raise UsageError(f"{what}: {label} must be a positive integer, got {shown(v)}")
        out.append(int(v))
    return out[0], out[1]


def frame_size(value: object, limit: int) -> tuple[int, int]:
    """A frame's (width, height) as the renderer takes it: two positive integers (NumPy's
    too), each at most `limit` (the device's maxImageDimension2D)."""
    try:
        w, h = value  # type: ignore[misc]
    except (TypeError, ValueError):
        raise UsageError(f"image size {shown(value)}: expected (width, height)") from None
    if (not (isinstance(w, int | np.integer) and isinstance(h, int | np.integer))
            or isinstance(w, bool) or isinstance(h, bool) or w <= 0 or h <= 0):  # (True: no width)
        raise UsageError(f"image size {shown(w)}x{shown(h)}: width and height must be positive "
                         "integers")
    if w > limit or h > limit:
        raise UsageError(f"image size {w}x{h} exceeds this device's limit of {limit}x{limit}")
    return int(w), int(h)


def convention_arg(value: object, what: str) -> str:
    if not isinstance(value, str) or value not in ("opencv", "opengl"):
        raise UsageError(f'{what}: expected "opengl" (x right, y up, z backward: NeRF, Blender) '
                         f'or "opencv" (x right, y down, z forward), got {shown(value)}')
    return value


def rigid_pose(value: object, what: str) -> np.ndarray:
    """A (4, 4) rigid transform: last row (0, 0, 0, 1), rotation orthonormal, determinant +1."""
    m = matrix(value, (4, 4), what)
    if np.abs(m[3] - (0.0, 0.0, 0.0, 1.0)).max() > 1e-9:
        raise UsageError(f"{what}: the last row must be [0, 0, 0, 1], got {m[3].tolist()}")
    r = m[:3, :3]
    with np.errstate(all="ignore"):  # huge entries overflow to inf: reported just below
        err = float(np.abs(r.T @ r - np.eye(3)).max())
    if not err <= ORTHONORMAL_TOL:
        raise UsageError(f"{what}: not a rigid transform: the rotation is not orthonormal "
                         f"(max |R^T R - I| = {err:.3g}; scaled or sheared poses are not supported)")
    if np.linalg.det(r) < 0.0:
        raise UsageError(f"{what}: the rotation is a reflection (determinant -1): camera axes "
                         "must be right-handed (opencv: x right, y down, z forward; opengl: "
                         "x right, y up, z backward)")
    return m
