# Tests of the NumPy mip chains (vkpbr.scene.mips) against an independent float64 evaluation of
# what a linear vkCmdBlitImage computes (Vulkan spec, "Image Blits": each destination texel
# samples the source bilinearly at ((x + 0.5) * src / dst), texel centres at k + 0.5, edges
# clamped; sRGB texels linearised before filtering and encoded after), and of the sRGB curve.

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.reference import brdf
from vkpbr.scene import color
from vkpbr.scene.mips import is_mip_chain, mip_chain, mip_level_count, next_mip_level


def srgb_decode(e: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 written out again (not vkpbr's), float64."""
    e = np.asarray(e, np.float64)
    out = e / 12.92
    hi = e > 0.04045
    out[hi] = ((e[hi] + 0.055) / 1.055) ** 2.4
    return out


def srgb_encode(x: np.ndarray) -> np.ndarray:
    x = np.clip(np.asarray(x, np.float64), 0, 1)
    out = 12.92 * x
    hi = x > 0.0031308
    out[hi] = 1.055 * x[hi] ** (1 / 2.4) - 0.055
    return out


def blit_level(level: np.ndarray, srgb: bool) -> np.ndarray:
    """One linear blit from `level` (H, W, 4) uint8 to the next size, texel by texel."""
    h, w = level.shape[:2]
    nh, nw = max(h // 2, 1), max(w // 2, 1)
    x = level / 255.0
    if srgb:
        x[..., :3] = srgb_decode(x[..., :3])
    out = np.zeros((nh, nw, 4))

    def taps(i: int, n: int, m: int) -> list[tuple[int, float]]:
        u = (i + 0.5) * n / m - 0.5  # source coordinate, in texels from the first centre
        k = int(np.floor(u))
        f = u - k
        clamp = lambda j: min(max(j, 0), n - 1)  # noqa: E731
        return [(clamp(k), 1 - f), (clamp(k + 1), f)]

    for r in range(nh):
        for c in range(nw):
            for (y, wy) in taps(r, h, nh):
                for (xx, wx) in taps(c, w, nw):
                    out[r, c] += wy * wx * x[y, xx]
    if srgb:
        out[..., :3] = srgb_encode(out[..., :3])
    return np.rint(np.clip(out, 0, 1) * 255).astype(np.uint8)


@settings(max_examples=60, deadline=None)
@given(h=st.integers(1, 13), w=st.integers(1, 13), srgb=st.booleans(), seed=st.integers(0, 2**32 - 1))
def test_every_level_matches_a_linear_blit(h: int, w: int, srgb: bool, seed: int) -> None:
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
    chain = mip_chain(img, srgb)
    assert len(chain) == mip_level_count(w, h) and is_mip_chain(chain)
    np.testing.assert_array_equal(chain[0], img)
    for above, level in zip(chain, chain[1:], strict=False):
        want = blit_level(above, srgb)  # from the level above, as the GPU's chain was made
        assert level.shape == want.shape and level.dtype == np.uint8
        assert np.abs(level.astype(int) - want).max() <= 1  # rounding of exact ties only
    assert chain[-1].shape == (1, 1, 4)


def test_even_sides_agree_with_exact_and_float_evaluations() -> None:
    img = np.random.default_rng(7).integers(0, 256, (64, 48, 4), dtype=np.uint8)
    s = img.astype(np.int64)
    s = s[0::2, 0::2] + s[1::2, 0::2] + s[0::2, 1::2] + s[1::2, 1::2]
    # Plain data and alpha: the exact mean s / 4, rounded to nearest, ties to even (a quarter of
    # all sums are ties, so the float evaluation's noise is no reference for those).
    np.testing.assert_array_equal(next_mip_level(img, False), np.rint(s / 4))
    srgb = next_mip_level(img, True)
    np.testing.assert_array_equal(srgb[..., 3], np.rint(s[..., 3] / 4))
    # sRGB colour: 16-bit linear integers against float64; a code differs only at a boundary.
    diff = np.abs(srgb[..., :3].astype(int) - blit_level(img, True)[..., :3])
    assert diff.max() <= 1 and (diff > 0).mean() < 0.003


def test_srgb_is_averaged_in_linear_light() -> None:
    checker = np.zeros((2, 2, 4), np.uint8)
    checker[0, 0] = checker[1, 1] = 255  # black and white, alpha 0 and 255
    # Linear light: mean 0.5 -> sRGB 0.7354 * 255 = 187.5 -> 188. Alpha stays linear: 127.5 -> 128.
    assert next_mip_level(checker, srgb=True)[0, 0].tolist() == [188, 188, 188, 128]
    assert next_mip_level(checker, srgb=False)[0, 0].tolist() == [128, 128, 128, 128]
    odd = np.zeros((1, 3, 4), np.uint8)
    odd[0, 1] = 200  # 3 -> 1: the blit's single tap falls on the middle texel's centre
    assert next_mip_level(odd, srgb=True)[0, 0].tolist() == [200, 200, 200, 200]


@pytest.mark.parametrize("value", [0, 1, 17, 128, 254, 255])
def test_constant_images_stay_constant(value: int) -> None:
    for shape in ((16, 16), (5, 3), (1, 9)):
        for srgb in (False, True):
            chain = mip_chain(np.full((*shape, 4), value, np.uint8), srgb)
            assert all((lv == value).all() for lv in chain)


def test_level_counts_and_shapes() -> None:
    assert [mip_level_count(*s) for s in ((1, 1), (2, 1), (1024, 1024), (5, 3), (1, 1000))] == \
        [1, 2, 11, 3, 10]
    shapes = [lv.shape for lv in mip_chain(np.zeros((5, 12, 4), np.uint8), False)]
    assert shapes == [(5, 12, 4), (2, 6, 4), (1, 3, 4), (1, 1, 4)]
    chain = mip_chain(np.zeros((4, 4, 4), np.uint8), True)
    assert is_mip_chain(chain) and not is_mip_chain(chain[:-1]) and not is_mip_chain([])
    assert not is_mip_chain([chain[0], np.zeros((2, 1, 4), np.uint8), chain[2]])
    with pytest.raises(ValueError, match="H, W, 4"):
        mip_chain(np.zeros((4, 4, 3), np.uint8), False)


def test_one_srgb_curve() -> None:
    e = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(color.srgb_to_linear(e), srgb_decode(e), rtol=1e-12, atol=0)
    np.testing.assert_allclose(color.linear_to_srgb(e), srgb_encode(e), rtol=1e-12, atol=0)
    np.testing.assert_allclose(color.linear_to_srgb(color.srgb_to_linear(e)), e, atol=1e-12)
    assert color.srgb_to_linear(0.5) == pytest.approx(0.21404114048223255, abs=1e-15)
    np.testing.assert_array_equal(color.SRGB_TO_LINEAR_U8, color.srgb_to_linear(np.arange(256) / 255))
    # The NumPy reference of the shaders re-exports the same functions, not copies.
    assert brdf.srgb_to_linear is color.srgb_to_linear
    assert brdf.linear_to_srgb is color.linear_to_srgb
