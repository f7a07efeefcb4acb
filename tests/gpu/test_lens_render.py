"""Camera models rendered (render/post.py lens_frame, lens_steps; shaders/post_lens*.comp) with
OpenCV itself as the reference: 3D points of a test scene projected by cv2.projectPoints /
cv2.fisheye.projectPoints land, in the rendered image, on pixels whose instance id is the
points' surface and whose depth is the points' depth within 0.1 px.

The scene: a ground rectangle (y = 0) and small tiles above it (tests/shadow_scenes.py), seen
obliquely so that the ground's depth changes across the image. The depth test converts an
inverse-depth error into pixels by its own gradient there: |rendered - predicted| <= 0.1 px x
|grad 1/depth| (+ 1e-5 relative: float32), where predicted is the OpenCV point's 1/depth
carried to the pixel centre along that gradient (1/depth is affine in a pinhole's pixels on a
plane; through the lens, nearly: the second-order term is a few thousandths of a pixel).
"""

from __future__ import annotations

import numpy as np
import pytest
from shadow_scenes import rect_scene

from vkpbr.errors import UsageError
from vkpbr.scene import lens
from vkpbr.scene.camera import Camera

cv2 = pytest.importorskip("cv2", reason="opencv-python-headless (the test extra) is the reference")

SIZE = (160, 120)
GROUND = (0.0, -6.0, 6.0, -6.0, 4.0, None)
TILES = [(0.5, x - 0.2, x + 0.2, z - 0.2, z + 0.2, None)
         for x in (-2.0, -1.0, 0.0, 1.0, 2.0) for z in (-1.5, 0.0, 1.2)]
LENSES = {
    "opencv": ("opencv", (-0.25, 0.07, 0.002, -0.003, -0.01), 95.0),
    "full_opencv": ("opencv", (-0.2, 0.05, 0.001, -0.002, -0.005, 0.02, 0.003, 0.001), 95.0),
    "opencv_fisheye": ("opencv_fisheye", (0.04, -0.01, 0.002, -0.0005), 80.0),  # 146 degrees
    "equidistant": ("equidistant", (), 82.0),  # 141 degrees across the diagonal
}


@pytest.fixture(scope="module")
def lens_renderer():  # noqa: ANN201
    from vkpbr.render.renderer import Renderer

    r = Renderer(rect_scene([GROUND, *TILES]), validation=True)
    yield r
    instance = r.device.instance
    r.close()
    assert instance.errors == [], instance.errors[:3]


def camera_for(model: str, distortion: tuple, focal: float, eye: tuple = (0.3, 3.2, 4.6)
               ) -> tuple[Camera, np.ndarray, np.ndarray]:
    """A camera above the scene looking down at it obliquely: (Camera, K, camera_from_world)."""
    eye, target = np.array(eye, float), np.array([0.0, 0.0, -0.3])
    f = (target - eye) / np.linalg.norm(target - eye)
    s = np.cross(f, [0.0, 1.0, 0.0])
    s /= np.linalg.norm(s)
    down = np.cross(f, s)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = s, down, f, eye
    K = np.array([[focal, 0.0, 81.3], [0.0, focal * 1.02, 58.6], [0.0, 0.0, 1.0]])
    cam = Camera.from_opencv(K, pose, SIZE, model=model, distortion=distortion)
    return cam, K, np.linalg.inv(pose)


def opencv_pixels(model: str, distortion: tuple, K: np.ndarray, cam_from_world: np.ndarray,
                  points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's pixels of world points, and the points' camera z (NaN for points whose
    projection is folded back into the image by the distortion polynomial beyond its
    monotonic range: their pixel's ray is another, which the image shows instead)."""
    rvec, _ = cv2.Rodrigues(cam_from_world[:3, :3])
    tvec = cam_from_world[:3, 3]
    if model == "opencv":
        px = cv2.projectPoints(points, rvec, tvec, K, np.array(distortion))[0][:, 0]
    else:
        d = np.array(distortion if distortion else (0.0,) * 4)
        px = cv2.fisheye.projectPoints(points[:, None], rvec, tvec, K, d)[0][:, 0]
    cam = points @ cam_from_world[:3, :3].T + tvec
    rays = lens.pixel_rays(model, distortion, K, px)
    unit = cam / np.linalg.norm(cam, axis=1, keepdims=True)
    folded = ~(np.sum(rays * unit, axis=1) > 1 - 1e-9)
    return px, np.where(folded, np.nan, cam[:, 2])


@pytest.mark.parametrize("name", list(LENSES))
def test_rendered_depth_and_ids_where_opencv_projects(lens_renderer, name: str) -> None:  # noqa: ANN001
    model, distortion, focal = LENSES[name]
    cam, K, cfw = camera_for(model, distortion, focal)
    check_against_opencv(lens_renderer, cam, model, distortion, K, cfw)


def test_opencv_fisheye_camera_from_a_colmap_file(lens_renderer, tmp_path) -> None:  # noqa: ANN001
    """An OPENCV_FISHEYE camera written as COLMAP text by hand (COLMAP's pixel convention:
    cx, cy + 0.5) and read by read_colmap renders what cv2.fisheye.projectPoints projects."""
    from vkpbr.scene.camera_files import quaternion_from_rotation, read_colmap

    model, distortion, focal = LENSES["opencv_fisheye"]
    _, K, cfw = camera_for(model, distortion, focal)
    q, t = quaternion_from_rotation(cfw[:3, :3]), cfw[:3, 3]
    (tmp_path / "cameras.txt").write_text(
        f"1 OPENCV_FISHEYE {SIZE[0]} {SIZE[1]} {float(K[0, 0])!r} {float(K[1, 1])!r} "
        f"{float(K[0, 2]) + 0.5!r} {float(K[1, 2]) + 0.5!r} " + " ".join(map(repr, distortion)) + "\n")
    numbers = [repr(float(v)) for v in (*q, *t)]
    (tmp_path / "images.txt").write_text(" ".join(["1", *numbers, "1", "a.png"]) + "\n\n")
    (cam,) = read_colmap(tmp_path)
    assert cam.model == "opencv_fisheye"
    check_against_opencv(lens_renderer, cam, model, distortion, K, cfw)


def check_against_opencv(r, cam: Camera, model: str, distortion: tuple, K: np.ndarray,  # noqa: ANN001
                         cfw: np.ndarray) -> None:
    """The rendered depth at OpenCV's pixels of ground points within 0.1 px, and the tiles'
    ids at their centres' pixels."""
    out = r.render(cam, size=SIZE, lights=[], env="none",
                               outputs=("depth", "range", "instance"))
    depth, ids = out["depth"], out["instance"]
    ground_id = np.bincount(ids.ravel())[1:].argmax() + 1
    # The ground: random points, projected; the depth at the nearest pixel centre.
    rng = np.random.default_rng(7)
    pts = np.c_[rng.uniform(-6, 6, 6000), np.zeros(6000), rng.uniform(-6, 4, 6000)]
    px, z = opencv_pixels(model, distortion, K, cfw, pts)
    p = np.round(px).astype(int)
    inside = (p[:, 0] >= 1) & (p[:, 0] < SIZE[0] - 1) & (p[:, 1] >= 1) & (p[:, 1] < SIZE[1] - 1) & (z > 0)
    p, px, z = p[inside], px[inside], z[inside]
    # Only pixels whose 5x5 neighbourhood is all ground: the gradient's taps, and no edge in
    # the source texels (where the resample takes the nearest texel's depth, not bilinear).
    nb = np.stack([ids[np.clip(p[:, 1] + dy, 0, SIZE[1] - 1), np.clip(p[:, 0] + dx, 0, SIZE[0] - 1)]
                   for dy in range(-2, 3) for dx in range(-2, 3)])
    keep = (nb == ground_id).all(0)
    p, px, z = p[keep], px[keep], z[keep]
    assert len(p) > 1500, len(p)
    # In inverse depth, which is affine in a pinhole's pixels on a plane (nearly so here).
    inv = 1.0 / depth
    gx = (inv[p[:, 1], p[:, 0] + 1] - inv[p[:, 1], p[:, 0] - 1]) / 2
    gy = (inv[p[:, 1] + 1, p[:, 0]] - inv[p[:, 1] - 1, p[:, 0]]) / 2
    predicted = 1.0 / z + gx * (p[:, 0] - px[:, 0]) + gy * (p[:, 1] - px[:, 1])
    grad = np.maximum(np.hypot(gx, gy), 1e-12)
    error_px = np.abs(inv[p[:, 1], p[:, 0]] - predicted) / grad
    slack = 1e-5 / z / grad
    assert (error_px <= 0.1 + slack).all(), (error_px.max(), np.percentile(error_px, 99),
                                             p[error_px.argmax()], z[error_px.argmax()])
    # The range is the distance along each pixel's own ray: range >= depth, equal on the axis.
    finite = np.isfinite(depth)
    assert (out["range"][finite] >= depth[finite] * (1 - 1e-6)).all()
    # The tiles: each centre's pixel shows that tile (ids nearest, never blended).
    centres = np.array([((x0 + x1) / 2, y, (z0 + z1) / 2) for y, x0, x1, z0, z1, _ in TILES])
    cpx, cz = opencv_pixels(model, distortion, K, cfw, centres)
    cp = np.round(cpx).astype(int)
    seen = (cp[:, 0] >= 0) & (cp[:, 0] < SIZE[0]) & (cp[:, 1] >= 0) & (cp[:, 1] < SIZE[1]) & (cz > 0)
    assert seen.sum() >= 8
    got = ids[cp[seen, 1], cp[seen, 0]]
    assert len(set(got.tolist())) == seen.sum() and ground_id not in got and 0 not in got
    # Every id in the image is one the scene has (nearest sampling makes no new values).
    assert set(np.unique(ids).tolist()) <= set(range(len(TILES) + 2))


def test_colour_depth_and_batches(lens_renderer) -> None:  # noqa: ANN001
    """render(depth=True) gives the resampled depth (the outputs' depth); render_batch of
    Cameras with a lens renders view by view, each as render gives it; a pinhole camera with
    the default model is untouched (no resample: pass_ms has no "lens")."""
    r = lens_renderer
    model, distortion, focal = LENSES["opencv_fisheye"]
    cam, _, _ = camera_for(model, distortion, focal)
    color, depth = r.render(cam, size=SIZE, lights=[], env="none", depth=True)
    assert "lens" in r.last_stats.pass_ms
    out = r.render(cam, size=SIZE, lights=[], env="none", outputs=("color", "depth"))
    np.testing.assert_array_equal(depth, out["depth"])
    np.testing.assert_array_equal(color, out["color"])
    batch = r.render_batch([cam, cam], size=SIZE, lights=[], env="none")
    np.testing.assert_array_equal(batch[1], color)
    pin, _, _ = camera_for("pinhole", (), focal)
    r.render(pin, size=SIZE, lights=[], env="none")
    assert "lens" not in r.last_stats.pass_ms


def test_compute_batch_of_one_lens(lens_renderer) -> None:  # noqa: ANN001
    """A compute batch of cameras sharing one lens (render/post.py batch_post): the views'
    source pinholes drawn as the batch's tiles, then one resample dispatch over the atlas
    (post_lens_batch.comp, each view its constants) and the encode. Each view equals that
    camera rendered alone on the compute path (the compute batch's bound: 1/255 mean, 3/255
    p99); with colour noise too; views of different lenses go view by view."""
    from vkpbr.render.batch_route import batch_route
    from vkpbr.render.options import RenderOptions
    from vkpbr.scene.camera_batch import CameraBatch

    r = lens_renderer
    if r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    model, distortion, focal = LENSES["opencv_fisheye"]
    cams = [camera_for(model, distortion, focal, eye=eye)[0]
            for eye in ((0.3, 3.2, 4.6), (-0.6, 2.9, 4.4), (1.1, 3.4, 5.0))]
    views = CameraBatch.from_cameras(cams, cams[0])
    opts = RenderOptions(pipeline="compute", env="none")
    assert batch_route(r.parts, views, SIZE, opts, False, False, None, "cpu", None)[0] == "compute"
    mixed = CameraBatch.from_cameras([cams[0], camera_for("opencv", LENSES["opencv"][1], 95.0)[0]],
                                     cams[0])
    assert batch_route(r.parts, mixed, SIZE, opts, False, False, None, "cpu", None)[0] == "views"
    for extra in ({}, {"noise": "realsense-d435,seed=2"}):
        kw = {"lights": [], **extra}  # (lit by the sky, GTAO on)
        got = r.render_batch(cams, SIZE, pipeline="compute", **kw)
        assert "lens" in r.last_stats.pass_ms
        for i in range(len(cams)):
            one = r.render(views.camera(i), size=SIZE, pipeline="compute", raster="compute", **kw)
            off = np.abs(got[i].astype(int) - one)
            print(f"view {i} {extra}: mean {off.mean():.3f}, p99 {np.percentile(off, 99):.0f}, max {off.max()}")
            assert off.mean() <= 1.0 and np.percentile(off, 99) <= 3, (extra, i, off.mean())
            assert one[..., :3].std() > 10  # the scene is there
    # Two submissions (2 views, then 1: the noise keys and lens constants per submission),
    # linear: the same views (to float rounding: a view's place in the atlas moves).
    kw = {"lights": [], "noise": "realsense-d435,seed=2", "linear": True}
    whole = r.render_batch(cams, SIZE, pipeline="compute", **kw)
    np.testing.assert_allclose(r.render_batch(cams, SIZE, pipeline="compute", batch=2, **kw),
                               whole, rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize("name", ["opencv", "opencv_fisheye"])
def test_motion_through_the_lens(lens_renderer, name: str) -> None:  # noqa: ANN001
    """The motion output of a camera with a lens moving over the static scene, against
    OpenCV: each ground pixel's ray (lens.pixel_rays, checked against cv2.undistortPoints in
    tests/scene/test_lens.py) meets the ground at a world point; cv2's projection of that
    point with the first frame's pose, less the pixel, is its motion. Within 0.05 px on 99% of
    the ground pixels away from tiles, 0.2 px on all (measured: 0.0002 and 0.013 px); 0 on
    the background."""
    r = lens_renderer
    model, distortion, focal = LENSES[name]
    cam0, K, cfw0 = camera_for(model, distortion, focal)
    cam1, _, cfw1 = camera_for(model, distortion, focal, eye=(0.5, 3.0, 4.9))
    kw = {"size": SIZE, "lights": [], "env": "none", "outputs": ("motion", "instance")}
    r.render(cam0, **kw)  # the previous frame: the same model and size
    out = r.render(cam1, **kw)
    motion, ids = out["motion"], out["instance"]
    assert np.all(motion[ids == 0] == 0)
    ground_id = np.bincount(ids.ravel())[1:].argmax() + 1
    rows, cols = np.nonzero(ids == ground_id)
    nb = np.stack([ids[np.clip(rows + dy, 0, SIZE[1] - 1), np.clip(cols + dx, 0, SIZE[0] - 1)]
                   for dy in range(-2, 3) for dx in range(-2, 3)])
    keep = (nb == ground_id).all(0)
    rows, cols = rows[keep], cols[keep]
    assert len(rows) > 3000, len(rows)
    pixels = np.c_[cols, rows].astype(np.float64)
    rays = lens.pixel_rays(model, distortion, K, pixels) @ np.linalg.inv(cfw1)[:3, :3].T
    eye1 = np.linalg.inv(cfw1)[:3, 3]
    world = eye1 + rays * (-eye1[1] / rays[:, 1])[:, None]  # on the ground, y = 0
    was, z = opencv_pixels(model, distortion, K, cfw0, world)
    assert np.isfinite(z).all()
    err = np.abs(motion[rows, cols] - (was - pixels)).max(axis=1)
    assert np.abs(was - pixels).max() > 2.0  # the camera moved
    print(f"{name}: motion error p99 {np.percentile(err, 99):.4f} px, max {err.max():.4f}")
    assert np.percentile(err, 99) <= 0.05 and err.max() <= 0.2, (np.percentile(err, 99), err.max())


def test_too_wide_is_one_line(lens_renderer) -> None:  # noqa: ANN001
    cam, _, _ = camera_for("equidistant", (), 30.0)
    with pytest.raises(UsageError, match="at most 75 are rendered"):
        lens_renderer.render(cam, size=SIZE)
