"""examples/ and the README's Python example run as written (public API only), at a small
size, each in its own process."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"


def _run(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    # VKPBR_VALIDATION=1: every Renderer the script makes runs under the validation layer,
    # and an error raises (a non-zero exit fails the test).
    env = dict(os.environ, VKPBR_VALIDATION="1", PYTHONPATH=os.pathsep.join(
        p for p in (str(REPO / "src"), os.environ.get("PYTHONPATH", "")) if p))
    proc = subprocess.run([sys.executable, *argv], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc


def _varied(image: np.ndarray) -> bool:
    """Not one colour: more than a handful of distinct pixel values."""
    flat = image.reshape(-1, image.shape[-1]) if image.ndim == 3 else image.reshape(-1, 1)
    return len(np.unique(flat, axis=0)) > 8


@pytest.mark.parametrize("name, shape", [
    ("render_default", (48, 64, 4)), ("render_views", (48, 4 * 64, 4)),
    ("render_turntable", (2 * 48, 4 * 64, 4)), ("render_glass", (48, 64, 4)),
    ("batch_outputs", (4 * 48, 4 * 64, 4)),
])
def test_image_examples(tmp_path: Path, name: str, shape: tuple[int, ...]) -> None:
    out = tmp_path / f"{name}.png"
    proc = _run([str(EXAMPLES / f"{name}.py"), "--size", "64x48", "--out", str(out)], tmp_path)
    image = np.asarray(Image.open(out))
    assert image.shape == shape and _varied(image) and "wrote" in proc.stdout


def test_turntable_of_a_gltf(tmp_path: Path, assets: Path) -> None:
    """The eight frames differ: the camera really goes round the model."""
    src = assets / "OrientationTest" / "glTF" / "OrientationTest.gltf"
    out = tmp_path / "tt.png"
    _run([str(EXAMPLES / "render_turntable.py"), str(src), "--size", "48x36", "--out", str(out)], tmp_path)
    sheet = np.asarray(Image.open(out))
    frames = [sheet[r * 36:(r + 1) * 36, c * 48:(c + 1) * 48] for r in range(2) for c in range(4)]
    assert all(_varied(f) for f in frames)
    assert len({f.tobytes() for f in frames}) == 8


def test_depth_example(tmp_path: Path) -> None:
    _run([str(EXAMPLES / "depth_to_npy.py"), "--size", "64x48", "--out", str(tmp_path / "r")], tmp_path)
    color, depth = np.load(tmp_path / "r_color.npy"), np.load(tmp_path / "r_depth.npy")
    assert color.shape == (48, 64, 4) and color.dtype == np.float32 and _varied(color)
    hit = np.isfinite(depth)
    assert depth.shape == (48, 64) and 0.05 < hit.mean() < 1 and np.ptp(depth[hit]) > 0


def readme_python(readme: str, scene: Path, size: tuple[int, int], index: int = 0) -> str:
    """The README's ```python block `index` with only the scene path and the image size
    replaced (```py blocks are shown, not run: the PyTorch one needs CUDA)."""
    blocks = re.findall(r"^```python\n(.*?)^```", readme, flags=re.S | re.M)
    assert len(blocks) == 2, f"expected two ```python blocks in README.md, found {len(blocks)}"
    code, n_scene = re.subn(r'"[^"\n]*\.(?:gltf|glb|obj|vkpbr)"', repr(str(scene)), blocks[index])
    code, n_size = re.subn(r"size=\(\d+, \d+\)", f"size={size}", code)
    assert n_scene >= 1 and n_size >= 1, "the README example names no scene file or size"
    return code


def test_readme_python_example_runs_as_written(tmp_path: Path, assets: Path) -> None:
    scene = assets / "TextureCoordinateTest" / "glTF" / "TextureCoordinateTest.gltf"
    code = readme_python((REPO / "README.md").read_text(), scene, (64, 48))
    script = tmp_path / "readme_example.py"
    script.write_text(code + "\nprint('README example ran', rgba.shape, rgba.dtype)\n")
    proc = _run([str(script)], tmp_path)
    assert "README example ran (48, 64, 4) uint8" in proc.stdout


def test_readme_batch_example_runs_as_written(tmp_path: Path, assets: Path) -> None:
    scene = assets / "TextureCoordinateTest" / "glTF" / "TextureCoordinateTest.gltf"
    code = readme_python((REPO / "README.md").read_text(), scene, (32, 24), index=1)
    script = tmp_path / "readme_batch.py"
    script.write_text(code + "\nprint('README batch ran', views.shape, views.dtype)\n")
    proc = _run([str(script)], tmp_path)
    assert "README batch ran (256, 24, 32, 4) uint8" in proc.stdout
