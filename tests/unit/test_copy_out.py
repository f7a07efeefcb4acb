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


@pytest.mark.parametrize("mib", [8, 32])
def test_a_collector_copies_a_frame_alone_below_its_limit(monkeypatch, mib: int) -> None:  # noqa: ANN001
    """split=False (render_many's collector thread): a 1080p RGBA8 frame (under ALONE_BYTES)
    is copied on the calling thread, a bigger one (4K, float32 frames) still on the copy
    threads; both are the source, whole."""
    from vkpbr.gpu import target

    handed: list[int] = []
    real = target.pool

    def counted():  # noqa: ANN202
        handed.append(1)
        return real()

    monkeypatch.setattr(target, "pool", counted)
    rows = (mib << 20) // (4 * 1024)
    src = np.random.default_rng(mib).integers(0, 256, (rows, 1024, 4), dtype=np.uint8)
    np.testing.assert_array_equal(copy_out(src, split=False), src)
    if src.nbytes < target.ALONE_BYTES or src.nbytes < PARALLEL_BYTES:
        assert handed == []
    else:
        assert handed, "a frame over ALONE_BYTES was copied by one thread"
