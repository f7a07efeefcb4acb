# Paths the user gives (vkpbr/user_paths.py) and the writers behind the API: a path no file
# can have, an output under /proc, under a file, in a folder that takes no file, or with a
# name too long is one line of vkpbr's own error before any work (UsageError), and a write
# that fails after the checks is an OutputError naming the file (an OSError too). No GPU.

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import OutputError, UsageError, VkpbrError
from vkpbr.user_paths import (
    NAME_MAX,
    PATH_MAX,
    check_writable_file,
    check_writable_folder,
    path_problem,
)


def one_line(exc: BaseException) -> str:
    text = str(exc)
    assert "\n" not in text and "\0" not in text and len(text) < 400, text
    return text


def test_path_problems() -> None:
    assert path_problem("/tmp/x.png") is None
    assert path_problem("/tmp/" + "n" * NAME_MAX) is None
    assert "NUL byte" in path_problem("/tmp/a\0b.png")
    assert f"more than the {NAME_MAX} the file system allows" in path_problem(
        "/tmp/" + "n" * (NAME_MAX + 1))
    assert f"more than the {PATH_MAX:,} a path may have" in path_problem("/a" * 2100)
    assert "cannot be encoded" in path_problem("/tmp/\ud800.png")
    assert path_problem("/tmp/\udcff.png") is None  # the byte 0xff, as argv decodes it


@pytest.mark.parametrize(("out", "problem"), [
    ("/proc/x.png", "cannot write in /proc"),
    ("{tmp}/afile/x.png", "afile is a file, not a folder"),
    ("{tmp}/afile/deeper/x.png", "afile is a file, not a folder"),
    ("{tmp}/missing/x.png", "folder {tmp}/missing does not exist"),
    ("{tmp}", "is a directory"),
    ("{tmp}/a\0b.png", "holds a NUL byte"),
    ("{tmp}/" + "n" * 300 + ".png", "has a name of 304 bytes"),
    ("{tmp}/" + "m" * 250 + ".png", "the name is too long to write atomically"),
    ("{tmp}/" + "d/" * 2600 + "x.png", "more than the 4,096 a path may have"),
])
def test_outputs_are_checked_before_work(tmp_path: Path, out: str, problem: str) -> None:
    (tmp_path / "afile").write_bytes(b"x")
    out = out.replace("{tmp}", str(tmp_path))
    problem = problem.replace("{tmp}", str(tmp_path))
    with pytest.raises(UsageError) as info:
        check_writable_file(out, "--out")
    text = one_line(info.value)
    assert text.startswith("--out ") and problem in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]  # the probe left nothing


def test_a_folder_to_make_is_checked_without_making_it(tmp_path: Path) -> None:
    (tmp_path / "afile").write_bytes(b"x")
    assert check_writable_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert not (tmp_path / "a").exists()  # check first, create last
    for folder, problem in ((tmp_path / "afile" / "f", "afile is a file, not a folder"),
                            (Path("/proc/frames"), "cannot write in /proc"),
                            (tmp_path / ("d" * 300), "has a name of 300 bytes")):
        with pytest.raises(UsageError, match=problem) as info:
            check_writable_folder(folder, "--out", "frame_00000.depth.exr")
        one_line(info.value)
    assert check_writable_folder(tmp_path / ("d" * 250)) == tmp_path / ("d" * 250)
    with pytest.raises(UsageError, match="its files would be too long: .* too long to write "
                                         "atomically") as info:
        check_writable_folder(tmp_path / "f", "--out", "n" * 240)
        one_line(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_a_write_that_fails_is_an_output_error(tmp_path: Path) -> None:
    """What the file system refuses at write time (no check before, or a folder gone since)
    is OutputError: vkpbr's one line naming the file, and the OSError it always was."""
    from vkpbr.io import write_image

    image = np.zeros((4, 4, 4), np.uint8)
    (tmp_path / "afile").write_bytes(b"x")
    for path, reason, code in ((tmp_path / "afile" / "x.png", "Not a directory", errno.ENOTDIR),
                               (Path("/proc/x.png"), "No such file or directory", errno.ENOENT),
                               (tmp_path / "a\0b.png", "the path holds a NUL byte", None),
                               (tmp_path / ("m" * 250 + ".png"), "File name too long",
                                errno.ENAMETOOLONG)):
        with pytest.raises(OutputError) as info:
            write_image(path, image)
        text = one_line(info.value)
        assert text.startswith(f"{str(path).replace(chr(0), chr(92) + '0')[:60]}") and reason in text
        assert isinstance(info.value, OSError) and isinstance(info.value, VkpbrError)
        assert info.value.errno == code and info.value.filename == str(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_api_writers_check_before_their_work(tmp_path: Path) -> None:
    """bake_file checks its output before loading the scene (a missing source is not even
    looked at); write_colmap its folder before writing; each one line."""
    from vkpbr.bake.bake import bake_file
    from vkpbr.scene.camera import Camera
    from vkpbr.scene.camera_files import write_colmap

    (tmp_path / "afile").write_bytes(b"x")
    with pytest.raises(UsageError, match=r"^bake_file: out /proc/x.vkpbr: cannot write in /proc"):
        bake_file(tmp_path / "missing.gltf", "/proc/x.vkpbr", progress=False)
    cams = [Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0))]
    with pytest.raises(UsageError, match="^write_colmap: folder .*afile is a file, not a folder"):
        write_colmap(tmp_path / "afile" / "sparse", cams, (8, 6))


def test_job_file_paths_are_one_line(tmp_path: Path) -> None:
    """A 5,000-character scene path and an out folder with a NUL byte in a job file: one
    UsageError naming the file and the entry, not OSError(ENAMETOOLONG) or ValueError."""
    from vkpbr.distributed import load_job

    job = tmp_path / "job.json"
    for entry, problem in (({"scene": "a/" * 2500 + "s.gltf", "cameras": [], "out": "o"},
                            "is 5,006 bytes long, more than the 4,096 a path may have"),
                           ({"cameras": ["0,0,5,0,0,0"], "out": "o\0x"},
                            "out o\\0x: holds a NUL byte"),
                           ({"cameras": "c\0.json", "out": "o"}, "holds a NUL byte"),
                           ({"cameras": ["0,0,5,0,0,0"], "out": "o" * 300},
                            "has a name of 300 bytes")):
        job.write_text(json.dumps([entry]))
        with pytest.raises(UsageError) as info:
            load_job(job)
        text = one_line(info.value)
        assert text.startswith(f"{job}: entry 0: ") and problem in text, text


def test_the_cli_says_one_line_for_hostile_outputs(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    """`vkpbr bake` with its --out under /proc, under a file, or with an over-long name:
    exit status 2, one line, before the scene is read."""
    from vkpbr.app.cli import main

    (tmp_path / "afile").write_bytes(b"x")
    for out in ("/proc/x.vkpbr", str(tmp_path / "afile" / "x.vkpbr"),
                str(tmp_path / ("n" * 300 + ".vkpbr"))):
        assert main(["bake", str(tmp_path / "missing.gltf"), "--out", out]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("vkpbr: error: --out "), err
        assert "missing.gltf" not in err


def test_messages_show_nul_bytes_escaped() -> None:
    assert str(UsageError("a\0b")) == "a\\0b"
    assert str(OutputError("/x/a\0b", "reason")) == "/x/a\\0b: cannot write: reason"
    assert os.fspath(OutputError("/x", "r").filename) == "/x"


def test_animate_checks_its_output_and_frame_count_first(tmp_path: Path,
                                                         capsys: pytest.CaptureFixture) -> None:
    """`render --animate`: an output it cannot write, a frame count that overflows (1e308 s)
    and a 5,000-digit --animation index are one line before any rendering (found by the
    command-line fuzzing)."""
    import sys

    from vkpbr.app.cli import main

    sys.path.insert(0, str(Path(__file__).parents[1]))
    from fuzz_surfaces import _animated_doc, _gltf_buffer, _png

    (tmp_path / "t.png").write_bytes(_png())
    (tmp_path / "b.bin").write_bytes(_gltf_buffer())
    scene = tmp_path / "a.gltf"
    scene.write_text(json.dumps(_animated_doc()))
    for extra, message in ((["--out", "/proc/anim"], "--out /proc/anim: cannot write in /proc"),
                           (["--out", "/proc/a.gif"], "--out /proc/a.gif: cannot write in /proc"),
                           (["--out", f"{tmp_path}/x\0y"], "holds a NUL byte"),
                           (["--out", str(tmp_path / "f"), "--duration", "1e308"],
                            "--animate would render inf frames (at most 100000)"),
                           (["--out", str(tmp_path / "f"), "--fps", "1e300", "--duration", "1"],
                            "--animate would render 1e+300 frames"),
                           (["--out", str(tmp_path / "f"), "--animation", "9" * 5000],
                            "no animation has that index (the file has 1)")):
        assert main(["render", str(scene), "--animate", *extra]) == 2, extra
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gltf", "b.bin", "t.png"]
