"""Image comparisons the tests share."""

from __future__ import annotations

import numpy as np


def assert_batch_view(got: np.ndarray, want: np.ndarray, what: str = "") -> None:
    """A view of a compute batch against the same view rendered alone: docs/batch.md's
    bound, mean <= 1/255 and p99 <= 3/255 over the colour channels (the batch's shading
    builds round a few values differently; a few edge pixels differ where the batch's
    rasteriser and the frame's cover a pixel centre on a shared edge differently). The
    layered batch and the frame path it shares give the same bytes, which this admits too."""
    assert got.shape == want.shape, (what, got.shape, want.shape)
    d = np.abs(got[..., :3].astype(np.int32) - want[..., :3].astype(np.int32))
    mean, p99 = d.mean(), np.percentile(d, 99)
    assert mean <= 1.0 and p99 <= 3.0, f"{what}: mean {mean:.3f}, p99 {p99}, max {d.max()}"
