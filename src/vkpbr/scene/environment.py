"""Equirectangular HDR environments: read a panorama into float32 NumPy, with its checks.

Readers (maintained libraries, no system installs, wheels for Linux, Windows and macOS):

- ``.hdr`` / ``.pic`` (Radiance RGBE): `imagecodecs.rgbe_decode` (Christoph Gohlke's
  imagecodecs, the codec collection behind tifffile). Pillow cannot read RGBE, imageio needs
  the FreeImage binary (downloaded at run time) for it, and OpenCV 5's wheels dropped EXR.
- ``.exr`` (OpenEXR): the `OpenEXR` package, the Academy Software Foundation's own Python
  bindings of the reference library (any compression, half or float channels).
- ``.jpg`` / ``.jpeg`` / ``.png`` (LDR photographs): Pillow, 8 or 16 bits a channel, decoded
  from sRGB to linear with the one sRGB curve (scene/color.py). An LDR panorama's light is
  clipped: the sun and bright sky saturate at 1.0, so it lights more softly and dimly than
  the scene it photographed (`--env-intensity` scales it; an .hdr/.exr keeps the range).

Both are imported lazily, so scenes without an environment file never load them.

The panorama's convention (shared with shaders/env_common.glsl and reference/ibl.py): a
direction d = (x, y, z) (+Y up) maps to u = 0.5 + atan2(x, -z) / (2 pi), v = acos(y) / pi, so
the image's centre column looks along -Z (glTF's default camera forward) and row 0 is the
zenith.

Bad input is one `SceneError` line naming the file: unreadable, corrupt or truncated data, a
panorama that is not 2:1, more pixels than `VKPBR_MAX_TEXTURE_PIXELS`. NaN, infinite and
negative pixels are replaced (NaN and -inf by 0, +inf by the largest finite value, negatives
by 0) with one warning on the "vkpbr.scene.environment" logger.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import logging
import os
import re
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.limits import limits

__all__ = ["load_panorama", "check_panorama", "direction_to_equirect", "equirect_to_direction",
           "sample_equirect", "ENV_SUFFIXES", "LDR_SUFFIXES"]

log = logging.getLogger(__name__)

LDR_SUFFIXES = (".jpg", ".jpeg", ".png")
ENV_SUFFIXES = (".hdr", ".pic", ".exr", *LDR_SUFFIXES)
_RGBE_SIZE = re.compile(rb"^([-+])([YX]) (\d+) ([-+])([YX]) (\d+)$")


def _read_bytes(path: Path) -> bytes:
    cap = limits().max_texture_file_bytes
    try:
        if not path.is_file():
            raise SceneError(path, "not found" if not path.exists() else "not a regular file")
        with path.open("rb") as f:
            data = f.read(cap + 1)
    except OSError as exc:
        raise SceneError(path, f"cannot read ({exc.strerror or exc})") from None
    if len(data) > cap:
        raise SceneError(path, f"larger than {cap} bytes (VKPBR_MAX_TEXTURE_FILE_BYTES)")
    return data


def _check_pixels(path: Path, width: int, height: int) -> None:
    cap = limits().max_texture_pixels
    if width <= 0 or height <= 0:
        raise SceneError(path, f"panorama of {width}x{height} pixels")
    if width * height > cap:
        raise SceneError(path, f"{width}x{height} panorama has more than {cap} pixels "
                               "(VKPBR_MAX_TEXTURE_PIXELS)")


def _rgbe_size(path: Path, data: bytes) -> tuple[int, int]:
    """(width, height) from a Radiance header, read before decoding (the pixel limit)."""
    if not (data.startswith(b"#?")):
        raise SceneError(path, "not a Radiance HDR file (no '#?' signature)")
    end = data.find(b"\n\n", 0, 1 << 16)
    if end < 0:
        raise SceneError(path, "truncated Radiance header")
    line_end = data.find(b"\n", end + 2, end + 2 + 256)
    m = _RGBE_SIZE.match(data[end + 2 : line_end].strip()) if line_end > 0 else None
    if m is None:
        raise SceneError(path, "Radiance header without a resolution line")
    a, b = int(m.group(3)), int(m.group(6))
    # "-Y H +X W" is the usual order; "+X W -Y H" would be a transposed image.
    return (b, a) if m.group(2) == b"Y" else (a, b)


def _decode_hdr(path: Path, data: bytes) -> np.ndarray:
    import imagecodecs

    _check_pixels(path, *_rgbe_size(path, data))
    try:
        rgb = imagecodecs.rgbe_decode(data)
    except (imagecodecs.RgbeError, ValueError, RuntimeError) as exc:
        raise SceneError(path, f"corrupt or truncated Radiance HDR ({exc})") from None
    return np.asarray(rgb, dtype=np.float32)


@contextlib.contextmanager
def _native_output_captured() -> Iterator[list[str]]:
    """Capture what native code writes to file descriptors 1 and 2 (OpenEXR prints its
    diagnostics there): the caller's one error line replaces them. Yields a list that holds
    the captured text's last non-empty line once the block exits."""
    out: list[str] = []
    libc = ctypes.CDLL(None)  # fflush(NULL): native stdio buffers go to the captured file
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    py_text = io.StringIO()  # the bindings also print through sys.stdout (PySys_WriteStdout)
    with tempfile.TemporaryFile() as tmp:
        saved = [os.dup(1), os.dup(2)]
        try:
            os.dup2(tmp.fileno(), 1)
            os.dup2(tmp.fileno(), 2)
            with contextlib.redirect_stdout(py_text), contextlib.redirect_stderr(py_text):
                yield out
        finally:
            libc.fflush(None)
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            text = tmp.read().decode("utf-8", "replace") + "\n" + py_text.getvalue()
            out.extend([x for x in text.splitlines() if x.strip()][-1:])


def _decode_exr(path: Path) -> np.ndarray:
    import OpenEXR

    with _native_output_captured() as native:
        try:
            return _read_exr(OpenEXR, path)
        except SceneError:
            raise
        except Exception as exc:  # the bindings raise RuntimeError / ValueError / KeyError
            error = exc
    text = native[0] if native else (str(error).splitlines() or [type(error).__name__])[-1]
    raise SceneError(path, f"corrupt or truncated OpenEXR file ({text.strip()})") from None


def _read_exr(OpenEXR: Any, path: Path) -> np.ndarray:  # noqa: N803 (the module's name)
    with OpenEXR.File(str(path), separate_channels=False, header_only=True) as f:
        lo, hi = f.header()["dataWindow"]
    _check_pixels(path, int(hi[0] - lo[0] + 1), int(hi[1] - lo[1] + 1))
    with OpenEXR.File(str(path)) as f:
        channels = f.channels()
        if "RGB" in channels:
            rgb = channels["RGB"].pixels
        elif "RGBA" in channels:
            rgb = channels["RGBA"].pixels[..., :3]
        elif {"R", "G", "B"} <= set(channels):
            rgb = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
        elif "Y" in channels:  # luminance only
            rgb = np.repeat(channels["Y"].pixels[..., None], 3, axis=-1)
        else:
            raise SceneError(path, f"no RGB channels in the EXR (has {sorted(channels)})")
    return np.asarray(rgb, dtype=np.float32)


def _decode_ldr(path: Path, data: bytes) -> np.ndarray:
    """An 8- or 16-bit sRGB JPEG/PNG as linear float32 RGB (values in [0, 1]: clipped light)."""
    import warnings

    from PIL import Image as PILImage

    from vkpbr.scene.color import srgb_to_linear

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PILImage.DecompressionBombWarning)
            pil = PILImage.open(io.BytesIO(data))
            _check_pixels(path, *pil.size)
            if pil.mode.startswith("I;16"):  # 16-bit grey PNG (Pillow reads RGB as 8 bits)
                codes = np.asarray(pil, dtype=np.float64)[..., None].repeat(3, -1) / 65535.0
            else:
                codes = np.asarray(pil.convert("RGB"), dtype=np.float64) / 255.0
    except (OSError, ValueError, SyntaxError, PILImage.DecompressionBombError) as exc:
        raise SceneError(path, f"corrupt or unreadable image ({exc})") from None
    return srgb_to_linear(codes).astype(np.float32)


def check_panorama(pixels: np.ndarray, source: object = "<array>") -> np.ndarray:
    """Validate an equirectangular panorama and make its pixels finite and non-negative.

    Parameters
    ----------
    pixels : (H, W, 3) or (H, W, 4) array, any real dtype (alpha is dropped), W == 2 H.
    source : what messages name (a file path).

    Returns
    -------
    (H, W, 3) float32, C-contiguous, every value finite and >= 0.

    Raises
    ------
    SceneError : not (H, W, 3|4), not 2:1 (one pixel of slack for odd widths), too many pixels.
    """
    a = np.asarray(pixels)
    if a.ndim != 3 or a.shape[2] not in (3, 4) or not np.issubdtype(a.dtype, np.number):
        raise SceneError(source, f"expected an (H, W, 3) RGB panorama, got shape {a.shape}")
    h, w = a.shape[:2]
    _check_pixels(Path(str(source)), w, h)
    if abs(w - 2 * h) > 1:
        raise SceneError(source, f"{w}x{h} is not an equirectangular panorama (width must be "
                                 "twice the height)")
    rgb = np.ascontiguousarray(a[..., :3], dtype=np.float32)
    bad = ~np.isfinite(rgb) | (rgb < 0)
    if bad.any():
        n = int(bad.any(axis=-1).sum())
        log.warning("%s: %d pixel(s) NaN, infinite or negative: clamped to [0, max float]",
                    source, n)
        rgb = np.nan_to_num(rgb, nan=0.0, posinf=np.finfo(np.float32).max, neginf=0.0)
        np.maximum(rgb, 0.0, out=rgb)
    return rgb


def load_panorama(path: str | os.PathLike[str]) -> np.ndarray:
    """Read an equirectangular .hdr / .pic / .exr environment, or an LDR .jpg / .png one
    (sRGB decoded to linear; its light is clipped at 1).

    Returns
    -------
    (H, W, 3) float32 linear radiance, W == 2 H (see `check_panorama`), row 0 = zenith.

    Raises
    ------
    SceneError : one line naming the file (missing, unreadable, unknown suffix, corrupt or
        truncated, not 2:1, too many pixels).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in ENV_SUFFIXES:
        raise SceneError(path, f"unknown environment format {suffix or '(no suffix)'!r} "
                               f"(expected {', '.join(ENV_SUFFIXES)})")
    if suffix == ".exr":
        _read_bytes(path)  # existence, regular file, byte limit
        rgb = _decode_exr(path)
    elif suffix in LDR_SUFFIXES:
        rgb = _decode_ldr(path, _read_bytes(path))
    else:
        rgb = _decode_hdr(path, _read_bytes(path))
    return check_panorama(rgb, path)


# --- the panorama's mapping (mirrored in shaders/env_common.glsl) -------------------------------
def direction_to_equirect(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) in [0, 1] of unit directions (..., 3)."""
    d = np.asarray(d, dtype=np.float64)
    u = 0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi)
    v = np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi
    return u, v


def equirect_to_direction(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Unit directions (..., 3) of panorama coordinates (the inverse of the above)."""
    phi = (np.asarray(u, dtype=np.float64) - 0.5) * 2.0 * np.pi
    theta = np.asarray(v, dtype=np.float64) * np.pi
    s = np.sin(theta)
    return np.stack([s * np.sin(phi), np.cos(theta), -s * np.cos(phi)], axis=-1)


def sample_equirect(pixels: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Bilinear lookup (wrapping in u, clamped in v) of (H, W, 3) at directions (..., 3)."""
    h, w = pixels.shape[:2]
    u, v = direction_to_equirect(d)
    x = u * w - 0.5
    y = np.clip(v * h - 0.5, 0.0, h - 1.0)
    x0 = np.floor(x).astype(np.int64)
    y0 = np.floor(y).astype(np.int64)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    x1, y1 = (x0 + 1) % w, np.minimum(y0 + 1, h - 1)
    x0 %= w
    p = pixels.astype(np.float64)
    top = p[y0, x0] * (1 - fx) + p[y0, x1] * fx
    bot = p[y1, x0] * (1 - fx) + p[y1, x1] * fx
    return top * (1 - fy) + bot * fy
