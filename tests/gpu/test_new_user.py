"""What a new user tripped over (issue 35, must-have 4), each with a test: a poses file's own
image size, each frame's file_path kept, camera generators, and the one-line answers."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from PIL import Image

from vkpbr.app.cli import main

DOCS = Path(__file__).resolve().parents[2] / "docs"


def run(capsys, *argv: str) -> tuple[int, str, str]:  # noqa: ANN001
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _nerf(tmp_path: Path, w: int, h: int) -> Path:
    doc = json.loads((DOCS / "examples" / "transforms.json").read_text())
    doc.update(w=w, h=h)
    path = tmp_path / "transforms.json"
    path.write_text(json.dumps(doc))
    return path


def test_a_poses_file_that_states_its_size_is_rendered_at_that_size(capsys, tmp_path: Path) -> None:
    """No --size: the file's w x h, not 1280x720 (which would scale fl_x and fl_y apart);
    a --size of its aspect ratio rescales; another aspect ratio is one error line."""
    poses = _nerf(tmp_path, 40, 30)
    code, out, _ = run(capsys, "render", "--cameras", str(poses), "--out", str(tmp_path / "a"),
                       "--validation")
    assert code == 0 and "(40x30," in out, out
    first = tmp_path / "a" / "train" / "r_0.png"
    assert Image.open(first).size == (40, 30)
    doc = json.loads((tmp_path / "a" / "transforms.json").read_text())
    assert (doc.get("w"), doc.get("h")) == (40, 30)
    code, _, _ = run(capsys, "render", "--cameras", str(poses), "--out", str(tmp_path / "b"),
                     "--size", "80x60", "--validation")
    assert code == 0 and Image.open(tmp_path / "b" / "train" / "r_0.png").size == (80, 60)
    code, _, err = run(capsys, "render", "--cameras", str(poses), "--out", str(tmp_path / "c"),
                       "--size", "80x40")
    assert code == 2 and err.count("\n") == 1 and "calibrated for 40x30" in err, err
    assert not (tmp_path / "c").exists()


def test_each_frame_keeps_its_file_path(capsys, tmp_path: Path) -> None:
    """Re-rendering a NeRF transforms.json writes each frame under its own file_path (a NeRF
    loader's `file_path + ".png"`), and the transforms.json written names them so."""
    poses = _nerf(tmp_path, 32, 24)
    src = json.loads(poses.read_text())
    out = tmp_path / "out"
    assert run(capsys, "render", "--cameras", str(poses), "--out", str(out), "--validation")[0] == 0
    doc = json.loads((out / "transforms.json").read_text())
    assert [f["file_path"] for f in doc["frames"]] == [
        f["file_path"].removeprefix("./") for f in src["frames"]]
    for f in doc["frames"]:  # a NeRF synthetic loader's path
        assert (out / (f["file_path"] + ".png")).is_file()
    for f, g in zip(doc["frames"], src["frames"], strict=True):
        assert np.allclose(f["transform_matrix"], g["transform_matrix"], atol=1e-6)
    # A file_path outside the folder is refused in one line.
    bad = dict(src, frames=[dict(src["frames"][0], file_path="../../escape")])
    poses.write_text(json.dumps(bad))
    code, _, err = run(capsys, "render", "--cameras", str(poses), "--out", str(tmp_path / "x"))
    assert code == 2 and err.count("\n") == 1 and "file_path" in err, err


def test_camera_index_on_a_file_without_cameras(capsys, tmp_path: Path) -> None:
    """Not "the scene has 1 camera(s)" (the automatic one): the file has none, and the
    message says what the index means."""
    trimesh = __import__("pytest").importorskip("trimesh", reason="trimesh (test extra) builds the file")
    box = tmp_path / "box.glb"
    trimesh.creation.box().export(box)
    code, _, err = run(capsys, "render", str(box), "--camera-index", "3", "--out",
                       str(tmp_path / "x.png"))
    assert code == 2 and err.count("\n") == 1, err
    assert "the scene file has no cameras" in err and "counting from 0" in err, err
    assert not (tmp_path / "x.png").exists()


def test_view_without_a_display_is_one_clean_line(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    src = str(Path(__file__).resolve().parents[2] / "src")  # before what the run had (wheels)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (src, os.environ.get("PYTHONPATH")) if p)
    proc = subprocess.run([sys.executable, "-m", "vkpbr", "view"], capture_output=True,
                          text=True, env=env, timeout=120)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1, proc.stderr
    assert "b'" not in proc.stderr and "GLFWError" not in proc.stderr, proc.stderr
    assert proc.stderr.startswith("vkpbr: error: cannot open a window: ") and "--offscreen" in proc.stderr


def test_out_bmp_is_accepted_and_documented(capsys, tmp_path: Path) -> None:
    """--out x.bmp writes a BMP (as docs/outputs.md and --help say), the PNG's pixels less
    alpha where BMP keeps none."""
    assert run(capsys, "render", "--size", "32x24", "--out", str(tmp_path / "a.png"))[0] == 0
    assert run(capsys, "render", "--size", "32x24", "--out", str(tmp_path / "a.bmp"))[0] == 0
    bmp = Image.open(tmp_path / "a.bmp")
    assert bmp.format == "BMP"
    png = np.asarray(Image.open(tmp_path / "a.png").convert("RGB"))
    assert np.array_equal(np.asarray(bmp.convert("RGB")), png)
    code, out, _ = run(capsys, "render", "--help")
    assert ".bmp" in out
    assert ".bmp" in (DOCS / "outputs.md").read_text()


def test_bench_finds_sponza_under_vkpbr_assets(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    """`vkpbr bench` looks for Sponza where the tests do: $VKPBR_ASSETS/Sponza/glTF."""
    import argparse

    import pytest

    from vkpbr.app.bench_cmd import sponza_path
    from vkpbr.errors import UsageError

    (tmp_path / "Sponza" / "glTF").mkdir(parents=True)
    (tmp_path / "Sponza" / "glTF" / "Sponza.gltf").write_text("{}")
    monkeypatch.setenv("VKPBR_ASSETS", str(tmp_path))
    assert sponza_path(argparse.Namespace(sponza=None)) == tmp_path / "Sponza" / "glTF" / "Sponza.gltf"
    monkeypatch.setenv("VKPBR_ASSETS", str(tmp_path / "empty"))
    with pytest.raises(UsageError, match=r"\$VKPBR_ASSETS="):
        sponza_path(argparse.Namespace(sponza=None))


def test_transparent_background_alpha_is_coverage(capsys, tmp_path: Path) -> None:
    """Where no background is drawn (--env-background off, --env none, the course mode),
    alpha is coverage: 0 where the instance output says nothing was drawn, 255 where a
    surface was (no MSAA: every pixel whole); with the background drawn, 255 everywhere.
    The colour is premultiplied (over black): the background's pixels are (0, 0, 0, 0)."""
    from vkpbr import Renderer

    with Renderer(msaa=1) as r:
        for pipeline in ("forward", "compute"):
            frame = r.render(size=(64, 48), env_background=False, pipeline=pipeline,
                             outputs=("color", "instance"))
            alpha, ids = frame["color"][..., 3], frame["instance"]
            assert 0 < (ids == 0).sum() < ids.size
            assert np.array_equal(alpha == 255, ids > 0) and set(np.unique(alpha)) == {0, 255}
            assert not frame["color"][ids == 0][:, :3].any()  # premultiplied: black
            assert (r.render(size=(64, 48), pipeline=pipeline)[..., 3] == 255).all()
        batch = r.render_batch([r.default_camera()] * 2, size=(64, 48), env_background=False)
        assert np.array_equal(batch[0][..., 3], alpha)
    with Renderer(msaa=4) as r:  # edges: partial coverage
        a = r.render(size=(64, 48), env_background=False)[..., 3]
        assert ((a > 0) & (a < 255)).any() and (a == 0).any() and (a == 255).any()
    code, _, _ = run(capsys, "render", "--env-background", "off", "--size", "32x24", "--out",
                     str(tmp_path / "t.png"))
    assert code == 0 and np.asarray(Image.open(tmp_path / "t.png"))[..., 3].min() == 0


def test_render_orbit_writes_a_turntable(capsys, tmp_path: Path) -> None:
    """`vkpbr render --orbit N` renders N views around the scene into a frames folder, with
    its transforms.json; the views differ and the chart stays inside each image."""
    out = tmp_path / "orbit"
    code, stdout, _ = run(capsys, "render", "--orbit", "4", "--out", str(out), "--size", "32x24",
                          "--validation", "--outputs", "instance")
    assert code == 0 and "wrote 4 images" in stdout, stdout
    doc = json.loads((out / "transforms.json").read_text())
    assert len(doc["frames"]) == 4
    frames = [np.asarray(Image.open(out / f"frame_{i:05d}.png")) for i in range(4)]
    assert not np.array_equal(frames[0], frames[1])
    for i in range(4):
        ids = np.asarray(Image.open(out / f"frame_{i:05d}.instance.png"))
        edge = np.concatenate([ids[0], ids[-1], ids[:, 0], ids[:, -1]])
        assert ids.any() and not edge.any(), i  # framed: nothing cut at the borders
    code, _, err = run(capsys, "render", "--orbit", "0", "--out", str(tmp_path / "x"))
    assert code == 2 and "--orbit 0" in err


def test_render_batch_last_stats_are_the_calls() -> None:
    """render_batch's last_stats: the Python time up to the submit, the wait and the
    readback are measured (not 0), and the GPU steps' times add up to the GPU time, on the
    layered batch, the compute batch and the view-by-view route (with a post step), whose
    stats are every view's summed."""
    import math

    from vkpbr import Renderer

    with Renderer() as r:
        cams = [r.default_camera()] * 3
        for kw in ({"pipeline": "forward"}, {"pipeline": "compute"},
                   {"pipeline": "forward", "bloom": 0.2}):
            r.render_batch(cams, size=(32, 24), **kw)
            s = r.last_stats
            assert s.cpu_ms > 0 and s.wait_ms > 0 and s.readback_ms > 0, (kw, s)
            assert math.isclose(sum(s.pass_ms.values()), s.gpu_ms, rel_tol=1e-6, abs_tol=1e-6), (kw, s)
    # Every view's stats summed, not the last one's: the sum itself, without comparing
    # measured times (a timing is never asserted: two readbacks' times may be anything).
    from vkpbr.render.frames import FrameStats, summed_stats

    a = FrameStats(cpu_ms=1.0, wait_ms=2.0, gpu_ms=3.0, readback_ms=4.0, pass_ms={"bloom": 0.5})
    b = FrameStats(cpu_ms=10.0, wait_ms=20.0, gpu_ms=30.0, readback_ms=40.0,
                   pass_ms={"bloom": 5.0, "copy": 1.0})
    both = summed_stats(a, b)
    assert (both.cpu_ms, both.wait_ms, both.gpu_ms, both.readback_ms) == (11.0, 22.0, 33.0, 44.0)
    assert both.pass_ms == {"bloom": 5.5, "copy": 1.0}


def test_the_renderers_own_arguments_are_one_line() -> None:
    """A path where a Scene goes (Renderer("x.gltf"), set_scene(5)), a colour name as the
    background, another object as env_spec, semantics=5, outputs=5 (found by hand: an
    AttributeError or an AssertionError deep in the parts' making, a TypeError from the
    Vulkan binding's clear value, a TypeError iterating 5): one UsageError line each, and
    set_scene's leaves the scene drawn before."""
    import pytest

    from vkpbr.errors import UsageError
    from vkpbr.render.renderer import Renderer

    for kwargs, message in (({"scene": "x.gltf"}, "scene: expected a Scene .* got str"),
                            ({"background": "red"}, "background: expected a 3 matrix, got str"),
                            ({"background": (1, 2)}, "background: expected 3 items, got 2"),
                            ({"background": (float("nan"), 0, 0)}, r"background\[0\]: nan is not finite"),
                            ({"env_spec": "cpu"}, "env_spec: expected an EnvironmentSpec, got str"),
                            ({"semantics": 5}, "semantics: expected mesh, material, extras")):
        with pytest.raises(UsageError, match=message) as err:
            Renderer(**{"validation": True, **kwargs})
        assert "\n" not in str(err.value)
    with Renderer(validation=True) as r:
        before = r.render(size=(16, 12))
        with pytest.raises(UsageError, match="scene: expected a Scene .* got int"):
            r.set_scene(5)
        with pytest.raises(UsageError, match="outputs: expected names from color"):
            r.render(size=(16, 12), outputs=5)
        assert np.array_equal(r.render(size=(16, 12)), before)
        r.check_validation()
