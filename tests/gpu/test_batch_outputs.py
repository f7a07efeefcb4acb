"""Dataset outputs of the compute batch (`render_batch(outputs=..., pipeline="compute")`):
the atlas's own outputs pass (shade.comp's BATCH OUTPUTS build, render/batch_path.py), each
output's tiles read back view by view as the colour's. Before, a batch with outputs drew
every view again through render_many for them.

Against two references: each view rendered alone on the compute path with the compute
rasteriser (the same kernels with one camera: ids equal off the one-pixel band where a
batch's views may differ (docs/batch.md), floats within 1e-4 where the ids agree), and the
NumPy ray cast of the analytic scene from each view's own camera (tests/gpu/test_outputs.py's
bounds: ids wrong only on silhouettes, distances within 1e-4 relative, normals within 1e-3).
Validation and synchronization validation on.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pinhole import basis
from test_outputs import ALL, CAMERA, H, W, analytic_scene, ray_cast, silhouette_band

from vkpbr.render.batch_route import TILED_OUTPUTS
from vkpbr.scene.types import Camera, Light

POINT = [Light(kind="point", position=(0.5, 4.0, 2.0), intensity=30.0)]


def around(count: int, seed: int) -> list[Camera]:
    """`count` cameras around and above the analytic scene, each its own view."""
    rng = np.random.default_rng(seed)
    out = []
    for a in rng.uniform(0.0, 2.0 * np.pi, count):
        r, y = rng.uniform(4.0, 7.0), rng.uniform(1.0, 3.5)
        out.append(Camera(eye=(r * np.sin(a), y, r * np.cos(a)), target=(0.0, 0.5, 0.0),
                          yfov_deg=rng.uniform(40.0, 60.0), znear=0.05))
    return out


@pytest.fixture(scope="module")
def analytic():
    from vkpbr.render.renderer import Renderer

    with Renderer(analytic_scene(), validation=True, sync_validation=True) as r:
        if r.compute_batch_unavailable() is not None:
            pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
        yield r
        assert r.device.instance.errors == []


def test_outputs_come_from_the_batch_itself(analytic) -> None:  # noqa: ANN001
    """Every output but motion is the compute batch's own (no view drawn again); motion
    still comes from each view's own frame."""
    r = analytic
    ring = r.parts.ring
    before = ring.number
    r.render_batch(around(3, 1), (W, H), POINT, pipeline="compute", outputs=ALL)
    assert ring.number - before == 1  # (one submission: the batch's)
    assert "outputs" in r.last_stats.pass_ms and {*ALL, "ao"} <= TILED_OUTPUTS
    before = ring.number
    r.render_batch(around(2, 1), (W, H), POINT, pipeline="compute", outputs=["color", "motion"])
    assert ring.number - before == 2  # (view by view: a frame each)


@pytest.mark.parametrize("batch", ["auto", 4])
def test_views_equal_each_view_rendered_alone(analytic, batch: int | str) -> None:  # noqa: ANN001
    """Nine views in one submission and in three (batch=4: the last atlas part-filled)."""
    r = analytic
    cams = around(9, seed=3)
    got = r.render_batch(cams, (W, H), POINT, pipeline="compute", outputs=ALL, batch=batch)
    assert set(got) == set(ALL)
    for i, cam in enumerate(cams):
        one = r.render(cam, size=(W, H), lights=POINT, pipeline="compute", raster="compute",
                       outputs=ALL)
        ids = one["instance"]
        band = silhouette_band(ids)
        same = got["instance"][i] == ids
        assert same[~band].all() and same.mean() >= 0.99, f"view {i}: ids"
        for name in ("semantic",):
            assert np.array_equal(got[name][i][same], one[name][same]), f"view {i}: {name}"
        hit = same & (ids > 0)
        for name in ("depth", "range", "normal", "normal_camera", "normal_geometric"):
            np.testing.assert_allclose(got[name][i][hit], one[name][hit], rtol=1e-4, atol=1e-5,
                                       err_msg=f"view {i}: {name}")
        background = same & (ids == 0)
        assert np.isinf(got["depth"][i][background]).all()
        assert (got["normal"][i][background] == 0).all()
        d = np.abs(got["color"][i][..., :3].astype(int) - one["color"][..., :3])
        assert d.mean() <= 1.0 and np.percentile(d, 99) <= 3, f"view {i}: colour"


def test_each_views_outputs_match_its_ray_cast(analytic) -> None:  # noqa: ANN001
    """Five cameras, each view against the NumPy ray cast from its own camera: the ids,
    distances and normals, and the normal in that view's camera axes."""
    r = analytic
    cams = [CAMERA, *around(4, seed=11)]
    got = r.render_batch(cams, (W, H), POINT, pipeline="compute", outputs=ALL)
    names = {inst["id"]: inst["node"] for inst in r.instances}
    node_of = {n.name: k for k, n in enumerate(r.scene.nodes)}
    for i, cam in enumerate(cams):
        cast = ray_cast(r.scene, cam)
        node = np.vectorize(lambda j: node_of[names[j]] if j else -1)(got["instance"][i])
        band = silhouette_band(cast["node"])
        wrong = node != cast["node"]
        assert not wrong[~band].any(), f"view {i}: {wrong[~band].sum()} ids off silhouettes"
        inside = (cast["node"] >= 0) & ~band
        assert inside.sum() > 300, f"view {i} sees too little of the scene"
        for name in ("depth", "range"):
            np.testing.assert_allclose(got[name][i][inside], cast[name][inside], rtol=1e-4,
                                       err_msg=f"view {i}: {name}")
        err = np.linalg.norm(got["normal"][i][inside] - cast["normal"][inside], axis=-1)
        assert err.max() < 1e-3, f"view {i}: normal {err.max()}"
        right, up, forward = basis(cam)
        rot = np.stack([right, up, -forward], axis=1)  # OpenGL camera axes as columns
        np.testing.assert_allclose(got["normal_camera"][i][inside], cast["normal"][inside] @ rot,
                                   atol=1e-3, err_msg=f"view {i}: normal_camera")


def test_worlds_outputs_from_the_batch(analytic) -> None:  # noqa: ANN001
    """Worlds (each its own poses) with outputs through the compute batch: each world's ids
    and depth against the ray cast of its posed scene."""
    from test_living_scene import assert_outputs_match, moved_scene, pose_matrix
    from test_worlds import MOVED, world_poses

    r = analytic
    r.world_slots(MOVED)
    poses = world_poses(3, seed=9)
    got = r.render_batch([CAMERA] * 3, (W, H), POINT, worlds=poses, quaternion="wxyz",
                         pipeline="compute", outputs=["color", "instance", "depth"])
    for w in range(3):
        mats = [pose_matrix(row) for row in poses[w]]
        cast = ray_cast(moved_scene(r.scene, MOVED, mats))
        assert_outputs_match({k: v[w] for k, v in got.items()}, cast, r.scene)


@pytest.mark.parametrize("ao", ["gtao", "off"])
def test_ao_output_equals_each_views(analytic, ao: str) -> None:  # noqa: ANN001
    """The "ao" output from the batch's GTAO over its views' tiles (computed when asked for,
    with ao="off" too, as `render` does): each view's equals the view rendered alone."""
    r = analytic
    cams = around(5, seed=2)
    ring = r.parts.ring
    before = ring.number
    got = r.render_batch(cams, (W, H), POINT, pipeline="compute", outputs=["ao", "color"], ao=ao)
    assert ring.number - before == 1
    for i, cam in enumerate(cams):
        one = r.render(cam, size=(W, H), lights=POINT, pipeline="compute", raster="compute",
                       outputs=["ao", "color"], ao=ao)
        np.testing.assert_allclose(got["ao"][i], one["ao"], atol=1e-5, err_msg=f"view {i}")
        d = np.abs(got["color"][i][..., :3].astype(int) - one["color"][..., :3])
        assert d.mean() <= 1.0 and np.percentile(d, 99) <= 3, f"view {i}: colour"
    assert got["ao"].min() < 0.9 and got["ao"].max() == 1.0  # (occlusion seen; sky unoccluded)


def test_motion_still_renders_view_by_view(analytic) -> None:  # noqa: ANN001
    """"motion" (a batch's views are no sequence) keeps render_many's frames: the batch's
    arrays are those frames stacked, views after the first moved from the view before."""
    r = analytic
    cams = around(3, seed=5)
    got = r.render_batch(cams, (W, H), POINT, pipeline="compute", outputs=["instance", "motion"])
    frames = list(r.render_many(cams, POINT, (W, H), pipeline="compute",
                                outputs=["instance", "motion"]))
    for i, f in enumerate(frames):
        assert np.array_equal(got["instance"][i], f["instance"]), i
    assert np.abs(got["motion"][1:]).max() > 0


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(names=st.lists(st.sampled_from(sorted(TILED_OUTPUTS)), min_size=1, max_size=4,
                      unique=True),
       views=st.integers(1, 7), per=st.sampled_from(["auto", 1, 3]), depth=st.booleans())
def test_any_outputs_any_split_equal_the_full_call(analytic, names: list[str], views: int,  # noqa: ANN001
                                                   per: int | str, depth: bool) -> None:
    """Any outputs asked for (the batch copies back only the images they read), in any
    order, with depth or not, the views in one submission or split: each array is what the
    call asking every output in one submission gives."""
    r = analytic
    cams = around(views, seed=views)
    every = r.render_batch(cams, (W, H), POINT, pipeline="compute", outputs=[*ALL, "ao"])
    some = r.render_batch(cams, (W, H), POINT, pipeline="compute", outputs=names, batch=per,
                          depth=depth)
    assert list(some) == names
    for name in names:
        assert some[name].shape[0] == views and np.array_equal(some[name], every[name]), name
