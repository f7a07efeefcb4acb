"""The glTF Render Fidelity metric, as model-viewer's render-fidelity tools compute it
(packages/render-fidelity-tools: ImageComparator.analyze in src/common.ts, colorDelta from
pixelmatch in src/third_party/pixelmatch/color-delta.ts), re-derived here in NumPy:

- per pixel, the YIQ colour difference of Kotsarenko and Ramos ("Measuring perceived color
  difference using YIQ NTSC transmission color space in mobile applications", 2010), on 8-bit
  RGB: delta = 0.5053 dY^2 + 0.299 dI^2 + 0.1957 dQ^2 (already a squared distance; its
  largest value, black against white, is 35215);
- over the covered pixels, rms = sqrt(mean(delta^2)) / 35215 (model-viewer squares delta
  again: the "RMS" is of the squared distance);
- in decibels, 10 log10(rms). 0 dB: the largest possible difference everywhere; lower is closer.
  model-viewer fails its own regressions above -22 dB.

model-viewer blends a semi-transparent pixel with white and counts the pixels where the
candidate's alpha is not 0. Here both images are opaque over black and the caller passes the
pixels either renderer covered (the same mask for both sides).
"""

from __future__ import annotations

import numpy as np

MAX_DELTA = 35215.0
# RGB -> Y, I, Q rows of pixelmatch's rgb2y / rgb2i / rgb2q.
YIQ = np.array([[0.29889531, 0.58662247, 0.11448223],
                [0.59597799, -0.27417610, -0.32180189],
                [0.21147017, -0.52261711, 0.31114694]])
YIQ_WEIGHTS = np.array([0.5053, 0.299, 0.1957])


def yiq_delta(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-pixel squared YIQ distance of two (..., 3) RGB arrays in 0..255."""
    d = (np.asarray(a, np.float64)[..., :3] - np.asarray(b, np.float64)[..., :3]) @ YIQ.T
    return (d * d) @ YIQ_WEIGHTS


def rms_ratio(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    delta = yiq_delta(a, b)[mask]
    if delta.size == 0:
        raise ValueError("no covered pixel to compare")
    return float(np.sqrt(np.mean(delta * delta)) / MAX_DELTA)


def fidelity_db(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    """10 log10 of `rms_ratio`; -inf for identical images."""
    ratio = rms_ratio(a, b, mask)
    return float(10.0 * np.log10(ratio)) if ratio > 0 else float("-inf")
