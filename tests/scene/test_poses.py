# Poses files (vkpbr.scene.poses): every accepted form, the example files in docs/examples, NeRF
# transforms.json against NeRF's own ray convention, and every way a file can be wrong, which
# must give one UsageError line naming the file and the entry (nothing else may escape).

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vkpbr.errors import UsageError
from vkpbr.scene.camera import validate_camera
from vkpbr.scene.poses import Pose, load_poses
from vkpbr.scene.types import Camera

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "docs" / "examples"
BASE = Camera(eye=(0.0, 0.0, 5.0), yfov_deg=45.0, up=(0.0, 1.0, 0.0), name="auto")
EYE = np.eye(4).tolist()


def write(tmp_path: Path, doc: object, name: str = "poses.json") -> Path:
    path = tmp_path / name
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return path


def test_example_poses_file_loads(tmp_path: Path) -> None:
    doc = json.loads((EXAMPLES / "poses.json").read_text())
    poses = load_poses(EXAMPLES / "poses.json")
    assert len(poses) == len(doc) >= 6 and all(isinstance(p, Pose) for p in poses)
    cams = [p.camera(BASE) for p in poses]
    for cam in cams:
        validate_camera(cam)
    # Each form appears: two strings (6 and 9 numbers), eye/target, both matrix conventions, K.
    kinds = [e if isinstance(e, str) else tuple(sorted(e)) for e in doc]
    assert sum(isinstance(k, str) for k in kinds) >= 2
    by_name = {c.name: (c, e) for c, e in zip(cams, doc, strict=True) if isinstance(e, dict)}
    gl, entry = by_name["opengl"]
    np.testing.assert_allclose(gl.world_from_camera("opengl"), entry["world_from_camera"], atol=1e-5)
    assert gl.yfov_deg == entry["fov"]
    cv, entry = by_name["opencv"]
    np.testing.assert_allclose(cv.world_from_camera("opencv"), entry["world_from_camera"], atol=1e-5)
    assert cv.yfov_deg == BASE.yfov_deg  # no "fov": the base camera's
    k, entry = by_name["calibrated"]
    np.testing.assert_allclose(k.intrinsics(tuple(entry["size"])), entry["K"])
    assert cams[0].eye == (0.6, 3.2, 9.0) and cams[0].up == BASE.up and cams[0].yfov_deg == 45.0


def test_example_transforms_file_loads() -> None:
    doc = json.loads((EXAMPLES / "transforms.json").read_text())
    poses = load_poses(EXAMPLES / "transforms.json")
    assert len(poses) == len(doc["frames"]) >= 2
    fx = 0.5 * doc["w"] / math.tan(0.5 * doc["camera_angle_x"])
    for pose, frame in zip(poses, doc["frames"], strict=True):
        cam = pose.camera(BASE)
        assert cam.name == frame["file_path"]
        np.testing.assert_allclose(cam.world_from_camera("opengl"), frame["transform_matrix"],
                                   atol=1e-5)
        np.testing.assert_allclose(cam.intrinsics((doc["w"], doc["h"])),
                                   [[fx, 0, (doc["w"] - 1) / 2], [0, fx, (doc["h"] - 1) / 2], [0, 0, 1]])


def nerf_pixels(frame: dict, fl: tuple[float, float], c: tuple[float, float], pts: np.ndarray) -> np.ndarray:
    """Where NeRF puts world points: its ray through pixel (i, j) (pixel centres at i + 0.5, as
    nerfstudio's get_image_coords) is ((i + 0.5 - cx) / fx, -(j + 0.5 - cy) / fy, -1)."""
    m = np.array(frame["transform_matrix"])
    x, y, z = ((pts - m[:3, 3]) @ m[:3, :3]).T  # OpenGL camera axes: looks down -z
    return np.stack([fl[0] * x / -z + c[0] - 0.5, fl[1] * -y / -z + c[1] - 0.5], axis=1)


def test_nerf_intrinsics_match_nerf_rays(tmp_path: Path) -> None:
    cam = Camera(eye=(3.0, 1.0, 4.0), target=(0.0, 0.5, 0.0))
    frame = {"transform_matrix": cam.world_from_camera("opengl").tolist(), "file_path": "a.png"}
    doc = {"fl_x": 300.0, "fl_y": 310.0, "cx": 150.0, "cy": 90.0, "w": 320, "h": 200,
           "k1": 0.0, "p1": 0, "camera_model": "OPENCV", "aabb_scale": 16, "frames": [frame]}
    got = load_poses(write(tmp_path, doc))[0].camera(BASE)
    assert got.pixel_intrinsics == (300.0, 310.0, 149.5, 89.5, 320, 200)
    rng = np.random.default_rng(3)
    pts = np.array(got.target) + rng.uniform(-1, 1, (20, 3))
    K, pose = got.intrinsics((320, 200)), got.world_from_camera("opencv")
    uvw = ((pts - pose[:3, 3]) @ pose[:3, :3]) @ K.T
    np.testing.assert_allclose(uvw[:, :2] / uvw[:, 2:], nerf_pixels(frame, (300, 310), (150, 90), pts),
                               atol=1e-6)


def test_nerf_variants(tmp_path: Path) -> None:
    frame = {"transform_matrix": EYE}
    # No size: the vertical field of view is camera_angle_y, else camera_angle_x (square images).
    [p] = load_poses(write(tmp_path, {"camera_angle_x": 0.5, "frames": [frame]}))
    assert p.camera(BASE).yfov_deg == pytest.approx(math.degrees(0.5))
    assert p.camera(BASE).pixel_intrinsics is None and p.camera(BASE).name == "frame 0"
    [p] = load_poses(write(tmp_path, {"camera_angle_x": 0.5, "camera_angle_y": 0.4, "frames": [frame]}))
    assert p.camera(BASE).yfov_deg == pytest.approx(math.degrees(0.4))
    # colmap2nerf writes the size as floats; per-frame intrinsics override the file's.
    doc = {"camera_angle_x": 1.0, "w": 640.0, "h": 480.0,
           "frames": [frame, {**frame, "fl_x": 100.0, "cx": 10.0}]}
    a, b = (p.camera(BASE) for p in load_poses(write(tmp_path, doc)))
    f = 320 / math.tan(0.5)
    assert a.pixel_intrinsics == pytest.approx((f, f, 319.5, 239.5, 640, 480))
    assert b.pixel_intrinsics == pytest.approx((100.0, 100.0, 9.5, 239.5, 640, 480))
    assert a.yfov_deg == pytest.approx(2 * math.degrees(math.atan(240 / f)))


def test_pose_without_up_fails_late_but_names_the_entry(tmp_path: Path) -> None:
    # Looking straight down: valid with most base cameras, not with one whose up is +y.
    [pose] = load_poses(write(tmp_path, ["0,5,0,0,0,0"]))
    assert pose.camera(Camera(up=(0.0, 0.0, -1.0))).up == (0.0, 0.0, -1.0)
    with pytest.raises(UsageError, match=r"poses.json: entry 0: up is parallel"):
        pose.camera(BASE)


GOOD_K = [[100, 0, 32], [0, 100, 24], [0, 0, 1]]
SCALED = np.diag([2.0, 2.0, 2.0, 1.0]).tolist()


@pytest.mark.parametrize("doc, match", [
    ("", "not valid JSON (Expecting value: line 1 column 1 (char 0))"),
    ("[1, 2", "not valid JSON"),
    ("[" * 100_000 + "]" * 100_000, "not valid JSON"),
    ("[" + "9" * 5000 + "]", "not valid JSON"),
    ([], "the list of poses is empty"),
    (3, "expected a JSON list of poses or a NeRF transforms.json object"),
    ({"cameras": []}, "got an object with keys ['cameras']"),
    ([3], 'entry 0: expected a "ex,ey,ez,tx,ty,tz" string or an object, got a number'),
    (["0,0,5,0,0,0", None], "entry 1: expected a \"ex,ey,ez,tx,ty,tz\" string or an object, got null"),
    ([EYE], "entry 0: expected a \"ex,ey,ez,tx,ty,tz\" string or an object, got a list"),
    (["1,2,3"], "entry 0: '1,2,3': expected 6 or 9 numbers, got 3"),
    (["0,0,5,0,0,x"], "entry 0: '0,0,5,0,0,x': expected 6 or 9 comma-separated numbers"),
    (["0,0,0,0,0,0"], "entry 0: eye and target coincide"),
    ([{"eye": [0, 0, 5]}], "entry 0: missing 'target'"),
    ([{"target": [0, 0, 5]}], "entry 0: missing 'eye'"),
    ([{"eye": [0, 0, 5], "target": [0, 0]}], 'entry 0: "target": expected 3 items, got 2'),
    ([{"eye": [0, 0, "5"], "target": [0, 0, 0]}], 'entry 0: "eye"[2]: expected a number, got str'),
    ([{"eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 0, 1]}], "entry 0: up is parallel"),
    ([{"eye": [0, 0, 5], "target": [0, 0, 0], "fov": 180}], '"fov": 180 must be in (0, 180)'),
    ([{"eye": [0, 0, 5], "target": [0, 0, 0], "fov": True}], '"fov": expected a number, got bool'),
    ([{"eye": [0, 0, 5], "target": [0, 0, 0], "fov": None}], '"fov": expected a number, got None'),
    ([{"eye": [0, 0, 5], "target": [0, 0, 0], "file_path": "x"}], "unknown key 'file_path'"),
    ('[{"eye": [0, 0, NaN], "target": [0, 0, 0]}]', '"eye"[2]: nan is not finite'),
    ('[{"eye": [0, 0, 1e999], "target": [0, 0, 0]}]', '"eye"[2]: inf is not finite'),
    # Refused by the JSON reader's integer limit (vkpbr/json_input.py) before the checks.
    ([{"eye": [0, 0, 10**400], "target": [0, 0, 0]}], "not valid JSON (an integer of more than"),
    ([{"world_from_camera": EYE}], "entry 0: missing 'convention'"),
    ([{"world_from_camera": EYE, "convention": "blender"}], 'convention: expected "opengl"'),
    ([{"world_from_camera": SCALED, "convention": "opengl"}], "not a rigid transform"),
    ([{"world_from_camera": EYE[:3], "convention": "opengl"}], "world_from_camera: expected 4 items"),
    ([{"K": GOOD_K, "world_from_camera": EYE}], "entry 0: missing 'size'"),
    ([{"K": GOOD_K, "world_from_camera": EYE, "size": [64, 0]}], "height must be a positive integer"),
    ([{"K": [[100, 1, 32], [0, 100, 24], [0, 0, 1]], "world_from_camera": EYE, "size": [64, 48]}],
     "skewed intrinsics are not supported"),
    ({"frames": []}, '"frames" must be a non-empty list of frames, got an empty list'),
    ({"frames": {}}, '"frames" must be a non-empty list of frames, got an object'),
    ({"camera_angle_x": 0.7, "frames": [{"transform_matrix": EYE}, 3]}, "frame 1: expected an object"),
    ({"camera_angle_x": 0.7, "frames": [{"file_path": "a"}]}, 'frame 0: missing "transform_matrix"'),
    ({"camera_angle_x": 0.7, "frames": [{"transform_matrix": SCALED}]},
     'frame 0: "transform_matrix": not a rigid transform'),
    ({"frames": [{"transform_matrix": EYE}]}, 'missing "camera_angle_x"'),
    ({"camera_angle_x": "wide", "frames": [{"transform_matrix": EYE}]},
     '"camera_angle_x": expected a number, got str'),
    ({"camera_angle_x": 4.0, "frames": [{"transform_matrix": EYE}]}, "must be in (0, pi) radians"),
    ({"fl_x": 300, "frames": [{"transform_matrix": EYE}]}, '"fl_x" needs the image size "w" and "h"'),
    ({"fl_x": 300, "w": 64, "frames": [{"transform_matrix": EYE}]}, 'missing "h"'),
    ({"fl_x": -3, "w": 64, "h": 48, "frames": [{"transform_matrix": EYE}]}, "must be > 0"),
    ({"fl_x": 300, "w": 64.5, "h": 48, "frames": [{"transform_matrix": EYE}]},
     "width must be a positive integer, got 64.5"),
    ({"camera_angle_x": 0.7, "k1": 0.01, "frames": [{"transform_matrix": EYE}]},
     'a opencv lens needs the image size "w" and "h"'),
    ({"camera_angle_x": 0.7, "camera_model": "EQUIRECTANGULAR", "frames": [{"transform_matrix": EYE}]},
     "\"camera_model\" 'EQUIRECTANGULAR' is not supported"),
    ({"camera_angle_x": 0.7, "w": 8, "h": 8, "camera_model": "OPENCV_FISHEYE", "p1": 0.1,
      "frames": [{"transform_matrix": EYE}]}, "OPENCV_FISHEYE takes k1..k4, not p1"),
    ({"camera_angle_x": 0.7, "frames": [{"transform_matrix": EYE}, {"transform_matrix": EYE, "k2": 1}]},
     'frame 1: a opencv lens needs the image size'),
    ([{"K": [[100, 0, 50], [0, 100, 40], [0, 0, 1]], "world_from_camera": EYE, "size": [100, 80],
       "model": "opencv", "distortion": [0.1]}], "takes 4 or 5 or 8 distortion coefficients"),
    ([{"K": [[100, 0, 50], [0, 100, 40], [0, 0, 1]], "world_from_camera": EYE, "size": [100, 80],
       "model": "kannala"}], "model 'kannala': choose from pinhole, opencv"),
])
def test_bad_files_give_one_line_naming_file_and_entry(tmp_path: Path, doc, match) -> None:  # noqa: ANN001
    path = write(tmp_path, doc)
    with pytest.raises(UsageError) as err:
        load_poses(path)
    message = str(err.value)
    assert type(err.value) is UsageError
    assert message.startswith(f"{path}: ") and match in message and "\n" not in message, message


def test_huge_integers_from_python_are_checked_too() -> None:
    """A poses document built in Python (`parse_poses`) never met the JSON reader's integer
    limit; the checks still refuse a number that float() cannot hold."""
    from vkpbr.scene.poses import parse_poses

    with pytest.raises(UsageError, match=r'inline: entry 0: "eye"\[2\]: the number is too large'):
        parse_poses([{"eye": [0, 0, 10**400], "target": [0, 0, 0]}], "inline")


def test_unreadable_files(tmp_path: Path) -> None:
    for path, match in ((tmp_path / "missing.json", "cannot read the poses file: No such file"),
                        (tmp_path, "cannot read the poses file:")):
        with pytest.raises(UsageError, match=match):
            load_poses(path)
    bad = tmp_path / "latin1.json"
    bad.write_bytes(b'["\xff\xfe\xfa"]')
    with pytest.raises(UsageError, match="latin1.json: not valid JSON"):
        load_poses(bad)
    with pytest.raises(UsageError, match="poses file: expected a path, got int"):
        load_poses(3)  # type: ignore[arg-type]


# Junk JSON: any value at all, and near-misses of each accepted form with junk inside.
json_junk = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=10),
    lambda children: st.lists(children, max_size=5) | st.dictionaries(st.text(max_size=8), children,
                                                                      max_size=5),
    max_leaves=25,
)
keys = st.sampled_from(["eye", "target", "up", "fov", "name", "world_from_camera", "convention",
                        "K", "size"])
entry = st.one_of(
    json_junk,
    st.dictionaries(keys, json_junk, max_size=5),
    st.fixed_dictionaries({"eye": json_junk, "target": json_junk},
                          optional={"up": json_junk, "fov": json_junk}),
    st.fixed_dictionaries({"world_from_camera": st.just(EYE) | json_junk,
                           "convention": st.sampled_from(["opengl", "opencv"]) | json_junk}),
    st.fixed_dictionaries({"K": st.just(GOOD_K) | json_junk, "world_from_camera": st.just(EYE) | json_junk,
                           "size": st.just([64, 48]) | json_junk}),
    st.lists(st.floats() | st.integers(), max_size=10).map(lambda v: ",".join(map(str, v))),
)
nerf_keys = st.sampled_from(["camera_angle_x", "camera_angle_y", "fl_x", "fl_y", "cx", "cy", "w",
                             "h", "k1", "camera_model"])
document = st.one_of(
    json_junk,
    st.lists(entry, max_size=4),
    st.builds(lambda g, f: {**g, "frames": f}, st.dictionaries(nerf_keys, json_junk | st.floats(0, 3)),
              st.lists(st.dictionaries(st.sampled_from(["transform_matrix", "fl_x", "w", "h"]),
                                       st.just(EYE) | json_junk), max_size=3) | json_junk),
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(document)
def test_junk_json_raises_only_usage_errors(doc) -> None:  # noqa: ANN001
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "junk.json"
        path.write_text(json.dumps(doc))
        try:
            poses = load_poses(path)
        except UsageError as exc:
            assert str(exc).startswith(f"{path}: ") and "\n" not in str(exc)
            return
        for pose in poses:  # what loads applies to a base (only an up-less pose may fail)
            try:
                validate_camera(pose.camera(BASE))
            except UsageError as exc:
                assert pose.up is None and "up is parallel" in str(exc)


@settings(max_examples=100, deadline=None)
@given(st.binary(max_size=64))
def test_junk_bytes_raise_only_usage_errors(data: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "junk.json"
        path.write_bytes(data)
        try:
            load_poses(path)
        except UsageError as exc:
            assert "\n" not in str(exc)
