"""vkpbr.distributed without a cluster: the job file's checks (one line each, before any actor
starts), the manifest's records, and a missing ray extra."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vkpbr.app.cli import main
from vkpbr.distributed import MANIFEST_NAME, Manifest, job_from_doc, load_job
from vkpbr.errors import UsageError

SRC = Path(__file__).resolve().parents[2] / "src"
POSES = ["3,1,3,0,0,0", "3,1.2,2.8,0,0,0", "2.8,1,3.2,0,0,0"]


def write_job(tmp_path: Path, doc: object) -> Path:
    (tmp_path / "poses.json").write_text(json.dumps(POSES))
    path = tmp_path / "job.json"
    path.write_text(json.dumps(doc))
    return path


def test_job_file_entries_and_items(tmp_path: Path) -> None:
    (tmp_path / "m.glb").write_bytes(b"")  # only its existence is checked here
    job = load_job(write_job(tmp_path, {"views_per_item": 2, "retries": 1, "scenes": [
        {"scene": "m.glb", "cameras": "poses.json", "out": "a", "size": "64x48",
         "outputs": ["depth", "color", "instance"]},
        {"cameras": [{"eye": [0, 1, 3], "target": [0, 0, 0]}], "out": "b", "size": [32, 16],
         "linear": True, "options": {"view": "d"}}]}))
    a, b = job.scenes
    assert a.settings.scene == tmp_path / "m.glb" and a.settings.out == tmp_path / "a"
    assert a.settings.size == (64, 48) and a.settings.outputs == ("depth", "instance")
    assert b.settings.scene is None and b.settings.size == (32, 16) and len(b.poses) == 1
    assert b.settings.render_options().view.label == "d"
    assert job.views == 4 and job.retries == 1
    items = job.items()
    assert [(i.entry, i.frames) for i in items] == [(0, (0, 1)), (0, (2,)), (1, (0,))]
    # Views done before are left out; the rest is cut into items again.
    assert [(i.entry, i.frames) for i in job.items([{1}, set()])] == [(0, (0, 2)), (1, (0,))]


@pytest.mark.parametrize(("doc", "message"), [
    ({}, 'missing "scenes"'),
    ([], "the list of scene entries is empty"),
    ("x", "expected a list of scene entries, got a string"),
    ([{"out": "a"}], 'entry 0: missing "cameras"'),
    ([{"cameras": "poses.json"}], 'entry 0: missing "out"'),
    ([{"cameras": "poses.json", "out": "a", "colour": 1}], "entry 0: unknown key 'colour'"),
    ([{"cameras": "poses.json", "out": "a", "size": "64by48"}], "entry 0: size: expected"),
    ([{"cameras": "poses.json", "out": "a", "size": [0, 4]}], "width must be a positive"),
    ([{"cameras": "poses.json", "out": "a", "size": [99999, 4]}], "larger than 16384"),
    ([{"cameras": "poses.json", "out": "a", "outputs": ["dpeth"]}], "unknown output 'dpeth'"),
    ([{"cameras": "poses.json", "out": "a", "msaa": 2}], "msaa: expected 1 or 4"),
    ([{"cameras": "poses.json", "out": "a", "linear": "yes"}], "linear: expected true or false"),
    ([{"cameras": "poses.json", "out": "a", "options": {"veiw": "d"}}], "unknown option 'veiw'"),
    ([{"cameras": "poses.json", "out": "a", "options": {"exposure": 99}}], "options: exposure"),
    ([{"cameras": "missing.json", "out": "a"}], "cannot read the poses file"),
    ([{"cameras": ["1,2"], "out": "a"}], "entry 0: cameras: entry 0"),
    ([{"scene": "nope.glb", "cameras": "poses.json", "out": "a"}], "nope.glb: no such file"),
    ([{"cameras": "poses.json", "out": "a"}, {"cameras": "poses.json", "out": "a/"}],
     "entry 1: out"),
    ({"scenes": [{"cameras": "poses.json", "out": "a"}], "views_per_item": 0}, "views_per_item"),
    ([{"cameras": "poses.json", "out": "a", "semantics": "node"}], "semantics: expected mesh"),
    ([{"cameras": "poses.json", "out": "a", "semantics": "classes.json"}], "classes.json: No such file"),
    ([{"cameras": "poses.json", "out": "a", "semantics": {"floor": -3}}], "the value must be an id"),
    ([{"cameras": [{"eye": [0, 1, 3], "target": [0, 0, 0], "time": 0.5},
                   {"eye": [0, 1, 3], "target": [0, 0, 0]}], "out": "a"}],
     'entry 0: cameras: entry 1 has no "time" while others do'),
    ([{"cameras": "poses.json", "out": "a", "animation": True}], "animation: expected an animation"),
])
def test_bad_job_file_is_one_line_before_any_work(capsys, tmp_path: Path, doc: object,
                                                  message: str) -> None:
    path = write_job(tmp_path, doc)
    code = main(["batch", str(path)])
    _, err = capsys.readouterr()
    assert code == 2 and err.startswith("vkpbr: error: ") and err.count("\n") == 1, err
    assert message in err and str(path) in err, err
    assert not (tmp_path / "a").exists()  # nothing was created: checked before any work


def test_job_file_not_json(capsys, tmp_path: Path) -> None:
    path = tmp_path / "job.json"
    path.write_text("[{")
    assert main(["batch", str(path)]) == 2
    err = capsys.readouterr().err
    assert "not valid JSON" in err and err.count("\n") == 1


def _job(tmp_path: Path, out: Path) -> Path:
    return write_job(tmp_path, [{"cameras": "poses.json", "out": str(out), "size": "16x16"}])


@pytest.mark.parametrize("how", ["beneath-a-file", "read-only"])
def test_unwritable_out_folder_is_one_line(capsys, tmp_path: Path, how: str) -> None:
    if how == "beneath-a-file":
        (tmp_path / "file").write_text("x")
        out = tmp_path / "file" / "frames"
    else:
        if os.geteuid() == 0:
            pytest.skip("root writes into a read-only folder")
        out = tmp_path / "ro"
        out.mkdir(mode=0o555)
    code = main(["batch", str(_job(tmp_path, out))])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"out {out}: not writable" in err, err


def test_missing_ray_extra_is_one_line(tmp_path: Path) -> None:
    """With ray unimportable (a package of that name that raises ImportError ahead of the
    real one), `vkpbr batch --ray` and `render --ray` say how to install it, in one line;
    `vkpbr batch` without --ray renders on this machine's processes instead (the documented
    fallback), and says so with -v."""
    shadow = tmp_path / "shadow" / "ray"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text('raise ImportError("No module named \'ray\'")\n')
    # (ahead of the path the tests run with: the fallback's renderer needs its packages)
    path = [str(shadow.parent), str(SRC), *filter(None, os.environ.get("PYTHONPATH", "").split(
        os.pathsep))]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(path), "VKPBR_VALIDATION": "1",
           "VKPBR_CACHE_DIR": str(tmp_path / "cache")}
    job = _job(tmp_path, tmp_path / "frames")
    fallback = subprocess.run([sys.executable, "-m", "vkpbr", "-v", "batch", str(job),
                               "--actors", "1"],
                              capture_output=True, text=True, env=env, timeout=120)
    assert fallback.returncode == 0, fallback.stderr
    assert "ray is not installed: rendering on renderer processes" in fallback.stderr
    assert "on 1 process)" in fallback.stdout + fallback.stderr
    assert sorted(p.name for p in (tmp_path / "frames").glob("frame_*.png")) == \
        [f"frame_{i:05d}.png" for i in range(len(POSES))]
    for argv in (["batch", str(job), "--ray"],
                 ["render", "--cameras", str(tmp_path / "poses.json"), "--out",
                  str(tmp_path / "f2"), "--ray"]):
        proc = subprocess.run([sys.executable, "-m", "vkpbr", *argv], capture_output=True,
                              text=True, env=env, timeout=120)
        assert proc.returncode == 2, proc.stderr
        assert proc.stderr.count("\n") == 1 and "pip install 'vkpbr[ray]'" in proc.stderr, proc.stderr
    # Checked first, created last: the failed run left no out folder.
    assert not (tmp_path / "f2").exists()


@pytest.mark.parametrize("line", [
    {"type": "done", "views": {"0": 1}, "files": [], "sizes": [], "cameras": []},
    {"type": "done", "views": [0], "files": ["frame_00000.png"], "sizes": [3], "cameras": [7]},
    {"type": "done", "views": [0], "files": ["frame_00000.png\x00"], "sizes": [3], "cameras": [{}]},
    {"type": "failed", "views": [0], "error": 5},
    {"type": "gone"},
    ["done"],
])
def test_a_hostile_manifest_in_a_job_folder_is_one_line(capsys, tmp_path: Path, line: object) -> None:  # noqa: ANN001
    """`vkpbr batch` reads an out folder's manifest with validation before Ray is touched:
    wrong types, unknown types and NUL bytes are one line, exit 2, no traceback."""
    job = _job(tmp_path, tmp_path / "frames")
    scene = load_job(job).scenes[0]
    (tmp_path / "frames").mkdir()
    header = {"type": "job", "version": 2, **scene.fingerprint()}
    (tmp_path / "frames" / MANIFEST_NAME).write_text(json.dumps(header) + "\n" + json.dumps(line) + "\n")
    code = main(["batch", str(job)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "line 2" in err and "Traceback" not in err, err


def test_render_ray_needs_cameras_and_no_camera_flags(capsys, tmp_path: Path) -> None:
    assert main(["render", "--out", str(tmp_path / "x"), "--ray"]) == 2
    assert "--ray renders a --cameras batch" in capsys.readouterr().err
    (tmp_path / "p.json").write_text(json.dumps(POSES))
    assert main(["render", "--cameras", str(tmp_path / "p.json"), "--out", str(tmp_path / "x"),
                 "--ray", "--light", "1,2,3"]) == 2
    assert "--light is not available with --ray" in capsys.readouterr().err


def test_times_of_an_entry(tmp_path: Path) -> None:
    """Poses with a "time" render at it (view_times: what the actors pass to render_many);
    the times are in the poses' digest, so a folder rendered at other times is refused."""
    from vkpbr.distributed.job import view_times

    def entry(times: list[float], **more: object) -> object:
        cams = [{"eye": [0, 1, 3], "target": [0, 0, 0], "time": t} for t in times]
        return job_from_doc([{"cameras": cams, "out": str(tmp_path), "size": "16x8", **more}]).scenes[0]

    a = entry([0.5, 1.25], animation="Walk")
    assert view_times(a.poses, a.settings) == [0.5, 1.25] and a.settings.animation == "Walk"
    assert view_times(_entry(tmp_path).poses, _entry(tmp_path).settings) is None
    # (the manifest refuses a folder whose header differs: test_manifest_records_...)
    other = entry([0.5, 1.5], animation="Walk").fingerprint()
    assert other["poses_sha256"] != a.fingerprint()["poses_sha256"]
    assert entry([0.5, 1.25]).fingerprint() != a.fingerprint()  # another animation


def _entry(tmp_path: Path) -> object:
    return job_from_doc([{"cameras": POSES, "out": str(tmp_path), "size": "16x8"}]).scenes[0]


def test_manifest_records_resume_and_refuses_another_job(tmp_path: Path) -> None:
    scene = _entry(tmp_path)
    m = Manifest.open(tmp_path, scene.fingerprint(), "entry 0")
    assert m.done_views() == set()
    cams = [{"eye": [0.0, 1.0, 3.0], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
             "yfov_deg": 60.0, "znear": None, "zfar": None, "name": "a", "pixel_intrinsics": None}]
    (tmp_path / "frame_00000.png").write_bytes(b"x")
    m.done([0], ["frame_00000.png"], cams)
    m.failed([1], "SceneError: bad", 3)
    m.close()
    # A driver killed mid-line: the cut-short line is dropped, the next append is whole.
    with open(tmp_path / MANIFEST_NAME, "ab") as f:
        f.write(b'{"type": "done", "views": [2], "fi')
    again = Manifest.open(tmp_path, scene.fingerprint(), "entry 0")
    assert again.done_views() == {0} and again.failures == {1: "SceneError: bad"}
    assert again.cameras(1)[0].eye == (0.0, 1.0, 3.0)
    assert again.cameras(2) is None
    (tmp_path / "frame_00002.png").write_bytes(b"x")
    again.done([2], ["frame_00002.png"], cams)
    again.close()
    lines = (tmp_path / MANIFEST_NAME).read_text().splitlines()
    assert [json.loads(line)["type"] for line in lines] == ["job", "done", "failed", "done"]
    assert Manifest.open(tmp_path, scene.fingerprint(), "e").done_views() == {0, 2}
    # A done view whose file was deleted is rendered again.
    (tmp_path / "frame_00000.png").unlink()
    assert Manifest.open(tmp_path, scene.fingerprint(), "e").done_views() == {2}
    # Another size: the files would be stale; refused in one line.
    other = job_from_doc([{"cameras": POSES, "out": str(tmp_path), "size": "16x9"}]).scenes[0]
    with pytest.raises(UsageError, match=r"written by a run with another size \(\[16, 8\], now \[16, 9\]\)"):
        Manifest.open(tmp_path, other.fingerprint(), "e")


@settings(max_examples=60, deadline=None)
@given(views=st.integers(1, 40), per_item=st.integers(1, 9), data=st.data())
def test_items_cover_every_view_not_done_exactly_once(views: int, per_item: int, data) -> None:  # noqa: ANN001
    done = data.draw(st.sets(st.integers(0, views - 1)))
    poses = [f"3,1,{1 + i / 10},0,0,0" for i in range(views)]
    job = job_from_doc({"scenes": [{"cameras": poses, "out": "/nonexistent/a"},
                                   {"cameras": POSES[:2], "out": "/nonexistent/b"}],
                        "views_per_item": per_item})
    items = job.items([done, set()])
    first = [v for i in items if i.entry == 0 for v in i.frames]
    assert first == [v for v in range(views) if v not in done]  # in order, each once
    assert [v for i in items if i.entry == 1 for v in i.frames] == [0, 1]
    assert all(1 <= len(i.frames) <= per_item for i in items)
    assert all(i.poses == tuple(job.scenes[i.entry].poses[v] for v in i.frames) for i in items)


def test_semantics_of_an_entry(tmp_path: Path) -> None:
    """An entry's semantics: a source, an inline mapping (part of the scene key and the
    fingerprint) or a mapping file resolved against the job's folder."""
    from vkpbr.distributed import job_from_doc

    (tmp_path / "poses.json").write_text(json.dumps(["0,1,5,0,0,0"]))
    (tmp_path / "classes.json").write_text(json.dumps({"floor": 2}))
    doc = [{"cameras": "poses.json", "out": "a", "semantics": {"floor": 2, "card": "card"}},
           {"cameras": "poses.json", "out": "b", "semantics": "classes.json"},
           {"cameras": "poses.json", "out": "c"}]
    job = job_from_doc(doc, "job", tmp_path)
    s = [e.settings for e in job.scenes]
    assert s[0].semantic_source() == {"card": "card", "floor": 2}
    assert s[1].semantic_source() == str(tmp_path / "classes.json") and s[2].semantics == "mesh"
    assert len({x.scene_key() for x in s}) == 3
    assert "semantics" in job.scenes[0].fingerprint() and "semantics" not in job.scenes[2].fingerprint()


def test_batch_of_an_entry(tmp_path: Path) -> None:
    """An entry's "batch" (views per GPU submission, as render --batch): 64 by default, 0
    frame by frame (which changes directional shadows: part of the fingerprint)."""
    from vkpbr.distributed import job_from_doc

    (tmp_path / "poses.json").write_text(json.dumps(["0,1,5,0,0,0"]))
    doc = [{"cameras": "poses.json", "out": "a"}, {"cameras": "poses.json", "out": "b", "batch": 0},
           {"cameras": "poses.json", "out": "c", "batch": 8}]
    job = job_from_doc(doc, "job", tmp_path)
    assert [e.settings.batch for e in job.scenes] == [64, 0, 8]
    prints = [e.fingerprint() for e in job.scenes]
    assert "batch" not in prints[0] and prints[1]["batch"] == 0 and "batch" not in prints[2]
    with pytest.raises(UsageError, match="batch: expected an integer >= 0"):
        job_from_doc([{"cameras": "poses.json", "out": "d", "batch": -1}], "job", tmp_path)
