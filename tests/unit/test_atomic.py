"""Atomic writes after signals (issue 11, class 6): SIGTERM cleans up, SIGKILL's leftovers
are removed by the next write to the same path, and nothing else is touched."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from vkpbr.atomic import STALE_SECONDS, atomic_writer, remove_stale_temporaries

SRC = Path(__file__).resolve().parents[2] / "src"

# Writes "new" into argv[1] and sleeps inside the with-block until a signal arrives.
SLOW_WRITER = textwrap.dedent("""
    import sys, time
    from vkpbr.app.cli import Terminated, sigterm_raises
    from vkpbr.atomic import atomic_writer
    with sigterm_raises():
        try:
            with atomic_writer(sys.argv[1]) as f:
                f.write(b"new" * 1000)
                f.flush()
                print("writing", flush=True)
                time.sleep(60)
        except Terminated:
            sys.exit(143)
""")


def temporaries(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.name.endswith(".tmp"))


def start_slow_write(target: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": f"{SRC}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    proc = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)], env=env,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "writing"  # inside the with-block now
    return proc


def test_sigterm_removes_the_temporary_and_keeps_the_old_file(tmp_path: Path) -> None:
    target = tmp_path / "out.png"
    target.write_bytes(b"old")
    proc = start_slow_write(target)
    assert len(temporaries(tmp_path)) == 1
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=30) == 143
    assert temporaries(tmp_path) == []
    assert target.read_bytes() == b"old"


def test_sigkill_leftover_is_removed_by_the_next_write(tmp_path: Path) -> None:
    target = tmp_path / "out.png"
    target.write_bytes(b"old")
    proc = start_slow_write(target)
    proc.kill()
    assert proc.wait(timeout=30) == -signal.SIGKILL
    (left,) = temporaries(tmp_path)
    assert left.name.startswith(f".out.png.{proc.pid}.")  # the writer's PID is in the name
    assert target.read_bytes() == b"old"
    with atomic_writer(target) as f:
        f.write(b"next")
    assert temporaries(tmp_path) == []
    assert target.read_bytes() == b"next"


def test_only_leftovers_of_this_target_are_removed(tmp_path: Path) -> None:
    target = tmp_path / "a.png"
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        dead = subprocess.Popen([sys.executable, "-c", "pass"])
        dead.wait()
        now = time.time()
        old = now - STALE_SECONDS - 60
        files = {
            "dead": f".a.png.{dead.pid}.abcd1234.tmp",           # its writer is gone
            "live": f".a.png.{sleeper.pid}.abcd1234.tmp",        # a writer still at work
            "live_idle": f".a.png.{sleeper.pid}.idle_123.tmp",   # alive, idle too long
            "mine": f".a.png.{os.getpid()}.abcd1234.tmp",       # this process's own
            "legacy_old": ".a.png.k2j4h5g6.tmp",                 # no PID, idle too long
            "legacy_new": ".a.png.q1w2e3r4.tmp",                 # no PID, recent
            "other_target": f".a.png.1.{dead.pid}.abcd1234.tmp",  # a file "a.png.1"'s
            "not_temp": f".a.png.{dead.pid}.abcd1234.txt",
        }
        for key, name in files.items():
            (tmp_path / name).write_bytes(b"x")
            if key in ("live_idle", "legacy_old"):
                os.utime(tmp_path / name, (old, old))
        os.mkdir(tmp_path / f".a.png.{dead.pid}.dir_5678.tmp")  # not a regular file
        removed = remove_stale_temporaries(target)
        assert sorted(p.name for p in removed) == sorted(
            files[k] for k in ("dead", "live_idle", "legacy_old"))
        left = {p.name for p in tmp_path.iterdir()}
        assert left == {files[k] for k in ("live", "mine", "legacy_new", "other_target",
                                           "not_temp")} | {f".a.png.{dead.pid}.dir_5678.tmp"}
    finally:
        sleeper.kill()
        sleeper.wait()


def test_temporary_name_carries_the_pid(tmp_path: Path) -> None:
    target = tmp_path / "x.npy"
    with atomic_writer(target) as f:
        (tmp,) = temporaries(tmp_path)
        assert tmp.name.startswith(f".x.npy.{os.getpid()}.") and tmp.name.endswith(".tmp")
        f.write(b"1")
    assert temporaries(tmp_path) == [] and target.read_bytes() == b"1"


def test_pid_one_counts_as_alive(tmp_path: Path) -> None:
    """PID 1 always runs: os.kill(1, 0) succeeds for root and raises PermissionError for
    anyone else, and either way its file is kept."""
    name = tmp_path / ".b.png.1.abcd1234.tmp"
    name.write_bytes(b"x")
    assert remove_stale_temporaries(tmp_path / "b.png") == []
    assert name.exists()
