"""tests/raycast.py's cull (each chunk of rays against only the triangles its projected box
can meet) gives exactly what testing every ray against every triangle gives: the GPU tests'
ray-cast references rest on it."""

from __future__ import annotations

import numpy as np
import pytest
from raycast import _hits, first_hits


def every_pair(tri: np.ndarray, eye: np.ndarray, dirs: np.ndarray):  # noqa: ANN201
    return _hits(tri, np.asarray(eye, np.float64), dirs)


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@pytest.mark.parametrize("seed", range(4))
def test_culled_hits_equal_every_pair(seed: int) -> None:
    """Triangles scattered around the eye (some behind it, some straddling its plane), rays
    in every direction, in narrow bundles, and just inside triangles' corners (most of them
    unoccluded): the same triangle, distance and barycentrics, bit for bit."""
    rng = np.random.default_rng(seed)
    tri = rng.normal(size=(400, 1, 3)) * 4.0 + rng.normal(size=(400, 3, 3)) * 0.5
    eye = rng.normal(size=3)
    c = unit(rng.normal(size=3))
    # Just inside each of 100 triangles' first corners: on the edge of a one-ray chunk's box.
    corners = unit(np.einsum("k,tkc->tc", [1 - 2e-7, 1e-7, 1e-7], tri[:100]) - eye)
    for dirs in (unit(rng.normal(size=(300, 3))), unit(c + 0.1 * rng.normal(size=(300, 3))),
                 corners):
        want = every_pair(tri, eye, dirs)
        assert np.count_nonzero(want[0] >= 0) > 20  # the rays hit things
        for chunk in (1, 16, 256) if dirs is corners else (16, 256):
            got = first_hits(tri, eye, dirs, chunk=chunk)
            for g, w in zip(got, want, strict=True):
                np.testing.assert_array_equal(g, w)
