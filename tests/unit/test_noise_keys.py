"""A compute batch's noise keys (render/post.py noise_keys, made for all views at once) hash
each view as `noise_key` hashes that view's camera rendered alone: the batch's noise is the
single frames' (tests/gpu/test_noise.py renders both); other seeds, views and sizes differ."""

from __future__ import annotations

import numpy as np

from vkpbr.render.options import parse_noise
from vkpbr.render.post import noise_key, noise_keys
from vkpbr.scene.camera import Camera
from vkpbr.scene.camera_batch import CameraBatch


def hashes(keys: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(keys, np.float32).view(np.uint32)[..., 0]


def test_batch_keys_are_the_single_frames() -> None:
    noise = parse_noise("realsense-d435,seed=11")
    K = np.array([[100.0, 0, 63.5], [0, 101.0, 64.0], [0, 0, 1]])
    poses = np.tile(np.eye(4), (6, 1, 1))
    poses[:, 0, 3] = np.arange(6) * 0.1
    fisheye = Camera.from_opencv(K, poses[0], (128, 128), model="opencv_fisheye",
                                 distortion=(0.01, 0.0, 0.0, 0.0))
    batches = [CameraBatch.orbit(40, center=(0, 0, 0), radius=3.0),
               CameraBatch.from_opencv(K, poses, (128, 128)),
               CameraBatch.from_cameras([fisheye, Camera(eye=(0, 1, 2))], Camera())]
    for views in batches:
        got = hashes(noise_keys(noise, views, (128, 128)))
        want = [hashes(noise_key(noise, views.camera(i), (128, 128))) for i in range(len(views))]
        np.testing.assert_array_equal(got, want)
        assert len(set(got.tolist())) == len(views)  # every view its own noise
    views = batches[0]
    base = hashes(noise_keys(noise, views, (128, 128)))
    assert (hashes(noise_keys(parse_noise("realsense-d435,seed=12"), views, (128, 128))) != base).all()
    assert (hashes(noise_keys(noise, views, (64, 64))) != base).all()
