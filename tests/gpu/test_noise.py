"""Sensor noise (render/options.py SensorNoise; render/post.py Noise; shaders/post_noise*.comp)
on lavapipe: the measured statistics of rendered noise against the model's, from thousands of
pixels of planes (tests/shadow_scenes.py rectangles) seen by pinhole cameras.

- depth: sigma(Z) = Z^2 sigma_d / (f b) within 5% at three distances (36,864 samples each:
  the sample std's own error is 0.4%; sigma_d / d <= 3.6%, so the first-order model's
  bias is < 0.5%);
- quantisation: every disparity f b / Z a multiple of the step;
- dropouts: their count at grazing angles against the model's probabilities summed over the
  pixels (NumPy: each pixel's angle from its pinhole ray and the clean render's normal), and
  their rate at depth discontinuities, within 5% (plus 4 binomial standard deviations);
- colour: Poisson-Gaussian sigma = sqrt(x / full_well + (read / full_well)^2) within 5% at
  three levels;
- reproducible per (seed, view): the same seed and camera give the same noise in any order,
  another seed or camera other noise; invalid depth is 0.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from pinhole import pixel_rays
from shadow_scenes import rect_scene

from vkpbr.errors import UsageError
from vkpbr.render.options import RenderOptions
from vkpbr.scene.camera import Camera

SIZE = (192, 192)
FOCAL = (SIZE[1] / 2) / np.tan(np.radians(30.0))  # yfov 60 degrees
GROUND = (0.0, -50.0, 50.0, -50.0, 50.0, None)
TILE = (0.6, -0.5, 0.5, -0.5, 0.5, None)
QUIET = "grazing_start=90,edge_rate=0,max_range=inf"  # no dropouts


@pytest.fixture(scope="module")
def noise_renderer():  # noqa: ANN201
    from vkpbr.render.renderer import Renderer

    scene = rect_scene([GROUND, TILE, *[(0.01, x, x + 1.0, 2.0, 3.0, None) for x in (-2, -1, 0)]])
    for m, v in zip(scene.materials[2:], (0.05, 0.25, 0.8), strict=True):
        m.base_color_factor = (v, v, v, 1.0)
    r = Renderer(scene, validation=True)
    yield r
    instance = r.device.instance
    r.close()
    assert instance.errors == [], instance.errors[:3]


def down(height: float, x: float = 3.0) -> Camera:
    """Straight down at the ground (away from the tile): a fronto-parallel plane."""
    return Camera(eye=(x, height, -3.0), target=(x, 0.0, -3.0), up=(0, 0, -1), yfov_deg=60.0)


def depth_of(r, cam: Camera, noise: str | None, outputs=("depth",)) -> dict:  # noqa: ANN001
    return r.render(cam, size=SIZE, lights=[], env="none", outputs=outputs, noise=noise)


@pytest.mark.parametrize("height", [1.0, 2.0, 3.0])
def test_axial_sigma_grows_with_z_squared(noise_renderer, height: float) -> None:  # noqa: ANN001
    sigma_d, baseline = 0.1, 0.05
    d = depth_of(noise_renderer, down(height), f"disparity_sigma={sigma_d},baseline={baseline},"
                 f"seed=5,{QUIET}")["depth"]
    want = height**2 * sigma_d / (FOCAL * baseline)
    assert (d > 0).all()
    assert abs(d.std() / want - 1) < 0.05, (d.std(), want)
    assert abs(d.mean() - height) < 0.01 * height


def test_disparity_quantised(noise_renderer) -> None:  # noqa: ANN001
    step, baseline = 0.25, 0.05
    d = depth_of(noise_renderer, down(2.0), f"disparity_sigma=0.3,disparity_step={step},"
                 f"baseline={baseline},{QUIET}")["depth"]
    disparity = FOCAL * baseline / d
    levels = disparity / step
    np.testing.assert_allclose(levels, np.round(levels), atol=1e-3)
    assert len(np.unique(np.round(levels))) >= 3  # the noise spans several steps


def test_grazing_dropouts_match_their_probability(noise_renderer) -> None:  # noqa: ANN001
    """A ground plane seen obliquely: pixel i drops with p_i = clamp((angle_i - 50) / 30);
    the count of zeros = sum p_i within 5% + 4 binomial sigmas."""
    r = noise_renderer
    cam = Camera(eye=(0.0, 1.2, 6.0), target=(0.0, 0.0, -6.0), up=(0, 1, 0), yfov_deg=60.0)
    clean = depth_of(r, cam, None, ("depth", "normal", "instance"))
    rays = pixel_rays(cam, *SIZE)
    ground = (clean["instance"] == 1) & np.isfinite(clean["depth"])
    cosang = np.abs(np.sum(rays * clean["normal"], -1))
    angle = np.degrees(np.arccos(np.clip(cosang, 0, 1)))
    p = np.clip((angle - 50.0) / 30.0, 0, 1)
    # Only pixels away from the tile and the horizon: no discontinuity dropouts there.
    noisy = depth_of(r, cam, "grazing_start=50,grazing_end=80,edge_rate=0,disparity_sigma=0,"
                     "max_range=inf,seed=11")["depth"]
    interior = ground.copy()
    for axis, shift in ((0, 1), (0, -1), (1, 1), (1, -1)):
        interior &= np.roll(ground, shift, axis)
    expected, got = p[interior].sum(), (noisy[interior] == 0).sum()
    sd = np.sqrt((p[interior] * (1 - p[interior])).sum())
    assert 0.1 * interior.sum() < expected < 0.9 * interior.sum()
    assert abs(got - expected) <= 0.05 * expected + 4 * sd, (got, expected, sd)
    # Kept pixels keep their depth (no disparity noise asked for).
    kept = interior & (noisy > 0)
    np.testing.assert_allclose(noisy[kept], clean["depth"][kept], rtol=1e-5)


def test_discontinuity_dropouts(noise_renderer) -> None:  # noqa: ANN001
    """The tile's silhouette (a 4-neighbour's depth differs by more than 5%): dropped at
    `edge_rate` 0.5 within 5% + 4 sigmas; elsewhere never (grazing off); background 0."""
    r = noise_renderer
    cam = Camera(eye=(0.2, 3.0, 0.3), target=(0.0, 0.0, 0.0), up=(0, 0, -1), yfov_deg=60.0)
    clean = depth_of(r, cam, None)["depth"]
    noisy = depth_of(r, cam, "edge_rate=0.5,edge_jump=0.05,grazing_start=90,disparity_sigma=0,"
                     "max_range=inf,seed=2")["depth"]
    pad = np.pad(clean, 1, mode="edge")
    jump = np.zeros_like(clean)
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        n = pad[1 + dy:1 + dy + SIZE[1], 1 + dx:1 + dx + SIZE[0]]
        jump = np.maximum(jump, np.abs(n - clean) / clean)
    edge = jump > 0.05
    assert 200 < edge.sum() < 4000
    rate = (noisy[edge] == 0).mean()
    sd = np.sqrt(0.25 / edge.sum())
    assert abs(rate - 0.5) <= 0.05 * 0.5 + 4 * sd, (rate, edge.sum())
    assert (noisy[~edge] > 0).all()


def test_colour_poisson_gaussian(noise_renderer) -> None:  # noqa: ANN001
    """Three grey patches (base colour 0.05, 0.25, 0.8 in the base_color view: constant linear
    values x): the noisy minus the clean image's std per patch = the model's within 5%."""
    r = noise_renderer
    cam = Camera(eye=(-0.5, 2.0, 2.5), target=(-0.5, 0.0, 2.5), up=(0, 0, -1), yfov_deg=60.0)
    kw = {"size": SIZE, "lights": [], "env": "none", "linear": True, "view": "base_color",
          "outputs": ("color", "semantic")}
    clean = r.render(cam, **kw)
    noisy = r.render(cam, noise=f"full_well=800,read_noise=6,seed=9,{QUIET}", **kw)["color"]
    for label, x in zip((3, 4, 5), (0.05, 0.25, 0.8), strict=True):
        patch = clean["semantic"] == label
        inner = patch & np.roll(patch, 2, 0) & np.roll(patch, -2, 0) & np.roll(patch, 2, 1) & np.roll(patch, -2, 1)
        assert inner.sum() > 1000
        diff = (noisy - clean["color"])[inner][:, :3]
        want = np.sqrt(x / 800 + (6 / 800) ** 2)
        np.testing.assert_allclose(clean["color"][inner][:, :3], x, rtol=1e-5)
        assert abs(diff.std() / want - 1) < 0.05, (x, diff.std(), want)
        assert abs(diff.mean()) < 4 * want / np.sqrt(diff.size)


def test_reproducible_per_seed_and_view(noise_renderer) -> None:  # noqa: ANN001
    r = noise_renderer
    spec = "realsense-d435,seed=4"
    a, b = down(2.0), down(2.5)
    frames = list(r.render_many([a, b, a], size=SIZE, lights=[], env="none",
                                outputs=("color", "depth"), noise=spec))
    np.testing.assert_array_equal(frames[0]["depth"], frames[2]["depth"])
    np.testing.assert_array_equal(frames[0]["color"], frames[2]["color"])
    again = depth_of(r, a, spec)["depth"]
    np.testing.assert_array_equal(again, frames[0]["depth"])
    other_seed = depth_of(r, a, "realsense-d435,seed=5")["depth"]
    assert (other_seed != again).mean() > 0.5
    # render(depth=True) gives the outputs' noisy depth.
    _, depth = r.render(a, size=SIZE, lights=[], env="none", depth=True, noise=spec)
    np.testing.assert_array_equal(depth, again)


def test_invalid_depth_is_zero_and_bad_specs(noise_renderer) -> None:  # noqa: ANN001
    r = noise_renderer
    sky = Camera(eye=(0.0, 1.0, 0.0), target=(0.0, 1.0, -5.0), up=(0, 1, 0), yfov_deg=60.0)
    d = depth_of(r, sky, "disparity_sigma=0,grazing_start=90,edge_rate=0,max_range=1000")["depth"]
    assert (d[: SIZE[1] // 3] == 0).all()  # above the horizon: nothing, so 0
    assert (d[-SIZE[1] // 3:] > 0).all()
    # With every part off, the depth is the clean one (inf where nothing is).
    assert np.isinf(depth_of(r, sky, f"disparity_sigma=0,{QUIET}")["depth"][0]).all()
    far = depth_of(r, down(2.0), "disparity_sigma=0,grazing_start=90,edge_rate=0,max_range=1.5")
    assert (far["depth"] == 0).all()
    for spec, message in (("bogus", "noise preset 'bogus'"), ("seed=-1", "seed=-1"),
                          ("baseline=x", "expected a number"), ("foo=1", "unknown parameter 'foo'")):
        with pytest.raises(UsageError, match=message):
            RenderOptions(noise=spec)
    assert RenderOptions(noise="none").noise is None
    preset = RenderOptions(noise="kinect-v1,seed=3").noise
    assert dataclasses.replace(preset, seed=0) == RenderOptions(noise="kinect-v1").noise


def test_lateral_noise_moves_samples(noise_renderer) -> None:  # noqa: ANN001
    """lateral_sigma 1 px on a ground plane whose depth changes row by row (and not along a
    row): each pixel shows the clean depth of the row round(n) pixels off, n ~ N(0, 1), so the
    offsets' frequencies are P(0) = 0.383, P(+-1) = 0.242, P(+-2) = 0.061 (within 0.02)."""
    from math import erf, sqrt

    r = noise_renderer
    cam = Camera(eye=(0.0, 1.2, 6.0), target=(0.0, 0.0, -6.0), up=(0, 1, 0), yfov_deg=60.0)
    out = depth_of(r, cam, None, ("depth", "instance"))
    clean = out["depth"]
    moved = depth_of(r, cam, "lateral_sigma=1,disparity_sigma=0,grazing_start=90,edge_rate=0,"
                     "max_range=inf,seed=3")["depth"]
    y0, y1, x0, x1 = SIZE[1] // 2 + 12, SIZE[1] - 12, 12, SIZE[0] - 12
    got = moved[y0:y1, x0:x1]
    # Pixels whose 11x11 neighbourhood is all ground (not the tile, not the grey patches).
    ground = out["instance"] == 1
    near = np.ones_like(got, bool)
    for oy in range(-5, 6):
        for ox in range(-5, 6):
            near &= ground[y0 + oy:y1 + oy, x0 + ox:x1 + ox]
    candidates = np.stack([clean[y0 + dy:y1 + dy, x0:x1] for dy in range(-5, 6)])
    dy = (np.abs(candidates - got).argmin(0) - 5)[near]
    assert near.sum() > 3000
    # clean depths (1e-4: the H200 rounds the depth copy differently from lavapipe, 1e-5 there)
    assert (np.abs(candidates - got).min(0)[near] <= 1e-4 * got[near]).all()
    phi = [0.5 * (1 + erf(v / sqrt(2))) for v in (0.5, 1.5, 2.5)]
    want = {0: 2 * phi[0] - 1, 1: phi[1] - phi[0], 2: phi[2] - phi[1]}
    for k, p in want.items():
        for sign in ((1,) if k == 0 else (1, -1)):
            assert abs((dy == sign * k).mean() - p) < 0.02, (k, (dy == sign * k).mean(), p)


def test_compute_batch_views_equal_single_renders(noise_renderer) -> None:  # noqa: ANN001
    """Colour noise in a compute batch (render/post.py batch_post: over the atlas in one
    dispatch, each tile its view's key and its own pixel coordinates): each view equals that
    camera rendered alone with the same noise (the same random numbers: reproducible per
    (seed, view)); the batch takes the compute route, not view by view."""
    from vkpbr.render.batch_route import batch_route
    from vkpbr.render.options import RenderOptions
    from vkpbr.scene.camera_batch import CameraBatch

    r = noise_renderer
    if r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    size = (64, 48)
    cams = [Camera(eye=(x, 2.0, 2.5), target=(-0.5, 0.0, 2.5), up=(0, 0, -1), yfov_deg=60.0)
            for x in (-0.8, -0.5, -0.1)]
    spec = f"full_well=800,read_noise=6,seed=3,{QUIET}"
    kw = {"lights": [], "env": "none", "linear": True, "view": "base_color", "noise": spec}
    batch = CameraBatch.from_cameras(cams, r.default_camera())
    opts = RenderOptions(view="base_color", env="none", noise=spec, pipeline="compute")
    assert batch_route(r.parts, batch, size, opts, True, False, None, "cpu", None)[0] == "compute"
    got = r.render_batch(cams, size, pipeline="compute", **kw)
    assert "noise" in r.last_stats.pass_ms
    clean = r.render_batch(cams, size, pipeline="compute", **{**kw, "noise": None})
    for i in range(len(cams)):
        one = r.render(batch.camera(i), size=size, pipeline="compute", raster="compute", **kw)
        close = np.isclose(got[i], one, rtol=0, atol=1e-6).all(axis=-1)
        assert close.mean() >= 0.995, (i, close.mean())  # (patch edges: a ray's rounding)
        assert np.abs(got[i] - clean[i])[..., :3].std() > 0.005  # the noise is there
    assert not np.array_equal(got[0] - clean[0], got[1] - clean[1])  # each view its own
    # 8-bit: the encode's tone map after the noise, as a single frame's.
    kw = {**kw, "linear": False, "view": "final", "env": "sky"}
    got = r.render_batch(cams, size, pipeline="compute", **kw)
    for i in range(len(cams)):
        one = r.render(batch.camera(i), size=size, pipeline="compute", raster="compute", **kw)
        off = np.abs(got[i].astype(int) - one).max(axis=-1)
        assert (off <= 1).mean() >= 0.995 and off.mean() < 0.05, (i, off.max(), off.mean())
