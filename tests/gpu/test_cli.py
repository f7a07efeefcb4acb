"""The command line: outputs, batch mode, and one-line errors with non-zero exits."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from vkpbr.app.cli import main
from vkpbr.render.layouts import View


def run(capsys, *argv: str) -> tuple[int, str, str]:  # noqa: ANN001
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_render_default_scene_writes_png(capsys, tmp_path: Path) -> None:
    out = tmp_path / "a.png"
    code, stdout, _ = run(capsys, "render", "--out", str(out), "--size", "64x48", "--validation")
    assert code == 0 and out.exists() and f"wrote {out}" in stdout
    assert np.asarray(Image.open(out)).shape == (48, 64, 4)
    assert not list(tmp_path.glob(".*.tmp"))  # atomic write leaves no temporary behind
    assert out.stat().st_mode & 0o777 == 0o666 & ~_umask()  # as open() would, not 0600


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_render_through_bake_cache(capsys, tmp_path: Path, assets: Path) -> None:
    """--cache DIR bakes the source on first use and loads the baked copy after; the image
    is the same either way (within one 8-bit step: the bake re-orders vertices)."""
    src = assets / "NormalTangentMirrorTest" / "glTF" / "NormalTangentMirrorTest.gltf"
    cache = tmp_path / "cache"
    direct, first, second = (tmp_path / f"{n}.png" for n in ("direct", "first", "second"))
    common = ("--size", "64x48", "--validation")
    assert run(capsys, "render", str(src), "--out", str(direct), *common)[0] == 0
    code, _, err = run(capsys, "-v", "render", str(src), "--cache", str(cache), "--out", str(first), *common)
    assert code == 0 and "vkpbr: info: scene cache:" in err  # a diagnostic: shown with -v
    baked = list(cache.glob("NormalTangentMirrorTest-*.vkpbr"))
    assert len(baked) == 1
    mtime = baked[0].stat().st_mtime_ns
    assert run(capsys, "render", str(src), "--cache", str(cache), "--out", str(second), *common)[0] == 0
    assert baked[0].stat().st_mtime_ns == mtime  # a hit: not baked again
    a, b, c = (np.asarray(Image.open(p)).astype(int) for p in (direct, first, second))
    assert np.array_equal(b, c) and np.abs(a - b).max() <= 1


def test_render_linear_npy(capsys, tmp_path: Path) -> None:
    out = tmp_path / "hdr.npy"
    code, _, _ = run(capsys, "render", "--out", str(out), "--size", "32x24", "--linear", "--validation")
    assert code == 0 and np.load(out).dtype == np.float32


def test_batch_cameras(capsys, tmp_path: Path) -> None:
    cams = tmp_path / "cams.json"
    cams.write_text(json.dumps(["0.6,3.2,9,0.4,2.2,0", {"eye": [3, 3, 8], "target": [0, 2, 0], "fov": 50}]))
    code, stdout, _ = run(capsys, "render", "--cameras", str(cams), "--out", str(tmp_path / "frames"),
                          "--size", "40x30", "--validation")
    assert code == 0 and "wrote 2 images" in stdout
    assert sorted(p.name for p in (tmp_path / "frames").iterdir()) == [
        "frame_00000.png", "frame_00001.png", "transforms.json", "vkpbr-manifest.jsonl"]


def test_batch_writes_camera_files_that_reproduce_the_images(capsys, tmp_path: Path) -> None:
    """--cameras writes transforms.json (and, with --colmap, COLMAP text) beside the frames;
    a NeRF-style loader (a few lines of json and numpy here) reads the intrinsics and poses,
    and rendering its cameras again gives the same images."""
    cams = tmp_path / "cams.json"
    cams.write_text(json.dumps(["0.6,3.2,9,0.4,2.2,0", {"eye": [3, 3, 8], "target": [0, 2, 0], "fov": 50},
                                "-4,2,6,0,1,0"]))
    out = tmp_path / "frames"
    code, stdout, _ = run(capsys, "render", "--cameras", str(cams), "--out", str(out),
                          "--size", "48x32", "--colmap", "--validation")
    assert code == 0 and "transforms.json" in stdout and "images.txt" in stdout
    doc = json.loads((out / "transforms.json").read_text())
    frames = doc["frames"]
    assert [f["file_path"] for f in frames] == [f"frame_{i:05d}.png" for i in range(3)]
    assert all(doc.get("w", f.get("w")) == 48 and doc.get("h", f.get("h")) == 32 for f in frames)
    for f in frames:  # world-from-camera, OpenGL axes: a rigid transform with unit rows
        m = np.asarray(f["transform_matrix"], dtype=np.float64)
        assert m.shape == (4, 4) and np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-6)
    assert (out / "cameras.txt").is_file() and (out / "points3D.txt").is_file()
    again = tmp_path / "again"
    code, _, _ = run(capsys, "render", "--cameras", str(out / "transforms.json"), "--out",
                     str(again), "--size", "48x32", "--validation")
    assert code == 0
    for i in range(3):
        a = np.asarray(Image.open(out / f"frame_{i:05d}.png")).astype(int)
        b = np.asarray(Image.open(again / f"frame_{i:05d}.png")).astype(int)
        assert np.abs(a - b).max() <= 1, i


def test_poses_file_is_checked_before_the_scene_loads(capsys, tmp_path: Path) -> None:
    """A bad entry is reported (file, entry, problem) before anything else: here the scene
    file does not even exist, and the poses file's error is the one the user sees."""
    bad = tmp_path / "poses.json"
    bad.write_text(json.dumps(["0,0,5,0,0,0", {"eye": [0, 0, 5]}]))
    code, _, err = run(capsys, "render", str(tmp_path / "missing.gltf"), "--cameras", str(bad),
                       "--out", str(tmp_path / "frames"))
    assert code == 2 and "poses.json" in err and "entry 1" in err and "target" in err, err


def test_docs_example_poses_render(capsys, tmp_path: Path) -> None:
    """docs/examples/poses.json (every accepted form) renders the built-in scene."""
    example = Path(__file__).resolve().parents[2] / "docs" / "examples" / "poses.json"
    n = len(json.loads(example.read_text()))
    code, stdout, _ = run(capsys, "render", "--cameras", str(example), "--out",
                          str(tmp_path / "frames"), "--size", "32x24", "--validation")
    assert code == 0 and f"wrote {n} images" in stdout
    images = sorted((tmp_path / "frames").glob("frame_*.png"))
    assert len(images) == n


@pytest.mark.parametrize("argv, message", [
    (["render", "--view", "nope"], "argument --view: invalid choice: 'nope'"),
    (["render", "--brdf", "phong"], "argument --brdf: invalid choice: 'phong'"),
    (["render", "--tbn", "x"], "argument --tbn: invalid choice: 'x'"),
    (["view", "--tonemap", "filmic"], "argument --tonemap: invalid choice: 'filmic'"),
    (["render", "--light", "-5,0.6"], "argument --light: '-5,0.6': expected three"),
    (["render", "--no-such-option"], "unrecognized arguments: --no-such-option"),
    (["render", "--size", "0x10"], "must be positive"),
    (["render", "--size=-3x10"], "must be positive"),
    (["render", "--size", "abc"], "expected WIDTHxHEIGHT"),
    (["render", "--size", "100000x10"], "exceeds this device's limit"),
    (["render", "--out", "/nonexistent-dir/x.png"], "does not exist"),
    (["render", "--out", "x.gif"], "unknown image type"),
    (["render", "--camera", "1,2,3"], "expected 6 or 9 numbers"),
    (["render", "--camera", "0,0,0,0,0,0"], "eye and target coincide"),
    (["render", "--light", "1,2"], "three comma-separated"),
    (["render", "--exposure", "nan"], "exposure"),
    (["render", "--env", "missing.hdr", "--size", "16x16"], "missing.hdr: not found"),
    (["render", "--env", "sky.tga"], "env 'sky.tga': expected sky, none or a panorama"),
    (["render", "--env", "missing.jpg", "--size", "16x16"], "missing.jpg: not found"),
    (["render", "--noise", "bogus"], "noise preset 'bogus': choose from realsense-d435"),
    (["render", "--noise", "kinect-v1,baseline=-1"], "noise: baseline=-1: expected a finite number"),
    (["render", "--env-intensity", "-1"], "env-intensity -1.0: expected a finite number >= 0"),
    (["render", "--env-background", "maybe"], "argument --env-background: invalid choice"),
    (["render", "no-such-file.gltf"], "no such file"),
    (["render", "--cameras", "missing.json", "--out", "d"], "No such file"),
    # (5,000 digits: int() refuses past 4,300; "²" is a digit int() refuses: the fuzz suite's)
    (["render", "--device", "9" * 5000], "--device 9999999999...9999999999: no such device"),
    (["render", "--device", "\u00b2"], "no device matches"),
])
def test_bad_input_is_one_line_and_nonzero(capsys, tmp_path: Path, monkeypatch, argv, message) -> None:  # noqa: ANN001
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, *argv)
    assert code != 0
    assert message in err and err.count("\n") == 1 and err.startswith("vkpbr: error:"), err


def test_no_vulkan_driver_says_what_to_install(tmp_path: Path) -> None:
    env = {"VK_DRIVER_FILES": str(tmp_path / "none.json"), "VK_ICD_FILENAMES": str(tmp_path / "none.json"),
           "PATH": "/usr/bin:/bin", "PYTHONPATH": os.environ.get("PYTHONPATH", "")}
    proc = subprocess.run([sys.executable, "-m", "vkpbr", "render", "--out", str(tmp_path / "x.png")],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 1
    assert "install a Vulkan loader and driver" in proc.stderr and "Traceback" not in proc.stderr


def test_info_json(capsys) -> None:
    code, stdout, _ = run(capsys, "info", "--json")
    report = json.loads(stdout)
    assert code == 0 and report["devices"] and any(d["chosen"] for d in report["devices"])


def test_list_views(capsys) -> None:
    code, stdout, _ = run(capsys, "render", "--list-views")
    lines = stdout.strip().splitlines()
    assert code == 0 and len(lines) == len(View) and lines[0].startswith("final")


def _obj_with_missing_textures(folder: Path) -> Path:
    (folder / "m.mtl").write_text("newmtl m\nKd 0.8 0.8 0.8\nmap_Kd missing.png\nmap_Bump missing_n.png\n")
    obj = folder / "tri.obj"
    obj.write_text("mtllib m.mtl\nusemtl m\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\n"
                   "vt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    return obj


def test_quiet_verbose_and_one_line_warnings(capsys, tmp_path: Path) -> None:
    """Missing textures warn in lines of their own ("vkpbr: ..."), no Python source echoed;
    -q keeps stdout and stderr empty; -v adds info lines; the light accepts negatives."""
    obj, out = _obj_with_missing_textures(tmp_path), tmp_path / "t.png"
    argv = ("render", str(obj), "--size", "32x24", "--out", str(out), "--light", "-5,0.6,-0.9")
    code, stdout, err = run(capsys, *argv)
    assert code == 0 and stdout.startswith(f"wrote {out}") and len(stdout.splitlines()) == 2
    lines = err.splitlines()
    assert lines and all(line.startswith("vkpbr: ") for line in lines), err
    assert "missing.png" in err and "not found" in err
    assert "warn(" not in err and "UserWarning" not in err and "info:" not in err
    out.unlink()
    code, stdout, err = run(capsys, "-q", *argv)
    assert code == 0 and out.exists() and stdout == "" and err == ""
    code, stdout, err = run(capsys, *argv, "-v")
    assert code == 0 and "vkpbr: info: scene " in err and "1 meshes, 1 triangles" in err


def test_strict_turns_missing_textures_into_an_error(capsys, tmp_path: Path) -> None:
    import inspect

    from vkpbr.scene.loader import load_scene

    obj = _obj_with_missing_textures(tmp_path)
    code, _, err = run(capsys, "render", str(obj), "--strict", "--size", "32x24",
                       "--out", str(tmp_path / "t.png"))
    assert err.startswith("vkpbr: error: ") and err.count("\n") == 1, err
    assert not (tmp_path / "t.png").exists()
    if "strict" in inspect.signature(load_scene).parameters:
        assert code == 1 and "missing" in err
    else:  # the loader's strict mode has not landed: --strict says so, it does not pass silently
        assert code == 2 and "no strict mode" in err


def test_outputs_beside_the_frame(capsys, tmp_path: Path) -> None:
    """--outputs writes each dataset output beside --out (ids as 16-bit PNG, the rest as
    float EXR) from the same frame; the PNG holds the ids render(outputs=...) gives."""
    out = tmp_path / "frame.png"
    code, stdout, _ = run(capsys, "render", "--size", "48x36", "--out", str(out), "--outputs",
                          "depth,instance,normal", "--validation")
    assert code == 0 and "frame.instance.png" in stdout
    assert {p.name for p in tmp_path.iterdir()} == {
        "frame.png", "frame.depth.exr", "frame.instance.png", "frame.normal.exr"}
    ids = np.asarray(Image.open(tmp_path / "frame.instance.png"))
    from vkpbr.render.renderer import Renderer

    with Renderer(validation=True) as r:
        want = r.render(size=(48, 36), outputs=("instance",))["instance"]
        assert r.device.instance.errors == []
    assert np.array_equal(ids.astype(np.uint32), want)
    code, _, err = run(capsys, "render", "--outputs", "albedo")
    assert code == 2 and "unknown output 'albedo'" in err
    code, _, err = run(capsys, "render", "--colmap", "--out", str(tmp_path / "c.png"))
    assert code == 2 and "give --cameras too" in err and err.count("\n") == 1


def test_fisheye_transforms_json_with_noise(capsys, tmp_path: Path) -> None:
    """--cameras with nerfstudio's OPENCV_FISHEYE renders through that lens, --noise makes the
    depth output noisy (invalid pixels 0), and the folder's transforms.json keeps the lens."""
    import OpenEXR

    doc = {"camera_model": "OPENCV_FISHEYE", "fl_x": 30.0, "fl_y": 30.0, "cx": 24.0, "cy": 18.0,
           "w": 48, "h": 36, "k1": 0.05, "k2": -0.01, "k3": 0.0, "k4": 0.0,
           "frames": [{"file_path": "a.png", "transform_matrix": [
               [1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, 1, 4], [0, 0, 0, 1]]}]}
    (tmp_path / "t.json").write_text(json.dumps(doc))
    out = tmp_path / "frames"
    code, _, err = run(capsys, "render", "--cameras", str(tmp_path / "t.json"), "--out", str(out),
                       "--size", "48x36", "--outputs", "depth", "--noise", "realsense-d435,seed=2")
    assert code == 0, err
    written = json.loads((out / "transforms.json").read_text())
    assert written["camera_model"] == "OPENCV_FISHEYE" and written["k1"] == 0.05
    depth_file = next(out.glob("*.depth.exr"))
    with OpenEXR.File(str(depth_file)) as f:
        depth = next(iter(f.channels().values())).pixels
    assert (depth == 0).any() and (depth > 0).any() and np.isfinite(depth).all()
