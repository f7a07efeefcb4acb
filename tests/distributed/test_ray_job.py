"""vkpbr.distributed on a real local Ray cluster (2 CPU workers, lavapipe, the validation layer
on in the actors): the files equal the single-process `vkpbr render --cameras` byte for byte,
an actor killed midway loses and duplicates nothing, a killed driver's job resumes, a broken
scene fails only its items, an unreachable cluster is one line."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # a local Ray cluster: the end-to-end tier

ray = pytest.importorskip("ray", reason="the ray extra is not installed (pip install 'vkpbr[ray]')",
                          exc_type=ImportError)

from vkpbr.app.cli import main  # noqa: E402
from vkpbr.distributed import MANIFEST_NAME, render  # noqa: E402

SRC = Path(__file__).resolve().parents[2] / "src"
SIZE = "64x48"
# An orbit of the built-in chart: views that differ.
POSES = [f"{3 * __import__('math').cos(a / 3):.4f},1.2,{3 * __import__('math').sin(a / 3):.4f},0,0,0"
         for a in range(12)]


@pytest.fixture(scope="module")
def box(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny glTF scene (a box) made here."""
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path_factory.mktemp("box") / "box.glb"
    trimesh.creation.box(extents=(1.0, 0.6, 0.8)).export(path)
    return path


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory, box: Path, cluster: dict) -> dict:
    """The single-process renders (`vkpbr render --cameras`) the Ray jobs must equal."""
    base = tmp_path_factory.mktemp("reference")
    (base / "poses.json").write_text(json.dumps(POSES))
    out = {}
    for name, argv in {
        "chart": ["--outputs", "depth,instance"],
        "box": [str(box)],
        "box-cached": [str(box), "--cache", str(cluster["cache"])],
    }.items():
        folder = base / name
        assert main(["-q", "render", *argv, "--cameras", str(base / "poses.json"), "--out",
                     str(folder), "--size", SIZE, "--validation"]) == 0
        out[name] = folder
    return out


def check_exactly_once(out: Path, views: int, per_view: int) -> list[dict]:
    """Every file of every view exists once, under its final name, with no temporary file
    left; the manifest lists each view in exactly one "done" record, with its files."""
    files = sorted(p.name for p in out.iterdir())
    assert not [f for f in files if f.endswith(".tmp")], files
    frames = [f for f in files if f.startswith("frame_")]
    assert len(frames) == views * per_view
    assert {int(f[6:11]) for f in frames} == set(range(views))
    records = [json.loads(line) for line in (out / MANIFEST_NAME).read_text().splitlines()]
    assert records[0]["type"] == "job" and records[0]["views"] == views
    done = [r for r in records if r["type"] == "done"]
    counts = Counter(v for r in done for v in r["views"])
    assert counts == Counter(range(views)), counts  # each view done once
    listed = [f for r in done for f in r["files"]]
    assert sorted(listed) == frames  # and each file recorded once
    return records


def assert_same_files(a: Path, b: Path) -> None:
    names = sorted(p.name for p in b.iterdir() if p.name.startswith(("frame_", "transforms")))
    assert names and names == sorted(p.name for p in a.iterdir()
                                     if p.name.startswith(("frame_", "transforms")))
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def done_lines(manifest: Path) -> int:
    """Complete "done" lines (a killed driver may have cut the last line short)."""
    return sum('"type": "done"' in line for line in manifest.read_text().split("\n")[:-1])


def write_job(folder: Path, entries: list[dict], **settings: object) -> Path:
    (folder / "poses.json").write_text(json.dumps(POSES))
    path = folder / "job.json"
    path.write_text(json.dumps({"scenes": entries, **settings}))
    return path


def test_ray_job_equals_single_process_byte_for_byte(cluster: dict, reference: dict, box: Path,
                                                     tmp_path: Path) -> None:
    job = write_job(tmp_path, [
        {"cameras": "poses.json", "out": "chart", "size": SIZE, "outputs": ["depth", "instance"]},
        {"scene": str(box), "cameras": "poses.json", "out": "box", "size": SIZE, "cache": False},
        {"scene": str(box), "cameras": "poses.json", "out": "box-cached", "size": SIZE},
    ], views_per_item=5)
    result = render(job)
    assert result.ok and result.rendered == 3 * len(POSES) and result.actors == 2, result.summary()
    for name, per_view in (("chart", 3), ("box", 1), ("box-cached", 1)):
        check_exactly_once(tmp_path / name, len(POSES), per_view)
        assert_same_files(tmp_path / name, reference[name])
    frames = [(tmp_path / "box" / f"frame_{i:05d}.png").read_bytes() for i in (0, 6)]
    assert frames[0] != frames[1]  # the views really differ
    records = [json.loads(x) for x in (tmp_path / "chart" / MANIFEST_NAME).read_text().splitlines()]
    pids = {json.loads(x).get("pid") for name in ("chart", "box", "box-cached")
            for x in (tmp_path / name / MANIFEST_NAME).read_text().splitlines()[1:]}
    assert len(pids) == 2 and os.getpid() not in pids  # both actors rendered, none in-process
    again = render(job)  # a re-run renders nothing
    assert again.ok and again.rendered == 0 and again.skipped == 3 * len(POSES)
    assert records == [json.loads(x) for x in
                       (tmp_path / "chart" / MANIFEST_NAME).read_text().splitlines()]


def test_actor_killed_midway_loses_and_duplicates_nothing(cluster: dict, reference: dict, capsys,
                                                          tmp_path: Path) -> None:  # noqa: ANN001
    job = write_job(tmp_path, [{"cameras": "poses.json", "out": "chart", "size": SIZE,
                                "outputs": ["depth", "instance"]}], views_per_item=1)
    killed = []

    def kill_one(item, res) -> None:  # noqa: ANN001 - on the driver, after the first result
        if not killed:
            names = sorted(a["name"] for a in ray.util.list_named_actors(all_namespaces=True)
                           if a["name"].startswith("vkpbr-renderer-"))
            ray.kill(ray.get_actor(names[0]))
            killed.append(names[0])

    result = render(job, on_result=kill_one, progress=True)
    assert killed and result.ok, result.summary()
    bar = capsys.readouterr().err.split("\r")[-1]  # the progress bar's last state
    assert f"{len(POSES)}/{len(POSES)}" in bar and "view" in bar, bar
    assert result.actors_lost == 1 and result.retries >= 1  # the kill hit work it had
    records = check_exactly_once(tmp_path / "chart", len(POSES), 3)
    assert_same_files(tmp_path / "chart", reference["chart"])
    assert max(r.get("attempts", 1) for r in records[1:]) == 2  # the lost item, done again


def test_killed_driver_resumes(cluster: dict, reference: dict, tmp_path: Path) -> None:
    """A driver killed with SIGKILL mid-job (its actors die with it); the re-run renders only
    the views the manifest does not list, and the result is the same files, once each."""
    job = write_job(tmp_path, [{"cameras": "poses.json", "out": "chart", "size": SIZE,
                                "outputs": ["depth", "instance"]}], views_per_item=1)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-m", "vkpbr", "-q", "batch", str(job), "--ray",
                             cluster["address"]], env=env, stderr=subprocess.PIPE)
    manifest = tmp_path / "chart" / MANIFEST_NAME
    deadline = time.monotonic() + 90
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            if manifest.exists() and done_lines(manifest) >= 3:
                break
            time.sleep(0.02)
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    before = done_lines(manifest)
    assert 3 <= before < len(POSES)
    result = render(job)
    assert result.ok and result.skipped == before and result.rendered == len(POSES) - before
    check_exactly_once(tmp_path / "chart", len(POSES), 3)
    assert_same_files(tmp_path / "chart", reference["chart"])


def test_broken_scene_fails_only_its_items(cluster: dict, reference: dict, capsys,
                                           tmp_path: Path) -> None:  # noqa: ANN001
    broken = tmp_path / "broken.gltf"
    broken.write_text('{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": '
                      '{"POSITION": 7}}]}]}')
    job = write_job(tmp_path, [
        {"scene": str(broken), "cameras": POSES[:4], "out": "broken", "size": SIZE},
        {"cameras": "poses.json", "out": "chart", "size": SIZE, "outputs": ["depth", "instance"]},
    ], views_per_item=2)
    code = main(["batch", str(job)])
    err = capsys.readouterr().err
    assert code == 1
    lines = err.strip().splitlines()
    assert re.search(r"16 views: 12 rendered, 0 done before, 4 failed", lines[0]), err
    failed = [line for line in lines if "failed: broken.gltf views" in line]
    assert len(failed) == 2 and all("broken.gltf" in line.split(": ", 3)[-1] for line in failed), err
    assert "Traceback" not in err
    check_exactly_once(tmp_path / "chart", len(POSES), 3)
    assert_same_files(tmp_path / "chart", reference["chart"])
    records = [json.loads(x) for x in (tmp_path / "broken" / MANIFEST_NAME).read_text().splitlines()]
    assert sorted(v for r in records if r["type"] == "failed" for v in r["views"]) == [0, 1, 2, 3]
    assert all(r["attempts"] == 1 for r in records if r["type"] == "failed")  # input: no retry
    assert not (tmp_path / "broken" / "transforms.json").exists()  # incomplete entry


def test_render_cli_on_ray_equals_without(cluster: dict, reference: dict, capsys,
                                          tmp_path: Path) -> None:  # noqa: ANN001
    poses = tmp_path / "poses.json"
    poses.write_text(json.dumps(POSES))
    code = main(["render", "--cameras", str(poses), "--out", str(tmp_path / "f"), "--size", SIZE,
                 "--outputs", "depth,instance", "--ray", "--actors", "1"])
    out = capsys.readouterr().out
    assert code == 0 and f"{len(POSES)} views: {len(POSES)} rendered" in out and "1 actor)" in out
    assert_same_files(tmp_path / "f", reference["chart"])


@pytest.mark.timeout(60)  # the hang guard (ray.init on a dead address waits > 40 s): no clock asserted
def test_unreachable_cluster_is_one_line(cluster: dict, capsys, tmp_path: Path) -> None:  # noqa: ANN001
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    job = write_job(tmp_path, [{"cameras": "poses.json", "out": "o", "size": SIZE}])
    code = main(["batch", str(job), "--ray", f"127.0.0.1:{port}"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1, err
    assert f"Ray cluster at 127.0.0.1:{port}: cannot connect" in err
    assert not (tmp_path / "o").exists()  # a failed run leaves no out folder
    code = main(["batch", str(job), "--ray", "head-without-port"])
    err = capsys.readouterr().err
    assert code == 2 and "expected HOST:PORT" in err and err.count("\n") == 1


def test_plain_ray_and_batch_runs_share_one_folder(cluster: dict, reference: dict, capsys,
                                                   tmp_path: Path) -> None:  # noqa: ANN001
    """The issue's sequence (--ray at one size, plainly at another, --ray again) cannot mix
    sizes any more: every writer keeps the one manifest. --ray, then plain at another size
    (refused, nothing changed), plain at the same size (nothing to do), two files deleted
    and cut short, `vkpbr batch` (renders those two): the folder equals one plain run's."""
    from folder_checks import check_consistent

    poses = tmp_path / "poses.json"
    poses.write_text(json.dumps(POSES))
    out = tmp_path / "f"
    common = ["--cameras", str(poses), "--out", str(out), "--outputs", "depth,instance"]
    assert main(["render", *common, "--size", SIZE, "--ray", cluster["address"]]) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["render", *common, "--size", "32x24"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "written by a run with another size" in err, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert main(["render", *common, "--size", SIZE]) == 0
    assert f"wrote 0 images, {len(POSES)} done before" in capsys.readouterr().out
    (out / "frame_00003.png").unlink()
    depth = out / "frame_00007.depth.exr"
    depth.write_bytes(depth.read_bytes()[:100])
    job = write_job(tmp_path, [{"cameras": "poses.json", "out": "f", "size": SIZE,
                                "outputs": ["depth", "instance"]}])
    result = render(job, cluster["address"])
    assert result.ok and result.rendered == 2 and result.skipped == len(POSES) - 2, result.summary()
    assert check_consistent(out) == set(range(len(POSES)))
    assert_same_files(out, reference["chart"])


def test_a_killed_plain_run_resumes_on_ray(cluster: dict, tmp_path: Path) -> None:
    """A plain `render --cameras` killed with SIGKILL after its first recorded views; `--ray`
    renders only the rest, and the folder equals an uninterrupted plain run's."""
    from folder_checks import check_consistent, done_lines

    poses = tmp_path / "many.json"
    poses.write_text(json.dumps([f"{3 * __import__('math').cos(a / 9):.4f},1.2,"
                                 f"{3 * __import__('math').sin(a / 9):.4f},0,0,0" for a in range(80)]))
    out = tmp_path / "f"
    argv = ["-q", "render", "--cameras", str(poses), "--out", str(out), "--size", "32x24"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-m", "vkpbr", *argv, "--batch", "4"], env=env,
                            stderr=subprocess.PIPE)
    deadline = time.monotonic() + 90
    try:
        while time.monotonic() < deadline and proc.poll() is None and done_lines(out) < 1:
            time.sleep(0.01)
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    done = check_consistent(out)
    assert 0 < len(done) < 80
    assert main([*argv, "--ray", cluster["address"]]) == 0
    assert check_consistent(out) == set(range(80))
    whole = tmp_path / "whole"
    assert main(["-q", "render", "--cameras", str(poses), "--out", str(whole), "--size", "32x24"]) == 0
    assert_same_files(out, whole)


def test_render_cli_on_ray_plays_the_poses_times(cluster: dict, capsys, tmp_path: Path) -> None:  # noqa: ANN001
    """Poses with a "time" on Ray (each view at its time of the file's animation, --time for
    the views without one): the files equal `vkpbr render --cameras` without --ray, and the
    frames differ from one another (the triangle turns)."""
    from assets_path import assets_dir

    scene = assets_dir() / "AnimatedTriangle" / "glTF" / "AnimatedTriangle.gltf"
    if not scene.is_file():
        pytest.skip(f"{scene} is missing (the sample models: tests/assets_path.py)")
    cams = [{"eye": [0.5, 0.5, 3.0], "target": [0.5, 0.5, 0.0],
             **({"time": t} if t is not None else {})} for t in (None, 0.6, 1.7)]
    poses = tmp_path / "poses.json"
    poses.write_text(json.dumps(cams))
    common = ["render", str(scene), "--cameras", str(poses), "--size", "32x24", "--time", "0.3"]
    assert main([*common, "--out", str(tmp_path / "plain")]) == 0
    assert main([*common, "--out", str(tmp_path / "ray"), "--ray", cluster["address"],
                 "--actors", "1"]) == 0
    assert "3 views: 3 rendered" in capsys.readouterr().out
    assert_same_files(tmp_path / "ray", tmp_path / "plain")
    frames = [(tmp_path / "ray" / f"frame_{i:05d}.png").read_bytes() for i in range(3)]
    assert len(set(frames)) == 3
    doc = json.loads((tmp_path / "ray" / "transforms.json").read_text())
    assert [f["time"] for f in doc["frames"]] == [0.3, 0.6, 1.7]
