"""Notebook display: `vkpbr.show(image)` wraps an array so Jupyter shows it inline.

Renders stay plain NumPy arrays; `show` is the one place that returns a wrapper, `Shown`,
whose `_repr_png_` IPython calls when it is a cell's value (no IPython import needed here).
Inside a loop, `IPython.display.display(vkpbr.show(image))`. What is shown:

- (H, W, 4) / (H, W, 3) / (H, W) uint8: as is (sRGB colour, greyscale);
- float (H, W, 3|4): linear colour, clipped to [0, 1] and sRGB-encoded (alpha kept linear);
- float (H, W): depth or range, the finite values stretched to black (near) .. white (far),
  inf/nan (the background) black;
- float (H, W, 3) normals are shown as colour, so pass `(n + 1) / 2` for the usual view;
- integer (H, W) ids: 0 (background) black, every other id a fixed colour (a hash), so
  neighbouring ids differ.

The PNG comes from `vkpbr.io.encode_png`, the encoder every written PNG goes through.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from vkpbr.errors import UsageError

if TYPE_CHECKING:
    import numpy as np

__all__ = ["Shown", "show", "to_display"]


def _id_colors(ids: np.ndarray) -> np.ndarray:
    """(H, W) integer ids -> (H, W, 3) uint8: a multiplicative hash per id, 0 black."""
    import numpy as np

    h = ids.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)  # Knuth's golden-ratio hash
    rgb = np.stack([(h >> np.uint64(s)) & np.uint64(0xFF) for s in (56, 48, 40)], axis=-1)
    rgb = (rgb.astype(np.uint16) // 2 + 96).astype(np.uint8)  # no id as dark as the background
    rgb[ids == 0] = 0
    return rgb


def to_display(image: np.ndarray) -> np.ndarray:
    """The uint8 (H, W), (H, W, 3) or (H, W, 4) image `show` displays for `image` (rules in
    the module docstring). Raises UsageError for what it cannot show."""
    import numpy as np

    from vkpbr.scene.color import linear_to_srgb

    if not isinstance(image, np.ndarray):
        raise UsageError(f"show: expected a NumPy array, got {type(image).__name__}")
    a = image
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))) or 0 in a.shape[:2]:
        raise UsageError(f"show: expected an (H, W), (H, W, 3) or (H, W, 4) image, got shape "
                         f"{image.shape}")
    if a.dtype == np.uint8:
        return a
    if a.dtype.kind == "b":
        return a.astype(np.uint8) * 255
    if a.dtype.kind in "ui":
        if a.ndim != 2:
            raise UsageError(f"show: integer images must be (H, W) ids, got shape {image.shape}")
        return _id_colors(a)
    if a.dtype.kind != "f":
        raise UsageError(f"show: cannot show an array of {a.dtype}")
    if a.ndim == 2:
        finite = np.isfinite(a)
        out = np.zeros(a.shape, np.uint8)
        if finite.any():
            lo, hi = float(a[finite].min()), float(a[finite].max())
            scale = 1.0 / (hi - lo) if hi > lo else 0.0
            out[finite] = np.rint((a[finite] - lo) * scale * 255.0).astype(np.uint8)
        return out
    out = np.empty(a.shape, np.uint8)
    rgb = np.nan_to_num(a[..., :3].astype(np.float64), nan=0.0)
    out[..., :3] = np.rint(linear_to_srgb(rgb) * 255.0)
    if a.shape[2] == 4:
        out[..., 3] = np.rint(np.clip(np.nan_to_num(a[..., 3], nan=1.0), 0.0, 1.0) * 255.0)
    return out


class Shown:
    """An image for display: `_repr_png_` gives Jupyter its PNG; `array` is the array that
    was passed (never copied); `png` the bytes; `save(path)` writes them atomically."""

    def __init__(self, image: np.ndarray) -> None:
        self.array = image
        self._png: bytes | None = None
        self.png  # noqa: B018 - fail in show(), not later when IPython asks for the PNG

    @property
    def png(self) -> bytes:
        if self._png is None:
            from vkpbr.io import encode_png

            self._png = encode_png(to_display(self.array))
        return self._png

    def _repr_png_(self) -> bytes:
        return self.png

    def save(self, path: str) -> None:
        """Write the displayed PNG to `path` (atomically)."""
        from vkpbr.atomic import atomic_writer

        with atomic_writer(path) as f:
            f.write(self.png)

    def __repr__(self) -> str:
        return f"<vkpbr.show of {self.array.dtype} {tuple(self.array.shape)} image>"


def show(image: np.ndarray) -> Shown:
    """Wrap a rendered array (colour, depth, normals, ids) so a notebook displays it inline.

    Returns a `Shown`: the cell's value displays as a PNG; elsewhere,
    `IPython.display.display(vkpbr.show(image))`. The array itself is not changed or copied.
    """
    return Shown(image)
