"""`vkpbr` under SIGTERM (issue 11, class 6): handled like Ctrl-C, one line, exit 143, the
previous output untouched and no temporary file left."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"


def test_sigterm_during_a_render_exits_143(tmp_path: Path) -> None:
    out = tmp_path / "render.png"
    out.write_bytes(b"old")
    env = {**os.environ, "PYTHONPATH": f"{SRC}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    # 10^6 frames never finish: the signal lands in the frame loop.
    proc = subprocess.Popen(
        [sys.executable, "-m", "vkpbr", "-v", "render", "--size", "16x16", "--frames",
         "1000000", "--out", str(out)],
        env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    first = proc.stderr.readline()  # "vkpbr: info: scene: ...": the handler is installed
    assert first.startswith("vkpbr: info:"), first
    time.sleep(1.5)  # into the frames
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert err.strip().splitlines()[-1] == "vkpbr: terminated"
    assert "Traceback" not in err
    assert out.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["render.png"]


def test_main_maps_terminated_to_143(monkeypatch, capsys) -> None:  # noqa: ANN001
    """In-process: a SIGTERM while the command runs ends main() with 143, and the handler
    installed for the command is removed afterwards."""
    from vkpbr.app import cli, info_cmd

    def run(args):  # noqa: ANN001, ANN202
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises before this ends
        return 0

    before = signal.getsignal(signal.SIGTERM)
    monkeypatch.setattr(info_cmd, "run", run)
    assert cli.main(["info"]) == 143
    assert capsys.readouterr().err.strip() == "vkpbr: terminated"
    assert signal.getsignal(signal.SIGTERM) == before
