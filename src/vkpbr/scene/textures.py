# Decode a scene's images to RGBA8 NumPy arrays in parallel. Pillow releases the GIL while it
# decodes PNG/JPEG, so a thread pool scales with cores without pickling pixels between processes.
# Failures never raise: a missing or corrupt texture is returned as None and the renderer binds
# its own 1x1 default in its place. Diagnostics go through `logging` (logger vkpbr.scene.*),
# one summary line per kind of problem, never one line per texture: a scene whose 70 textures
# are missing says so once (check_texture_files, from load_scene), not 140 times.

from __future__ import annotations

import errno
import io
import logging
import os
import re
import threading
import warnings
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from PIL import Image as PILImage

from vkpbr.errors import SceneError
from vkpbr.scene.gltf_codecs import KTX2_MAGIC, decode_ktx2, ktx2_blocks, ktx2_size
from vkpbr.scene.limits import limits
from vkpbr.scene.resources import is_regular_file, read_resource
from vkpbr.scene.types import Image, Scene

__all__ = ["TextureBudget", "check_texture_files", "decode_image", "decode_images",
           "missing_texture_files"]

log = logging.getLogger(__name__)


def missing_texture_files(images: Sequence[Image]) -> list[Image]:
    """The images whose only source is a file that is not there (pixels and embedded bytes
    need no file), or one the path policy refused (`Image.refused`), in order. "Not there"
    includes a name the OS rejects (ENAMETOOLONG): never an exception."""
    return [img for img in images if img.pixels is None and img.data is None
            and img.path is not None and (img.refused or not is_regular_file(img.path))]


def _shown(file: Path, folder: Path) -> str:
    """`file` relative to `folder` when it lies below it, else absolute (for messages; a NUL
    byte shown as \\0, so that the line stays one printable line)."""
    def rel(f: Path, d: Path) -> str | None:
        try:
            return f.relative_to(d).as_posix()
        except ValueError:
            return None

    shown = rel(Path(file), Path(folder))
    if shown is None:
        try:
            shown = rel(Path(file).resolve(), Path(folder).resolve()) or str(Path(file).resolve())
        except (OSError, ValueError):  # a name the OS rejects (a NUL byte): as written
            shown = str(file)
    return shown.replace("\0", "\\0")


def check_texture_files(scene: Scene, source: str | os.PathLike[str], strict: bool = False) -> int:
    """Report the scene's texture files that do not exist or that the path policy refused
    (vkpbr.scene.resources), in one line.

    Parameters
    ----------
    scene : a loaded scene (its `images`).
    source : the file it came from; messages name it, and texture paths are shown relative
        to its folder.
    strict : raise instead of logging.

    Returns
    -------
    The number of textures not loaded (0: nothing logged). Otherwise one WARNING on the
    "vkpbr.scene.textures" logger: "N of M textures not found next to SOURCE (first: F), K of
    M textures of SOURCE outside the scene's folder (first: G; pass --allow-outside-paths ...);
    rendering with default values (...)"; the renderer binds its defaults in their place.

    Raises
    ------
    SceneError : with `strict`, when any texture is missing or refused (one line: the file,
        the counts and the first texture of each kind).
    """
    missing = missing_texture_files(scene.images)
    if not missing:
        return 0
    source = Path(source)
    groups: dict[str, list[Image]] = {}
    for img in missing:
        groups.setdefault(img.refused or "", []).append(img)
    n = len(scene.images)
    parts = []
    for reason, imgs in groups.items():
        first = _shown(Path(imgs[0].path), source.parent)  # type: ignore[arg-type]
        if not reason:
            where = "not found" if strict else f"not found next to {source}"
            parts.append(f"{len(imgs)} of {n} textures {where} (first: {first})")
        else:
            of = "" if strict else f" of {source}"
            hint = ("; pass --allow-outside-paths (allow_outside_paths=True) to read them"
                    if reason == "outside the scene's folder" else "")
            parts.append(f"{len(imgs)} of {n} textures{of} {reason} (first: {first}{hint})")
    if strict:
        raise SceneError(source, ", ".join(parts))
    log.warning("%s; rendering with default values (pass strict=True / --strict to make this "
                "an error)", ", ".join(parts))
    return len(missing)


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


class TextureBudget:
    """The decoded RGBA8 bytes one scene's textures may take together (VKPBR_MAX_TEXTURE_BYTES),
    shared by the decoding threads. Each texture takes its share from its header, before its
    pixels are decoded; the first that does not fit makes every later one stop at once.

    Parameters
    ----------
    cap : bytes allowed (default: `limits().max_texture_bytes`).
    """

    def __init__(self, cap: int | None = None) -> None:
        self.cap = limits().max_texture_bytes if cap is None else cap
        self.used = 0
        self.over: str | None = None  # the first texture that did not fit, and its size
        self._lock = threading.Lock()

    def take(self, nbytes: int, name: str, size: tuple[int, int]) -> None:
        """Reserve `nbytes` for texture `name` of `size` (W, H); raises _OverBudget."""
        with self._lock:
            if self.over is None and self.used + nbytes > self.cap:
                self.over = (f"{name} ({size[0]}x{size[1]}, {nbytes:,} bytes) after "
                             f"{self.used:,} bytes of earlier textures")
            if self.over is not None:
                raise _OverBudget
            self.used += nbytes

    def error(self, source: object) -> SceneError:
        """The one-line error naming the scene file, the texture and the option."""
        return SceneError(source, f"its textures decode to more than {self.cap:,} bytes of "
                                  f"RGBA8 (at {self.over}); raise the limit with "
                                  "VKPBR_MAX_TEXTURE_BYTES")


class _OverBudget(Exception):  # noqa: N818 - internal signal, never leaves decode_images
    """A texture did not fit in the TextureBudget (never caught as "undecodable")."""


def decode_image(image: Image, max_size: int | None = None,
                 budget: TextureBudget | None = None, blocks: str | None = None,
                 block_levels: list[np.ndarray] | None = None
                 ) -> tuple[np.ndarray | None, list[str]]:
    """Decode one image.

    `blocks` ("bc7"): a KTX2 (Basis Universal) image with its full mip chain, not downscaled,
    is also transcoded to those GPU blocks, its levels appended to `block_levels`.

    `budget`, if given, is charged the decoded bytes before decoding; a texture that does not
    fit raises (decode_images turns that into the scene's SceneError).

    Returns
    -------
    pixels : (H, W, 4) uint8 RGBA, or None when the image cannot be had.
    messages : (kind, text) notes, kind "missing", "undecodable" or "downscaled"; collected
        so that `decode_images` can summarise them in image order after the threads finish.
    """
    messages: list[tuple[str, str]] = []
    if image.refused and image.pixels is None and image.data is None:
        # Refused by the path policy when the scene was loaded: never opened (load_scene has
        # said why in its summary line).
        messages.append(("missing", f"{image.name} ({image.refused})"))
        return None, messages
    try:
        if budget is not None and budget.over is not None:
            raise _OverBudget  # another thread went over: decode nothing more
        with np.errstate(all="ignore"):
            return _decode(image, max_size, messages, budget, blocks, block_levels), messages
    except (FileNotFoundError, NotADirectoryError):
        messages.append(("missing", image.name))
    except PILImage.UnidentifiedImageError:  # "cannot identify image file <_io.BytesIO ...>"
        messages.append(("undecodable", f"{image.name} ({_what_it_is(image)})"))
    except OSError as exc:
        # Pillow reports some corrupt data as OSError (no errno); a name too long for the OS
        # is a texture that is not there, as load_scene's summary already counted it.
        if exc.errno == errno.ENAMETOOLONG:
            messages.append(("missing", f"{image.name} (name too long)"))
        else:
            messages.append(("undecodable", f"{image.name} ({_format_of(image)}"
                                            f"{_no_repr(exc.strerror or str(exc), image)})"))
    except (ValueError, SyntaxError, PILImage.DecompressionBombError) as exc:
        # ...and others as ValueError/SyntaxError, depending on the codec.
        messages.append(("undecodable", f"{image.name} ({_format_of(image)}"
                                        f"{_no_repr(str(exc), image)})"))
    return None, messages


# What the first bytes of a file say it is: for the message about one that cannot be decoded.
_SIGNATURES = ((b"\x89PNG\r\n\x1a\n", "PNG"), (b"\xff\xd8\xff", "JPEG"), (KTX2_MAGIC, "KTX2"),
               (b"GIF8", "GIF"), (b"BM", "BMP"), (b"DDS ", "DDS"), (b"II*\x00", "TIFF"),
               (b"MM\x00*", "TIFF"), (b"\x00\x00\x00\x0cjP  ", "JPEG 2000"),
               (b"#?RADIANCE", "Radiance HDR"), (b"v/1\x01", "OpenEXR"), (b"glTF", "GLB"))


def _head(image: Image) -> bytes:
    try:
        return image.data[:16] if image.data is not None else (
            read_resource(image.path, max_bytes=16) if image.path is not None else b"")
    except OSError:
        return b""


def _format_of(image: Image) -> str:
    """"PNG data: " (the format the first bytes show, for a codec's own message), or ""."""
    head = _head(image)
    name = next((n for magic, n in _SIGNATURES if head.startswith(magic)), None)
    return f"{name} data: " if name else ""


def _what_it_is(image: Image) -> str:
    """'not a decodable image: found <format> data' from the data's first bytes."""
    head = _head(image)
    if head[:4] == b"RIFF" and head[8:12] == b"WEBP":
        kind = "WebP data (corrupt, or a variant Pillow does not read)"
    else:
        name = next((n for magic, n in _SIGNATURES if head.startswith(magic)), None)
        if name is not None:
            kind = f"{name} data that cannot be decoded (corrupt or truncated)"
        elif not head:
            kind = "an empty file"
        elif head.lstrip()[:1] in (b"<", b"{", b"["):
            kind = "text (HTML, XML or JSON), not an image"
        else:
            kind = f"data of no known image format (first bytes {head[:8].hex(' ')})"
    declared = f"; declared {image.mime_type}" if image.mime_type else ""
    return f"not a decodable image: {kind}{declared}"


def _no_repr(text: str, image: Image) -> str:
    """A codec's message without Python object reprs (Pillow names its stream by repr)."""
    return re.sub(r"<_io\.BytesIO object at 0x[0-9a-f]+>", image.name, text)


def _decode(image: Image, max_size: int | None, messages: list[tuple[str, str]],
            budget: TextureBudget | None = None, blocks: str | None = None,
            block_levels: list[np.ndarray] | None = None) -> np.ndarray:
    """decode_image's body; raises on failure, appends notes (downscaling) to `messages`."""
    if image.pixels is not None:
        px = np.asarray(image.pixels)
        if px.ndim != 3 or px.shape[2] != 4 or px.dtype != np.uint8:
            raise ValueError(f"pixels must be (H, W, 4) uint8, not {px.shape} {px.dtype}")
        if not _too_big(px.shape[1], px.shape[0], max_size):
            if budget is not None:
                budget.take(px.nbytes, image.name, (px.shape[1], px.shape[0]))
            return np.ascontiguousarray(px)
        pil = PILImage.fromarray(px, "RGBA")
    else:
        if image.data is not None:
            source = io.BytesIO(image.data)
        elif image.path is not None:
            # Regular files only, opened non-blocking: a FIFO or device named as a texture
            # is refused instead of blocking or being read forever.
            cap = limits().max_texture_file_bytes
            data = read_resource(image.path, max_bytes=cap + 1)
            if len(data) > cap:
                raise ValueError(f"file is over the {cap:,}-byte texture file limit "
                                 "(VKPBR_MAX_TEXTURE_FILE_BYTES)")
            source = io.BytesIO(data)
        else:
            raise ValueError("no pixels, data or path")
        if source.getbuffer()[:12] == KTX2_MAGIC:  # KHR_texture_basisu: not a Pillow format
            return _decode_ktx2(image, source.getvalue(), max_size, messages, budget, blocks,
                                block_levels)
        # Pillow's own decompression-bomb limit (DecompressionBombError) still applies.
        with warnings.catch_warnings():  # over Pillow's bomb warning is over our limit too
            warnings.simplefilter("ignore", PILImage.DecompressionBombWarning)
            pil = PILImage.open(source)  # reads the header only
        cap = limits().max_texture_pixels
        if pil.width * pil.height > cap:  # refused before a byte is decoded
            raise ValueError(f"{pil.width}x{pil.height} is over the {cap:,}-pixel texture limit "
                             "(VKPBR_MAX_TEXTURE_PIXELS)")
        if budget is not None:  # the bytes this texture will take, before decoding it
            w, h = _out_size(pil.width, pil.height, max_size)
            budget.take(4 * w * h, image.name, (w, h))
        if max_size and pil.format == "JPEG":
            pil.draft("RGB", (max_size, max_size))  # JPEG can decode at 1/2..1/8 scale: faster
        pil.load()
    if _too_big(pil.width, pil.height, max_size):
        if budget is not None and image.pixels is not None:
            w, h = _out_size(pil.width, pil.height, max_size)
            budget.take(4 * w * h, image.name, (w, h))
        size = _out_size(pil.width, pil.height, max_size)
        messages.append(("downscaled",
                         f"{image.name}: {pil.width}x{pil.height} downscaled to {size[0]}x{size[1]}"))
        if pil.mode not in ("RGB", "RGBA", "L", "LA"):
            pil = PILImage.fromarray(_to_rgba8(pil), "RGBA")  # resize wide/palette modes as RGBA8
        pil = pil.resize(size, PILImage.Resampling.LANCZOS)
    return _to_rgba8(pil)


def _decode_ktx2(image: Image, data: bytes, max_size: int | None, messages: list[tuple[str, str]],
                 budget: TextureBudget | None, blocks: str | None = None,
                 block_levels: list[np.ndarray] | None = None) -> np.ndarray:
    """A KTX2 texture -> RGBA8 under the same limits as Pillow's formats (pixel cap and
    budget from the header, before transcoding); with `blocks`, its levels as those GPU
    blocks too, into `block_levels`, when it is not downscaled (decode_image)."""
    width, height = ktx2_size(data)
    cap = limits().max_texture_pixels
    if width * height > cap:
        raise ValueError(f"{width}x{height} is over the {cap:,}-pixel texture limit "
                         "(VKPBR_MAX_TEXTURE_PIXELS)")
    w, h = _out_size(width, height, max_size)
    if budget is not None:
        budget.take(4 * w * h, image.name, (w, h))
    px = decode_ktx2(data)
    if (w, h) == (width, height):
        if blocks and block_levels is not None:
            _add_blocks(image, data, blocks, block_levels, budget)
        return px
    messages.append(("downscaled", f"{image.name}: {width}x{height} downscaled to {w}x{h}"))
    return _to_rgba8(PILImage.fromarray(px, "RGBA").resize((w, h), PILImage.Resampling.LANCZOS))


def _add_blocks(image: Image, data: bytes, blocks: str, block_levels: list[np.ndarray],
                budget: TextureBudget | None) -> None:
    """`data`'s levels as GPU blocks into `block_levels` (none for a file without its mip
    chain). The RGBA8 decode worked, so a transcoder refusal here leaves the texture RGBA8
    rather than undecodable."""
    try:
        levels = ktx2_blocks(data, blocks) or []
    except ValueError:
        return
    if levels and budget is not None:
        budget.take(sum(a.nbytes for a in levels), image.name, ktx2_size(data))
    block_levels.extend(levels)


def _too_big(width: int, height: int, max_size: int | None) -> bool:
    return max_size is not None and max(width, height) > max_size


def _out_size(width: int, height: int, max_size: int | None) -> tuple[int, int]:
    """(W, H) after downscaling to at most `max_size` (aspect kept), as decoded."""
    if not _too_big(width, height, max_size):
        return width, height
    assert max_size is not None
    scale = max_size / max(width, height)
    return max(1, round(width * scale)), max(1, round(height * scale))


def decode_images(
    scene_or_images: Scene | Sequence[Image],
    max_size: int | None = None,
    workers: int | None = None,
    source: str | os.PathLike[str] | None = None,
    blocks: str | None = None,
    block_levels: dict[int, list[np.ndarray]] | None = None,
) -> list[np.ndarray | None]:
    """Decode every image of a scene (or a list of images) to RGBA8, in parallel.

    Parameters
    ----------
    scene_or_images : a Scene (its `images`) or a sequence of Image.
    max_size : images wider or taller than this are downscaled (aspect kept).
    workers : decoding threads; default min(16, CPU count) (the H200 machine has 16 cores;
        decoding is the largest part of a scene's load there: benchmarks/bench_load.py).
    source : the scene file, for the total-bytes error (default: the Scene's `source`, else
        its name).
    blocks, block_levels : "bc7" and a dict: the KTX2 (Basis Universal) images that hold
        their full mip chain and are not downscaled are also transcoded to BC7, every level
        into `block_levels[image index]` ((blocks high, blocks wide, 16) uint8 each), for a
        GPU that samples BC7 (a quarter of RGBA8's memory, the file's own mips).

    Returns
    -------
    One entry per image, in order: (H, W, 4) uint8 C-contiguous RGBA, or None for an image
    that is missing or undecodable. The caller supplies the default for None (the renderer
    binds a 1x1 white, or flat-normal, texture), because only it knows which default suits
    the slot the image is used in.

    Raises
    ------
    SceneError : naming the scene, when the decoded RGBA8 bytes of all its textures would pass
        VKPBR_MAX_TEXTURE_BYTES (`limits().max_texture_bytes`, default 4 GiB). Checked from
        each header before that texture is decoded; nothing more is decoded after.

    Notes
    -----
    Logged on "vkpbr.scene.textures", at most one line per kind: undecodable images and
    downscaled images as WARNING (count and first), missing files as INFO only, because
    `load_scene` has already said so in its own summary line (check_texture_files).
    """
    if isinstance(scene_or_images, Scene):
        images = scene_or_images.images
        source = source or scene_or_images.source or scene_or_images.name
    else:
        images = scene_or_images
    if not images:
        return []
    workers = workers or min(16, os.cpu_count() or 1)
    if max_size is not None and max_size < 1:
        raise ValueError(f"max_size must be >= 1, got {max_size}")
    budget = TextureBudget()
    levels: list[list[np.ndarray]] = [[] for _ in images]
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        futures = [pool.submit(decode_image, img, max_size, budget, blocks, levels[i])
                   for i, img in enumerate(images)]
    if budget.over is not None:  # every future is done (the pool is shut down)
        raise budget.error(source or "the scene's textures")
    results = [f.result() for f in futures]
    if block_levels is not None:
        block_levels.update({i: lv for i, lv in enumerate(levels) if lv and results[i][0] is not None})
    notes: dict[str, list[str]] = {}
    for _, messages in results:
        for kind, text in messages:
            notes.setdefault(kind, []).append(text)
    n = len(images)
    if "undecodable" in notes:
        bad = notes["undecodable"]
        log.warning("%d of %d textures cannot be decoded (first: %s); using default values",
                    len(bad), n, bad[0])
    if "downscaled" in notes:
        small = notes["downscaled"]
        log.warning("%d of %d textures downscaled to at most %d px (first: %s)",
                    len(small), n, max_size, small[0])
    if "missing" in notes:
        gone = notes["missing"]
        log.info("%d of %d texture files not found (first: %s); using default values",
                 len(gone), n, gone[0])
    return [pixels for pixels, _ in results]
