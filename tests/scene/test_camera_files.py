# Camera files (vkpbr.scene.camera_files) against what other tools compute from them: the
# transforms.json and COLMAP files are parsed here with plain json / str.split (a NeRF-style
# loader's few lines), and points projected with the written K and pose are compared with the
# independent pinhole of tests/pinhole.py (pixel centres at i + 0.5, the NeRF/COLMAP
# convention) to 1e-6 px.

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from pinhole import project as pinhole_project

from vkpbr.errors import UsageError
from vkpbr.scene.camera_files import (
    colmap_text,
    quaternion_from_rotation,
    read_colmap,
    read_transforms,
    rotation_from_quaternion,
    transforms_dict,
    write_colmap,
    write_transforms,
)
from vkpbr.scene.types import Camera

coord = st.floats(-20.0, 20.0, allow_nan=False)
vec = st.tuples(coord, coord, coord)
sizes = st.tuples(st.integers(1, 2048), st.integers(1, 2048))


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


@st.composite
def cameras(draw: st.DrawFn, calibrated: bool | None = None) -> Camera:
    eye = np.array(draw(vec))
    direction = draw(hnp.arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(
        lambda d: np.linalg.norm(d) > 0.1))
    target = eye + _unit(direction) * draw(st.floats(0.1, 30.0))
    up = draw(hnp.arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(
        lambda u: np.linalg.norm(u) > 0.1
        and np.linalg.norm(np.cross(u, direction)) > 0.1 * np.linalg.norm(u)))
    yfov = draw(st.floats(10.0, 120.0))
    cam = Camera(eye=tuple(eye), target=tuple(target), up=tuple(up), yfov_deg=yfov)
    if calibrated is None:
        calibrated = draw(st.booleans())
    if calibrated:
        w, h = draw(sizes)
        fy = (h / 2.0) / math.tan(math.radians(yfov) / 2.0)
        fx = fy * draw(st.floats(0.5, 2.0))
        cx, cy = draw(st.floats(-0.2, 1.2)) * w, draw(st.floats(-0.2, 1.2)) * h
        cam.pixel_intrinsics = (fx, fy, cx, cy, w, h)
    return cam


def _basis(cam: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Unit forward and the up vector made orthogonal to it."""
    f = _unit(np.subtract(cam.target, cam.eye))
    u = np.asarray(cam.up, dtype=np.float64)
    return f, _unit(u - (u @ f) * f)


def assert_same_camera(a: Camera, b: Camera, size: tuple[int, int]) -> None:
    scale = max(1.0, float(np.abs(a.eye).max()))
    np.testing.assert_allclose(b.eye, a.eye, rtol=0, atol=1e-12 * scale)
    fa, ua = _basis(a)
    fb, ub = _basis(b)
    np.testing.assert_allclose(fb, fa, atol=1e-12)  # target: the same viewing ray
    np.testing.assert_allclose(ub, ua, atol=1e-12)
    ka, kb = a.intrinsics(size), b.intrinsics(size)
    np.testing.assert_allclose(kb, ka, rtol=1e-12, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(cams=st.lists(cameras(), min_size=1, max_size=3), size=sizes)
def test_transforms_round_trip(cams: list[Camera], size: tuple[int, int]) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "transforms.json"
        write_transforms(path, cams, size)
        back = read_transforms(path)
        assert [p.name for p in Path(tmp).iterdir()] == ["transforms.json"]  # no temporaries
    assert [c.name for c in back] == [f"frame_{i:05d}.png" for i in range(len(cams))]
    for a, b in zip(cams, back, strict=True):
        assert_same_camera(a, b, size)
        np.testing.assert_allclose(b.world_from_camera("opengl"), a.world_from_camera("opengl"),
                                   atol=1e-12 * max(1.0, float(np.abs(a.eye).max())))


@st.composite
def visible_points(draw: st.DrawFn, cam: Camera, size: tuple[int, int]) -> np.ndarray:
    """A world point in front of `cam`, inside (or a little outside) its view."""
    f, u = _basis(cam)
    r = np.cross(f, u)
    t = math.tan(math.radians(cam.yfov_deg) / 2.0)
    z = draw(st.floats(0.2, 40.0))
    x = draw(st.floats(-1.2, 1.2)) * z * t * size[0] / size[1]
    y = draw(st.floats(-1.2, 1.2)) * z * t
    return np.asarray(cam.eye) + z * f + x * r + y * u


def nerf_project(doc: dict, frame: dict, point: np.ndarray) -> tuple[float, float]:
    """A NeRF-style loader's projection: (row, column) in pixels from the top-left corner."""
    keys = {**doc, **frame}
    c2w = np.array(frame["transform_matrix"])
    p = np.linalg.inv(c2w) @ np.append(point, 1.0)  # OpenGL camera axes: x right, y up, -z
    x, y, z = p[0], -p[1], -p[2]  # to x right, y down, z forward
    return keys["fl_y"] * y / z + keys["cy"], keys["fl_x"] * x / z + keys["cx"]


def colmap_project(folder: Path, index: int, point: np.ndarray) -> tuple[float, float]:
    """A COLMAP reader's projection, parsing the text files with str.split."""
    cams = {}
    for line in (folder / "cameras.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            cid, model, _w, _h, *params = line.split()
            assert model == "PINHOLE"
            cams[cid] = [float(v) for v in params]
    data = [ln for ln in (folder / "images.txt").read_text().splitlines() if not ln.startswith("#")]
    fields = data[2 * index].split()
    assert data[2 * index + 1] == ""  # no 2D points
    qw, qx, qy, qz, tx, ty, tz = map(float, fields[1:8])
    w, x, y, z = qw, qx, qy, qz
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    pc = R @ point + np.array([tx, ty, tz])
    fx, fy, cx, cy = cams[fields[8]]
    return fy * pc[1] / pc[2] + cy, fx * pc[0] / pc[2] + cx


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), size=sizes)
def test_written_k_and_pose_project_like_the_pinhole(data: st.DataObject,
                                                      size: tuple[int, int]) -> None:
    cam = data.draw(cameras(calibrated=False))
    points = [data.draw(visible_points(cam, size)) for _ in range(3)]
    doc = transforms_dict([cam], size)
    with tempfile.TemporaryDirectory() as tmp:
        write_colmap(tmp, [cam], size)
        colmap = [colmap_project(Path(tmp), 0, p) for p in points]
    for p, by_colmap in zip(points, colmap, strict=True):
        row, col, _depth = pinhole_project(cam, p, *size)
        by_nerf = nerf_project(doc, doc["frames"][0], p)
        assert abs(by_nerf[0] - row) < 1e-6 and abs(by_nerf[1] - col) < 1e-6, (by_nerf, row, col)
        assert abs(by_colmap[0] - row) < 1e-6 and abs(by_colmap[1] - col) < 1e-6
    assert doc["w"] == size[0] and doc["h"] == size[1]
    assert math.isclose(doc["camera_angle_y"], math.radians(cam.yfov_deg), rel_tol=1e-12)


@settings(max_examples=60, deadline=None)
@given(cams=st.lists(cameras(), min_size=1, max_size=3), size=sizes)
def test_colmap_round_trip(cams: list[Camera], size: tuple[int, int]) -> None:
    names = [f"img{i}.png" for i in range(len(cams))]
    with tempfile.TemporaryDirectory() as tmp:
        paths = write_colmap(tmp, cams, size, names)
        assert sorted(p.name for p in paths) == ["cameras.txt", "images.txt", "points3D.txt"]
        back = read_colmap(tmp)
    assert [c.name for c in back] == names
    for a, b in zip(cams, back, strict=True):
        scale = max(1.0, float(np.abs(a.eye).max()))
        np.testing.assert_allclose(b.eye, a.eye, atol=1e-9 * scale)
        fa, ua = _basis(a)
        fb, ub = _basis(b)
        np.testing.assert_allclose(fb, fa, atol=1e-12)
        np.testing.assert_allclose(ub, ua, atol=1e-12)
        np.testing.assert_allclose(b.intrinsics(size), a.intrinsics(size), rtol=1e-12, atol=1e-9)


def test_calibrated_intrinsics_are_written_in_the_corner_convention() -> None:
    # An OpenCV calibration at 640x480 with cx = 300 (OpenCV, top-left pixel centre at 0):
    # NeRF's and COLMAP's cx is 300.5, and rendering at twice the size doubles everything.
    K = np.array([[500.0, 0.0, 300.0], [0.0, 510.0, 200.0], [0.0, 0.0, 1.0]])
    cam = Camera.from_opencv(K, np.eye(4), (640, 480))
    doc = transforms_dict([cam], (640, 480))
    assert (doc["fl_x"], doc["fl_y"], doc["cx"], doc["cy"]) == (500.0, 510.0, 300.5, 200.5)
    assert doc["camera_angle_x"] == 2 * math.atan(640 / 1000.0)
    doc2 = transforms_dict([cam], (1280, 960))
    assert (doc2["fl_x"], doc2["cx"], doc2["cy"], doc2["w"]) == (1000.0, 601.0, 401.0, 1280)
    text = colmap_text([cam], (640, 480))["cameras.txt"].splitlines()[-1]
    assert text == "1 PINHOLE 640 480 500.0 510.0 300.5 200.5"
    # The identity OpenCV pose: COLMAP's identity quaternion; NeRF's matrix flips y and z.
    image = colmap_text([cam], (640, 480))["images.txt"].splitlines()[4]
    assert image.split() == ["1", "1.0", "0.0", "0.0", "0.0", "0.0", "0.0", "0.0", "1",
                             "frame_00000.png"]
    assert doc["frames"][0]["transform_matrix"] == np.diag([1.0, -1.0, -1.0, 1.0]).tolist()


def test_intrinsics_shared_or_per_frame(tmp_path: Path) -> None:
    a, b = Camera(yfov_deg=40.0), Camera(eye=(1.0, 0.0, 3.0), yfov_deg=40.0)
    doc = transforms_dict([a, b], (64, 48), ["a.png", "b.png"])
    assert "fl_x" in doc and all(set(f) == {"file_path", "transform_matrix"} for f in doc["frames"])
    doc = transforms_dict([a, Camera(yfov_deg=50.0)], (64, 48))
    assert "fl_x" not in doc and all("fl_x" in f and f["w"] == 64 for f in doc["frames"])
    write_transforms(tmp_path / "t.json", [a, Camera(yfov_deg=50.0)], (64, 48))
    back = read_transforms(tmp_path / "t.json")
    assert [round(c.yfov_deg, 9) for c in back] == [40.0, 50.0]
    text = colmap_text([a, b, Camera(yfov_deg=50.0)], (64, 48))
    cams = [ln for ln in text["cameras.txt"].splitlines() if not ln.startswith("#")]
    ids = [ln.split()[8] for ln in text["images.txt"].splitlines()[4::2]]
    assert len(cams) == 2 and ids == ["1", "1", "2"]


def test_extra_keys(tmp_path: Path) -> None:
    doc = write_transforms(tmp_path / "t.json", [Camera()], (8, 8), extra={"aabb_scale": 16})
    assert json.loads((tmp_path / "t.json").read_text())["aabb_scale"] == 16 == doc["aabb_scale"]
    with pytest.raises(UsageError, match="would replace"):
        write_transforms(tmp_path / "u.json", [Camera()], (8, 8), extra={"w": 3})
    assert not (tmp_path / "u.json").exists()


R90 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # 90 degrees about x


@pytest.mark.parametrize("R, q", [
    (np.eye(3), (1.0, 0.0, 0.0, 0.0)),
    (R90, (math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0)),
    (np.diag([1.0, -1.0, -1.0]), (0.0, 1.0, 0.0, 0.0)),  # 180 degrees: trace -1
    (np.diag([-1.0, 1.0, -1.0]), (0.0, 0.0, 1.0, 0.0)),
    (np.diag([-1.0, -1.0, 1.0]), (0.0, 0.0, 0.0, 1.0)),
])
def test_quaternion_known_values(R: np.ndarray, q: tuple[float, ...]) -> None:
    np.testing.assert_allclose(quaternion_from_rotation(R), q, atol=1e-15)
    np.testing.assert_allclose(rotation_from_quaternion(q), R, atol=1e-15)


@given(hnp.arrays(np.float64, 4, elements=st.floats(-1, 1)).filter(
    lambda q: np.linalg.norm(q) > 0.1))
def test_quaternion_round_trip(q: np.ndarray) -> None:
    q = q / np.linalg.norm(q)
    q = -q if q[0] < 0 else q
    R = rotation_from_quaternion(q)
    back = quaternion_from_rotation(R)
    np.testing.assert_allclose(rotation_from_quaternion(back), R, atol=1e-14)
    if q[0] > 1e-9:  # w = 0: q and -q are both canonical
        np.testing.assert_allclose(back, q, atol=1e-12)


@pytest.mark.parametrize("cameras_txt, images_txt, message", [
    ("1 OPENCV 8 8 1 1 4 4 0.1 0 0\n", "", "camera model OPENCV with 7 parameters"),
    ("1 PINHOLE 8 8 1 1 4\n", "", "PINHOLE with 3 parameters"),
    ("x PINHOLE 8 8 1 1 4 4\n", "", "bad camera id"),
    ("1 PINHOLE 8 8 1 1 4 4\n", "1 1 0 0 0 0 0 0 2 a.png\n\n", "camera 2 is not in"),
    ("1 PINHOLE 8 8 1 1 4 4\n", "1 0 0 0 0 0 0 0 1 a.png\n\n", "quaternion is zero"),
    ("1 PINHOLE 8 8 1 1 4 4\n", "1 1 0 0 0 0 0\n\n", "expected IMAGE_ID"),
    ("1 PINHOLE 8 8 1 1 4 nan\n", "", "finite"),
    ("1 PINHOLE 8 8 1 1 4 4\n", "# only comments\n", "no images"),
])
def test_colmap_errors_are_one_line(tmp_path: Path, cameras_txt: str, images_txt: str,
                                    message: str) -> None:
    (tmp_path / "cameras.txt").write_text(cameras_txt)
    (tmp_path / "images.txt").write_text(images_txt)
    with pytest.raises(UsageError, match=message) as info:
        read_colmap(tmp_path)
    assert "\n" not in str(info.value) and str(tmp_path) in str(info.value)


def test_colmap_reads_an_image_with_points(tmp_path: Path) -> None:
    # COLMAP's own files carry 2D points on the line after each image: skipped, not parsed.
    (tmp_path / "cameras.txt").write_text("# c\n3 SIMPLE_PINHOLE 100 50 80 50 25\n")
    (tmp_path / "images.txt").write_text(
        "# i\n7 1 0 0 0 1 2 3 3 a b.png\n10.0 20.0 -1 11.5 3.0 4\n"
        "8 1 0 0 0 0 0 0 3 c.png\n\n")
    a, c = read_colmap(tmp_path)
    assert a.name == "a b.png" and c.name == "c.png"
    np.testing.assert_allclose(a.eye, (-1.0, -2.0, -3.0))
    np.testing.assert_allclose(a.intrinsics((100, 50)), [[80, 0, 49.5], [0, 80, 24.5], [0, 0, 1]])


def test_bad_arguments() -> None:
    with pytest.raises(UsageError, match="2 names for 1 cameras"):
        transforms_dict([Camera()], (8, 8), ["a", "b"])
    with pytest.raises(UsageError, match="no cameras"):
        transforms_dict([], (8, 8))
    with pytest.raises(UsageError, match="size"):
        transforms_dict([Camera()], (0, 8))
    with pytest.raises(UsageError, match="spaces"):
        colmap_text([Camera()], (8, 8), ["a b.png"])
    with pytest.raises(UsageError, match="expected Cameras"):
        colmap_text(["1,2,3,0,0,0"], (8, 8))
