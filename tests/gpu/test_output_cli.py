"""`vkpbr render --linear` into EXR: the same float32 pixels as the .npy output, and refused
EXR/format combinations fail before the scene loads (one line, non-zero exit, no file)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vkpbr.app.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:  # noqa: ANN001
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_linear_exr_holds_the_npy_pixels(capsys, tmp_path: Path) -> None:  # noqa: ANN001
    OpenEXR = pytest.importorskip("OpenEXR")
    for name in ("a.npy", "a.exr"):
        code, stdout, err = run(capsys, "render", "--linear", "--size", "40x30", "--validation",
                                "--out", str(tmp_path / name))
        assert code == 0, err
    npy = np.load(tmp_path / "a.npy")
    with OpenEXR.File(str(tmp_path / "a.exr")) as f:
        (name, channel), = f.channels().items()
        exr = np.array(channel.pixels)
    assert name == "RGBA" and npy.dtype == exr.dtype == np.float32 and npy.shape == (30, 40, 4)
    np.testing.assert_array_equal(exr, npy)


@pytest.mark.parametrize("argv, message", [
    (["--out", "x.exr"], "EXR holds linear float colour: add --linear"),
    (["--linear", "--out", "x.png"], "give an --out path ending in .exr or .npy"),
    (["--out", "x.tga"], "unknown image type '.tga'"),
])
def test_refused_outputs_fail_before_loading(capsys, tmp_path: Path, monkeypatch, argv,  # noqa: ANN001
                                             message: str) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "render", "no-such-scene.gltf", *argv)
    # The scene does not exist: a format error first proves the output was checked first.
    assert code != 0 and message in err and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []
