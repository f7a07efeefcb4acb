"""vkpbr.io: rendered arrays into image files, the `imageio.imwrite` of vkpbr.

The one place vkpbr encodes images: the CLI, the viewer's screenshots, Ray jobs
(vkpbr.distributed) and `vkpbr.show` all come here. Every write is atomic
(vkpbr/atomic.py): the file is encoded in memory, written to a temporary file beside the
target and renamed, so an interrupted or refused write never leaves a truncated file under
the final name.

    import vkpbr.io
    vkpbr.io.write_image("frame.png", rgba)                       # (H, W, 4) uint8 sRGB
    vkpbr.io.write_image("frame.depth.exr", frame["depth"], kind="depth")
    vkpbr.io.write_image("frame.instance.png", frame["instance"], kind="instance")

Kinds of array and the formats each takes (the suffix of the path picks the format):

- "color": (H, W, 4) (or (H, W, 3), (H, W)) uint8 sRGB as .png/.jpg/.bmp/.tif/.webp;
  float32 linear as .exr (channels R, G, B, A; ZIP compression, values exact) or .npy.
- "ids" (instance, semantic): (H, W) unsigned integers as 16-bit greyscale .png (ids up to
  65,535) or .npy (any dtype as given).
- "data" (depth, range, normals): float32 (H, W) as .exr (channel Y) or (H, W, 3) (channels
  R, G, B = x, y, z) or .npy. Infinite depth stays inf in both.

`write_image` also takes the renderer's output names for `kind` ("depth", "normal",
"instance", ...: `OUTPUT_KINDS`). `check_writable` and `check_output_path` fail at once, before
any rendering, when an output cannot be written. EXR goes through the ASWF's OpenEXR package
(a dependency; a missing one is a one-line error with the install command). Errors are
UsageError (what vkpbr refuses) or OutputError (what the file system refuses, naming the
path; an OSError too).
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from vkpbr.atomic import atomic_writer
from vkpbr.errors import UsageError

if TYPE_CHECKING:
    import numpy as np

__all__ = [
    "FORMATS",
    "IMAGE_SUFFIXES",
    "MAX_PNG_ID",
    "OUTPUT_KINDS",
    "OUTPUT_SUFFIXES",
    "Kind",
    "check_id_count",
    "check_output_path",
    "check_outputs",
    "check_writable",
    "encode_png",
    "output_kind",
    "output_path",
    "write_image",
    "write_image_atomic",
    "write_output",
    "write_outputs",
]

Kind = Literal["color", "ids", "data"]

IMAGE_SUFFIXES = frozenset({".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp"})
OUTPUT_SUFFIXES = IMAGE_SUFFIXES | {".npy", ".exr"}
FORMATS: dict[str, frozenset[str]] = {
    "color": OUTPUT_SUFFIXES,
    "ids": frozenset({".png", ".npy"}),
    "data": frozenset({".exr", ".npy"}),
}
MAX_PNG_ID = 65_535  # a 16-bit PNG's largest value

# Output name (render(outputs=...), --outputs) -> kind of file. The renderer's names.
OUTPUT_KINDS: dict[str, Kind] = {
    "color": "color",
    "depth": "data",
    "range": "data",
    "normal": "data",
    "normal_camera": "data",
    "normal_geometric": "data",
    "motion": "data",  # (H, W, 2): EXR channels R (x) and G (y), in pixels
    "ao": "data",
    "instance": "ids",
    "semantic": "ids",
}

_EXR_INSTALL = "pip install 'OpenEXR>=3.5'"


def check_writable(path: Path, option: str = "--out") -> None:
    """Raise UsageError when `path` cannot be written as a file: a name no file can have, a
    folder, a folder that is missing or is a file, a folder that takes no new file (read-only,
    /proc, full): vkpbr.user_paths.check_writable_file, which tries."""
    from vkpbr.user_paths import check_writable_file

    check_writable_file(path, option)


def output_kind(name: str, option: str = "--outputs") -> Kind:
    """The kind of file output `name` is written as; UsageError listing the known names."""
    kind = OUTPUT_KINDS.get(name) if isinstance(name, str) else None
    if kind is None:
        raise UsageError(f"{option}: unknown output {name!r} (known: {', '.join(OUTPUT_KINDS)})")
    return kind


def _suffix(path: Path, kind: Kind, option: str) -> str:
    suffix = path.suffix.lower()
    allowed = FORMATS.get(kind)
    if allowed is None:
        raise UsageError(f"{option} {path}: unknown kind of output {kind!r} (color, ids or data)")
    if suffix not in allowed:
        if kind == "color":
            raise UsageError(f"{option} {path}: unknown image type {suffix or 'without suffix'!r} "
                             "(use .png, .jpg, .exr or .npy)")
        hint = {"ids": "ids are .png (16-bit, up to 65,535) or .npy",
                "data": "float data is .exr or .npy"}[kind]
        raise UsageError(f"{option} {path}: {suffix or 'no suffix'} is not a format for {kind} "
                         f"output ({hint})")
    return suffix


def _openexr(path: Path, option: str):  # noqa: ANN202 - the OpenEXR module
    try:
        import OpenEXR
    except ImportError:
        raise UsageError(f"{option} {path}: writing EXR needs the OpenEXR package: "
                         f"{_EXR_INSTALL}") from None
    if not hasattr(OpenEXR, "File"):  # the pre-3.3 bindings
        raise UsageError(f"{option} {path}: the installed OpenEXR is too old: {_EXR_INSTALL}")
    return OpenEXR


def check_output_path(path: Path, kind: Kind = "color", option: str = "--out") -> None:
    """Everything about writing `kind` to `path` that can fail before rendering: the folder
    (`check_writable`), the suffix for the kind, and the OpenEXR package for .exr."""
    check_writable(path, option)
    if _suffix(path, kind, option) == ".exr":
        _openexr(path, option)


def check_id_count(count: int, path: Path, option: str = "--out") -> None:
    """Before rendering: a 16-bit PNG cannot hold ids above 65,535 (ids 1..count, 0 is the
    background). UsageError naming the count and the way out (.npy)."""
    if path.suffix.lower() == ".png" and count > MAX_PNG_ID:
        raise UsageError(f"{option} {path}: {count:,} ids do not fit a 16-bit PNG (at most "
                         f"{MAX_PNG_ID:,}); write .npy instead")


def _encode_pil(image: np.ndarray, suffix: str, path: Path, option: str) -> bytes:
    import numpy as np
    from PIL import Image

    if image.dtype == np.uint8:
        if not (image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (1, 3, 4))):
            raise UsageError(f"{option} {path}: an 8-bit image must be (H, W), (H, W, 3) or "
                             f"(H, W, 4), got shape {image.shape}")
        if image.ndim == 3 and image.shape[2] == 1:
            image = image[..., 0]
        if suffix in {".jpg", ".jpeg"} and image.ndim == 3:
            image = image[..., :3]  # JPEG has no alpha
    else:
        raise UsageError(f"{option} {path}: {image.dtype} data needs a .npy (or .exr) file; "
                         f"{suffix} holds 8-bit colour")
    fmt = Image.registered_extensions()[suffix]
    # PNG at zlib level 1: 4.5x faster than Pillow's default 6 for a 1080p render
    # (0.21 vs 0.94 s), files ~12% larger; the encode would otherwise outlast the render.
    extra = {"compress_level": 1} if fmt == "PNG" else {}
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(out, format=fmt, **extra)
    return out.getvalue()


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of an (H, W), (H, W, 3) or (H, W, 4) uint8 image (zlib level 1)."""
    return _encode_pil(image, ".png", Path("<image>"), "encode_png:")


def _encode_ids(ids: np.ndarray, path: Path, option: str) -> bytes:
    import numpy as np
    from PIL import Image

    if ids.ndim != 2 or ids.dtype.kind not in "ui":
        raise UsageError(f"{option} {path}: ids must be (H, W) integers, got {ids.dtype} of "
                         f"shape {ids.shape}")
    if ids.size:
        lo, hi = int(ids.min()), int(ids.max())
        if lo < 0 or hi > MAX_PNG_ID:
            bad = lo if lo < 0 else hi
            raise UsageError(f"{option} {path}: id {bad:,} does not fit a 16-bit PNG (0 to "
                             f"{MAX_PNG_ID:,}); write .npy instead")
    out = io.BytesIO()
    # Pillow's "I;16" mode is a 16-bit greyscale PNG (colour type 0, bit depth 16).
    Image.fromarray(np.ascontiguousarray(ids, dtype=np.uint16)).save(out, format="PNG",
                                                                     compress_level=1)
    return out.getvalue()


def _exr_channels(array: np.ndarray, path: Path, option: str) -> dict[str, np.ndarray]:
    import numpy as np

    if array.dtype.kind != "f":
        raise UsageError(f"{option} {path}: EXR holds float data, got {array.dtype} (render "
                         "linear colour for .exr, or write .png)")
    a = np.ascontiguousarray(array, dtype=np.float16 if array.dtype == np.float16 else np.float32)
    if a.ndim == 2:
        return {"Y": a}
    if a.ndim == 3 and a.shape[2] == 1:
        return {"Y": np.ascontiguousarray(a[..., 0])}
    if a.ndim == 3 and a.shape[2] == 2:  # a flow field (the motion output): R = x, G = y
        return {"R": np.ascontiguousarray(a[..., 0]), "G": np.ascontiguousarray(a[..., 1])}
    if a.ndim == 3 and a.shape[2] in (3, 4):
        return {"RGB" if a.shape[2] == 3 else "RGBA": a}
    raise UsageError(f"{option} {path}: EXR takes (H, W), (H, W, 2), (H, W, 3) or (H, W, 4) arrays, got "
                     f"shape {array.shape}")


def write_output(path: Path, array: np.ndarray, kind: Kind = "color", option: str = "--out") -> None:
    """Write one output array to `path` atomically, in the format its suffix names.

    Parameters
    ----------
    path : the file; its suffix must be one of `FORMATS[kind]`.
    array : "color": (H, W, 4) uint8 sRGB for 8-bit formats, float32 linear for .exr/.npy;
        "ids": (H, W) uint32 (0 = background); "data": (H, W) or (H, W, 3) float32.
    kind : "color", "ids" or "data" (`output_kind(name)` maps an output name to it).
    option : what error messages name (the command-line option, or the API function).

    Raises
    ------
    UsageError : a suffix the kind does not take, an array the format cannot hold (float in a
        PNG, an id above 65,535 in a PNG), EXR without the OpenEXR package. Nothing is written.
    OutputError : from the file system (one line naming `path`; an OSError too); nothing is
        left under `path`.
    """
    import numpy as np

    path = Path(path)
    suffix = _suffix(path, kind, option)
    if not isinstance(array, np.ndarray):
        raise UsageError(f"{option} {path}: expected a NumPy array, got {type(array).__name__}")
    # Encode first, in memory: a refused array leaves no file, not even a temporary one.
    if suffix == ".npy":
        buf = io.BytesIO()
        np.save(buf, array, allow_pickle=False)
        data = buf.getvalue()
    elif suffix == ".exr":
        OpenEXR = _openexr(path, option)
        channels = _exr_channels(array, path, option)
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        buf = io.BytesIO()
        OpenEXR.File(header, channels).write(buf)
        data = buf.getvalue()
    elif kind == "ids":
        data = _encode_ids(array, path, option)
    else:
        data = _encode_pil(array, suffix, path, option)
    with atomic_writer(path) as f:
        f.write(data)


def write_image(path: str | os.PathLike[str], array: np.ndarray, kind: str = "color") -> None:
    """Write a rendered array to `path` atomically, in the format its suffix names.

    Parameters
    ----------
    path : the file: .png/.jpg/.jpeg/.bmp/.tif/.tiff/.webp (8-bit colour), .png (16-bit
        ids), .exr (float colour or data) or .npy (any array); `FORMATS[kind]` lists what
        each kind takes.
    array : for "color", (H, W, 4), (H, W, 3) or (H, W) uint8 sRGB for the 8-bit formats,
        float32 linear colour for .exr; for "ids", (H, W) integers, 0 to 65,535 in a PNG; for
        "data", (H, W) or (H, W, 3) float32 (depth and range in scene units, normals as
        unit vectors). A .npy file holds any array as given.
    kind : "color", "ids" or "data", or one of the renderer's output names (`OUTPUT_KINDS`:
        "color", "depth", "range", "normal", "normal_camera", "normal_geometric", "ao",
        "instance", "semantic"), which name their kind.

    Raises
    ------
    UsageError : an unknown kind, a suffix the kind does not take, an array the format cannot
        hold (float in a PNG, an id above 65,535 in a PNG), EXR without the OpenEXR package.
        Nothing is written.
    OutputError : from the file system (one line naming `path`; an OSError too); nothing is
        left under `path`.
    """
    file_kind = None  # a kind of file ("ids"), else the kind an output name ("instance") has
    if isinstance(kind, str):
        file_kind = kind if kind in FORMATS else OUTPUT_KINDS.get(kind)
    if file_kind is None:
        raise UsageError(f"write_image: unknown kind {kind!r} (color, ids, data or an output "
                         f"name: {', '.join(OUTPUT_KINDS)})")
    write_output(Path(path), array, file_kind, "write_image:")


def write_image_atomic(path: Path, image: np.ndarray) -> None:
    """Write a colour image to `path` by its suffix: `write_output(path, image, "color")`.

    Parameters
    ----------
    path : .png, .jpg/.jpeg, .bmp, .tif/.tiff, .webp (uint8 images), .exr (float linear
        colour) or .npy (any array).
    image : (H, W, 4) uint8 sRGB (JPEG keeps RGB), or float32 linear colour for .exr/.npy;
        any array for .npy (e.g. (H, W) float32 depth).
    """
    write_output(Path(path), image, "color")


def output_path(out: Path, name: str) -> Path:
    """Where dataset output `name` of the frame written to `out` goes: beside it, by kind
    (frame.png -> frame.depth.exr, frame.instance.png)."""
    out = Path(out)
    return out.with_name(f"{out.stem}.{name}{'.png' if output_kind(name) == 'ids' else '.exr'}")


def check_outputs(out: Path, names: tuple[str, ...], ids: int, option: str = "--outputs") -> None:
    """Before rendering: each output of the frame `out` can be written (`check_output_path`),
    and `ids` instance ids fit the id images."""
    for name in names:
        path = output_path(out, name)
        check_output_path(path, output_kind(name), option)
        if output_kind(name) == "ids":
            check_id_count(ids, path, option)


def write_outputs(out: Path, frame: dict, names: tuple[str, ...], option: str = "--outputs") -> None:
    """Write outputs `names` of `frame` (a dict of arrays, `Renderer.render(outputs=...)`)
    beside the frame `out`, each atomically."""
    for name in names:
        write_output(output_path(out, name), frame[name], output_kind(name), option)
