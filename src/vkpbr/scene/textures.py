# Decode a scene's images to RGBA8 NumPy arrays in parallel. Pillow releases the GIL while it
# decodes PNG/JPEG, so a thread pool scales with cores without pickling pixels between processes.
# Failures never raise: a missing or corrupt texture is warned about (one line naming the file)
# and returned as None, and the renderer binds its own 1x1 default in its place.

from __future__ import annotations

import io
import os
import warnings
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from PIL import Image as PILImage

from vkpbr.scene.types import Image, Scene

__all__ = ["decode_image", "decode_images"]


def _to_rgba8(img: PILImage.Image) -> np.ndarray:
    """Any Pillow mode -> (H, W, 4) uint8, scaling wide modes instead of clipping them."""
    mode = img.mode
    if mode.startswith("I;16") or mode == "I":
        # Pillow's convert("L") clips 16-bit values at 255; scale 0..65535 -> 0..255 instead.
        wide = np.asarray(img).astype(np.float64)
        grey = np.clip(np.rint(wide / 257.0), 0, 255).astype(np.uint8)
        return _grey_to_rgba(grey)
    if mode == "F":
        grey = np.clip(np.rint(np.asarray(img) * 255.0), 0, 255).astype(np.uint8)
        return _grey_to_rgba(grey)
    if mode != "RGBA":
        # P with tRNS, LA, La, PA, 1, L, CMYK, YCbCr, RGBX...: Pillow's conversions are correct
        # for these (palette transparency becomes alpha, grey is replicated into RGB).
        img = img.convert("RGBA")
    return np.asarray(img, dtype=np.uint8).copy()


def _grey_to_rgba(grey: np.ndarray) -> np.ndarray:
    out = np.empty((*grey.shape, 4), np.uint8)
    out[..., :3] = grey[..., None]
    out[..., 3] = 255
    return out


def decode_image(image: Image, max_size: int | None = None) -> tuple[np.ndarray | None, list[str]]:
    """Decode one image.

    Returns
    -------
    pixels : (H, W, 4) uint8 RGBA, or None when the image cannot be had.
    messages : warnings to emit (collected so the caller can emit them from the main thread
        in image order; `warnings` state is process-global and not thread-safe).
    """
    messages: list[str] = []
    try:
        with np.errstate(all="ignore"):
            return _decode(image, max_size, messages), messages
    except FileNotFoundError:
        messages.append(f"{image.name}: texture file not found; using a default")
    except (OSError, ValueError, SyntaxError, PILImage.DecompressionBombError) as exc:
        # Pillow reports corrupt data as OSError/ValueError/SyntaxError depending on the codec.
        messages.append(f"{image.name}: cannot decode ({exc}); using a default")
    return None, messages


def _decode(image: Image, max_size: int | None, messages: list[str]) -> np.ndarray:
    """decode_image's body; raises on failure, appends notes (downscaling) to `messages`."""
    if image.pixels is not None:
        px = np.asarray(image.pixels)
        if px.ndim != 3 or px.shape[2] != 4 or px.dtype != np.uint8:
            raise ValueError(f"pixels must be (H, W, 4) uint8, not {px.shape} {px.dtype}")
        if not _too_big(px.shape[1], px.shape[0], max_size):
            return np.ascontiguousarray(px)
        pil = PILImage.fromarray(px, "RGBA")
    else:
        source = io.BytesIO(image.data) if image.data is not None else image.path
        if source is None:
            raise ValueError("no pixels, data or path")
        # Pillow's own decompression-bomb limit (DecompressionBombError) still applies.
        pil = PILImage.open(source)
        if max_size and pil.format == "JPEG":
            pil.draft("RGB", (max_size, max_size))  # JPEG can decode at 1/2..1/8 scale: faster
        pil.load()
    if _too_big(pil.width, pil.height, max_size):
        assert max_size is not None
        scale = max_size / max(pil.width, pil.height)
        size = (max(1, round(pil.width * scale)), max(1, round(pil.height * scale)))
        messages.append(f"{image.name}: {pil.width}x{pil.height} downscaled to {size[0]}x{size[1]}")
        if pil.mode not in ("RGB", "RGBA", "L", "LA"):
            pil = PILImage.fromarray(_to_rgba8(pil), "RGBA")  # resize wide/palette modes as RGBA8
        pil = pil.resize(size, PILImage.Resampling.LANCZOS)
    return _to_rgba8(pil)


def _too_big(width: int, height: int, max_size: int | None) -> bool:
    return max_size is not None and max(width, height) > max_size


def decode_images(
    scene_or_images: Scene | Sequence[Image],
    max_size: int | None = None,
    workers: int | None = None,
) -> list[np.ndarray | None]:
    """Decode every image of a scene (or a list of images) to RGBA8, in parallel.

    Parameters
    ----------
    scene_or_images : a Scene (its `images`) or a sequence of Image.
    max_size : images wider or taller than this are downscaled (aspect kept), with a warning.
    workers : decoding threads; default min(8, CPU count).

    Returns
    -------
    One entry per image, in order: (H, W, 4) uint8 C-contiguous RGBA, or None for an image
    that is missing or undecodable (a one-line warning names it). The caller supplies the
    default for None (the renderer binds a 1x1 white, or flat-normal, texture), because only
    it knows which default suits the slot the image is used in.
    """
    images = scene_or_images.images if isinstance(scene_or_images, Scene) else scene_or_images
    if not images:
        return []
    workers = workers or min(8, os.cpu_count() or 1)
    if max_size is not None and max_size < 1:
        raise ValueError(f"max_size must be >= 1, got {max_size}")
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        results = list(pool.map(lambda img: decode_image(img, max_size), images))
    for _, messages in results:
        for message in messages:
            warnings.warn(message, stacklevel=2)
    return [pixels for pixels, _ in results]
