"""The compute batch (`render_batch(pipeline="compute")`, render/batch_path.py): all views
tiled in one atlas, rasterised (shaders/raster.comp BATCH) and shaded (shade.comp BATCH) in
compute shaders, the environment behind them in background_batch.comp. Against each view
rendered alone on the compute path with the compute rasteriser: the same kernels with one
camera, so within 1/255 mean and 3/255 p99 (the rays come from the ViewRecord's inverse, a
few float roundings away from the frame's); measured on the chart: max 1/255.

Lights are point lights (the batch's directional shadows are one scene-wide map, unlike a
single frame's cascades: docs/batch.md). Validation and synchronization validation on.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_batch import SIZE, blended_spheres, cameras_of
from test_compute_path import assert_same

from vkpbr.scene.types import Light

POINT = [Light(kind="point", position=(0.5, 4.0, 2.0), intensity=30.0)]


@pytest.fixture(scope="module")
def chart():
    from vkpbr.render.renderer import Renderer

    with Renderer(validation=True, sync_validation=True) as r:
        if r.compute_batch_unavailable() is not None:
            pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
        yield r
        assert r.device.instance.errors == []


def alone(r, cams, **options) -> list[np.ndarray]:  # noqa: ANN001
    return [r.render(c, size=SIZE, lights=POINT, pipeline="compute", raster="compute", **options)
            for c in cams]


@pytest.mark.parametrize("count", [1, 7, 30])
def test_views_match_views_rendered_alone(chart, count: int) -> None:  # noqa: ANN001
    cams = cameras_of(chart, count, seed=count)
    batch = chart.render_batch(cams, SIZE, POINT, pipeline="compute")
    assert batch.shape == (count, SIZE[1], SIZE[0], 4)
    for i, one in enumerate(alone(chart, cams)):
        assert_same(one, batch[i], f"view {i} of {count}")
    assert not np.array_equal(batch[0], batch[-1]) or count == 1


def test_submissions_depth_linear_and_options(chart) -> None:  # noqa: ANN001
    """Several submissions (batch=4 of 9 views: the last atlas part-filled), depth, linear
    output, the course's lighting, a debug view and no alpha mask."""
    cams = cameras_of(chart, 9, seed=5)
    color, depth = chart.render_batch(cams, SIZE, POINT, pipeline="compute", depth=True, batch=4)
    for i, c in enumerate(cams):
        one, one_depth = chart.render(c, size=SIZE, lights=POINT, pipeline="compute",
                                      raster="compute", depth=True)
        assert_same(one, color[i], f"view {i}")
        both = np.isfinite(one_depth) & np.isfinite(depth[i])
        assert (np.isfinite(one_depth) != np.isfinite(depth[i])).mean() <= 0.01
        np.testing.assert_allclose(depth[i][both], one_depth[both], rtol=1e-4)
    lin = chart.render_batch(cams[:3], SIZE, POINT, pipeline="compute", linear=True)
    for i, one in enumerate(alone(chart, cams[:3], linear=True)):
        covered = np.isfinite(one).all(-1)
        assert np.median(np.abs(lin[i] - one)[covered]) <= 1e-3
    for options in ({"lighting": "course"}, {"view": "mapped-normal"}, {"alpha_mask": False}):
        got = chart.render_batch(cams[:3], SIZE, POINT, pipeline="compute", **options)
        for i, one in enumerate(alone(chart, cams[:3], **options)):
            assert_same(one, got[i], f"{options} view {i}")


def test_blended_draws_in_the_atlas(make_renderer) -> None:  # noqa: ANN001
    """Blended materials in the compute batch: the raster units draw each group of views that
    share a back-to-front order into their tiles of the atlas (pbr.vert's ATLAS build: the
    view's clip space mapped onto its tile, clipped to it by clip distances) over the
    compute-rasterised depth. Each view within the batch's bound of the compute path's
    render of it, from cameras around and inside the spheres that disagree on the order (a
    draw spilling out of its tile would change a neighbour), in one submission and in
    three; GTAO on."""
    r = make_renderer(blended_spheres())
    assert r.compute_batch_unavailable() is None, r.compute_batch_unavailable()
    cams = cameras_of(r, 12, seed=21)
    assert len({r.blend_order(c.eye) for c in cams}) >= 4, "the cameras should disagree"
    singles = alone(r, cams, ao="gtao")
    for batch in ("auto", 5):
        got = r.render_batch(cams, SIZE, POINT, pipeline="compute", batch=batch, ao="gtao")
        assert "blend" in r.last_stats.pass_ms
        for i, one in enumerate(singles):
            assert_same(one, got[i], f"batch={batch} view {i}")


@pytest.fixture(scope="module")
def spheres():
    from vkpbr.render.renderer import Renderer

    with Renderer(blended_spheres(), validation=True) as r:
        if r.compute_batch_unavailable() is not None:
            pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
        yield r
        assert r.device.instance.errors == []


SPHERE_CAMERAS = 10


@settings(max_examples=10, deadline=None, derandomize=True)
@given(picked=st.lists(st.integers(0, SPHERE_CAMERAS - 1), min_size=1, max_size=8),
       per=st.sampled_from(["auto", 1, 2, 5]))
def test_blended_views_in_any_atlas(spheres, picked: list[int], per: int | str) -> None:  # noqa: ANN001
    """Any views of the translucent spheres, in any order and repeated, one submission or
    split (so each view lands in another tile of atlases of other shapes): each view within
    the batch's bound of that camera rendered alone (a blended draw clipped wrongly at its
    tile's edges would show in its neighbours or itself)."""
    cams = cameras_of(spheres, SPHERE_CAMERAS, seed=33)
    got = spheres.render_batch([cams[i] for i in picked], SIZE, POINT, pipeline="compute",
                               batch=per)
    singles = _spheres_alone(spheres, cams)
    for k, i in enumerate(picked):
        assert_same(singles[i], got[k], f"camera {i} as view {k} of {len(picked)}")


_ALONE: dict = {}


def _spheres_alone(r, cams: list) -> list[np.ndarray]:  # noqa: ANN001
    """Each camera rendered alone, once for the module's renderer (hypothesis asks again)."""
    if id(r) not in _ALONE:
        _ALONE[id(r)] = alone(r, cams)
    return _ALONE[id(r)]


def test_blended_sample_model(make_renderer, sample_scene) -> None:  # noqa: ANN001
    """AlphaBlendModeTest (a glTF sample: blended, masked and opaque materials side by side)
    in the compute batch: each view within the bound of the compute path's render."""
    r = make_renderer(sample_scene("AlphaBlendModeTest"))
    assert r.compute_batch_unavailable() is None, r.compute_batch_unavailable()
    cams = cameras_of(r, 6, seed=2)
    got = r.render_batch(cams, SIZE, POINT, pipeline="compute")
    for i, one in enumerate(alone(r, cams)):
        assert_same(one, got[i], f"view {i}")


def test_blended_worlds(make_renderer) -> None:  # noqa: ANN001
    """A batch of worlds that moves blended spheres and sets their factors, lights and
    environment: each view within the batch's bound of `render` of its world alone (set
    through set_poses, set_material, the lights and the environment options). The views'
    back-to-front orders come from their worlds' poses, not the renderer's state (they
    differ here: drawn in the state's order, overlapping spheres would composite wrongly)."""
    import dataclasses

    r = make_renderer(blended_spheres())
    nodes, materials = [1, 2, 3, 4, 5], [1, 2, 3, 4, 5]
    r.world_slots(nodes, materials=materials)
    rng = np.random.default_rng(3)
    worlds = 4
    poses = np.zeros((worlds, 5, 7))
    poses[..., 6] = 1.0  # (x, y, z, w) identity rotations
    poses[..., :3] = rng.uniform(-1.2, 1.2, (worlds, 5, 3))
    base = rng.uniform(0.1, 1.0, (worlds, 5, 4))
    base[..., 3] = [r.scene.materials[m].base_color_factor[3] for m in materials]
    factors = {"base_color": base, "roughness": rng.uniform(0.2, 1.0, (worlds, 5))}
    intensity = rng.uniform(10.0, 60.0, (worlds, 1))
    env = {"intensity": np.array([0.3, 1.0, 2.0, 0.7]), "rotation": np.array([0.0, 90.0, 200.0, 10.0])}
    which = np.array([0, 1, 2, 3, 1, 2])
    cams = cameras_of(r, len(which), seed=4)
    opts = {"shadows": False, "ao": "off"}
    got = r.render_batch(cams, SIZE, POINT, worlds=poses, world_of_view=which,
                         world_materials=factors, world_lights={"intensity": intensity},
                         world_environment=env, pipeline="compute", **opts)
    reordered = 0
    for b, cam in enumerate(cams):
        w = which[b]
        state_order = r.blend_order(cam.eye)
        before = {k: dict(v) for k, v in r.state.materials.items()}
        for k, m in enumerate(materials):
            r.set_material(m, base_color=base[w, k], roughness=float(factors["roughness"][w, k]))
        r.set_poses(nodes, poses[w], space="world")
        reordered += r.blend_order(cam.eye) != state_order
        try:
            want = r.render(cam, size=SIZE, lights=[dataclasses.replace(
                POINT[0], intensity=float(intensity[w, 0]))], env_intensity=float(env["intensity"][w]),
                env_rotation=float(env["rotation"][w]), pipeline="compute", raster="compute", **opts)
        finally:
            r.state.materials = before
            r.state.material_version += 1
            r.state.version += 1
            r.reset_pose()
        assert_same(want, got[b], f"view {b} (world {w})")
    assert reordered >= 3, "the worlds should reorder the blended spheres"


def test_cli_cameras_through_the_compute_batch(tmp_path, capsys) -> None:  # noqa: ANN001
    """`vkpbr render --cameras ... --pipeline compute` renders the poses as one compute batch:
    each frame within the bounds of the same pose rendered frame by frame (`--batch 0`) on
    the compute path with the compute rasteriser."""
    import json

    from PIL import Image

    from vkpbr.app.cli import main
    from vkpbr.render.renderer import Renderer

    with Renderer() as r:
        if r.compute_batch_unavailable() is not None:
            pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    cams = tmp_path / "cams.json"
    cams.write_text(json.dumps(["0.6,3.2,9,0.4,2.2,0", "-4,2,6,0,1,0", "2,1.5,-7,0,1,0"]))
    common = ["render", "--cameras", str(cams), "--size", "40x30", "--light", "point:0.5,4,2",
              "--validation", "--pipeline", "compute"]
    assert main([*common, "--out", str(tmp_path / "a")]) == 0
    assert main([*common, "--out", str(tmp_path / "b"), "--batch", "0", "--raster", "compute"]) == 0
    capsys.readouterr()
    for i in range(3):
        got, want = (np.asarray(Image.open(tmp_path / d / f"frame_{i:05d}.png").convert("RGBA"))
                     for d in ("a", "b"))
        assert_same(want, got, f"frame {i}")


def test_batches_of_changing_sizes_keep_two_atlases(chart) -> None:  # noqa: ANN001
    """A job's batches change size (its last one is shorter; a user tries several): each
    size has its own atlas, and only the two most recently used are kept, so the device
    memory a run of sizes holds stays that of two, and a size met again renders the same."""
    cams = cameras_of(chart, 12, seed=3)
    first = chart.render_batch(cams[:5], SIZE, POINT, pipeline="compute")
    held = []
    for n in (7, 3, 12, 5, 7):
        out = chart.render_batch(cams[:n], SIZE, POINT, pipeline="compute")
        assert out.shape[0] == n
        held.append(chart.device.bytes_allocated()[0])
        assert len(chart.batch_path._atlases) <= 2
    assert np.array_equal(out[:5], first)
    # The last two calls hold atlases for 5 and 7 views, as the 2nd and 3rd calls held
    # (3 and 7): no more than the most any pair of sizes held before.
    assert held[-1] <= max(held[:-1])
