# The sRGB transfer curve, defined once for all Python code: texture mip filtering (scene/mips),
# the NumPy reference of the shaders (reference/brdf re-exports these) and the tests. The GLSL
# copy is shaders/brdf.glsl `srgb_to_linear`; the GPU's own R8G8B8A8_SRGB conversions follow
# the same curve. Reference: IEC 61966-2-1:1999 (sRGB), section 5.2; the Khronos Data Format
# Specification 1.3, section 13.3 (the thresholds 0.04045 and 0.0031308).
"""The sRGB electro-optical transfer function and its inverse, vectorised over NumPy arrays.

Encoded values and linear values are both in [0, 1] (divide 8-bit codes by 255 first).
`SRGB_TO_LINEAR_U8` is the 256-entry table for 8-bit codes, for code that converts whole images.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SRGB_TO_LINEAR_U8", "linear_to_srgb", "srgb_to_linear"]


def srgb_to_linear(e: np.ndarray | float) -> np.ndarray:
    """Decode sRGB-encoded values to linear light.

    Parameters
    ----------
    e : array_like, any shape, encoded values in [0, 1].

    Returns
    -------
    np.ndarray of float64, same shape: e / 12.92 up to 0.04045, ((e + 0.055) / 1.055)^2.4 above.
    """
    e = np.asarray(e, dtype=np.float64)
    return np.where(e > 0.04045, ((np.maximum(e, 0.04045) + 0.055) / 1.055) ** 2.4, e / 12.92)


def linear_to_srgb(x: np.ndarray | float) -> np.ndarray:
    """Encode linear values with the sRGB curve (what an R8G8B8A8_SRGB store applies before
    rounding to 8 bits).

    Parameters
    ----------
    x : array_like, any shape, linear values; clipped to [0, 1] first.

    Returns
    -------
    np.ndarray of float64, same shape, in [0, 1]: 12.92 x up to 0.0031308,
    1.055 x^(1/2.4) - 0.055 above.
    """
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x > 0.0031308, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055,
                    12.92 * x)


# (256,) float64: the linear value of every 8-bit sRGB code (code / 255 decoded).
SRGB_TO_LINEAR_U8 = srgb_to_linear(np.arange(256) / 255.0)
SRGB_TO_LINEAR_U8.setflags(write=False)
