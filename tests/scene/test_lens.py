"""Camera models (scene/lens.py) against OpenCV itself, and their files (transforms.json,
COLMAP text, poses files). No GPU."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.scene import lens
from vkpbr.scene.camera import Camera, validate_camera
from vkpbr.scene.camera_files import read_colmap, read_transforms, write_colmap, write_transforms

cv2 = pytest.importorskip("cv2", reason="opencv-python-headless (the test extra) is the reference")

K = np.array([[400.0, 0.0, 330.0], [0.0, 410.0, 245.0], [0.0, 0.0, 1.0]])
LENSES = [
    ("opencv", (-0.28, 0.09, 0.001, -0.002)),
    ("opencv", (-0.28, 0.09, 0.001, -0.002, -0.01)),
    ("opencv", (-0.2, 0.05, 0.001, -0.002, -0.005, 0.02, 0.003, 0.001)),
    ("opencv_fisheye", (0.05, -0.01, 0.003, -0.001)),
    ("equidistant", ()),
]


def opencv_project(model: str, distortion: tuple[float, ...], points: np.ndarray) -> np.ndarray:
    """cv2.projectPoints / cv2.fisheye.projectPoints of camera-space points (N, 3)."""
    if model == "opencv":
        return cv2.projectPoints(points, np.zeros(3), np.zeros(3), K, np.array(distortion))[0][:, 0]
    d = np.array(distortion if distortion else (0.0,) * 4)
    return cv2.fisheye.projectPoints(points[:, None], np.zeros(3), np.zeros(3), K, d)[0][:, 0]


@pytest.mark.parametrize("model, distortion", LENSES)
def test_projection_and_its_inverse_match_opencv(model: str, distortion: tuple) -> None:
    """lens.project = OpenCV's projection within 1e-9 px; lens.pixel_rays (the Newton
    inverse that post_lens.comp mirrors) of OpenCV's pixels gives the points' rays to 1e-9,
    and cv2.undistortPoints agrees where it applies."""
    rng = np.random.default_rng(3)
    points = rng.uniform([-1.0, -0.8, 1.0], [1.0, 0.8, 2.0], (2000, 3))
    pixels = opencv_project(model, distortion, points)
    np.testing.assert_allclose(lens.project(model, distortion, K, points), pixels, atol=1e-9)
    rays = lens.pixel_rays(model, distortion, K, pixels)
    unit = points / np.linalg.norm(points, axis=1, keepdims=True)
    np.testing.assert_allclose(rays, unit, atol=1e-9)
    if model == "opencv":
        # OpenCV's own inverse (a fixed-point iteration: to 1e-5 with 100 steps).
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
        xy = cv2.undistortPoints(pixels[:, None], K, np.array(distortion), criteria=crit)[:, 0]
        np.testing.assert_allclose(rays[:, :2] / rays[:, 2:], xy, atol=1e-5)


def test_fisheye_beyond_90_degrees() -> None:
    """Rays behind the image plane (theta > 90 degrees) keep their angle through the fisheye
    models (OpenCV's fisheye cannot say, its atan(r) folds them): theta_d = theta there."""
    theta = np.radians([10.0, 89.0, 95.0, 100.0])
    rays = np.stack([np.sin(theta), np.zeros(4), np.cos(theta)], -1)
    xy = lens.distort("equidistant", (), rays)
    np.testing.assert_allclose(xy[:, 0], theta, atol=1e-12)
    np.testing.assert_allclose(lens.undistort("equidistant", (), xy), rays, atol=1e-12)


def test_source_view_covers_and_outsamples_the_model() -> None:
    """The pinhole a model's image is resampled from sees every ray of it with a texel of
    margin, and its texels are no larger than the model's smallest pixel."""
    model, distortion = "opencv_fisheye", (0.05, -0.01, 0.003, -0.001)
    view = lens.source_view(model, distortion, K, (640, 480), 4 * 640 * 480, 16384)
    gx, gy = np.meshgrid(np.arange(640.0), np.arange(480.0))
    rays = lens.pixel_rays(model, distortion, K, np.stack([gx, gy], -1))
    src = lens.project("pinhole", (), view.K(), rays)
    assert src.min() >= 0.5 and src[..., 0].max() <= view.size[0] - 1.5
    assert src[..., 1].max() <= view.size[1] - 1.5
    step = np.linalg.norm(np.diff(src, axis=1), axis=-1)  # source texels per output pixel
    assert step.min() >= 0.999


def test_too_wide_is_one_line() -> None:
    """Rays more than 75 degrees off the axis: a UsageError line saying what is rendered."""
    wide = K.copy()
    wide[0, 0] = wide[1, 1] = 150.0
    with pytest.raises(UsageError, match="at most 75 are rendered"):
        lens.source_view("equidistant", (), wide, (640, 480), 1 << 22, 16384)


def test_camera_checks() -> None:
    with pytest.raises(UsageError, match="needs pixel_intrinsics"):
        validate_camera(Camera(model="opencv_fisheye", distortion=(0.0,) * 4))
    with pytest.raises(UsageError, match="takes 4 distortion coefficients"):
        Camera.from_opencv(K, np.eye(4), (640, 480), model="opencv_fisheye", distortion=(0.1,))
    with pytest.raises(UsageError, match="choose from pinhole, opencv, opencv_fisheye, equidistant"):
        Camera.from_opencv(K, np.eye(4), (640, 480), model="fisheye")


def _cameras() -> list[Camera]:
    pose = np.eye(4)
    pose[:3, 3] = (0.5, -1.0, 2.0)
    return [Camera.from_opencv(K, pose, (640, 480), model=m, distortion=d, name=f"c{i}.png")
            for i, (m, d) in enumerate(LENSES)]


def test_transforms_json_round_trip(tmp_path: Path) -> None:
    """write_transforms writes nerfstudio's keys ("camera_model" OPENCV + k1, k2, p1, p2 (k3..),
    OPENCV_FISHEYE + k1..k4) per frame, and read_transforms gives the same lenses back (an
    equidistant lens as OPENCV_FISHEYE with zeros: the same model)."""
    cams = _cameras()
    doc = write_transforms(tmp_path / "transforms.json", cams, (640, 480))
    frames = json.loads((tmp_path / "transforms.json").read_text())["frames"]
    assert frames[0]["camera_model"] == "OPENCV" and frames[0]["p2"] == -0.002
    assert "k3" not in frames[0] and frames[1]["k3"] == -0.01 and frames[2]["k6"] == 0.001
    assert frames[3]["camera_model"] == "OPENCV_FISHEYE" and frames[3]["k4"] == -0.001
    assert doc["frames"][4]["camera_model"] == "OPENCV_FISHEYE"
    for cam, back in zip(cams, read_transforms(tmp_path / "transforms.json"), strict=True):
        want = ("opencv_fisheye", (0.0,) * 4) if cam.model == "equidistant" else (cam.model, cam.distortion)
        assert (back.model, back.distortion) == want
        np.testing.assert_allclose(back.intrinsics((640, 480)), K, atol=1e-9)


def test_colmap_round_trip_and_opencv_fisheye_file(tmp_path: Path) -> None:
    """write_colmap writes OPENCV, FULL_OPENCV and OPENCV_FISHEYE cameras; read_colmap reads
    them (and SIMPLE_RADIAL, RADIAL) back; a hand-written OPENCV_FISHEYE camera projects as
    cv2.fisheye does with the same numbers (COLMAP's cx, cy - 0.5)."""
    cams = _cameras()
    write_colmap(tmp_path, cams, (640, 480))
    text = (tmp_path / "cameras.txt").read_text()
    assert " OPENCV 640 480 " in text and " FULL_OPENCV 640 480 " in text
    assert " OPENCV_FISHEYE 640 480 " in text
    for cam, back in zip(cams, read_colmap(tmp_path), strict=True):
        want = lens.distortion_vector(cam.model, cam.distortion) if cam.model == "opencv" else None
        if want is not None:
            np.testing.assert_allclose(lens.distortion_vector("opencv", back.distortion), want)
        np.testing.assert_allclose(back.world_from_camera(), cam.world_from_camera(), atol=1e-12)
    folder = tmp_path / "fisheye"
    folder.mkdir()
    (folder / "cameras.txt").write_text("1 OPENCV_FISHEYE 640 480 400 410 330.5 245.5 0.05 -0.01 0.003 -0.001\n"
                                        "2 SIMPLE_RADIAL 640 480 400 330.5 245.5 -0.1\n")
    (folder / "images.txt").write_text("1 1 0 0 0 0 0 0 1 a.png\n\n2 1 0 0 0 0 0 0 2 b.png\n\n")
    fish, radial = read_colmap(folder)
    assert fish.model == "opencv_fisheye" and radial.distortion == (-0.1, 0.0, 0.0, 0.0)
    points = np.random.default_rng(0).uniform([-1, -1, 1], [1, 1, 2], (100, 3))
    np.testing.assert_allclose(lens.project(fish.model, fish.distortion, fish.intrinsics((640, 480)), points),
                               opencv_project("opencv_fisheye", LENSES[3][1], points), atol=1e-9)
    (folder / "cameras.txt").write_text("1 THIN_PRISM_FISHEYE 640 480 1 2 3 4\n")
    with pytest.raises(UsageError, match="line 1: camera model THIN_PRISM_FISHEYE with 4 parameters"):
        read_colmap(folder)


def test_a_model_of_the_wrong_type_is_a_problem_not_a_type_error() -> None:
    """A baked file's scene JSON can hold any value as a camera's model (the fuzz suite gave
    a dict: `dict in COEFFICIENTS` raised TypeError)."""
    from vkpbr.scene.lens import check_model

    for model in ({"a": 1}, ["opencv"], 3, None):
        problem = check_model(model, [])
        assert problem is not None and problem.startswith("model ") and "choose from" in problem
