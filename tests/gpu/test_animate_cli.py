"""`vkpbr render --time / --animate`: frames, clips and poses files with times, from the user's
side: each written frame equals the API's render at its time; bad arguments are one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from vkpbr.app.cli import main
from vkpbr.render.renderer import Renderer
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Camera

SIZE = (48, 40)
CAMERA = Camera(eye=(3.0, 2.0, 4.0), target=(0.0, 0.5, 0.0), yfov_deg=50.0)
CAM_ARG = "3,2,4,0,0.5,0"


def run(capsys, *argv: str) -> tuple[int, str, str]:  # noqa: ANN001
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def model(assets: Path, name: str) -> Path:
    path = assets / name / "glTF" / f"{name}.gltf"
    if not path.is_file():
        pytest.skip(f"{path} not in the assets")
    return path


def test_animate_writes_the_frames_the_api_renders(capsys, tmp_path: Path, assets: Path) -> None:  # noqa: ANN001
    path = model(assets, "BoxAnimated")
    out = tmp_path / "clip"
    code, stdout, err = run(capsys, "render", str(path), "--animate", "--fps", "4", "--duration",
                            "1.5", "--size", "48x40", "--camera", CAM_ARG, "--light", "none",
                            "--out", str(out), "--validation")
    assert code == 0, err
    files = sorted(out.glob("frame_*.png"))
    assert len(files) == 7 and "wrote 7 frames" in stdout  # 0, 0.25, ..., 1.5
    doc = json.loads((out / "transforms.json").read_text())
    assert [f["time"] for f in doc["frames"]] == [i / 4 for i in range(7)]
    for i in (0, 3, 6):  # each frame is `render --time` of its time
        one = tmp_path / f"one{i}.png"
        code, _, err = run(capsys, "render", str(path), "--time", str(i / 4), "--size", "48x40",
                           "--camera", CAM_ARG, "--light", "none", "--out", str(one),
                           "--validation")
        assert code == 0, err
        assert np.array_equal(np.asarray(Image.open(files[i])), np.asarray(Image.open(one)))
    assert not np.array_equal(np.asarray(Image.open(files[0])), np.asarray(Image.open(files[3])))


def test_poses_file_times_and_the_sequence_read_back(capsys, tmp_path: Path, assets: Path) -> None:  # noqa: ANN001
    """A poses file whose entries carry "time" renders each view at its time; the
    transforms.json written beside the frames reads back with the same times."""
    path = model(assets, "BoxAnimated")
    poses = tmp_path / "poses.json"
    poses.write_text(json.dumps([{"eye": [3, 2, 4], "target": [0, 0.5, 0], "time": t}
                                 for t in (0.0, 0.9, 2.1)]))
    out = tmp_path / "views"
    code, _, err = run(capsys, "render", str(path), "--cameras", str(poses), "--size", "48x40",
                       "--light", "none", "--out", str(out), "--validation")
    assert code == 0, err
    got = [np.asarray(Image.open(f)) for f in sorted(out.glob("frame_*.png"))]
    with Renderer(load_scene(path), validation=True) as r:  # the API, frame by frame
        want = [r.render(Camera(eye=(3, 2, 4), target=(0, 0.5, 0)), lights=[], size=SIZE,
                         time=t) for t in (0.0, 0.9, 2.1)]
    # The API's default environment differs from the CLI's: compare what moved.
    for i in (1, 2):
        assert np.array_equal(got[i] != got[0], want[i] != want[0])


def test_a_gif_clip(capsys, tmp_path: Path, assets: Path) -> None:  # noqa: ANN001
    path = model(assets, "AnimatedMorphCube")
    out = tmp_path / "cube.gif"
    code, _, err = run(capsys, "render", str(path), "--animate", "--fps", "5", "--duration", "1",
                       "--size", "48x40", "--out", str(out), "--validation")
    assert code == 0, err
    with Image.open(out) as gif:
        assert gif.n_frames == 6 and gif.size == SIZE
    assert not list(tmp_path.glob(".*.tmp*"))


def test_an_mp4_clip(capsys, tmp_path: Path, assets: Path) -> None:  # noqa: ANN001
    iio = pytest.importorskip("imageio.v3", reason="the video extra is not installed "
                              "(pip install 'vkpbr[video]')")
    pytest.importorskip("imageio_ffmpeg", reason="the video extra is not installed")
    path = model(assets, "BoxAnimated")
    out = tmp_path / "box.mp4"
    code, _, err = run(capsys, "render", str(path), "--animate", "--fps", "8", "--duration", "1",
                       "--size", "48x40", "--out", str(out), "--validation")
    assert code == 0, err
    frames = iio.imread(out, plugin="FFMPEG")
    assert frames.shape[0] == 9 and frames.shape[1:3] == (40, 48)


@pytest.mark.parametrize(("args", "message"), [
    (["--fps", "0"], "--fps"),
    (["--duration", "-1"], "--duration"),
    (["--animation", "no such animation"], "no such animation"),
    (["--out", "clip.avi"], ".gif or a .mp4"),
    (["--fps", "1e9"], "at most"),
])
def test_bad_animation_arguments_are_one_line(capsys, tmp_path: Path, assets: Path, args, message) -> None:  # noqa: ANN001
    path = model(assets, "BoxAnimated")
    argv = ["render", str(path), "--animate", "--out", str(tmp_path / "c"), *args]
    argv = [a if a != "clip.avi" else str(tmp_path / "clip.avi") for a in argv]
    code, _, err = run(capsys, *argv)
    assert code != 0 and message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err


def test_a_still_scene_has_nothing_to_animate(capsys, tmp_path: Path) -> None:  # noqa: ANN001
    code, _, err = run(capsys, "render", "--animate", "--out", str(tmp_path / "x.gif"))
    assert code != 0 and "animation" in err and "Traceback" not in err
