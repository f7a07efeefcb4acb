# Tests of QTangent encoding and the 32-bit packed frame: round trips, handedness, the
# stated precision of the packed layout.
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from vkpbr.bake.frames import (
    QTANGENT_BIAS,
    frame_angular_error_deg,
    frame_streams,
    pack_qtangent,
    qtangent_to_tbn,
    tbn_to_qtangent,
    unpack_qtangent,
)


def random_frames(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(count, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    t = rng.normal(size=(count, 3))
    t -= n * np.einsum("ij,ij->i", n, t)[:, None]
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    w = rng.choice([-1.0, 1.0], count)
    return n.astype(np.float32), np.concatenate([t, w[:, None]], axis=1).astype(np.float32)


finite = st.floats(-10, 10, allow_nan=False, width=32)


@settings(max_examples=200, deadline=None)
@given(arrays(np.float32, (16, 3), elements=finite), arrays(np.float32, (16, 3), elements=finite),
       arrays(np.bool_, 16))
@np.errstate(under="ignore")  # subnormal inputs may underflow in the test's own arithmetic
def test_quaternion_round_trip_any_frame(n: np.ndarray, t: np.ndarray, mirrored: np.ndarray) -> None:
    t4 = np.concatenate([t, np.where(mirrored, -1.0, 1.0)[:, None]], axis=1).astype(np.float32)
    q = tbn_to_qtangent(n, t4)
    assert np.isfinite(q).all()
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-5)
    assert (np.abs(q[:, 3]) >= np.float32(QTANGENT_BIAS) * 0.999).all()
    np.testing.assert_array_equal(np.sign(q[:, 3]), np.where(mirrored, -1.0, 1.0))
    n2, t2 = qtangent_to_tbn(q)
    # Compared with the orthonormalised input frame; the bias turns it by <= 0.0035 deg.
    assert frame_angular_error_deg(n, t4, n2, t2).max() < 0.01
    # The packed path keeps handedness too, and stays within its bound.
    u = unpack_qtangent(pack_qtangent(q))
    np.testing.assert_array_equal(np.sign(u[:, 3]), np.sign(q[:, 3]))
    assert frame_angular_error_deg(n, t4, *qtangent_to_tbn(u)).max() < 0.25


def test_packed_precision_over_1e5_random_frames() -> None:
    # Measured: mean 0.10, p99 0.16, max 0.19 degrees (frames.py docstring).
    n, t = random_frames(100_000, seed=7)
    q = tbn_to_qtangent(n, t)
    n2, t2 = qtangent_to_tbn(unpack_qtangent(pack_qtangent(q)))
    err = frame_angular_error_deg(n, t, n2, t2)
    assert err.mean() <= 0.11
    assert np.percentile(err, 99) <= 0.17
    assert err.max() <= 0.2
    np.testing.assert_array_equal(t2[:, 3], t[:, 3])


def test_handedness_survives_packing_when_w_is_zero() -> None:
    # 180-degree rotations have q.w == 0: the bias and the handedness bit must carry the sign.
    n = np.array([[0, 0, -1], [0, 0, -1], [0, -1, 0], [-1, 0, 0]], np.float32)
    t = np.array([[-1, 0, 0, -1], [1, 0, 0, 1], [-1, 0, 0, -1], [0, 0, 1, -1]], np.float32)
    q = tbn_to_qtangent(n, t)
    np.testing.assert_array_equal(np.sign(q[:, 3]), t[:, 3])
    u = unpack_qtangent(pack_qtangent(q))
    np.testing.assert_array_equal(np.sign(u[:, 3]), t[:, 3])
    n2, t2 = qtangent_to_tbn(u)
    assert frame_angular_error_deg(n, t, n2, t2).max() < 0.25


def test_any_uint32_unpacks_to_a_unit_quaternion() -> None:
    rng = np.random.default_rng(1)
    p = np.concatenate([rng.integers(0, 2**32, 10_000, dtype=np.uint64).astype(np.uint32),
                        np.array([0, 0xFFFFFFFF, 0x1FFFFFFF, 0x80000000], np.uint32)])
    q = unpack_qtangent(p)
    assert np.isfinite(q).all()
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-5)
    np.testing.assert_array_equal(q[:, 3] < 0, (p >> 31) == 1)


def test_pack_is_canonical_for_q_and_minus_q() -> None:
    n, t = random_frames(1000, seed=2)
    q = tbn_to_qtangent(n, t)
    a = qtangent_to_tbn(unpack_qtangent(pack_qtangent(q)))
    b = qtangent_to_tbn(unpack_qtangent(pack_qtangent(-q)))
    assert frame_angular_error_deg(*a, *b).max() > 90  # -q flips handedness by convention
    np.testing.assert_array_equal(a[0], b[0])  # ... but not the normal


def test_frame_error_sees_handedness() -> None:
    n, t = random_frames(10, seed=4)
    t2 = t.copy()
    t2[:, 3] *= -1
    np.testing.assert_allclose(frame_angular_error_deg(n, t, n, t2), 180.0, atol=1e-3)
    np.testing.assert_allclose(frame_angular_error_deg(n, t, n, t), 0.0, atol=1e-3)


def test_frame_streams_equal_one_call_per_mesh() -> None:
    """frame_streams (one encode over every mesh, in chunks on threads) is bit for bit the
    per-mesh calls, a mesh's own QTangents / packed frames kept as they are."""
    rng = np.random.default_rng(7)
    sizes = (5, 70_000, 1, 40_000)  # > frames._CHUNK: several threads' shares
    meshes = [(rng.normal(size=(n, 3)).astype(np.float32),
               np.concatenate([rng.normal(size=(n, 3)), rng.choice([-1.0, 1.0], (n, 1))], 1)
               .astype(np.float32)) for n in sizes]
    qs = [tbn_to_qtangent(n, t) for n, t in meshes]
    packed = [pack_qtangent(q) for q in qs]
    own_q = [None, None, qs[2], qs[3] * 2]  # a baked mesh's own are used, not recomputed
    own_pk = [None, packed[1], None, packed[3] ^ 1]
    sources = [(n, t, q, pk) for (n, t), q, pk in zip(meshes, own_q, own_pk, strict=True)]
    want_q = np.concatenate([q if o is None else o for q, o in zip(qs, own_q, strict=True)])
    want_pk = np.concatenate([pack_qtangent(q) if o is None else o for q, o in
                              zip([qs[0], qs[1], qs[2], qs[3] * 2], own_pk, strict=True)])
    for threads in (1, 3):
        got_q, got_pk = frame_streams(sources, threads=threads)
        np.testing.assert_array_equal(got_q, want_q)
        np.testing.assert_array_equal(got_pk, want_pk)
    got_q, got_pk = frame_streams(sources, packed=False)
    assert got_pk is None
    np.testing.assert_array_equal(got_q, want_q)
