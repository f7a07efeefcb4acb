"""The motion output against the NumPy projection of the same surface points in two frames.

For every pixel of the second frame, a NumPy ray cast (pinhole rays of tests/pinhole.py,
Moller-Trumbore in float64) finds the triangle and barycentrics the pixel sees; the same
triangle and barycentrics in the first frame's geometry (the first frame's node matrices, or
its posed vertices from a NumPy skin written from the glTF specification) give where that
point was; both are projected with the pinhole model (tests/pinhole.project). The motion is
where it was minus where it is, in pixels (x right, y down). Bound: within 0.05 px on pixels
away from silhouettes and creases (a ray there may take the neighbouring triangle). Camera
motion, node motion and a skinned, animated mesh; both frame paths; 0 on the first frame.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from pinhole import pixel_rays, project
from raycast import first_hits
from test_deform import posed_triangles
from test_outputs import CAMERA, H, W, analytic_scene, silhouette_band

from vkpbr.scene.types import Camera


def cast(tri: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(H*W,) triangle index (-1: none) and (H*W, 3) barycentrics of the pixel-centre rays."""
    best, _, bary = first_hits(tri, np.asarray(camera.eye), pixel_rays(camera, W, H).reshape(-1, 3))
    return best, bary


def expected_motion(before: np.ndarray, after: np.ndarray, cam0: Camera, cam1: Camera
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 2) motion and (H, W) triangle seen, from the triangles in both frames."""
    tri, bary = cast(after, cam1)
    hit = tri >= 0
    out = np.zeros((H * W, 2))
    for i in np.flatnonzero(hit):
        p1 = bary[i] @ after[tri[i]]
        p0 = bary[i] @ before[tri[i]]
        r0, c0, _ = project(cam0, p0, W, H)
        r1, c1, _ = project(cam1, p1, W, H)
        out[i] = (c0 - c1, r0 - r1)
    return out.reshape(H, W, 2), tri.reshape(H, W)


def scene_triangles(scene, models: list[np.ndarray]) -> np.ndarray:  # noqa: ANN001
    tris = []
    for node, m in zip(scene.nodes, models, strict=True):
        mesh = scene.meshes[node.mesh]
        p = mesh.positions.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        tris.append(p[mesh.indices.reshape(-1, 3)])
    return np.concatenate(tris)


def check(got: np.ndarray, want: np.ndarray, tri: np.ndarray, owner: np.ndarray | None = None
          ) -> None:
    """Motion within 0.05 px on 99% of the pixels away from silhouettes (`owner`: which
    object each triangle belongs to; None: every triangle its own), 0.2 px on all; the
    motion field is continuous across a mesh's shared edges, so those need no band."""
    seen = np.where(tri >= 0, owner[tri] if owner is not None else tri, -1)
    ok = (tri >= 0) & ~silhouette_band(seen)
    assert ok.sum() > 100
    err = np.abs(got[ok] - want[ok]).max(axis=1)
    assert np.abs(want[ok]).max() > 0.5  # something moved
    assert np.percentile(err, 99) <= 0.05 and err.max() <= 0.2, (np.percentile(err, 99), err.max())


PATHS = [("forward", "hardware"), ("compute", "compute")]


@pytest.mark.parametrize(("pipeline", "raster"), PATHS, ids=["forward", "compute-raster"])
def test_camera_and_node_motion(make_renderer, pipeline: str, raster: str) -> None:  # noqa: ANN001
    scene = analytic_scene()
    r = make_renderer(scene)
    if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
        pytest.skip("this device has no compute path")
    kw = {"size": (W, H), "outputs": ["motion", "instance"], "pipeline": pipeline, "raster": raster}
    first = r.render(CAMERA, **kw)
    assert not np.any(first["motion"])  # a renderer's first frame: nothing to compare with
    models0 = [np.asarray(n.matrix, np.float64) for n in scene.nodes]
    # The camera moves: a static scene's motion is the camera's.
    cam1 = dataclasses.replace(CAMERA, eye=(0.8, 2.0, 5.7), target=(0.1, 0.5, 0.0))
    got = r.render(cam1, **kw)["motion"]
    tris = scene_triangles(scene, models0)
    want, tri = expected_motion(tris, tris, CAMERA, cam1)
    check(got, want, tri)
    # A node moves too (the box: rotated and lifted), and the camera again.
    box = models0[2].copy()
    turn = np.array([[np.cos(0.3), 0, np.sin(0.3)], [0, 1, 0], [-np.sin(0.3), 0, np.cos(0.3)]])
    box[:3, :3] = turn
    box[:3, 3] += (0.1, 0.2, 0.0)
    r.set_pose("box", box)
    cam2 = dataclasses.replace(cam1, eye=(0.6, 2.1, 5.9))
    got = r.render(cam2, **kw)["motion"]
    models1 = list(models0)
    models1[2] = box
    want, tri = expected_motion(tris, scene_triangles(scene, models1), cam1, cam2)
    check(got, want, tri)


@pytest.mark.parametrize(("pipeline", "raster"), PATHS, ids=["forward", "compute-raster"])
def test_skinned_motion_between_times(make_renderer, sample_scene, pipeline: str, raster: str) -> None:  # noqa: ANN001
    scene = sample_scene("CesiumMan")
    r = make_renderer(scene)
    if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
        pytest.skip("this device has no compute path")
    cam = Camera(eye=(1.4, 1.1, 1.8), target=(0.0, 0.8, 0.0), yfov_deg=45.0, znear=0.05)
    kw = {"size": (W, H), "outputs": ["motion"], "pipeline": pipeline, "raster": raster}
    frames = list(r.render_many([cam, cam], times=[0.40, 0.45], **kw))
    tri0, _ = posed_triangles(scene, 0.40)
    tri1, _ = posed_triangles(scene, 0.45)
    want, tri = expected_motion(tri0, tri1, cam, cam)
    check(frames[1]["motion"], want, tri, np.zeros(len(tri1), np.int64))
