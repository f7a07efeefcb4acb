"""CameraBatch and the batch's camera maths (issue 14; issue 30's one views record): the same
numbers as one camera at a time, bit for bit, for cameras anywhere (so a batch's views can
equal single frames)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.errors import UsageError
from vkpbr.render import layouts as L
from vkpbr.render.camera import (
    batch_frame_terms,
    camera_frame_columns,
    depth_range,
    forward,
    view_projection,
)
from vkpbr.render.views import ViewTerms, batch_view_terms, camera_view_terms, fill_views, pack_view
from vkpbr.scene.camera_batch import CameraBatch, as_camera_batch
from vkpbr.scene.types import Camera

CORNERS = tuple((x, y, z) for x in (-3.0, 4.5) for y in (-0.5, 6.0) for z in (-2.0, 2.5))
SCALE = 5.3

coord = st.floats(-50, 50, allow_nan=False)
vec = st.tuples(coord, coord, coord)


@st.composite
def cameras(draw) -> Camera:  # noqa: ANN001
    eye, target = draw(vec), draw(vec)
    up = draw(st.sampled_from([(0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.3, 0.9, -0.1)]))
    f = np.subtract(target, eye)
    if np.linalg.norm(f) < 1e-3 or np.linalg.norm(np.cross(f, up)) < 1e-6 * np.linalg.norm(f):
        target = (eye[0] + 1.0, eye[1] + 0.25, eye[2] - 0.5)
    cam = Camera(eye=eye, target=target, up=up, yfov_deg=draw(st.floats(1.0, 170.0)))
    if draw(st.booleans()):
        cam = dataclasses.replace(cam, znear=draw(st.floats(1e-3, 10.0)))
    if draw(st.booleans()):
        w, h = draw(st.integers(16, 4000)), draw(st.integers(16, 4000))
        fx, fy = draw(st.floats(10.0, 5000.0)), draw(st.floats(10.0, 5000.0))
        cx, cy = draw(st.floats(0.0, w)), draw(st.floats(0.0, h))
        cam = dataclasses.replace(cam, pixel_intrinsics=(fx, fy, cx, cy, w, h),
                                  yfov_deg=float(np.degrees(2 * np.arctan(h / (2 * fy)))))
    return cam


SIZES = st.sampled_from([(64, 48), (128, 128), (1920, 1080)])


@settings(max_examples=200, deadline=None)
@given(st.lists(cameras(), min_size=1, max_size=6), SIZES)
def test_batch_views_equal_single_frame_views(cams: list[Camera], size: tuple[int, int]) -> None:
    """The views record's one function over a batch's (N,) arrays gives each view the float64
    terms, and then the record bytes, that a single frame of that camera gets from it in
    Python floats: every bit, for cameras anywhere, with and without intrinsics and planes."""
    b = CameraBatch.from_cameras(cams, cams[0])
    n = len(cams)
    terms = batch_view_terms(b, size, CORNERS, SCALE)
    records = np.zeros(n, L.VIEW_RECORD.dtype)
    fill_views(records, terms, np.tile(np.array([0, 0, *size], np.uint32), (n, 1)),
               np.zeros(n, np.uint32))
    for i, cam in enumerate(cams):
        one = camera_view_terms(cam, size, CORNERS, SCALE)
        for name, batch_value, value in zip(ViewTerms._fields, terms, one, strict=True):
            got = [np.broadcast_to(v, n)[i] for v in batch_value] if isinstance(value, tuple) \
                else np.broadcast_to(batch_value, n)[i]
            assert np.array_equal(got, value), name  # float64, every bit
        packed = bytearray(L.VIEW_RECORD.size)
        pack_view(packed, one, (0, 0, *size))
        assert records[i].tobytes() == bytes(packed)
        assert b.camera(i) == cam


@settings(max_examples=100, deadline=None)
@given(cameras(), SIZES)
def test_view_terms_equal_the_numpy_matrices(cam: Camera, size: tuple[int, int]) -> None:
    """The plain-float VP equals the NumPy reference P @ V (render/camera.py); the old names
    return the views record's values."""
    t = camera_view_terms(cam, size, CORNERS, SCALE)
    want = view_projection(cam, size, t.znear)
    np.testing.assert_allclose(np.array(t.vp).reshape(4, 4).T, want, rtol=1e-12,
                               atol=1e-12 * np.abs(want).max())
    assert depth_range(cam, CORNERS, SCALE) == (t.znear, t.zfar)
    assert camera_frame_columns(cam, size, t.znear) == (t.vp, t.inv_vp, t.rotation)
    assert forward(cam) == t.forward
    b = CameraBatch.from_cameras([cam], cam)
    old = batch_frame_terms(b.eye, b.target, b.up, b.yfov_deg, b.intrinsics, b.znear, b.zfar,
                            size, CORNERS, SCALE)
    assert tuple(old["vp"][0]) == t.vp and tuple(old["inv_vp"][0]) == t.inv_vp
    assert (old["znear"][0], old["zfar"][0]) == (t.znear, t.zfar)


@settings(max_examples=100, deadline=None)
@given(st.lists(cameras(), min_size=1, max_size=4))
def test_poses_round_trip(cams: list[Camera]) -> None:
    """from_poses of Camera.world_from_camera gives Camera.from_pose's cameras exactly."""
    cams = [dataclasses.replace(c, pixel_intrinsics=None, znear=None) for c in cams]
    for conv in ("opengl", "opencv"):
        poses = np.stack([c.world_from_camera(conv) for c in cams])
        b = CameraBatch.from_poses(poses, 50.0, conv)
        for i, m in enumerate(poses):
            assert b.camera(i) == Camera.from_pose(m, conv, yfov_deg=50.0)


def test_bad_batches_name_the_view() -> None:
    eye = np.zeros((4, 3))
    eye[2] = (0.0, 0.0, 1.0)
    with pytest.raises(UsageError, match=r"cameras\[0\]: eye and target coincide"):
        CameraBatch.from_look_at(eye, np.zeros(3))
    with pytest.raises(UsageError, match=r"field of view"):
        CameraBatch.from_look_at(np.ones((2, 3)), np.zeros(3), yfov_deg=[45.0, 180.0])
    with pytest.raises(UsageError, match=r"yfov_deg must be one number or 2 numbers"):
        CameraBatch.from_look_at(np.ones((2, 3)), np.zeros(3), yfov_deg=[45.0, 50.0, 55.0])
    with pytest.raises(UsageError, match=r"eye must have shape \(B, 3\)"):
        CameraBatch.from_look_at(np.ones((2, 2)), np.zeros(3))
    with pytest.raises(UsageError, match="K's fx and fy must be > 0"):
        CameraBatch.from_opencv(np.zeros((3, 3)), np.tile(np.eye(4), (2, 1, 1)), (64, 48))
    with pytest.raises(UsageError, match="convention 'blender'"):
        CameraBatch.from_poses(np.tile(np.eye(4), (2, 1, 1)), convention="blender")
    with pytest.raises(UsageError, match="expected a list of cameras"):
        as_camera_batch(42, Camera())


def test_absurd_magnitudes_are_refused_for_one_camera_too() -> None:
    """A camera at 1e300 (finite, far beyond float32) was a ZeroDivisionError in render()."""
    from vkpbr.scene.camera import validate_camera

    with pytest.raises(UsageError, match=r"within \+-1e\+15"):
        validate_camera(Camera(eye=(1e300, 0.0, 0.0), target=(0.0, 0.0, 0.0)))
    validate_camera(Camera(eye=(1e14, 0.0, 0.0), target=(0.0, 0.0, 0.0)))  # large, still fine


# -- generators (issue 35): orbits, spheres, random views, checked with tests/pinhole.py --------

def _corners(lo, hi):  # noqa: ANN001, ANN202
    return [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]


def _sees_all(batch, bounds, size=(64, 48)) -> bool:  # noqa: ANN001
    from pinhole import project

    for i in range(len(batch)):
        cam = batch.camera(i)
        for p in _corners(*bounds):
            row, col, z = project(cam, p, *size)
            if not (z > 0 and 0 <= row <= size[1] and 0 <= col <= size[0]):
                return False
    return True


def test_orbit_is_a_framed_turntable() -> None:
    import numpy as np

    from vkpbr.scene.camera_batch import CameraBatch, framing_distance

    bounds = ((-1.0, 0.0, -0.5), (3.0, 2.0, 0.5))
    b = CameraBatch.orbit(12, bounds=bounds, elevation_deg=30.0)
    centre = np.array([1.0, 1.0, 0.0])
    rel = b.eye - centre
    r = framing_distance(bounds, 45.0)
    assert np.allclose(np.linalg.norm(rel, axis=1), r) and np.allclose(b.target, centre)
    assert np.allclose(np.degrees(np.arcsin(rel[:, 1] / r)), 30.0)  # the elevation
    az = np.unwrap(np.arctan2(rel[:, 0], rel[:, 2]))
    assert np.allclose(np.diff(az), 2 * np.pi / 12) and abs(az[0]) < 1e-12  # +Z first, CCW
    assert _sees_all(b, bounds)  # every corner of the bounds in every image
    explicit = CameraBatch.orbit(4, center=(0, 0, 0), radius=2.0, elevation_deg=0.0)
    assert np.allclose(explicit.eye, [[0, 0, 2], [2, 0, 0], [0, 0, -2], [-2, 0, 0]], atol=1e-12)


def test_sphere_spreads_views_evenly() -> None:
    import numpy as np

    from vkpbr.scene.camera_batch import CameraBatch

    b = CameraBatch.sphere(200, center=(1, 2, 3), radius=5.0)
    d = (b.eye - (1, 2, 3)) / 5.0
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.linalg.norm(d.mean(axis=0)) < 0.02  # balanced
    gaps = np.sort(np.linalg.norm(d[:, None] - d[None], axis=-1), axis=1)[:, 1]
    assert gaps.min() > 0.5 * gaps.mean()  # no clumps (a Fibonacci lattice: ~0.25 apart here)
    upper = CameraBatch.sphere(50, bounds=((0, 0, 0), (1, 1, 1)), upper=True)
    assert (upper.eye[:, 1] > 0.5).all() and _sees_all(upper, ((0, 0, 0), (1, 1, 1)))


def test_look_at_random_views_of_the_bounds() -> None:
    import numpy as np
    import pytest

    from vkpbr.errors import UsageError
    from vkpbr.scene.camera_batch import CameraBatch, framing_distance

    bounds = ((0.0, 0.0, 0.0), (1.0, 2.0, 3.0))
    a = CameraBatch.look_at_random(300, bounds, seed=7, distance=(1.0, 1.5))
    assert np.array_equal(a.eye, CameraBatch.look_at_random(300, bounds, seed=7, distance=(1.0, 1.5)).eye)
    assert ((a.target >= 0) & (a.target <= (1, 2, 3))).all()
    dist = np.linalg.norm(a.eye - a.target, axis=1) / framing_distance(bounds)
    assert dist.min() >= 1.0 - 1e-9 and dist.max() <= 1.5 + 1e-9
    for bad in (dict(n=0, bounds=bounds), dict(n=3, bounds=((0, 0, 0), (1, 1)))):
        with pytest.raises(UsageError):
            CameraBatch.look_at_random(**bad)
    with pytest.raises(UsageError, match="center"):
        CameraBatch.orbit(3)
