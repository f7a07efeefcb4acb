"""`--pipeline auto` on GPUs: the frame path measured fastest on the device, recorded once
per device (render/path_choice.py). The measuring and the record run here on lavapipe
through `resolve` (auto itself never measures on a CPU: checked too)."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.render import path_choice as pc
from vkpbr.render.renderer import Renderer, RenderOptions

SIZE = (48, 36)


@pytest.fixture(autouse=True)
def _auto(monkeypatch: pytest.MonkeyPatch) -> None:
    """auto as a user gets it (tests/conftest.py gives the other tests the rule)."""
    monkeypatch.setenv("VKPBR_FRAME_PATHS", "auto")


def _unmeasured(r: Renderer) -> str:
    """`vkpbr info`'s autoFramePath line for `r`'s device with nothing recorded."""
    return "autoFramePath                " + ("forward (CPUs are not measured)" if r.device.info.kind == "cpu"
                                             else "not measured yet (the rule until a renderer has drawn 10 s)")


@pytest.fixture(autouse=True)
def few_frames(monkeypatch: pytest.MonkeyPatch) -> None:
    """What is tested is the choosing and the record, not the timing: few frames a round
    (lavapipe takes milliseconds a frame), two rounds still."""
    monkeypatch.setattr(pc, "WARM_UP", 2)
    monkeypatch.setattr(pc, "TIMED", 3)


@pytest.fixture(scope="module")
def chart():
    with Renderer(validation=True) as r:
        yield r
        assert r.device.instance.errors == []


def test_every_candidate_is_timed_and_the_fastest_chosen(chart) -> None:  # noqa: ANN001
    record = pc.measure(chart, SIZE)
    labels = ["forward", "compute/hardware"] + (["compute/compute"] if chart.device.compute_raster else [])
    assert list(record["gpu_ms"]) == labels
    times = record["gpu_ms"]
    assert all(np.isfinite(v) and v > 0 for v in times.values()), times
    assert record["choice"] == min(times, key=times.get)
    assert record["size"] == list(SIZE) and record["frames"] == pc.TIMED


def test_the_choice_is_recorded_once_per_device(chart, tmp_path: Path) -> None:  # noqa: ANN001
    first = pc.resolve(chart, SIZE, tmp_path)
    path = tmp_path / pc.CACHE_FILE
    records = json.loads(path.read_text())
    key = pc.device_key(chart)
    assert list(records) == [key] and records[key]["choice"] == first.label and first.measured
    # Read back, not measured again: a choice put in the file by hand is what comes back.
    other = "forward" if first.label != "forward" else "compute/hardware"
    records[key]["choice"] = other
    path.write_text(json.dumps(records))
    again = pc.resolve(chart, SIZE, tmp_path)
    assert again.label == other
    assert json.loads(path.read_text())[key]["choice"] == other  # untouched


def test_a_broken_cache_file_is_measured_again(chart, tmp_path: Path,  # noqa: ANN001
                                               caplog: pytest.LogCaptureFixture) -> None:
    path = tmp_path / pc.CACHE_FILE
    key = pc.device_key(chart)
    for junk in ("{not json", "[1, 2]", json.dumps({key: {"choice": "warp"}}),
                 json.dumps({key: {"choice": "forward", "gpu_ms": [1], "size": [4, 4]}}),
                 json.dumps({key: {"choice": "forward", "gpu_ms": {"forward": 1.0}, "size": "4x4"}})):
        path.write_text(junk)
        with caplog.at_level(logging.WARNING):
            got = pc.resolve(chart, SIZE, tmp_path)
        assert got.measured
        assert json.loads(path.read_text())[pc.device_key(chart)]["choice"] == got.label
    assert "ignored (the next auto frame measures again)" in caplog.text  # the unreadable one said so


def test_a_read_only_cache_is_no_error(chart, tmp_path: Path) -> None:  # noqa: ANN001
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        assert pc.resolve(chart, SIZE, ro).measured
    finally:
        ro.chmod(0o700)


def test_auto_on_a_cpu_takes_the_compute_path_without_measuring(tmp_path: Path) -> None:
    """CPUs take RULE_CPU, the compute path with the raster units (lavapipe measured it 1.6-2x
    the forward path: docs/compute-path.md), without measuring: the frame is that path's."""
    with Renderer(validation=True, cache_dir=tmp_path) as r:
        if r.device.info.kind != "cpu":  # the GPU pass: auto measures there (tests above)
            pytest.skip(f"{r.device.info.name} is not a CPU")
        auto = r.render(size=SIZE)
        assert not (tmp_path / pc.CACHE_FILE).exists()
        target = r.new_offscreen_target(SIZE, linear=False)
        try:
            assert r.uses_compute(target, RenderOptions())
            assert not r.paths.uses_compute_raster(RenderOptions(), target)
        finally:
            r.drop_target(target)
        assert np.array_equal(auto, r.render(size=SIZE, pipeline="compute", raster="hardware"))
        assert r.device.instance.errors == []


def test_auto_takes_what_was_measured(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """VKPBR_FRAME_PATHS=measure on lavapipe: the first auto frame measures and records,
    frames then take the recorded path (one put in the file by hand in a new renderer), and
    they are the pixels of that path asked for by name; =rule never measures; a bad value
    is one line."""
    monkeypatch.setenv("VKPBR_FRAME_PATHS", "measure")
    with Renderer(validation=True, cache_dir=tmp_path) as r:
        r.render(size=SIZE)
        path = tmp_path / pc.CACHE_FILE
        records = json.loads(path.read_text())
        key = pc.device_key(r)
        measured = records[key]["choice"]
    for label, pipeline, raster in (("compute/hardware", "compute", "hardware"),
                                    ("forward", "forward", "hardware")):
        records[key]["choice"] = label
        path.write_text(json.dumps(records))
        with Renderer(validation=True, cache_dir=tmp_path) as r:
            auto = r.render(size=SIZE)
            assert json.loads(path.read_text())[key]["choice"] == label  # read, not measured
            target = r.new_offscreen_target(SIZE, linear=False)
            try:
                assert r.uses_compute(target, RenderOptions()) == (pipeline == "compute")
            finally:
                r.drop_target(target)
            np.testing.assert_array_equal(auto, r.render(size=SIZE, pipeline=pipeline, raster=raster))
            assert r.device.instance.errors == []
    assert measured in ("forward", "compute/hardware", "compute/compute")
    monkeypatch.setenv("VKPBR_FRAME_PATHS", "rule")
    with Renderer(validation=True, cache_dir=tmp_path / "rule") as r:
        r.render(size=SIZE)
        assert not (tmp_path / "rule" / pc.CACHE_FILE).exists()
    monkeypatch.setenv("VKPBR_FRAME_PATHS", "sometimes")
    with pytest.raises(UsageError, match="VKPBR_FRAME_PATHS='sometimes': use one of auto, measure, rule"):
        pc.frame_paths_mode()


def test_info_shows_the_recorded_choice(chart, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,  # noqa: ANN001
                                        capsys: pytest.CaptureFixture[str]) -> None:
    from vkpbr.app.cli import main

    monkeypatch.setenv("VKPBR_CACHE_DIR", str(tmp_path))
    assert main(["info"]) == 0
    assert _unmeasured(chart) in capsys.readouterr().out
    choice = pc.resolve(chart, SIZE, tmp_path)
    assert main(["info", "--json"]) == 0
    [device] = [d for d in json.loads(capsys.readouterr().out)["devices"]
                if d["name"] == chart.device.info.name]
    assert device["frame_paths"]["choice"] == choice.label
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    assert f"autoFramePath                {choice.label} (" in out and " ms at 48x36)" in out


def test_info_ignores_a_hand_edited_record(chart, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,  # noqa: ANN001
                                           capsys: pytest.CaptureFixture[str]) -> None:
    from vkpbr.app.cli import main

    monkeypatch.setenv("VKPBR_CACHE_DIR", str(tmp_path))
    (tmp_path / pc.CACHE_FILE).write_text(json.dumps(
        {pc.device_key(chart): {"choice": "compute/compute", "gpu_ms": "fast", "size": [1, 1]}}))
    assert main(["info"]) == 0
    assert _unmeasured(chart) in capsys.readouterr().out


def test_when_auto_measures() -> None:
    """The policy (path_choice.when): a GPU with nothing recorded reads the record once, then
    waits on the rule, and measures at the first auto frame MEASURE_AFTER_S after its first;
    =measure measures at once (CPUs too); =rule and CPUs under auto never measure."""
    after = pc.MEASURE_AFTER_S
    assert [pc.when("auto", False, w) for w in (None, 0.0, after - 0.1, after)] == [
        "read", "wait", "wait", "measure"]
    assert [pc.when("measure", cpu, None) for cpu in (False, True)] == ["measure", "measure"]
    assert {pc.when(m, cpu, w) for m, cpu in (("rule", False), ("rule", True), ("auto", True))
            for w in (None, after)} == {"rule"}


def test_a_gpu_measures_only_after_rendering_a_while(chart, tmp_path: Path,  # noqa: ANN001
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """On a GPU (the H200's test pass): the first auto frames take the rule and record
    nothing; the first auto frame MEASURE_AFTER_S later measures and records."""
    if chart.device.info.kind == "cpu":  # auto never measures on a CPU (tested above)
        pytest.skip(f"{chart.device.info.name} is a CPU: auto does not measure there")
    with Renderer(validation=True, cache_dir=tmp_path) as r:
        target = r.new_offscreen_target(SIZE, linear=False)
        try:
            r.render(size=SIZE)
            r.render(size=SIZE)
            assert not (tmp_path / pc.CACHE_FILE).exists() and not r.paths.choice.measured
            assert r.uses_compute(target, RenderOptions()) == (r.compute_unavailable(target) is None)
            monkeypatch.setattr(pc, "MEASURE_AFTER_S", 0.0)
            r.render(size=SIZE)
            records = json.loads((tmp_path / pc.CACHE_FILE).read_text())
            assert records[pc.device_key(r)]["choice"] == r.paths.choice.label and r.paths.choice.measured
        finally:
            r.drop_target(target)
        assert r.device.instance.errors == []
