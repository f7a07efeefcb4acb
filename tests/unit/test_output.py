# Output files (vkpbr.io): every format read back by an independent reader (Pillow for
# PNG, OpenEXR's own File for EXR, np.load for NPY) and compared exactly; the PNG headers
# checked byte by byte; refused writes leave nothing behind (no file, no temporary file, an
# existing file untouched).

from __future__ import annotations

import io
import struct
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from vkpbr.errors import UsageError
from vkpbr.io import (
    MAX_PNG_ID,
    check_id_count,
    check_output_path,
    encode_png,
    output_kind,
    write_image,
    write_image_atomic,
    write_output,
)


def png_header(data: bytes) -> tuple[int, int, int, int]:
    """(width, height, bit depth, colour type) from a PNG's IHDR chunk."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    w, h, depth, colour = struct.unpack(">IIBB", data[16:26])
    return w, h, depth, colour


def only_file(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_color_png_and_jpeg(tmp_path: Path, rng: np.random.Generator) -> None:
    rgba = rng.integers(0, 256, (5, 7, 4), dtype=np.uint8)
    write_image_atomic(tmp_path / "a.png", rgba)
    data = (tmp_path / "a.png").read_bytes()
    assert png_header(data) == (7, 5, 8, 6)  # RGBA, 8 bits
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "a.png")), rgba)
    write_output(tmp_path / "b.jpg", rgba)
    assert Image.open(tmp_path / "b.jpg").mode == "RGB"
    assert only_file(tmp_path) == ["a.png", "b.jpg"]


def test_encode_png_is_what_write_writes(tmp_path: Path, rng: np.random.Generator) -> None:
    rgb = rng.integers(0, 256, (3, 4, 3), dtype=np.uint8)
    write_output(tmp_path / "c.png", rgb)
    assert encode_png(rgb) == (tmp_path / "c.png").read_bytes()
    assert png_header(encode_png(rgb[..., 0])) == (4, 3, 8, 0)  # greyscale


def test_ids_as_16_bit_png(tmp_path: Path) -> None:
    ids = np.array([[0, 1, 2, 3], [65535, 256, 257, 40000], [7, 7, 0, 1]], dtype=np.uint32)
    write_output(tmp_path / "ids.png", ids, "ids")
    data = (tmp_path / "ids.png").read_bytes()
    assert png_header(data) == (4, 3, 16, 0)  # greyscale, 16 bits
    back = np.asarray(Image.open(io.BytesIO(data)))
    assert back.dtype == np.uint16
    np.testing.assert_array_equal(back, ids)


@pytest.mark.parametrize("bad", [MAX_PNG_ID + 1, 2**32 - 1])
def test_ids_overflowing_a_png_write_nothing(tmp_path: Path, bad: int) -> None:
    path = tmp_path / "ids.png"
    path.write_bytes(b"old")
    ids = np.zeros((2, 2), np.uint32)
    ids[1, 1] = bad
    with pytest.raises(UsageError, match=f"id {bad:,} does not fit a 16-bit PNG") as info:
        write_output(path, ids, "ids")
    assert "\n" not in str(info.value) and str(path) in str(info.value)
    assert path.read_bytes() == b"old" and only_file(tmp_path) == ["ids.png"]
    write_output(tmp_path / "ids.npy", ids, "ids")  # what the message says to do
    np.testing.assert_array_equal(np.load(tmp_path / "ids.npy"), ids)
    assert np.load(tmp_path / "ids.npy").dtype == np.uint32


def test_check_id_count() -> None:
    check_id_count(MAX_PNG_ID, Path("a.png"))
    check_id_count(10**6, Path("a.npy"))
    with pytest.raises(UsageError, match="65,536 ids do not fit a 16-bit PNG"):
        check_id_count(MAX_PNG_ID + 1, Path("a.png"), "--outputs")


def exr_channels(path: Path) -> dict[str, np.ndarray]:
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        return {name: np.array(ch.pixels) for name, ch in f.channels().items()}


def test_exr_float_outputs_are_exact(tmp_path: Path, rng: np.random.Generator) -> None:
    pytest.importorskip("OpenEXR")
    color = rng.standard_normal((6, 5, 4)).astype(np.float32) * 100
    depth = rng.random((6, 5), dtype=np.float32)
    depth[0, 0] = np.inf  # the background
    normal = rng.standard_normal((6, 5, 3)).astype(np.float32)
    write_output(tmp_path / "c.exr", color, "color")
    write_output(tmp_path / "d.exr", depth, "data")
    write_output(tmp_path / "n.exr", normal, "data")
    c, d, n = (exr_channels(tmp_path / f"{x}.exr") for x in "cdn")
    assert list(c) == ["RGBA"] and list(d) == ["Y"] and list(n) == ["RGB"]
    assert c["RGBA"].dtype == d["Y"].dtype == np.float32
    np.testing.assert_array_equal(c["RGBA"], color)
    np.testing.assert_array_equal(d["Y"], depth)
    np.testing.assert_array_equal(n["RGB"], normal)
    assert (tmp_path / "c.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"  # EXR magic


def test_exr_without_the_package_is_one_line(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setitem(sys.modules, "OpenEXR", None)  # import OpenEXR raises ImportError
    path = tmp_path / "d.exr"
    for call in (lambda: write_output(path, np.zeros((2, 2), np.float32), "data"),
                 lambda: check_output_path(path, "data")):
        with pytest.raises(UsageError, match=r"writing EXR needs the OpenEXR package: pip "
                                             r"install 'OpenEXR>=3.5'") as info:
            call()
        assert "\n" not in str(info.value)
    assert only_file(tmp_path) == []


@pytest.mark.parametrize("name, kind, array, message", [
    ("a.gif", "color", np.zeros((2, 2, 4), np.uint8), "unknown image type '.gif'"),
    ("a", "color", np.zeros((2, 2, 4), np.uint8), "unknown image type"),
    ("a.png", "color", np.zeros((2, 2, 4), np.float32), "float32 data needs a .npy"),
    ("a.png", "color", np.zeros((2, 2, 2), np.uint8), "must be (H, W), (H, W, 3)"),
    ("a.png", "data", np.zeros((2, 2), np.float32), ".png is not a format for data output"),
    ("a.exr", "ids", np.zeros((2, 2), np.uint32), ".exr is not a format for ids output"),
    ("a.exr", "color", np.zeros((2, 2, 4), np.uint8), "EXR holds float data, got uint8"),
    ("a.exr", "data", np.zeros((2, 2, 5), np.float32), "EXR takes (H, W), (H, W, 2), (H, W, 3)"),
    ("a.png", "ids", np.zeros((2, 2), np.float32), "ids must be (H, W) integers"),
    ("a.png", "ids", np.zeros((2, 2, 1), np.uint32), "ids must be (H, W) integers"),
    ("a.png", "ids", np.full((2, 2), -1, np.int32), "id -1 does not fit"),
    ("a.npy", "depth", np.zeros(2), "unknown kind of output 'depth'"),
])
def test_refused_outputs_are_one_line_and_write_nothing(tmp_path: Path, name: str, kind: str,
                                                        array: np.ndarray, message: str) -> None:
    pytest.importorskip("OpenEXR")
    with pytest.raises(UsageError) as info:
        write_output(tmp_path / name, array, kind, "--outputs")  # type: ignore[arg-type]
    text = str(info.value)
    assert message in text and "\n" not in text and text.startswith("--outputs "), text
    assert only_file(tmp_path) == []


def test_npy_keeps_any_array(tmp_path: Path) -> None:
    a = np.arange(24, dtype=np.float64).reshape(2, 3, 4)
    for kind in ("color", "ids", "data"):
        write_output(tmp_path / f"{kind}.npy", a, kind)  # type: ignore[arg-type]
        back = np.load(tmp_path / f"{kind}.npy")
        assert back.dtype == a.dtype
        np.testing.assert_array_equal(back, a)


def test_output_kinds() -> None:
    assert output_kind("instance") == "ids" and output_kind("depth") == "data"
    assert output_kind("color") == "color"
    with pytest.raises(UsageError, match="unknown output 'normals' .known: color, depth"):
        output_kind("normals")


def test_check_output_path(tmp_path: Path) -> None:
    check_output_path(tmp_path / "a.png", "ids")
    with pytest.raises(UsageError, match="does not exist"):
        check_output_path(tmp_path / "missing" / "a.png")
    with pytest.raises(UsageError, match="is a directory"):
        check_output_path(tmp_path, "color")
    with pytest.raises(UsageError, match=".jpg is not a format for ids"):
        check_output_path(tmp_path / "a.jpg", "ids")


def test_os_errors_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "missing" / "a.png"
    with pytest.raises(OSError) as info:
        write_output(path, np.zeros((2, 2, 4), np.uint8))
    assert info.value.filename == str(path)


def test_write_image_takes_kinds_and_output_names(tmp_path: Path, rng: np.random.Generator) -> None:
    """vkpbr.io.write_image: the public writer, by kind of file or by the renderer's output
    name; str paths as well as Paths."""
    ids = rng.integers(0, MAX_PNG_ID + 1, (3, 4), dtype=np.uint32)
    write_image(str(tmp_path / "i.png"), ids, kind="instance")
    write_image(tmp_path / "j.png", ids, kind="ids")
    assert (tmp_path / "i.png").read_bytes() == (tmp_path / "j.png").read_bytes()
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "i.png")), ids)
    rgba = rng.integers(0, 256, (3, 4, 4), dtype=np.uint8)
    write_image(tmp_path / "c.png", rgba)
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "c.png")), rgba)
    depth = rng.random((3, 4), dtype=np.float32)
    write_image(tmp_path / "d.npy", depth, kind="depth")
    np.testing.assert_array_equal(np.load(tmp_path / "d.npy"), depth)


@pytest.mark.parametrize("kind", ["normals", "", None, ["color"]])
def test_write_image_refuses_unknown_kinds_in_one_line(tmp_path: Path, kind: object) -> None:
    with pytest.raises(UsageError, match=r"write_image: unknown kind .* \(color, ids, data or an "
                                         r"output name: color, depth") as info:
        write_image(tmp_path / "a.png", np.zeros((2, 2, 4), np.uint8), kind=kind)  # type: ignore[arg-type]
    assert "\n" not in str(info.value) and only_file(tmp_path) == []


def test_write_image_messages_name_the_function_and_file(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match=r"^write_image: .*a.png: float32 data needs a .npy"):
        write_image(tmp_path / "a.png", np.zeros((2, 2, 4), np.float32))


def test_the_cli_module_keeps_the_names() -> None:
    """vkpbr.app.output (the name earlier READMEs gave) is vkpbr.io's writers, not a copy."""
    import vkpbr.app.output as old
    import vkpbr.io as new

    assert set(old.__all__) == set(new.__all__)
    assert all(getattr(old, n) is getattr(new, n) for n in old.__all__)
