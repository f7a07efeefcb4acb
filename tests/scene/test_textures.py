# Tests of texture decoding (every Pillow mode to RGBA8, 16-bit scaled not clipped, embedded
# bytes, downscaling, failures -> None + one warning) and of geometry.auto_camera.

from __future__ import annotations

import io
import math
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

from vkpbr.scene.geometry import auto_camera
from vkpbr.scene.textures import decode_images
from vkpbr.scene.types import Image, Mesh, Node, Scene

ASSETS = Path(__file__).resolve().parents[2] / ".." / "shared" / "assets"


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


def test_failures_give_none_and_one_warning_each(tmp_path: Path) -> None:
    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    images = [Image("gone.png", path=tmp_path / "gone.png"), Image("bad.png", path=tmp_path / "bad.png"),
              Image("junk", data=b"12345"), Image("ok", data=png(PILImage.new("L", (1, 1))))]  # fmt: skip
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = decode_images(images)
    assert out[:3] == [None, None, None] and out[3].shape == (1, 1, 4)
    messages = [str(w.message) for w in caught]
    assert len(messages) == 3
    assert "gone.png" in messages[0] and "bad.png" in messages[1] and "junk" in messages[2]
    assert all("\n" not in m for m in messages)


def test_downscale_warns(tmp_path: Path) -> None:
    big = PILImage.new("RGB", (64, 32), (200, 100, 50))
    with pytest.warns(UserWarning, match="64x32 downscaled to 16x8"):
        (out,) = decode_images(Scene("s", images=[Image("big", data=png(big))]), max_size=16)
    assert out.shape == (8, 16, 4)
    np.testing.assert_allclose(out[4, 8], [200, 100, 50, 255], atol=1)
    with pytest.warns(UserWarning, match="downscaled"):
        (out,) = decode_images([Image("p", pixels=np.zeros((40, 10, 4), np.uint8))], max_size=20)
    assert out.shape == (20, 5, 4)
    assert decode_images([]) == []


def test_sponza_textures_decode_in_parallel() -> None:
    if not ASSETS.is_dir():
        pytest.skip("shared assets folder absent")
    from vkpbr.scene.gltf import load_gltf

    scene = load_gltf(ASSETS / "Sponza/glTF/Sponza.gltf")
    t = time.perf_counter()
    out = decode_images(scene, workers=2)
    elapsed = time.perf_counter() - t
    assert len(out) == 69 and all(o is not None and o.shape[2] == 4 for o in out)
    assert elapsed < 30


def test_auto_camera_frames_bounds() -> None:
    pos = np.array([[-1, -1, -1], [1, 1, 1], [1, -1, 1]], np.float32)
    mesh = Mesh("m", pos, np.arange(3, dtype=np.uint32))
    matrix = np.eye(4, dtype=np.float32)
    matrix[:3, 3] = [10, 0, 0]
    cam = auto_camera(Scene("s", meshes=[mesh], nodes=[Node(0, matrix)]))
    assert cam.target == (10, 0, 0) and cam.yfov_deg == 60
    eye = np.subtract(cam.eye, cam.target)
    distance = np.linalg.norm(eye)
    radius = math.sqrt(3)
    assert distance * math.sin(math.radians(30)) >= radius - 1e-9  # sphere fits the fov
    assert eye[2] > abs(eye[0]) and eye[2] > abs(eye[1])  # mostly +Z
    assert cam.znear is None and cam.zfar is None  # chosen per render from the bounds
    empty = auto_camera(Scene("e"))
    assert np.isfinite(empty.eye).all()
