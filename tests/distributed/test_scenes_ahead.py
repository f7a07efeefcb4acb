"""Jobs of many scenes without Ray (issue 32, must-have 7): `vkpbr batch --in-process` and the
actor it runs, which changes scene with `Renderer.set_scene` and loads the next scene on a
thread while it renders this one. The files equal `vkpbr render --cameras` of each scene
byte for byte on lavapipe (within 1 level on a GPU: check_against), in the job's order; a
scene that fails to load ahead fails only its own items, when they come; a job stopped
midway resumes and renders only what is missing."""

from __future__ import annotations

import contextlib
import functools
import io
import json
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from vkpbr.app.cli import main
from vkpbr.distributed import MANIFEST_NAME, job_from_doc, render
from vkpbr.distributed.actor import RendererActor
from vkpbr.distributed.driver import IN_PROCESS, PROCESSES
from vkpbr.errors import UsageError

SIZE = "48x32"
POSES = ["3,1.2,2,0,0,0", "2,1,3,0,0,0", "-2,1.5,3,0,0,0"]
MODELS = ("TextureCoordinateTest", "OrientationTest")


@pytest.fixture(scope="module")
def scenes(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path | None]:
    from assets_path import ASSETS

    found = {m: ASSETS / m / "glTF" / f"{m}.gltf" for m in MODELS}
    if not all(p.is_file() for p in found.values()):
        pytest.skip(f"sample models {', '.join(MODELS)} not found in {ASSETS}")
    bad = tmp_path_factory.mktemp("bad") / "broken.gltf"
    bad.write_text('{"asset": {"version": "2.0"}, "scenes": [')  # cut short
    return {"chart": None, **found, "broken": bad}


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory, scenes: dict) -> dict[str, Path]:
    """Each good scene's frames from the single-process `vkpbr render --cameras`."""
    base = tmp_path_factory.mktemp("reference")
    (base / "poses.json").write_text(json.dumps(POSES))
    out = {}
    for name, path in scenes.items():
        if name == "broken":
            continue
        argv = [str(path)] if path is not None else []
        assert main(["-q", "render", *argv, "--cameras", str(base / "poses.json"), "--out",
                     str(base / name), "--size", SIZE, "--validation"]) == 0
        out[name] = base / name
    return out


def job_doc(folder: Path, scenes: dict) -> dict:
    """chart, model, model, broken, chart again: every item a change of scene but the views
    of one entry, which come in two items."""
    (folder / "poses.json").write_text(json.dumps(POSES))
    order = ["chart", *MODELS, "broken", "chart"]
    entries = []
    for k, name in enumerate(order):
        entry = {"cameras": "poses.json", "out": f"{k}-{name}", "size": SIZE}
        if scenes[name] is not None:
            entry["scene"] = str(scenes[name])
        entries.append(entry)
    return {"scenes": entries, "views_per_item": 2}


def frames(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.glob("frame_*"))}


@functools.cache
def on_cpu() -> bool:
    from vkpbr.gpu.device import Device

    with Device() as device:
        return device.info.kind == "cpu"


def check_against(reference: dict[str, Path], folder: Path) -> None:
    """The same frames as the reference: byte for byte on lavapipe; on a GPU within 1 level
    a channel, where a view in a batch of 2 and the same view in the reference's batch of 3
    may round apart (the compute batch's stated bound, docs/batch.md)."""
    for out in sorted(folder.glob("[0-9]-*")):
        name = out.name.split("-", 1)[1]
        if name == "broken":
            assert not frames(out)
            continue
        got, want = frames(out), frames(reference[name])
        assert got and sorted(got) == sorted(want), out.name
        for file in got:
            if got[file] != want[file]:
                assert not on_cpu(), f"{out.name}/{file}"
                a = np.asarray(Image.open(io.BytesIO(got[file]))).astype(int)
                b = np.asarray(Image.open(io.BytesIO(want[file]))).astype(int)
                assert a.shape == b.shape and np.abs(a - b).max() <= 1, f"{out.name}/{file}"


@pytest.fixture(autouse=True)
def validated(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("VKPBR_VALIDATION", "1")  # the actor's renderers, as in the Ray tests
    monkeypatch.setenv("VKPBR_CACHE_DIR", str(tmp_path / "cache"))


def test_in_process_job_equals_single_process(tmp_path: Path, scenes: dict, reference: dict) -> None:
    order: list[tuple[int, tuple[int, ...]]] = []
    result = render(job_from_doc(job_doc(tmp_path, scenes), base=tmp_path), IN_PROCESS,
                    on_result=lambda item, res: order.append((item.entry, item.frames)))
    assert order == sorted(order)  # the job's order
    assert result.rendered == 4 * len(POSES) and result.failed_views == len(POSES)
    assert {f.entry for f in result.failures} == {3}
    assert all("\n" not in f.error and "broken.gltf" in f.error for f in result.failures)
    check_against(reference, tmp_path)
    assert list((tmp_path / "cache").glob("pipelines-*.bin"))  # the renderer kept its pipelines


def gone(pid: int) -> bool:
    """Whether process `pid` has ended (and been waited for: no zombie left)."""
    return not Path(f"/proc/{pid}").exists()


def test_processes_job_equals_single_process(tmp_path: Path, scenes: dict, reference: dict,
                                             capsys: pytest.CaptureFixture) -> None:
    """`--processes 2`: two renderer processes share the items (an entry's items may go to
    both); the same files as one process, the broken scene's items failed with one line each
    and not retried, every worker ended when the job returns."""
    (tmp_path / "job.json").write_text(json.dumps(job_doc(tmp_path, scenes)))
    pids: set[int] = set()
    result = render(tmp_path / "job.json", PROCESSES, actors=2,
                    on_result=lambda item, res: pids.add(res["pid"]))
    assert result.actors == 2 and result.actor_kind == "process" and not result.retries
    assert result.rendered == 4 * len(POSES) and result.failed_views == len(POSES)
    assert {f.entry for f in result.failures} == {3}
    assert all("\n" not in f.error and f.error.count("broken.gltf") == 1
               for f in result.failures)
    check_against(reference, tmp_path)
    assert len(pids) == 2 and os.getpid() not in pids and all(gone(p) for p in pids)
    capsys.readouterr()
    assert main(["batch", str(tmp_path / "job.json"), "--processes", "2"]) == 1  # (broken)
    out = capsys.readouterr()
    assert f"{len(POSES)} failed" in out.err and "on 2 processes" in out.err


def test_a_process_changes_scene_while_the_files_encode(tmp_path: Path, scenes: dict,
                                                        reference: dict) -> None:
    """A renderer process has its next item by the time this one's views are rendered (two
    in flight), and changes to its scene then, as the in-process driver's actor does; the
    first scene is the only one loaded when needed."""
    results: list[dict] = []
    result = render(job_from_doc(job_doc(tmp_path, scenes), base=tmp_path), PROCESSES,
                    actors=1, on_result=lambda item, res: results.append(res))
    assert result.rendered == 4 * len(POSES) and not result.retries
    # (the last result's: the broken scene's items, whose load counts too, may come last)
    loads = [r for r in results if "loads" in r][-1]["loads"]
    # The driver hands the last entry's chart items out with the first's (the scene the
    # process has), so: the chart now, the two models and the broken one ahead. 2 changes
    # could be early (to the models); whether the next request had come by then is up to
    # the machine's scheduling, so at least one.
    assert loads["now"] == 1 and loads["ahead"] == 3 and 1 <= loads["early"] <= 2, loads
    check_against(reference, tmp_path)


def test_processes_open_the_devices_named_in_turn(tmp_path: Path, scenes: dict,
                                                 reference: dict) -> None:
    """`devices`: process k opens the k-th device named (modulo their count), by index or
    name part as `--device` takes them; a name no device has fails that process's items in
    one line naming it, while the other process renders."""
    from vkpbr.gpu.device import Device

    with Device() as device:
        name = device.info.name
    job = job_from_doc(job_doc(tmp_path, scenes), base=tmp_path)
    results: list[dict] = []
    result = render(job, PROCESSES, actors=2, devices=["0", name.split()[0]],
                    on_result=lambda item, res: results.append(res))
    assert result.rendered == 4 * len(POSES) and {f.entry for f in result.failures} == {3}
    assert {r["device"] for r in results if r["ok"]} == {name}
    assert len({r["pid"] for r in results}) == 2
    check_against(reference, tmp_path)

    bad = tmp_path / "bad"
    bad.mkdir()
    result = render(job_from_doc(job_doc(bad, scenes), base=bad), PROCESSES, actors=2,
                    devices=[0, "no-such-gpu"])
    failed = [f.error for f in result.failures if f.entry != 3]
    assert failed and all("no-such-gpu" in e and "\n" not in e for e in failed)
    with pytest.raises(UsageError, match="devices: for renderer processes"):
        render(job, IN_PROCESS, devices=[0])


def test_a_killed_process_is_replaced(tmp_path: Path, scenes: dict, reference: dict) -> None:
    """A renderer process killed between items (as by the kernel's out-of-memory killer): its
    next item fails with "its renderer process ended", a new process takes its place and
    renders that item again; the files are the same."""
    import signal

    killed: list[int] = []

    def kill_first(item, res) -> None:  # noqa: ANN001
        if not killed and res.get("ok"):
            killed.append(res["pid"])
            os.kill(res["pid"], signal.SIGKILL)

    result = render(job_from_doc(job_doc(tmp_path, scenes), base=tmp_path), PROCESSES,
                    actors=1, on_result=kill_first)
    assert result.actors_lost == 1 and 1 <= result.retries <= 2  # (its items in flight)
    assert result.rendered == 4 * len(POSES) and {f.entry for f in result.failures} == {3}
    check_against(reference, tmp_path)
    assert gone(killed[0])


def test_ctrl_c_stops_a_processes_job_in_one_line(tmp_path: Path) -> None:
    """Ctrl-C (SIGINT to the terminal's process group: the driver and its workers) during a
    `--processes` job: exit 130 with one line, no traceback from any process, no worker
    left running, and a re-run renders only what is missing."""
    import signal
    import subprocess
    import sys
    import time

    poses = [f"{3 - k * 0.02:.2f},1.2,2,0,0,0" for k in range(100)]  # (long enough on a GPU)
    (tmp_path / "poses.json").write_text(json.dumps(poses))
    job = tmp_path / "job.json"
    job.write_text(json.dumps({"views_per_item": 2, "scenes": [
        {"cameras": "poses.json", "out": f"o{k}", "size": "32x24"} for k in range(3)]}))
    marker = str(tmp_path / "cache")  # (finds this test's workers in /proc)
    env = {**os.environ, "VKPBR_CACHE_DIR": marker}
    # (SIGINT's default disposition, as a terminal's job has it: a test run started in the
    # background of a script inherits it ignored, and the job would then run to its end)
    proc = subprocess.Popen([sys.executable, "-m", "vkpbr", "batch", str(job), "--processes",
                             "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 120
    while not list(tmp_path.glob("o*/frame_*.png")) and time.monotonic() < deadline \
            and proc.poll() is None:
        time.sleep(0.05)
    workers = [int(p.parent.name) for p in _ours(marker) if int(p.parent.name) != proc.pid]
    assert workers
    for pid in workers:  # (the first of a terminal's signals to reach them)
        os.kill(pid, signal.SIGINT)
    time.sleep(0.3)  # a worker that stopped on it would have printed its traceback by now
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and err.strip() and \
        all(line.startswith("vkpbr") for line in err.strip().splitlines()), err
    assert not _ours(marker)
    assert main(["-q", "batch", str(job), "--processes", "2"]) == 0
    for k in range(3):
        assert len(list((tmp_path / f"o{k}").glob("frame_*.png"))) == len(poses)


def _ours(marker: str) -> list[Path]:
    """/proc/PID/environ of the processes whose environment holds `marker`."""
    return [p for p in Path("/proc").glob("[0-9]*/environ") if marker.encode() in _read_or_empty(p)]


def _read_or_empty(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError:  # (a process that ended meanwhile, or not ours)
        return b""


def test_no_more_processes_than_items(tmp_path: Path) -> None:
    """`--processes 50` for a job of 2 items starts 2 processes, not 50."""
    (tmp_path / "poses.json").write_text(json.dumps(POSES))
    doc = {"views_per_item": 2, "scenes": [{"cameras": "poses.json", "out": "o", "size": SIZE}]}
    pids: set[int] = set()
    result = render(job_from_doc(doc, base=tmp_path), PROCESSES, actors=50,
                    on_result=lambda item, res: pids.add(res["pid"]))
    assert result.ok and result.actors == 2 and result.rendered == len(POSES)
    assert len(pids) <= 2


def test_calls_to_an_ended_process_fail_at_once() -> None:
    """Once a renderer process has ended and its answers' reader finished, a call to it fails
    with ActorLost (saying how it ended) instead of waiting for an answer that cannot come."""
    from vkpbr.distributed.processes import ActorLost, ProcessActor

    actor = ProcessActor(encoders=2)
    actor.kill()  # (joins its reader)
    with pytest.raises(ActorLost, match="its renderer process ended \\(killed by SIGKILL\\)"):
        actor.render(None, None).result(timeout=30)  # type: ignore[arg-type]
    actor.close()


@pytest.mark.parametrize(("argv", "problem"), [
    (["--processes", "0"], "--processes: expected a whole number of at least 1, got '0'"),
    (["--processes", "two"], "--processes: expected a whole number of at least 1, got 'two'"),
    (["--processes", "--in-process"], "--in-process and --processes: choose one"),
    (["--processes", "--ray", "head:6379"], "--ray and --processes: choose one"),
    (["--processes", "2", "--num-gpus", "0.5"], "num_cpus and num_gpus are Ray's resources"),
    (["--in-process", "--devices", "0"], "--devices goes with --processes"),
    (["--processes", "--devices", "0,,1"], "--devices: expected device indices or names"),
])
def test_processes_bad_arguments(tmp_path: Path, capsys: pytest.CaptureFixture,
                                 argv: list[str], problem: str) -> None:
    (tmp_path / "poses.json").write_text(json.dumps(POSES))
    (tmp_path / "job.json").write_text(json.dumps([{"cameras": "poses.json", "out": "o"}]))
    with contextlib.suppress(SystemExit):
        assert main(["batch", str(tmp_path / "job.json"), *argv]) != 0
    err = capsys.readouterr().err.strip()
    assert problem in err and "\n" not in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_next_scene_loads_ahead(tmp_path: Path, scenes: dict, reference: dict) -> None:
    job = job_from_doc(job_doc(tmp_path, scenes), base=tmp_path)
    items = job.items()
    actor = RendererActor()
    seen = []
    try:
        for n, item in enumerate(items):
            key = item.settings.scene_key()
            ahead = next((i.settings for i in items[n + 1:] if i.settings.scene_key() != key), None)
            (tmp_path / job.scenes[item.entry].settings.out.name).mkdir(exist_ok=True)
            res = actor.render(item, ahead)
            assert res["ok"] == (item.entry != 3), res
            if item.entry == 1 and actor._renderer is not None:
                seen.append(all(img.pixels is not None for img in actor._renderer.scene.images))
    finally:
        actor.close()
    # The first scene loads when needed; the four changes after it came from the thread (the
    # broken one's error too), the models' textures decoded there.
    assert actor.loads == {"now": 1, "ahead": 4, "early": 0}
    assert seen and all(seen)
    check_against(reference, tmp_path)


def test_scene_changes_while_the_files_encode(tmp_path: Path, scenes: dict,
                                             reference: dict) -> None:
    """`switch` (the in-process driver's: the next item is of the scene loaded ahead): the
    renderer changes scene inside the item's call, once its views are rendered, and the next
    item starts on it; a next scene that does not load leaves this item whole and fails its
    own item with one line."""
    job = job_from_doc(job_doc(tmp_path, scenes), base=tmp_path)
    items = job.items()
    actor = RendererActor()
    try:
        for n, item in enumerate(items):
            key = item.settings.scene_key()
            ahead = next((i.settings for i in items[n + 1:] if i.settings.scene_key() != key), None)
            switch = n + 1 < len(items) and items[n + 1].settings is ahead
            after = items[n + 1].settings.scene_key() if switch else None
            later = next((i.settings for i in items[n + 2:] if i.settings.scene_key() != after),
                         None) if switch else None
            (tmp_path / job.scenes[item.entry].settings.out.name).mkdir(exist_ok=True)
            res = actor.render(item, ahead, switch, later)
            assert res["ok"] == (item.entry != 3), res
            if item.entry == 3:
                assert "broken.gltf" in res["error"] and "\n" not in res["error"]
            if switch and job.scenes[items[n + 1].entry].settings.scene is not None \
                    and items[n + 1].entry != 3:
                assert actor._key == ahead.scene_key()  # changed before this call returned
                assert res["ok"] and all((tmp_path / job.scenes[item.entry].settings.out.name / f)
                                         .is_file() for f in res["files"])
    finally:
        actor.close()
    assert actor.loads == {"now": 1, "ahead": 4, "early": 2}  # (not to the broken one)
    check_against(reference, tmp_path)


def test_stopped_job_resumes(tmp_path: Path, scenes: dict, reference: dict,
                            capsys: pytest.CaptureFixture) -> None:
    doc = job_doc(tmp_path, scenes)

    class Stop(Exception):
        pass

    def stop_after_three(item, res) -> None:  # noqa: ANN001
        stop_after_three.n = getattr(stop_after_three, "n", 0) + 1
        if stop_after_three.n == 3:
            raise Stop  # as a killed run: after its third item is written, before recording

    with pytest.raises(Stop):
        render(job_from_doc(doc, base=tmp_path), IN_PROCESS, on_result=stop_after_three)
    (tmp_path / "job.json").write_text(json.dumps(doc))  # the rest through the command
    assert main(["batch", str(tmp_path / "job.json"), "--in-process"]) == 1  # (the broken one)
    out = capsys.readouterr()
    # items 1 and 2 were recorded: the chart's 2 + 1 views; the broken scene's 3 fail
    assert f"{5 * len(POSES)} views: {3 * len(POSES)} rendered, {len(POSES)} done before, " \
           f"{len(POSES)} failed" in out.out + out.err
    check_against(reference, tmp_path)
    for out in tmp_path.glob("[0-9]-*"):
        if "broken" not in out.name:
            done = [json.loads(line) for line in (out / MANIFEST_NAME).read_text().splitlines()]
            views = sorted(v for r in done if r["type"] == "done" for v in r["views"])
            assert views == list(range(len(POSES)))  # each view recorded once


def test_hand_outs_keep_scenes_together_and_hint_the_next(tmp_path: Path) -> None:
    """The driver's choices, without a cluster: an actor gets items of the scene it has (then
    of the one it loads ahead), and is told the first scene no actor has or loads."""
    import collections

    from vkpbr.distributed.driver import _next_scene, _pick, _scenes_after, _Task

    for name in "abc":
        (tmp_path / f"{name}.glb").write_bytes(b"")  # only their existence is checked here
    (tmp_path / "poses.json").write_text(json.dumps(POSES))
    doc = {"views_per_item": 1, "scenes": [
        {"scene": f"{name}.glb", "cameras": "poses.json", "out": f"{k}-{name}"}
        for k, name in enumerate("abca")]}
    items = job_from_doc(doc, base=tmp_path).items()
    key = {name: next(i.settings.scene_key() for i in items if i.settings.scene.stem == name)
           for name in "abc"}
    after = _scenes_after(items)
    assert [a.scene.stem if a else None for a in after] == ["b"] * 3 + ["c"] * 3 + ["a"] * 3 + [None] * 3
    pending = collections.deque(_Task(i) for i in items)
    scenes, ahead = {0: key["b"]}, {1: key["c"]}
    assert pending[_pick(pending, 0, (key["b"], None))].key == key["b"]  # its scene's first
    assert _pick(pending, 2, (None, None)) == 0  # a new actor: the first
    pending[0].avoid.add(2)
    assert _pick(pending, 2, (None, None)) == 1  # not one it failed
    hint = _next_scene(pending, 2, scenes, ahead)  # a is nobody's: the first waiting
    assert hint.scene.stem == "a" and ahead[2] == key["a"]
    scenes[2] = key["a"]
    assert _next_scene(pending, 3, scenes, ahead) is None and 3 not in ahead  # all taken


def test_an_item_switches_threads_quickly_and_puts_the_interval_back() -> None:
    """RendererActor.render runs under quick_switches (the GIL handed over every 1 ms, not
    5: its thread's Vulkan calls and the loading thread's reads wait less for it); the
    process's interval is as it was afterwards, after an error too."""
    import sys

    from vkpbr.distributed.actor import SWITCH_INTERVAL, quick_switches

    before = sys.getswitchinterval()
    with quick_switches():
        assert sys.getswitchinterval() == min(before, SWITCH_INTERVAL) <= 0.001
    assert sys.getswitchinterval() == before
    with pytest.raises(KeyError), quick_switches():
        raise KeyError("x")
    assert sys.getswitchinterval() == before
