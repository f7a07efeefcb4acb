"""The readback copy (gpu/target.py copy_out): big copies are split over threads; the result
must be the source, whole, whatever the split."""

import numpy as np
import pytest

from vkpbr.gpu.target import PARALLEL_BYTES, copy_out


@pytest.mark.parametrize("views", [1, 3, 7, 64])
@pytest.mark.parametrize("into", [False, True])
def test_copy_out_is_the_source(views: int, into: bool) -> None:
    h = max(1, PARALLEL_BYTES // (views * 4 * 97)) + 1  # at or over the threshold
    src = np.random.default_rng(views).integers(0, 256, (views, h, 97, 4), dtype=np.uint8)
    dst = np.zeros_like(src) if into else None
    got = copy_out(src, dst)
    assert got is not src and not np.shares_memory(got, src)
    if into:
        assert got is dst
    np.testing.assert_array_equal(got, src)


def test_small_copies_stay_on_the_caller() -> None:
    src = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    np.testing.assert_array_equal(copy_out(src), src)
