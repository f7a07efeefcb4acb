# Texture mip chains in NumPy, made once per image: by the bake (written into .vkpbr files) or
# at load, and uploaded level by level, so the GPU never rebuilds them.
#
# Each level is made from the one above it exactly as the GPU's linear vkCmdBlitImage used to
# make it, so images look the same as before: every destination texel samples the source
# bilinearly at its centre, mapped by the size ratio (Vulkan spec, "Image Blits": u = (x + 0.5)
# * src / dst, texel centres at k + 0.5, edges clamped). For an even side that is the 2x2 box
# average; for an odd side (5 -> 2, say) it is the same bilinear tap as the blit's. sRGB colour
# is averaged in linear light, as the blit does for *_SRGB formats (alpha is always linear), and
# each level is rounded to 8 bits before the next is made from it, as the blit's levels were.
"""Mip chains of RGBA8 images: `mip_chain`, `mip_level_count`, `next_mip_level`."""

from __future__ import annotations

import numpy as np

from vkpbr.scene.color import SRGB_TO_LINEAR_U8, linear_to_srgb, srgb_to_linear

__all__ = ["is_mip_chain", "mip_chain", "mip_level_count", "next_mip_level"]

_DECODE_SRGB = SRGB_TO_LINEAR_U8.astype(np.float32)
# The even-sided sRGB path works in 16-bit linear integers: code -> round(65535 * linear), and
# back through a 65536-entry table built from the exact code boundaries (a 16-bit linear step
# is 1/20 of the darkest code's, so this agrees with the float path to within a tie).
_DECODE_SRGB16 = np.rint(SRGB_TO_LINEAR_U8 * 65535.0).astype(np.uint32)
_ENCODE_SRGB16 = np.searchsorted(
    np.rint(srgb_to_linear((np.arange(255) + 0.5) / 255.0) * 65535.0), np.arange(65536),
    side="right").astype(np.uint8)


def mip_level_count(width: int, height: int) -> int:
    """Levels of a full chain for a `width` x `height` image, down to 1x1 (both >= 1)."""
    return int(max(width, height)).bit_length()


def _halve(a: np.ndarray, axis: int) -> np.ndarray:
    """Shrink one axis of a float32 (H, W, 4) array to max(n // 2, 1) texels like a linear blit."""
    n = a.shape[axis]
    if n == 1:
        return a
    m = n // 2
    if n == 2 * m:  # the blit's taps fall halfway between texel pairs: their mean
        lo, hi = (a[0::2], a[1::2]) if axis == 0 else (a[:, 0::2], a[:, 1::2])
        return (lo + hi) * np.float32(0.5)
    u = (np.arange(m) + 0.5) * (n / m) - 0.5  # source coordinate of each tap, in texel units
    k = np.floor(u).astype(np.intp)
    f = (u - k).astype(np.float32)
    k1 = np.minimum(k + 1, n - 1)
    f = f[:, None, None] if axis == 0 else f[None, :, None]
    a0, a1 = np.take(a, k, axis), np.take(a, k1, axis)
    return a0 + (a1 - a0) * f


def next_mip_level(level: np.ndarray, srgb: bool) -> np.ndarray:
    """The level below `level`.

    Parameters
    ----------
    level : (H, W, 4) uint8 RGBA, not 1x1.
    srgb : the RGB channels are sRGB-encoded colour (filtered in linear light); alpha and
        every channel of a non-sRGB image are filtered as they are.

    Returns
    -------
    (max(H // 2, 1), max(W // 2, 1), 4) uint8, C-contiguous.
    """
    h, w = level.shape[:2]
    if h % 2 == 0 and w % 2 == 0:
        # Even sides: the 2x2 mean in integers (4x faster than floats), rounded to nearest
        # with ties to even as np.rint does below.
        if srgb:
            x = _DECODE_SRGB16[level]  # all four channels at once (faster), then alpha as is
            x[..., 3] = level[..., 3]
        else:
            x = level.astype(np.uint16)
        s = x[0::2, 0::2] + x[1::2, 0::2] + x[0::2, 1::2] + x[1::2, 1::2]
        mean = (s + 1 + ((s >> 2) & 1)) >> 2
        if not srgb:
            return mean.astype(np.uint8)
        out = np.empty(mean.shape, np.uint8)
        out[..., :3] = _ENCODE_SRGB16[mean[..., :3]]
        out[..., 3] = mean[..., 3]
        return out
    x = np.empty(level.shape, np.float32)
    if srgb:
        x[..., :3] = _DECODE_SRGB[level[..., :3]]
        x[..., 3] = level[..., 3] * np.float32(1 / 255)
    else:
        x[...] = level * np.float32(1 / 255)
    x = _halve(_halve(x, 0), 1)
    out = np.empty(x.shape, np.uint8)
    if srgb:
        out[..., :3] = np.rint(linear_to_srgb(x[..., :3]) * 255.0)
        out[..., 3] = np.rint(np.clip(x[..., 3], 0.0, 1.0) * 255.0)
    else:
        out[...] = np.rint(np.clip(x, 0.0, 1.0) * 255.0)
    return out


def mip_chain(rgba: np.ndarray, srgb: bool) -> list[np.ndarray]:
    """The full mip chain of an image.

    Parameters
    ----------
    rgba : (H, W, 4) uint8, level 0.
    srgb : RGB is sRGB colour (base colour, emissive), filtered in linear light.

    Returns
    -------
    `mip_level_count(W, H)` arrays, level 0 (`rgba` itself, made C-contiguous) first, each
    level max(side // 2, 1) of the one before, down to 1x1; all (h, w, 4) uint8.
    """
    rgba = np.ascontiguousarray(rgba, dtype=np.uint8)
    if rgba.ndim != 3 or rgba.shape[2] != 4 or 0 in rgba.shape:
        raise ValueError(f"mip_chain needs (H, W, 4) uint8 pixels, not {rgba.shape}")
    levels = [rgba]
    while levels[-1].shape[0] > 1 or levels[-1].shape[1] > 1:
        levels.append(next_mip_level(levels[-1], srgb))
    return levels


def is_mip_chain(levels: list[np.ndarray]) -> bool:
    """True when `levels` are the shapes of a full chain: (H, W, 4), each level's sides
    max(side // 2, 1) of the previous, ending at 1x1."""
    if not levels:
        return False
    h, w = levels[0].shape[:2]
    if len(levels) != mip_level_count(w, h):
        return False
    for level in levels:
        if level.shape != (h, w, 4):
            return False
        h, w = max(h // 2, 1), max(w // 2, 1)
    return True
