# The camera API users bring their poses in (vkpbr.scene.camera), checked without a GPU against
# an independent NumPy pinhole projection: pixels = K @ (R^T (X - t)) / z, OpenCV's convention
# with the centre of the top-left pixel at (0, 0).

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from vkpbr.errors import UsageError
from vkpbr.scene import camera as cam_api
from vkpbr.scene.camera import as_camera, format_camera, parse_camera, validate_camera
from vkpbr.scene.types import Camera

FLIP = np.diag([1.0, -1.0, -1.0, 1.0])  # OpenCV <-> OpenGL camera axes


def rotation(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a (not necessarily unit) quaternion (w, x, y, z)."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def project(K: np.ndarray, world_from_camera: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The independent pinhole projection: (N, 3) world points -> (N, 2) OpenCV pixels."""
    r, t = world_from_camera[:3, :3], world_from_camera[:3, 3]
    cam = (points - t) @ r  # = R^T (X - t) per row
    uvw = cam @ K.T
    return uvw[:, :2] / uvw[:, 2:3]


finite = st.floats(-50.0, 50.0, allow_nan=False)
quaternions = hnp.arrays(np.float64, 4, elements=st.floats(-1.0, 1.0)).filter(
    lambda q: np.linalg.norm(q) > 0.1)
sizes = st.tuples(st.integers(1, 4096), st.integers(1, 4096))


@st.composite
def calibrations(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    w, h = draw(sizes)
    fx, fy = draw(st.floats(0.2, 20.0)) * w, draw(st.floats(0.2, 20.0)) * h
    cx, cy = draw(st.floats(-0.5, 1.5)) * w, draw(st.floats(-0.5, 1.5)) * h
    K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    pose = np.eye(4)
    pose[:3, :3] = rotation(draw(quaternions))
    pose[:3, 3] = draw(st.tuples(finite, finite, finite))
    return K, pose, (w, h)


def points_in_front(pose: np.ndarray, seed: int) -> np.ndarray:
    """World points 0.1 to 100 units in front of the camera (OpenCV pose), in any direction."""
    rng = np.random.default_rng(seed)
    cam = rng.uniform(-1.0, 1.0, (16, 3))
    cam[:, 2] = 1.0
    cam *= rng.uniform(0.1, 100.0, (16, 1))
    return cam @ pose[:3, :3].T + pose[:3, 3]


@settings(max_examples=200, deadline=None)
@given(calibrations(), st.integers(0, 2**32 - 1))
def test_from_opencv_reprojects_to_the_same_pixels(calib, seed) -> None:  # noqa: ANN001
    K, pose, size = calib
    pts = points_in_front(pose, seed)
    expected = project(K, pose, pts)
    cam = Camera.from_opencv(K, pose, size)
    np.testing.assert_allclose(cam.intrinsics(size), K, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(project(cam.intrinsics(size), cam.world_from_camera("opencv"), pts),
                               expected, rtol=0, atol=1e-6)
    np.testing.assert_allclose(cam.world_from_camera("opencv"), pose, rtol=0, atol=1e-9)


@settings(max_examples=100, deadline=None)
@given(calibrations(), st.integers(0, 2**32 - 1))
def test_camera_fields_alone_give_the_same_pixels(calib, seed) -> None:  # noqa: ANN001
    # eye/target/up and yfov_deg, read without world_from_camera or intrinsics: the look-at
    # basis the renderer builds, and fy from the field of view.
    K, pose, (w, h) = calib
    pts = points_in_front(pose, seed)
    cam = Camera.from_opencv(K, pose, (w, h))
    eye, target, up = (np.array(v) for v in (cam.eye, cam.target, cam.up))
    f = (target - eye) / np.linalg.norm(target - eye)
    s = np.cross(f, up) / np.linalg.norm(np.cross(f, up))
    u = np.cross(s, f)
    rel = pts - eye
    x, y, z = rel @ s, -(rel @ u), rel @ f
    fy = (h / 2) / math.tan(math.radians(cam.yfov_deg) / 2)
    assert fy == pytest.approx(K[1, 1], rel=1e-12)
    pix = np.stack([K[0, 0] * x / z + K[0, 2], fy * y / z + K[1, 2]], axis=1)
    np.testing.assert_allclose(pix, project(K, pose, pts), rtol=0, atol=1e-6)


@settings(max_examples=100, deadline=None)
@given(calibrations(), sizes)
def test_intrinsics_scale_to_other_sizes(calib, size2) -> None:  # noqa: ANN001
    K, pose, (w, h) = calib
    W, H = size2
    cam = Camera.from_opencv(K, pose, (w, h))
    pts = points_in_front(pose, 7)
    a = project(cam.intrinsics((w, h)), pose, pts)
    b = project(cam.intrinsics((W, H)), pose, pts)
    # The same place on the image: pixel-centre coordinates scale about the image's corner.
    np.testing.assert_allclose((b + 0.5) / (W, H), (a + 0.5) / (w, h), rtol=0, atol=1e-9)


def test_intrinsics_scaling_hand_worked() -> None:
    cam = Camera(yfov_deg=2 * math.degrees(math.atan(3 / (2 * 5.0))),
                 pixel_intrinsics=(4.0, 5.0, 1.5, 1.0, 4, 3))
    np.testing.assert_allclose(cam.intrinsics((8, 6)), [[8, 0, 3.5], [0, 10, 2.5], [0, 0, 1]])
    np.testing.assert_allclose(cam.intrinsics((2, 3)), [[2, 0, 0.5], [0, 5, 1], [0, 0, 1]])


@pytest.mark.parametrize("size", [(1, 1), (2, 2), (64, 48), (63, 47), (1920, 1080)])
def test_pixel_centre_convention(size) -> None:  # noqa: ANN001
    W, H = size
    cam = Camera(eye=(1.0, 2.0, 3.0), target=(0.0, 0.5, -1.0), yfov_deg=50.0)
    K = cam.intrinsics(size)
    assert (K[0, 2], K[1, 2]) == ((W - 1) / 2, (H - 1) / 2)
    pose = cam.world_from_camera("opencv")
    pts = np.array([cam.target, pose[:3, 3] + 7.0 * pose[:3, 2]])  # on the optical axis
    np.testing.assert_allclose(project(K, pose, pts), [[(W - 1) / 2, (H - 1) / 2]] * 2, atol=1e-9)
    # A point at half the field of view above the axis lands on the image's top edge, which
    # is y = -0.5 in this convention (the top-left pixel's centre is y = 0).
    t = math.tan(math.radians(50.0) / 2)
    edge = pose[:3, 3] + pose[:3, 2] - t * pose[:3, 1]
    assert project(K, pose, edge[None])[0, 1] == pytest.approx(-0.5, abs=1e-9)
    # And a centred K given to from_opencv keeps its principal point on the axis.
    cv = Camera.from_opencv(K, pose, size)
    assert project(cv.intrinsics(size), cv.world_from_camera(), pts[:1])[0] == pytest.approx(
        [(W - 1) / 2, (H - 1) / 2], abs=1e-9)


def test_conventions_hand_worked() -> None:
    gl = Camera.from_pose(np.eye(4))  # OpenGL: looks down -z, y up
    assert gl.eye == (0.0, 0.0, 0.0) and gl.target == (0.0, 0.0, -1.0) and gl.up == (0.0, 1.0, 0.0)
    cv = Camera.from_opencv(np.diag([2.0, 2.0, 1.0]), np.eye(4), (4, 4))  # looks down +z, y down
    assert cv.target == (0.0, 0.0, 1.0) and cv.up == (0.0, -1.0, 0.0)
    assert cv.yfov_deg == pytest.approx(2 * math.degrees(math.atan(1.0)))
    np.testing.assert_array_equal(gl.world_from_camera("opengl"), np.eye(4))
    np.testing.assert_array_equal(gl.world_from_camera("opencv"), FLIP)


@settings(max_examples=200, deadline=None)
@given(quaternions, st.tuples(finite, finite, finite))
def test_opencv_opengl_round_trips(q, t) -> None:  # noqa: ANN001
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation(q), t
    for convention, other in (("opencv", "opengl"), ("opengl", "opencv")):
        cam = Camera.from_pose(pose, convention)
        np.testing.assert_allclose(cam.world_from_camera(convention), pose, rtol=0, atol=1e-9)
        np.testing.assert_allclose(cam.world_from_camera(other), pose @ FLIP, rtol=0, atol=1e-9)
        again = Camera.from_pose(cam.world_from_camera(other), other)
        np.testing.assert_allclose(again.world_from_camera(convention), pose, rtol=0, atol=1e-9)
    # from_pose in OpenCV axes and from_opencv place the camera identically.
    a = Camera.from_pose(pose, "opencv")
    b = Camera.from_opencv(np.diag([10.0, 10.0, 1.0]), pose, (20, 20))
    np.testing.assert_allclose(a.world_from_camera(), b.world_from_camera(), rtol=0, atol=1e-12)


def test_from_pose_takes_the_rest_from_base() -> None:
    base = Camera(yfov_deg=33.0, znear=0.2, zfar=50.0, name="auto")
    cam = Camera.from_pose(np.eye(4).tolist(), base=base)
    assert (cam.yfov_deg, cam.znear, cam.zfar, cam.name) == (33.0, 0.2, 50.0, "")
    assert Camera.from_pose(np.eye(4), yfov_deg=70, base=base).yfov_deg == 70.0
    calibrated = Camera.from_opencv(np.diag([5.0, 5.0, 1.0]), np.eye(4), (8, 8))
    assert Camera.from_pose(np.eye(4), yfov_deg=40, base=calibrated).pixel_intrinsics is None


def test_as_camera_accepts_each_form() -> None:
    base = Camera(yfov_deg=40.0, up=(0.0, 0.0, 1.0))
    given_cam = Camera(eye=(1.0, 1.0, 1.0))
    assert as_camera(given_cam, base) is given_cam
    pose = np.eye(4)
    pose[:3, 3] = (1.0, 2.0, 3.0)
    for value in (pose, pose.tolist(), tuple(map(tuple, pose))):
        cam = as_camera(value, base)
        assert cam.eye == (1.0, 2.0, 3.0) and cam.target == (1.0, 2.0, 2.0)  # OpenGL default
        assert cam.yfov_deg == 40.0
    assert as_camera(pose, base, convention="opencv").target == (1.0, 2.0, 4.0)
    assert as_camera("1,2,3,0,0,0", base).up == (0.0, 0.0, 1.0)
    assert as_camera("1,2,3,0,0,0,0,1,0", base).up == (0.0, 1.0, 0.0)
    cam = as_camera({"eye": [5, 0, 0], "target": [0, 0, 0], "fov": 30, "name": "n"}, base)
    assert (cam.eye, cam.yfov_deg, cam.name, cam.up) == ((5.0, 0.0, 0.0), 30.0, "n", base.up)
    cam = as_camera({"world_from_camera": pose.tolist(), "convention": "opencv"}, base)
    assert cam.target == (1.0, 2.0, 4.0)
    cam = as_camera({"K": np.diag([4.0, 4.0, 1.0]).tolist(), "world_from_camera": pose, "size": [8, 8]},
                    base)
    assert cam.pixel_intrinsics == (4.0, 4.0, 0.0, 0.0, 8, 8) and cam.target == (1.0, 2.0, 4.0)


def test_as_camera_names_the_type_received() -> None:
    with pytest.raises(UsageError) as err:
        as_camera(np.eye(3), Camera())
    assert str(err.value) == ("camera: expected a Camera, a 4x4 pose, a pose dict or an "
                              "'ex,ey,ez,tx,ty,tz' string, got ndarray of shape (3, 3)")
    for value, name in ((None, "None"), (3.5, "float"), ([1, 2, 3], "list of length 3"),
                        (b"1,2,3,4,5,6", "bytes"), (np.eye(4)[None], "ndarray of shape (1, 4, 4)")):
        _raises_usage_error(as_camera, value, Camera(), match=f"got {name}")


def _raises_usage_error(call, *args, match: str = "", **kwargs) -> str:  # noqa: ANN001
    try:
        call(*args, **kwargs)
    except UsageError as exc:
        message = str(exc)
        assert "\n" not in message and match in message, message
        return message
    except Exception as exc:  # noqa: BLE001 - any other type is the failure under test
        pytest.fail(f"{type(exc).__name__} escaped: {exc}")
    pytest.fail("no error raised")


K_OK = np.array([[100.0, 0.0, 32.0], [0.0, 100.0, 24.0], [0.0, 0.0, 1.0]])
SCALED = np.diag([2.0, 2.0, 2.0, 1.0])
MIRROR = np.diag([1.0, 1.0, -1.0, 1.0])
SHEAR = np.eye(4)
SHEAR[0, 1] = 0.01


@pytest.mark.parametrize("K, pose, size, match", [
    (np.eye(3)[:2], np.eye(4), (64, 48), "K: expected shape (3, 3), got (2, 3)"),
    ([[1, 0, 0], [0, 1, 0]], np.eye(4), (64, 48), "K: expected 3 items, got 2"),
    ([[1, 0, 0], [0, 1, 0], [0, 0, "1"]], np.eye(4), (64, 48), "K[2][2]: expected a number, got str"),
    ([[1, 0, 0], [0, 1, 0], [0, 0, True]], np.eye(4), (64, 48), "K[2][2]: expected a number, got bool"),
    (K_OK * np.nan, np.eye(4), (64, 48), "K: the numbers must be finite"),
    (np.array([[100, 0.3, 32], [0, 100, 24], [0, 0, 1]]), np.eye(4), (64, 48),
     "skewed intrinsics are not supported"),
    (np.diag([-1.0, 1.0, 1.0]), np.eye(4), (64, 48), "fx (-1) and fy (1) must be > 0"),
    (np.diag([1.0, 0.0, 1.0]), np.eye(4), (64, 48), "must be > 0"),
    (np.diag([1.0, 1.0, 2.0]), np.eye(4), (64, 48), "K: expected [[fx, 0, cx]"),
    (K_OK.astype(str), np.eye(4), (64, 48), "K: expected numbers, got an array of <U"),
    ("K", np.eye(4), (64, 48), "K: expected a 3x3 matrix, got str"),
    (None, np.eye(4), (64, 48), "K: expected a 3x3 matrix, got None"),
    ({"fx": 1}, np.eye(4), (64, 48), "K: expected a 3x3 matrix, got dict"),
    (K_OK, np.eye(3), (64, 48), "world_from_camera: expected shape (4, 4), got (3, 3)"),
    (K_OK, np.full((4, 4), np.inf), (64, 48), "world_from_camera: the numbers must be finite"),
    (K_OK, SCALED, (64, 48), "not a rigid transform"),
    (K_OK, SHEAR, (64, 48), "not a rigid transform"),
    (K_OK, MIRROR, (64, 48), "reflection"),
    (K_OK, np.eye(4) + np.eye(4, k=-3), (64, 48), "the last row must be [0, 0, 0, 1]"),
    (K_OK, np.vstack([np.full((3, 4), 1e300), [0, 0, 0, 1]]), (64, 48), "not a rigid transform"),
    (K_OK, [[1, 0, 0, 0]] * 3 + [[0, 0, 0]], (64, 48), "world_from_camera[3]: expected 4 items"),
    (K_OK, np.eye(4), (0, 48), "width must be a positive integer, got 0"),
    (K_OK, np.eye(4), (64,), "size: expected (width, height), got tuple of length 1"),
    (K_OK, np.eye(4), "64x48", "size: expected (width, height), got str"),
    (K_OK, np.eye(4), (64.0, 48), "width must be a positive integer, got 64.0"),
    (K_OK, np.eye(4), (64, True), "height must be a positive integer, got True"),
])
def test_from_opencv_errors(K, pose, size, match) -> None:  # noqa: ANN001
    message = _raises_usage_error(Camera.from_opencv, K, pose, size, match=match)
    assert message.startswith("from_opencv: ")


@pytest.mark.parametrize("args, kwargs, match", [
    ((np.eye(3),), {}, "matrix: expected shape (4, 4), got (3, 3)"),
    ((np.eye(4), "blender"), {}, 'convention: expected "opengl"'),
    ((np.eye(4), None), {}, "got None"),
    ((np.eye(4), np.array(["opengl"])), {}, "convention"),
    ((SCALED,), {}, "not a rigid transform"),
    ((MIRROR,), {}, "reflection"),
    (([[1, 2], [3]],), {}, "matrix: expected 4 items, got 2"),
    ((np.eye(4).astype(object),), {}, "expected numbers, got an array of object"),
    ((np.eye(4).astype(bool),), {}, "expected numbers, got an array of bool"),
    ((np.eye(4),), {"yfov_deg": 200.0}, "field of view 200.0 must be in (0, 180)"),
    ((np.eye(4),), {"yfov_deg": "wide"}, "yfov_deg: expected a number, got str"),
    ((np.eye(4),), {"yfov_deg": np.array([45.0, 50.0])}, "yfov_deg: expected a number"),
])
def test_from_pose_errors(args, kwargs, match) -> None:  # noqa: ANN001
    message = _raises_usage_error(Camera.from_pose, *args, match=match, **kwargs)
    assert message.startswith("from_pose: ")


@pytest.mark.parametrize("value, match", [
    ("1,2,3", "expected 6 or 9 numbers, got 3"),
    ("a,b,c,d,e,f", "expected 6 or 9 comma-separated numbers"),
    ("0,0,0,0,0,0", "eye and target coincide"),
    ("0,0,0,0,0,1,0,0,1", "up is parallel"),
    ("inf,0,0,1,1,1", "must be finite"),
    ({}, 'expected "eye" and "target"'),
    ({"eye": [0, 0, 1]}, "missing 'target'"),
    ({"eye": [0, 0, 1], "target": [0, 0]}, '"target": expected 3 items, got 2'),
    ({"eye": [0, 0, 1], "target": "origin"}, '"target": expected a 3 matrix, got str'),
    ({"eye": [0, 0, 1], "target": [0, 0, 0], "fov": 0}, '"fov": 0 must be in (0, 180)'),
    ({"eye": [0, 0, 1], "target": [0, 0, 0], "fov": "45"}, '"fov": expected a number, got str'),
    ({"eye": [0, 0, 1], "target": [0, 0, 0], "fovy": 45}, "unknown key 'fovy'"),
    ({"eye": [0, 0, 1], "target": [0, 0, 0], "name": 3}, '"name": expected a string'),
    ({1: 2}, "keys must be strings"),
    ({"world_from_camera": np.eye(4).tolist()}, "missing 'convention'"),
    ({"world_from_camera": np.eye(4).tolist(), "convention": "cv"}, "convention: expected"),
    ({"world_from_camera": SCALED.tolist(), "convention": "opengl"}, "not a rigid transform"),
    ({"K": K_OK.tolist(), "world_from_camera": np.eye(4).tolist()}, "missing 'size'"),
    ({"K": K_OK.tolist(), "world_from_camera": np.eye(4).tolist(), "size": [64, 48], "fov": 3},
     "unknown key 'fov'"),
    (np.eye(4)[:3], "got ndarray of shape (3, 4)"),
    ([[1, 0, 0, 0]] * 3 + [[0, 0, 0, "1"]], "pose[3][3]: expected a number, got str"),
    (Camera, "got type"),
])
def test_as_camera_errors(value, match) -> None:  # noqa: ANN001
    message = _raises_usage_error(as_camera, value, Camera(), match=match)
    assert message.startswith("camera: ")


# Anything at all, as a user might pass it: JSON-like values and NumPy arrays of any dtype.
junk = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8)
    | hnp.arrays(hnp.scalar_dtypes(), hnp.array_shapes(max_dims=3, max_side=5)),
    lambda children: st.lists(children, max_size=5) | st.dictionaries(st.text(max_size=6), children,
                                                                      max_size=4),
    max_leaves=20,
)
pose_like = st.one_of(
    junk,
    st.lists(st.lists(st.floats() | st.integers() | st.none(), min_size=4, max_size=4), min_size=4,
             max_size=4),
    hnp.arrays(np.float64, (4, 4)),
    st.builds(lambda e, t, u, f: {"eye": e, "target": t, "up": u, "fov": f}, junk, junk, junk, junk),
    st.builds(lambda m, c: {"world_from_camera": m, "convention": c}, junk,
              st.sampled_from(["opengl", "opencv"]) | junk),
    st.builds(lambda k, m, s: {"K": k, "world_from_camera": m, "size": s}, junk, junk, junk),
)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pose_like, pose_like, junk)
def test_junk_raises_only_usage_errors(a, b, c) -> None:  # noqa: ANN001
    for call in (lambda: as_camera(a, Camera()), lambda: Camera.from_pose(a, yfov_deg=c),
                 lambda: Camera.from_pose(a, c), lambda: Camera.from_opencv(a, b, c),
                 lambda: Camera.from_opencv(K_OK, a, (64, 48)),
                 lambda: Camera.from_opencv(K_OK, np.eye(4), a)):
        try:
            result = call()
        except UsageError as exc:
            assert "\n" not in str(exc)
        else:
            validate_camera(result)


def test_validate_camera_planes_and_intrinsics() -> None:
    validate_camera(Camera(znear=None, zfar=None))
    validate_camera(Camera(znear=0.01, zfar=None))
    validate_camera(Camera(znear=None, zfar=10.0))
    validate_camera(Camera(znear=0.1, zfar=math.inf))
    for kwargs, match in (({"znear": 0.0}, "near plane 0.0 must be a finite number > 0"),
                          ({"znear": -1.0}, "near plane"),
                          ({"znear": math.nan}, "near plane nan must be a number"),
                          ({"znear": 1.0, "zfar": 1.0}, "far plane 1.0 must be beyond the near plane 1.0"),
                          ({"zfar": -5.0}, "far plane -5.0 must be beyond the near plane None"),
                          ({"znear": "0.1"}, "near plane '0.1' must be a number"),
                          ({"yfov_deg": 180.0}, "field of view 180.0 must be in (0, 180)"),
                          ({"yfov_deg": 3e-262}, "narrower than 0.0001 degrees"),
                          ({"eye": (0, 0)}, "three numbers"),
                          ({"pixel_intrinsics": (1.0, 1.0, 0.0, 0.0, 4)}, "pixel_intrinsics must be")):
        message = _raises_usage_error(validate_camera, Camera(**kwargs), match=match)
        assert message.startswith("camera: ")
    calibrated = Camera.from_opencv(K_OK, np.eye(4), (64, 48))
    validate_camera(calibrated)
    # A field of view changed without the intrinsics that define it is caught, not ignored.
    _raises_usage_error(validate_camera, dataclasses.replace(calibrated, yfov_deg=30.0),
                        match="disagrees with pixel_intrinsics")
    _raises_usage_error(validate_camera, dataclasses.replace(
        calibrated, pixel_intrinsics=(0.0, 100.0, 32.0, 24.0, 64, 48)), match="must be > 0")
    _raises_usage_error(calibrated.intrinsics, (0, 3), match="width must be a positive integer")
    _raises_usage_error(calibrated.world_from_camera, "blender", match='expected "opengl"')


def test_parse_and_format_camera() -> None:
    base = Camera(yfov_deg=33.0, znear=None, zfar=None, up=(0.0, 0.0, 1.0))
    cam = parse_camera("1, 2, 3, 0, 0, 0", base)
    assert (cam.eye, cam.target, cam.up, cam.yfov_deg) == ((1.0, 2.0, 3.0), (0.0, 0.0, 0.0),
                                                           (0.0, 0.0, 1.0), 33.0)
    assert parse_camera(format_camera(cam)) == dataclasses.replace(Camera(), eye=cam.eye,
                                                                   target=cam.target, up=cam.up)
    _raises_usage_error(parse_camera, "1,2,3", match="--camera '1,2,3': expected 6 or 9 numbers")


def test_render_camera_re_exports_the_scene_functions() -> None:
    from vkpbr.render import camera as render_camera

    for name in ("parse_camera", "format_camera", "validate_camera"):
        assert getattr(render_camera, name) is getattr(cam_api, name)


def test_scene_camera_imports_without_vulkan() -> None:
    code = ("import sys; sys.modules['vulkan'] = None\n"  # any `import vulkan` now fails
            "import vkpbr.scene.camera, vkpbr.scene.poses\n"
            "from vkpbr.scene.types import Camera\n"
            "Camera().intrinsics((4, 3)); Camera().world_from_camera('opengl')\n"
            "assert not [m for m in sys.modules if m.startswith('vulkan') and sys.modules[m]]\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("size", [(True, 4), (4, False), (np.bool_(True), 3), (0, 3), (-1, 3),
                                  (2.5, 3), ("a", 3), (3,), 7, (20000, 3)])
def test_a_bad_frame_size_is_one_line(size: object) -> None:
    """What `render(size=...)` refuses: not two positive integers (booleans neither: True is
    no width), or beyond the device's limit."""
    from vkpbr.scene._checks import frame_size

    with pytest.raises(UsageError) as got:
        frame_size(size, 16384)
    assert "\n" not in str(got.value)


def test_a_frame_size_of_numpy_integers() -> None:
    from vkpbr.scene._checks import frame_size

    assert frame_size((np.int64(3), np.uint16(5)), 100) == (3, 5)
