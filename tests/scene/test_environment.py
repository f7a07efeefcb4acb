"""HDR/EXR panoramas (scene/environment.py) and the built-in sky (scene/sky.py): no GPU."""

from __future__ import annotations

import logging

import imagecodecs
import numpy as np
import OpenEXR
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.environment import (
    direction_to_equirect,
    equirect_to_direction,
    load_panorama,
    sample_equirect,
)
from vkpbr.scene.sky import SKY_UNIT, sky_model, sky_radiance, sun_radiometry
from vkpbr.shading import SUN_DIRECTION


def write_exr(path, rgb) -> None:  # noqa: ANN001
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(rgb, np.float32)}) as f:
        f.write(str(path))


@pytest.fixture
def pano(rng) -> np.ndarray:  # noqa: ANN001
    return (rng.random((16, 32, 3)) * 8).astype(np.float32)


def test_hdr_round_trip(tmp_path, pano) -> None:  # noqa: ANN001
    p = tmp_path / "a.hdr"
    p.write_bytes(imagecodecs.rgbe_encode(pano))
    got = load_panorama(p)
    assert got.shape == (16, 32, 3) and got.dtype == np.float32
    # RGBE: 8-bit mantissas under the pixel's largest channel's exponent.
    assert (np.abs(got - pano) <= pano.max(-1, keepdims=True) / 64).all()


def test_exr_round_trip(tmp_path, pano) -> None:  # noqa: ANN001
    p = tmp_path / "a.exr"
    write_exr(p, pano)
    np.testing.assert_array_equal(load_panorama(p), pano)


@pytest.mark.parametrize("suffix", [".hdr", ".exr"])
@pytest.mark.parametrize("keep", [0.3, 0.8])
def test_truncated_file_is_one_line(tmp_path, pano, suffix: str, keep: float, capfd) -> None:  # noqa: ANN001
    p = tmp_path / f"cut{suffix}"
    if suffix == ".hdr":
        data = imagecodecs.rgbe_encode(pano)
    else:
        write_exr(p, pano)
        data = p.read_bytes()
    p.write_bytes(data[: int(len(data) * keep)])
    with pytest.raises(SceneError) as e:
        load_panorama(p)
    assert str(p) in str(e.value) and "\n" not in str(e.value)
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # native diagnostics do not leak to the terminal


def test_garbage_and_missing(tmp_path) -> None:  # noqa: ANN001
    for name, data in (("g.hdr", b"not an image"), ("g.exr", b"\x76\x2f\x31\x01garbage")):
        (tmp_path / name).write_bytes(data)
        with pytest.raises(SceneError, match=name):
            load_panorama(tmp_path / name)
    with pytest.raises(SceneError, match="not found"):
        load_panorama(tmp_path / "none.hdr")
    with pytest.raises(SceneError, match="unknown environment format"):
        load_panorama(tmp_path / "x.tga")
    (tmp_path / "g.jpg").write_bytes(b"not a jpeg")
    with pytest.raises(SceneError, match=r"g\.jpg: corrupt or unreadable image"):
        load_panorama(tmp_path / "g.jpg")


def test_ldr_png_decoded_from_srgb(tmp_path, rng) -> None:  # noqa: ANN001
    """An 8-bit sRGB PNG panorama: every code through IEC 61966-2-1's curve (written here from
    the standard, not through scene/color.py), alpha dropped."""
    from PIL import Image as PILImage

    codes = rng.integers(0, 256, (16, 32, 4), dtype=np.uint8)
    PILImage.fromarray(codes, "RGBA").save(tmp_path / "p.png")
    got = load_panorama(tmp_path / "p.png")
    e = codes[..., :3] / 255.0
    want = np.where(e <= 0.04045, e / 12.92, ((e + 0.055) / 1.055) ** 2.4)
    assert got.shape == (16, 32, 3) and got.dtype == np.float32
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-7)
    assert got.max() <= 1.0  # LDR light is clipped


def test_ldr_jpeg_and_aspect_error(tmp_path) -> None:  # noqa: ANN001
    """A grey JPEG decodes to its sRGB code's linear value (within JPEG's rounding); a
    photograph that is not 2:1 is one line naming it."""
    from PIL import Image as PILImage

    PILImage.new("RGB", (64, 32), (188, 188, 188)).save(tmp_path / "grey.jpg", quality=95)
    got = load_panorama(tmp_path / "grey.jpg")
    assert abs(float(got.mean()) - ((188 / 255 + 0.055) / 1.055) ** 2.4) < 0.01
    PILImage.new("RGB", (48, 32)).save(tmp_path / "wide.jpg")
    with pytest.raises(SceneError) as e:
        load_panorama(tmp_path / "wide.jpg")
    assert str(e.value).count("\n") == 0 and "wide.jpg" in str(e.value)
    assert "not an equirectangular panorama" in str(e.value)


def test_not_two_to_one(tmp_path, rng) -> None:  # noqa: ANN001
    p = tmp_path / "square.exr"
    write_exr(p, rng.random((16, 16, 3)))
    with pytest.raises(SceneError, match="not an equirectangular panorama"):
        load_panorama(p)


def test_nan_and_negative_pixels_clamped_with_one_warning(tmp_path, pano, caplog) -> None:  # noqa: ANN001
    pano[0, 0] = np.nan
    pano[1, 2, 1] = -3.0
    pano[2, 3] = np.inf
    p = tmp_path / "bad.exr"
    write_exr(p, pano)
    with caplog.at_level(logging.WARNING, logger="vkpbr.scene.environment"):
        got = load_panorama(p)
    assert np.isfinite(got).all() and (got >= 0).all()
    assert got[0, 0].tolist() == [0, 0, 0] and got[1, 2, 1] == 0
    records = [r for r in caplog.records if r.name == "vkpbr.scene.environment"]
    assert len(records) == 1 and "3 pixel(s)" in records[0].getMessage()


def test_too_many_pixels(tmp_path, pano, monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_PIXELS", "100")
    for name in ("big.hdr", "big.exr"):
        p = tmp_path / name
        if name.endswith(".hdr"):
            p.write_bytes(imagecodecs.rgbe_encode(pano))
        else:
            write_exr(p, pano)
        with pytest.raises(SceneError, match="more than 100 pixels"):
            load_panorama(p)


def test_equirect_mapping(rng) -> None:  # noqa: ANN001
    d = rng.normal(size=(100, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    np.testing.assert_allclose(equirect_to_direction(*direction_to_equirect(d)), d, atol=1e-12)
    u, v = direction_to_equirect(np.array([[0, 0, -1.0], [0, 1.0, 0], [1.0, 0, 0]]))
    np.testing.assert_allclose(u[[0, 2]], [0.5, 0.75])  # -Z is the centre, +X 3/4
    np.testing.assert_allclose(v[:2], [0.5, 0.0])
    img = np.zeros((8, 16, 3))
    img[:, 8:] = 1.0  # the right half: u in [0.5, 1)
    assert sample_equirect(img, np.array([[0.7, 0, -0.7]]))[0, 0] == pytest.approx(1.0)


def test_sun_radiometry() -> None:
    color, e = sun_radiometry(SUN_DIRECTION)
    assert 0.2126 * color[0] + 0.7152 * color[1] + 0.0722 * color[2] == pytest.approx(1.0)
    assert color[0] > color[1] > color[2]  # reddened by the atmosphere
    assert 3.0 < e < 6.0  # ~86 klux at 50 degrees, in 20 kcd/m^2 units
    low_c, low_e = sun_radiometry((0.0, -np.sin(np.radians(5)), -np.cos(np.radians(5))))
    assert low_e < e / 4 and low_c[2] < color[2]
    assert sun_radiometry((0.0, 1.0, 0.0))[1] == 0.0  # below the horizon


def test_sky_radiance() -> None:
    model = sky_model(SUN_DIRECTION)
    zenith = sky_radiance(np.array([0.0, 1.0, 0.0]), model)
    assert zenith[2] > zenith[1] > zenith[0] > 0  # blue
    # Preetham's zenith luminance (eq. A.2 in kcd/m^2) for T = 3, theta_s = 40 degrees.
    chi = (4 / 9 - 3 / 120) * (np.pi - 2 * np.radians(40))
    y_z = ((4.0453 * 3 - 4.9710) * np.tan(chi) - 0.2155 * 3 + 2.4192) * 1000 / SKY_UNIT
    assert 0.2126 * zenith[0] + 0.7152 * zenith[1] + 0.0722 * zenith[2] == pytest.approx(
        y_z, rel=0.02)
    toward_sun = -np.asarray(SUN_DIRECTION)
    away = toward_sun * np.array([-1, 1, -1])
    assert sky_radiance(toward_sun, model).sum() > sky_radiance(away, model).sum()
    ground = sky_radiance(np.array([0.0, -1.0, 0.0]), model)
    np.testing.assert_allclose(ground, model.ground)
    assert 0.0 < ground.mean() < zenith.mean() * 3
