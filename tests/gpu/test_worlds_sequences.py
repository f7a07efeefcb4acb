"""Batches of worlds under random calls (hypothesis), one renderer for them all, as a
dataset generator's loop makes them: 1-4 worlds, 1-5 views (world_of_view where they
differ), random poses, per-world visibility and base colours, shadows of a spot and a
point light on the compute batch, the worlds' kept map on or off, and `render` frames of
single worlds in between. Each view must equal `render` of its world alone (its poses,
visibility and colour set on the state): bit for bit on the layered batch, within the
compute batch's bound (mean 1/255, p99 3/255) on the compute batch; validation clean
throughout. 400 calls passed here; it found the world factors' buffer outgrown under
render()'s recorded frames (test_worlds.py pins that)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_outputs import analytic_scene
from test_worlds import MOVED, cameras, world_poses

from vkpbr.scene.types import Light

W, H = 32, 24
SPOT = Light(kind="spot", position=(0.5, 4.0, 0.5), direction=(0.0, -1.0, 0.0), intensity=40.0,
             falloff="inverse_square", outer_cone=0.9)
POINT = Light(kind="point", position=(-0.5, 3.0, 1.5), intensity=25.0, falloff="inverse_square")
M2 = (0.6, 0.5, 0.5, 1.0)  # the box's material as loaded (test_outputs.analytic_scene)


@pytest.fixture(scope="module")
def r() -> Iterator[Any]:
    from vkpbr.render.renderer import Renderer

    with Renderer(analytic_scene(), validation=True) as renderer:
        renderer.world_slots(MOVED, materials=["m2"])
        yield renderer
        renderer.check_validation()


def alone(r: Any, camera: Any, pose: np.ndarray, visible: Any, colour: Any, **opts: Any) -> np.ndarray:
    """`render` of one world: its poses, visibility and colour set on the state, then put back."""
    r.set_poses(MOVED, pose, space="world", quaternion="wxyz")
    if visible is not None:
        r.set_visible(MOVED, visible)
    if colour is not None:
        r.set_material("m2", base_color=tuple(colour))
    try:
        return r.render(camera, [SPOT, POINT], size=(W, H), **opts)
    finally:
        r.reset_pose()
        r.set_visible(MOVED, True)
        r.set_material("m2", base_color=M2)


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(worlds=st.integers(1, 4), views=st.integers(1, 5), seed=st.integers(0, 50),
       pipeline=st.sampled_from(["forward", "compute"]), shadows=st.booleans(),
       visible=st.booleans(), colours=st.booleans(), keep_still=st.booleans())
def test_every_view_equals_its_world_alone(r, worlds, views, seed, pipeline, shadows, visible,  # noqa: ANN001
                                           colours, keep_still) -> None:
    if pipeline == "compute" and r.compute_batch_unavailable() is not None:
        pipeline = "forward"
    rng = np.random.default_rng(seed)
    poses = world_poses(worlds, seed=seed)
    shadows = shadows and pipeline == "compute"  # (the layered batch: bit for bit without)
    opts = {"pipeline": pipeline, "ao": "off", "shadow_resolution": 128, "shadows": shadows}
    kw: dict[str, Any] = {"worlds": poses, "quaternion": "wxyz", "world_shadow_resolution": 128}
    which = np.arange(views) if views == worlds else rng.integers(0, worlds, views)
    if views != worlds:
        kw["world_of_view"] = which
    vis = rng.random((worlds, 2)) > 0.3 if visible else None
    colour = rng.random((worlds, 1, 3)) if colours else None
    if vis is not None:
        kw["world_visible"] = vis
    if colour is not None:
        kw["world_materials"] = {"base_color": colour}
    ws = getattr(r.batch_path, "world_shadows", None)
    if ws is not None:
        ws.keep_still = keep_still
    try:
        got = r.render_batch(cameras(views), (W, H), [SPOT, POINT], **kw, **opts)
    finally:
        if ws is not None:
            ws.keep_still = True
    for b, camera in enumerate(cameras(views)):
        w = int(which[b])
        want = alone(r, camera, poses[w], None if vis is None else vis[w],
                     None if colour is None else colour[w, 0], **opts)
        diff = np.abs(got[b].astype(int) - want)
        if pipeline == "forward":
            assert np.array_equal(got[b], want), (b, w)
        else:
            assert diff.mean() <= 1.0 and np.percentile(diff, 99) <= 3, (b, w, diff.mean())
    r.check_validation()
