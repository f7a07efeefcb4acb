"""Every fenced ```python and ```sh block of README.md and docs/*.md runs as written (issue
35): each in its own process, in an empty folder (docs/ beside it, for the paths the docs
name), with only two kinds of change, both listed here: a scene file's name becomes the
sample model it names (SCENES), and image sizes become small ones (`size=(W, H)`,
`--size WxH`). A block is skipped only when an optional extra or a sample model it needs is
missing, and the skip says which. The README's indented command lists are synopses
(`[--peers]`, a window) and are not run here; tests/gpu/test_cli.py runs their commands."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from assets_path import ASSETS

REPO = Path(__file__).resolve().parents[2]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
# Scene names in the docs -> the sample model (under $VKPBR_ASSETS) each stands for.
SCENES = {
    "Sponza.gltf": "Sponza/glTF/Sponza.gltf",
    "DamagedHelmet.gltf": "DamagedHelmet/glTF/DamagedHelmet.gltf",
    "CesiumMilkTruck.gltf": "CesiumMilkTruck/glTF/CesiumMilkTruck.gltf",
    "CesiumMan.gltf": "CesiumMan/glTF/CesiumMan.gltf",
    "scene.gltf": "TextureCoordinateTest/glTF/TextureCoordinateTest.gltf",
}
# What a block needs besides vkpbr: (a module, the extra or install that brings it).
NEEDS = {"vkpbr.distributed": ("ray", "the ray extra (pip install 'vkpbr[ray]')"),
         "import torch": ("torch", "PyTorch with CUDA (the cuda extra and an NVIDIA GPU)")}
# A block that reads what an earlier block of its page wrote runs after it, in one process.
DEPENDS = {"docs/camera-files.md#1": ("docs/camera-files.md#0",)}


def blocks() -> list[tuple[str, str, str]]:
    """(id, language, code) of every ```python, ```py and ```sh block."""
    out = []
    for doc in DOCS:
        found = re.findall(r"^```(python|py|sh)\n(.*?)^```", doc.read_text(), flags=re.S | re.M)
        for i, (lang, code) in enumerate(found):
            out.append((f"{doc.relative_to(REPO)}#{i}", lang, code))
    return out


def _small(code: str) -> str:
    code = re.sub(r"size=\(\d+, \d+\)", "size=(32, 24)", code)
    return re.sub(r"--size \d+x\d+", "--size 32x24", code)


def _scenes(code: str) -> tuple[str, list[str]]:
    """The code with scene names replaced by their sample models; the models missing."""
    missing = []
    for name, rel in SCENES.items():
        if re.search(rf"(?<![\w/.-]){re.escape(name)}", code):
            path = ASSETS / rel
            if not path.is_file():
                missing.append(str(path))
            code = re.sub(rf"(?<![\w/.-]){re.escape(name)}", path.as_posix(), code)
    return code, missing


@pytest.mark.slow
@pytest.mark.parametrize("block, lang, code",
                         [pytest.param(bid, lang, code, id=bid) for bid, lang, code in blocks()])
def test_doc_snippet_runs_as_written(tmp_path: Path, block: str, lang: str, code: str) -> None:
    for marker, (module, what) in NEEDS.items():
        if marker in code and importlib.util.find_spec(module) is None:
            pytest.skip(f"needs {what}")
    if lang == "py":  # shown for CUDA machines: PyTorch on an NVIDIA GPU
        import torch

        if not torch.cuda.is_available():
            pytest.skip("needs PyTorch with CUDA (an NVIDIA GPU)")
    code, missing = _scenes(_small(code))
    if missing:
        pytest.skip(f"needs the sample model {missing[0]} ($VKPBR_ASSETS)")
    (tmp_path / "docs").symlink_to(REPO / "docs")
    earlier = {bid: c for bid, _, c in blocks()}
    code = "".join(_scenes(_small(earlier[b]))[0] + "\n" for b in DEPENDS.get(block, ())) + code
    env = dict(os.environ, VKPBR_VALIDATION="1", PYTHONPATH=os.pathsep.join(
        p for p in (str(REPO / "src"), os.environ.get("PYTHONPATH", "")) if p))
    bin_dir = Path(sys.executable).parent
    env["PATH"] = os.pathsep.join([str(tmp_path / "bin"), str(bin_dir), env.get("PATH", "")])
    if lang == "sh":  # `vkpbr` as this checkout's (the tests' interpreter, src/ first)
        (tmp_path / "bin").mkdir()
        shim = tmp_path / "bin" / "vkpbr"
        shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m vkpbr "$@"\n')
        shim.chmod(0o755)
        argv = ["sh", "-e", "-c", code]
    else:
        script = tmp_path / "snippet.py"
        script.write_text(code)
        argv = [sys.executable, str(script)]
    proc = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, f"{code}\n--- stderr:\n{proc.stderr[-3000:]}"
