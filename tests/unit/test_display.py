# vkpbr.show: the PNG bytes a notebook gets, decoded by Pillow and compared with the rules
# worked out here in NumPy (the sRGB formula, the depth stretch, ids 0 black).

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import vkpbr
from vkpbr.display import Shown
from vkpbr.errors import UsageError


def decoded(shown: Shown) -> np.ndarray:
    data = shown._repr_png_()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return np.asarray(Image.open(io.BytesIO(data)))


def test_uint8_colour_is_shown_as_is(rng: np.random.Generator) -> None:
    rgba = rng.integers(0, 256, (5, 6, 4), dtype=np.uint8)
    shown = vkpbr.show(rgba)
    assert isinstance(shown, Shown) and shown.array is rgba  # not copied, not changed
    np.testing.assert_array_equal(decoded(shown), rgba)
    np.testing.assert_array_equal(decoded(vkpbr.show(rgba[..., :3])), rgba[..., :3])
    np.testing.assert_array_equal(decoded(vkpbr.show(rgba[..., 0])), rgba[..., 0])
    assert "uint8 (5, 6, 4)" in repr(shown)


def test_linear_float_colour_is_srgb_encoded() -> None:
    x = np.array([0.0, 0.001, 0.0031308, 0.18, 0.5, 1.0, 4.0, -1.0], np.float32)
    linear = np.stack([x, x[::-1], np.full_like(x, 0.5), np.linspace(0, 1, 8)], -1)[None]
    got = decoded(vkpbr.show(linear))
    c = np.clip(linear[..., :3].astype(np.float64), 0, 1)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    np.testing.assert_array_equal(got[..., :3], np.rint(srgb * 255).astype(np.uint8))
    np.testing.assert_array_equal(got[0, :, 3], np.rint(np.linspace(0, 1, 8) * 255))
    assert tuple(got[0, 3, :3]) == (118, 188, 188)  # linear 0.18 is sRGB 118, 0.5 is 188


def test_depth_is_stretched_and_the_background_black() -> None:
    depth = np.array([[1.0, 2.0, np.inf], [3.0, 5.0, np.nan]], np.float32)
    got = decoded(vkpbr.show(depth))
    np.testing.assert_array_equal(got, [[0, 64, 0], [128, 255, 0]])  # (d - 1) / 4 * 255
    assert (decoded(vkpbr.show(np.full((2, 2), np.inf, np.float32))) == 0).all()
    assert (decoded(vkpbr.show(np.full((2, 2), 7.0))) == 0).all()  # flat: no division by 0


def test_ids_are_distinct_colours_and_0_black() -> None:
    ids = np.arange(64, dtype=np.uint32).reshape(8, 8)
    got = decoded(vkpbr.show(ids))
    assert got.shape == (8, 8, 3) and (got[0, 0] == 0).all()
    colours = {tuple(c) for c in got.reshape(-1, 3)[1:]}
    assert len(colours) == 63 and min(map(max, colours)) >= 96  # none as dark as the background
    np.testing.assert_array_equal(decoded(vkpbr.show(ids.astype(np.int64))), got)  # by value


def test_save_writes_the_png(tmp_path: Path) -> None:
    shown = vkpbr.show(np.zeros((2, 3, 4), np.uint8))
    shown.save(str(tmp_path / "a.png"))
    assert (tmp_path / "a.png").read_bytes() == shown.png


@pytest.mark.parametrize("bad, message", [
    ([[1, 2]], "expected a NumPy array, got list"),
    (np.zeros((2, 2, 2), np.uint8), "got shape (2, 2, 2)"),
    (np.zeros((0, 3), np.uint8), "got shape (0, 3)"),
    (np.zeros((2, 2, 3), np.int32), "integer images must be (H, W) ids"),
    (np.zeros((2, 2), np.complex64), "cannot show an array of complex64"),
])
def test_what_cannot_be_shown_fails_at_once(bad: object, message: str) -> None:
    with pytest.raises(UsageError) as info:
        vkpbr.show(bad)  # type: ignore[arg-type]
    assert message in str(info.value)


def test_ipython_formatter_uses_the_png() -> None:
    formatters = pytest.importorskip("IPython.core.formatters", reason="IPython not installed")
    shown = vkpbr.show(np.zeros((2, 2, 4), np.uint8))
    assert formatters.PNGFormatter()(shown) == shown.png
