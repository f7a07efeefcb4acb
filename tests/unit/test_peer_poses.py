"""The peers' batch scenario (benchmarks/peers/common.py): the poses every peer and vkpbr render
are the same views, read the same way (OpenGL world-from-camera), and SAPIEN's camera axes are
derived correctly from them."""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.scene.camera_batch import CameraBatch

PEERS = Path(__file__).resolve().parents[2] / "benchmarks" / "peers"


def _load(name: str):  # noqa: ANN202
    sys.path.insert(0, str(PEERS))
    try:
        spec = importlib.util.spec_from_file_location(f"peers_{name}", PEERS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(PEERS))


common = _load("common")


@pytest.mark.parametrize("key", ["sponza", "helmet"])
def test_poses_are_rigid_and_repeatable(key: str) -> None:
    a = common.batch_poses(key, 64)
    assert a.shape == (64, 4, 4) and a.dtype == np.float64
    r = a[:, :3, :3]
    np.testing.assert_allclose(r @ r.transpose(0, 2, 1), np.broadcast_to(np.eye(3), r.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-12)
    np.testing.assert_array_equal(a[:, 3], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (64, 4)))
    np.testing.assert_array_equal(a, common.batch_poses(key, 64))  # same seed, same views
    assert common.poses_digest(a) == common.poses_digest(common.batch_poses(key, 64))
    assert common.poses_digest(a) != common.poses_digest(common.batch_poses(key, 64, seed=1))
    # the views differ from each other (an orbit, not one pose repeated)
    assert len(np.unique(a[:, :3, 3].round(6), axis=0)) == 64


def test_helmet_views_look_at_the_origin_and_vkpbr_reads_them_so() -> None:
    poses = common.batch_poses("helmet", 32)
    eye = poses[:, :3, 3]
    forward = -poses[:, :3, 2]  # OpenGL: the camera looks down its -Z
    np.testing.assert_allclose(forward, -eye / np.linalg.norm(eye, axis=1, keepdims=True), atol=1e-12)
    d = np.linalg.norm(eye, axis=1)
    assert np.all((d >= 2.5) & (d <= 3.5))
    assert np.all(poses[:, 1, 1] > 0)  # +Y up: the camera's up has a positive world Y
    views = CameraBatch.from_poses(poses, common.YFOV_DEG)
    np.testing.assert_allclose(views.eye, eye)
    along = views.target - views.eye
    np.testing.assert_allclose(along / np.linalg.norm(along, axis=1, keepdims=True), forward, atol=1e-12)


def test_poses_file_is_written_once_then_read(tmp_path: Path) -> None:
    path = tmp_path / "p.npy"
    first = common.load_poses(path, "sponza", 8)
    assert path.exists()
    np.save(path, first[:3])  # whatever the file holds wins over regeneration
    np.testing.assert_array_equal(common.load_poses(path, "sponza", 8), first[:3])
    np.save(path, np.zeros((2, 3, 3)))
    with pytest.raises(SystemExit, match=r"\(B, 4, 4\)"):
        common.load_poses(path, "sponza", 8)


def test_sapien_axes_from_opengl_pose() -> None:
    sapien_bench = _load("sapien_bench")
    pose = common.batch_poses("sponza", 4)[2]
    m = pose @ sapien_bench.GL_FROM_SAPIEN
    # SAPIEN's camera: x forward, y left, z up, same eye.
    np.testing.assert_allclose(m[:3, 0], -pose[:3, 2], atol=1e-12)
    np.testing.assert_allclose(m[:3, 1], -pose[:3, 0], atol=1e-12)
    np.testing.assert_allclose(m[:3, 2], pose[:3, 1], atol=1e-12)
    np.testing.assert_allclose(m[:3, 3], pose[:3, 3])
    np.testing.assert_allclose(np.linalg.det(m[:3, :3]), 1.0, atol=1e-12)


def test_bench_reads_earlier_peer_rows(tmp_path: Path) -> None:
    from vkpbr.app import bench_cmd

    good = tmp_path / "peers.json"
    good.write_text(json.dumps({"scenario": "batch", "peer": "sapien"}) + "\n\n")
    args = argparse.Namespace(peers_json=[str(good)])
    assert bench_cmd.read_peer_rows(args) == [{"scenario": "batch", "peer": "sapien", "source": "peers.json"}]
    bad = tmp_path / "bad.json"
    bad.write_text("{nope\n")
    with pytest.raises(UsageError, match=r"bad.json:1: not JSON"):
        bench_cmd.read_peer_rows(argparse.Namespace(peers_json=[str(bad)]))
    with pytest.raises(UsageError, match="no such file"):
        bench_cmd.read_peer_rows(argparse.Namespace(peers_json=[str(tmp_path / "none.json")]))
