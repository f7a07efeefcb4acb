"""A job with per-view worlds on a real local Ray cluster (issue 32, must-have 6): its frames
equal `render` of each world alone (set through set_poses(space="world") / set_visible; bit
for bit on lavapipe) and the single-process `vkpbr render --cameras --worlds` byte for byte;
a re-run renders nothing; a changed .npy re-renders only the views whose world changed."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_ray_job import assert_same_files, check_exactly_once
from test_worlds_job import NODES, world_rows

pytestmark = pytest.mark.slow  # a local Ray cluster: the end-to-end tier

ray = pytest.importorskip("ray", reason="the ray extra is not installed (pip install 'vkpbr[ray]')",
                          exc_type=ImportError)

from vkpbr.app.cli import main  # noqa: E402
from vkpbr.distributed import render  # noqa: E402
from vkpbr.scene.poses import parse_poses  # noqa: E402

SIZE = (64, 48)
POSES = ["0,1.5,6,0,1,0", "1,1.5,6,0,1,0", "-1,1.5,6,0,1,0", "0.5,2,6,0,1,0",
         "-0.5,1,6,0,1,0", "0,2.5,5.5,0,1,0"]
NO_SHADOWS = {"shadows": False, "ao": "off"}  # one batch of worlds per item


def frame(folder: Path, view: int) -> np.ndarray:
    return np.asarray(Image.open(folder / f"frame_{view:05d}.png"))


def alone(renderer, camera, rows: np.ndarray, shown: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """`render` of one world, set through the public API, then put back."""
    renderer.set_poses(NODES, rows, space="world")
    renderer.set_visible([n for n, s in zip(NODES, shown, strict=True) if not s], False)
    try:
        # (the compute batch's rasteriser: the same bytes in a batch as alone on lavapipe)
        return renderer.render(camera, size=SIZE, raster="compute", **NO_SHADOWS)
    finally:
        renderer.state.reset()


def test_ray_job_with_worlds(cluster: dict, make_renderer, capsys, tmp_path: Path) -> None:  # noqa: ANN001
    rows = world_rows(len(POSES), seed=3)
    shown = np.ones((len(POSES), 2), bool)
    shown[4, 1] = False  # view 4's world hides the second sphere
    np.save(tmp_path / "w.npy", rows)
    np.save(tmp_path / "v.npy", shown)
    np.save(tmp_path / "c.npy", np.random.default_rng(5).uniform(0, 1, (len(POSES), 1, 3)))
    worlds = {"nodes": NODES, "poses": "w.npy", "visible": "v.npy"}
    painted = {**worlds, "materials": {"names": ["floor"], "base_color": "c.npy"}}
    (tmp_path / "worlds.json").write_text(json.dumps(painted))
    (tmp_path / "poses.json").write_text(json.dumps(POSES))
    entry = {"cameras": "poses.json", "size": list(SIZE)}
    job = tmp_path / "job.json"  # the batch of worlds; world by world (shadows, materials)
    job.write_text(json.dumps({"views_per_item": 2, "scenes": [
        {**entry, "out": "batched", "options": NO_SHADOWS, "worlds": worlds},
        {**entry, "out": "shadowed", "worlds": painted}]}))
    result = render(job)
    assert result.ok and result.rendered == 2 * len(POSES) and result.actors == 2, result.summary()
    for name in ("batched", "shadowed"):
        check_exactly_once(tmp_path / name, len(POSES), 1)
    # Each view as its world alone; the shadowed entry as the single-process command.
    r = make_renderer()
    cams = [p.camera(r.default_camera()) for p in parse_poses(POSES, "poses")]
    for v in range(len(POSES)):
        assert np.array_equal(frame(tmp_path / "batched", v), alone(r, cams[v], rows[v], shown[v])), v
    single = tmp_path / "single"
    assert main(["-q", "render", "--cameras", str(tmp_path / "poses.json"), "--worlds",
                 str(tmp_path / "worlds.json"), "--out", str(single), "--size", "64x48",
                 "--validation"]) == 0
    assert_same_files(tmp_path / "shadowed", single)
    # A re-run renders nothing; the command line resumes the Ray folder as well.
    again = render(job)
    assert again.ok and again.rendered == 0 and again.skipped == 2 * len(POSES)
    capsys.readouterr()
    assert main(["render", "--cameras", str(tmp_path / "poses.json"), "--worlds",
                 str(tmp_path / "worlds.json"), "--out", str(tmp_path / "shadowed"),
                 "--size", "64x48"]) == 0
    assert f"wrote 0 images, {len(POSES)} done before" in capsys.readouterr().out
    # World 2 changes: view 2 alone renders again, in both entries.
    before = {v: frame(tmp_path / "batched", v) for v in range(len(POSES))}
    rows[2, 0, :3] += (0.4, 0.2, 0.0)
    np.save(tmp_path / "w.npy", rows)
    third = render(job)
    assert third.ok and third.rendered == 2 and third.skipped == 2 * len(POSES) - 2, third.summary()
    for v in range(len(POSES)):
        now = frame(tmp_path / "batched", v)
        assert np.array_equal(now, before[v]) == (v != 2), v
    assert np.array_equal(frame(tmp_path / "batched", 2), alone(r, cams[2], rows[2], shown[2]))
    assert (tmp_path / "batched" / "transforms.json").is_file()
