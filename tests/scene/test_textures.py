# Tests of texture decoding (every Pillow mode to RGBA8, 16-bit scaled not clipped, embedded
# bytes, downscaling, failures -> None + one summary log line per kind) and of
# geometry.auto_camera.

from __future__ import annotations

import io
import logging
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

from vkpbr.scene.geometry import auto_camera
from vkpbr.scene.textures import decode_images
from vkpbr.scene.types import Image, Mesh, Node, Scene


def png(img: PILImage.Image) -> bytes:
    buf = io.BytesIO()
    img.save(buf, "PNG")
    return buf.getvalue()


def test_modes_convert_to_rgba8(tmp_path: Path) -> None:
    grey = PILImage.fromarray(np.array([[0, 128], [255, 7]], np.uint8), "L")
    la = PILImage.merge("LA", [grey, PILImage.fromarray(np.full((2, 2), 9, np.uint8), "L")])
    pal = PILImage.new("P", (2, 2))
    pal.putpalette([255, 0, 0, 0, 255, 0] + [0] * 762)
    pal.putpixel((1, 0), 1)
    pal.info["transparency"] = 1
    wide = PILImage.fromarray(np.array([[0, 65535], [32896, 257]], np.uint16))
    (tmp_path / "w.png").write_bytes(png(wide))
    rgb = PILImage.new("RGB", (2, 2), (10, 20, 30))
    images = [Image("grey", data=png(grey)), Image("la", data=png(la)), Image("pal", data=png(pal)),
              Image("w.png", path=tmp_path / "w.png"), Image("rgb", data=png(rgb)),
              Image("raw", pixels=np.full((1, 3, 4), 5, np.uint8))]  # fmt: skip
    out = decode_images(images, workers=2)
    assert all(o.dtype == np.uint8 and o.shape[2] == 4 and o.flags.c_contiguous for o in out)
    np.testing.assert_array_equal(out[0][..., 0], [[0, 128], [255, 7]])
    np.testing.assert_array_equal(out[0][..., 3], 255)
    np.testing.assert_array_equal(out[1][..., 3], 9)
    np.testing.assert_array_equal(out[2][0, 0], [255, 0, 0, 255])
    assert out[2][0, 1, 3] == 0  # palette transparency becomes alpha
    np.testing.assert_array_equal(out[3][..., 0], [[0, 255], [128, 1]])  # scaled, not clipped
    np.testing.assert_array_equal(out[4][0, 0], [10, 20, 30, 255])
    assert out[5].shape == (1, 3, 4)


def test_failures_give_none_and_one_log_line_per_kind(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    images = [Image("gone.png", path=tmp_path / "gone.png"), Image("bad.png", path=tmp_path / "bad.png"),
              Image("junk", data=b"12345"), Image("ok", data=png(PILImage.new("L", (1, 1)))),
              Image("gone2.png", path=tmp_path / "gone2.png")]  # fmt: skip
    caplog.set_level(logging.INFO, logger="vkpbr.scene")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # diagnostics go through logging, never warnings
        out = decode_images(images)
    assert out[:3] == [None, None, None] and out[3].shape == (1, 1, 4) and out[4] is None
    records = [(r.name, r.levelno, r.getMessage()) for r in caplog.records]
    assert len(records) == 2, records
    (name, level, bad), (_, info_level, gone) = records
    assert name == "vkpbr.scene.textures" and level == logging.WARNING
    assert bad.startswith("2 of 5 textures cannot be decoded (first: bad.png (")
    # Missing files were already reported by load_scene (check_texture_files): INFO only.
    assert info_level == logging.INFO
    assert gone == "2 of 5 texture files not found (first: gone.png); using default values"
    assert all("\n" not in m for _, _, m in records)


def test_downscale_logs_one_line(caplog: pytest.LogCaptureFixture) -> None:
    big = PILImage.new("RGB", (64, 32), (200, 100, 50))
    (out,) = decode_images(Scene("s", images=[Image("big", data=png(big))]), max_size=16)
    assert [r.getMessage() for r in caplog.records] == [
        "1 of 1 textures downscaled to at most 16 px (first: big: 64x32 downscaled to 16x8)"]
    assert out.shape == (8, 16, 4)
    np.testing.assert_allclose(out[4, 8], [200, 100, 50, 255], atol=1)
    caplog.clear()
    images = [Image("p", pixels=np.zeros((40, 10, 4), np.uint8)), Image("q", data=png(big))]
    out = decode_images(images, max_size=20)
    assert [o.shape for o in out] == [(20, 5, 4), (10, 20, 4)]
    assert [r.getMessage() for r in caplog.records] == [
        "2 of 2 textures downscaled to at most 20 px (first: p: 10x40 downscaled to 5x20)"]
    assert decode_images([]) == []


@pytest.mark.timeout(120)
def test_sponza_textures_decode_in_parallel(assets: Path) -> None:
    from vkpbr.scene.gltf import load_gltf

    scene = load_gltf(assets / "Sponza/glTF/Sponza.gltf")
    out = decode_images(scene, workers=2)
    assert len(out) == 69 and all(o is not None and o.shape[2] == 4 for o in out)


def test_auto_camera_frames_bounds() -> None:
    pos = np.array([[-1, -1, -1], [1, 1, 1], [1, -1, 1]], np.float32)
    mesh = Mesh("m", pos, np.arange(3, dtype=np.uint32))
    matrix = np.eye(4, dtype=np.float32)
    matrix[:3, 3] = [10, 0, 0]
    cam = auto_camera(Scene("s", meshes=[mesh], nodes=[Node(0, matrix)]))
    assert cam.target == (10, 0, 0) and cam.yfov_deg == 60
    eye = np.subtract(cam.eye, cam.target)
    assert eye[2] > abs(eye[0]) and eye[2] > abs(eye[1])  # mostly +Z
    # The bounds framed to the field of view (issue 35), by an independent pinhole: every
    # corner of the box inside 95% of the half height (and of a square image's half width),
    # one of them at that limit: the model fills the view, not a seventh of it.
    from pinhole import project

    corners = [(x, y, z) for x in (9, 11) for y in (-1, 1) for z in (-1, 1)]
    size = 120
    reach = [max(abs(r - size / 2), abs(c - size / 2)) / (size / 2)
             for r, c, depth in (project(cam, p, size, size) for p in corners)]
    assert max(reach) <= 0.95 + 1e-9 and max(reach) > 0.95 - 1e-6, reach
    assert min(depth for _, _, depth in (project(cam, p, size, size) for p in corners)) > 0
    assert cam.znear is None and cam.zfar is None  # chosen per render from the bounds
    empty = auto_camera(Scene("e"))
    assert np.isfinite(empty.eye).all()
