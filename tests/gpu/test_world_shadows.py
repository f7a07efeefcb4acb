"""Each world's own shadow maps in a batch of worlds (render/world_shadows.py, docs/batch.md
"What the worlds share"): a view of world w equals `render` of the state with world w's poses
set (set_poses) within the compute batch's bound (mean 1/255, p99 3/255), shadows of a spot
and a point light included, on the compute batch and on the layered batch; a directional
light's scene-wide map per world equals the batch of that one world (here bit for bit). Each comparison also
shows that shared maps would fail: on the ground that both worlds show alike without
shadows, the moved box's shadow differs between the worlds. Synchronization validation on.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_outputs import CAMERA, analytic_scene

from vkpbr.errors import UsageError
from vkpbr.scene.types import Light

W, H = 64, 48
RES = 128  # world_shadow_resolution (and the single frames' shadow_resolution)
SPOT = Light(kind="spot", position=(0.5, 4.0, 0.5), direction=(0.0, -1.0, 0.0), intensity=40.0,
             falloff="inverse_square", outer_cone=0.9)
POINT = Light(kind="point", position=(-0.5, 3.0, 1.5), intensity=25.0, falloff="inverse_square")
SUN = Light(kind="directional", direction=(0.0, -0.6, 1.0), intensity=8.0)  # long shadows
# The box's world poses (x, y, z, qx, qy, qz, qw): two places on the ground, turned.
POSES = np.array([[[1.0, 0.5, -1.2, 0.0, 0.0, 0.0, 1.0]],
                  [[-0.4, 0.5, 1.3, 0.0, math.sin(0.3), 0.0, math.cos(0.3)]]])
OPTS = {"ao": "off", "world_shadow_resolution": RES, "shadow_resolution": RES}


@pytest.fixture(scope="module")
def r():  # noqa: ANN201
    from vkpbr.render.renderer import Renderer

    with Renderer(analytic_scene(), validation=True, sync_validation=True) as renderer:
        renderer.world_slots(["box"])
        yield renderer
        renderer.check_validation()


def within_bound(got: np.ndarray, want: np.ndarray, what: str) -> None:
    diff = np.abs(got.astype(int) - want)
    assert diff.mean() <= 1.0 and np.percentile(diff, 99) <= 3, (
        f"{what}: mean {diff.mean():.3f}, p99 {np.percentile(diff, 99)}")


def shadows_differ(r, got: np.ndarray, pipeline: str, lights: list) -> None:  # noqa: ANN001
    """On the pixels both worlds show alike without shadows (the ground the box covers in
    neither), shared maps would give both worlds the same values; their own maps do not."""
    bare = r.render_batch([CAMERA] * 2, (W, H), worlds=POSES, lights=lights, pipeline=pipeline,
                          shadows=False, ao="off")
    same = np.all(bare[0] == bare[1], axis=-1)
    moved = np.abs(got[0].astype(int) - got[1]).max(-1) > 16
    assert np.count_nonzero(same & moved) >= 20, "the moved box's shadow is the same in both worlds"


@pytest.mark.parametrize("pipeline", ["compute", "forward"])
def test_spot_and_point_shadows_follow_each_world(r, pipeline: str) -> None:  # noqa: ANN001
    if pipeline == "compute" and r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    lights = [SPOT, POINT]
    got = r.render_batch([CAMERA] * 2, (W, H), worlds=POSES, lights=lights, pipeline=pipeline,
                         **OPTS)
    # (the layered batch: world 1, the turned box, whose shadows both lights move)
    for w in range(2) if pipeline == "compute" else (1,):
        r.set_poses(["box"], POSES[w], space="world")
        try:
            alone = r.render(CAMERA, lights=lights, size=(W, H), pipeline=pipeline,
                             raster="compute", shadow_raster="compute", **OPTS)
        finally:
            r.reset_pose()
        within_bound(got[w], alone, f"{pipeline} world {w}")
    shadows_differ(r, got, pipeline, lights)


def test_directional_scene_map_per_world(r) -> None:  # noqa: ANN001
    why = r.compute_batch_unavailable()
    if why is not None:
        pytest.skip(f"no compute batch here: {why}")
    got = r.render_batch([CAMERA] * 2, (W, H), worlds=POSES, lights=[SUN], pipeline="compute",
                         **OPTS)
    one = r.render_batch([CAMERA], (W, H), worlds=POSES[1:], lights=[SUN], pipeline="compute",
                         **OPTS)[0]
    within_bound(got[1], one, "world 1")
    shadows_differ(r, got, "compute", [SUN])


def test_maps_past_one_binding_are_one_line(r) -> None:  # noqa: ANN001
    limit = int(r.device.limits.maxStorageBufferRange)
    worlds = limit // (4 * 6 * 8192 ** 2) + 1  # a point light's cube of 8192^2 faces each
    poses = np.repeat(POSES[:1], worlds, 0)
    with pytest.raises(UsageError, match="world shadows: .* lower world_shadow_resolution") as e:
        r.render_batch([CAMERA] * worlds, (W, H), worlds=poses, lights=[POINT], ao="off",
                       world_shadow_resolution=16384)
    assert "\n" not in str(e.value)


def test_a_world_holds_one_layer_a_light() -> None:
    """A world's maps: one 2D layer a directional or spot light (the scene-wide map), a cube
    a point light, at world_shadow_resolution (docs/batch.md's MiB per 1,000 worlds)."""
    from vkpbr.render.shadows import plan_shadows
    from vkpbr.render.world_shadows import world_layout, world_plan

    plan = world_plan(plan_shadows([SUN, SPOT, POINT]))
    assert [(e.kind, e.first, e.count) for e in plan.entries] == [
        ("directional", 0, 1), ("spot", 1, 1), ("point", 0, 6)]
    stride, cube_base, cube = world_layout(plan, 256)
    assert (cube_base, cube) == (2 * 256 ** 2, 128)
    assert 4 * (stride - cube_base) * 1000 / 2 ** 20 == 375.0  # a point light: MiB per 1,000 worlds
    for light in (SUN, SPOT):  # 250 MiB per 1,000 worlds
        assert 4 * world_layout(world_plan(plan_shadows([light])), 256)[0] * 1000 / 2 ** 20 == 250.0


@pytest.mark.parametrize("pipeline", ["compute", "forward"])
def test_casters_the_worlds_do_not_move_are_drawn_once(r, pipeline: str) -> None:  # noqa: ANN001
    """The spheres and the ground are no world's (no slot moves them): their maps are drawn
    once into a kept map that every world's maps copy before its own box is drawn over it
    (render/world_shadows.py). Every world's maps, and the views, equal bit for bit those of
    one pass over every caster in every world (WorldShadows.keep_still False); the kept map is
    drawn again only when what it holds changes (here: a light moved)."""
    from vkpbr.gpu.buffer import download_buffer

    if pipeline == "compute" and r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    ws_of = lambda: r.batch_path.world_shadows  # noqa: E731
    moved_spot = Light(kind="spot", position=(0.2, 4.0, 0.9), direction=(0.0, -1.0, 0.0),
                       intensity=40.0, falloff="inverse_square", outer_cone=0.9)
    for lights in ([SPOT, POINT, SUN], [SPOT, POINT, SUN], [moved_spot, POINT, SUN]):
        runs = {}
        for keep in (True, False):
            r.render_batch([CAMERA] * 2, (W, H), worlds=POSES, lights=lights, pipeline=pipeline,
                           **OPTS)  # (the first fits the buffers)
            ws = ws_of()
            ws.keep_still = keep
            key = ws._kept_key
            views = r.render_batch([CAMERA] * 2, (W, H), worlds=POSES, lights=lights,
                                   pipeline=pipeline, **OPTS)
            stride = r.batch_path._wshadow[1].stride
            maps = download_buffer(r.device, ws.depths, np.float32)[:2 * stride]
            runs[keep] = (views, maps, key, ws._kept_key, r.batch_path._wshadow[1].kept)
        ws.keep_still = True
        (views, maps, before, after, kept), (views1, maps1, *_rest) = runs[True], runs[False]
        assert kept is not None and _rest[2] is None  # (kept: the map copied in; one pass: none)
        assert np.array_equal(maps, maps1) and maps.max() > 0
        assert np.array_equal(views, views1)
        assert before == after  # (drawn when the lights came, by the first call: not again)


def test_a_masked_materials_alpha_per_world_shadows_each_world_alike() -> None:
    """World base colour alphas of an alpha-masked material (the holed card of the shadow
    scene) over and under its cutoff: the card and its shadow show in one world and in
    neither in the other. The worlds' maps are drawn with the state's factors, so such a
    call renders view by view (batch_call._alpha_differs): each view equals `render` with
    that world's set_material, bit for bit, with or without poses; an RGB-only factor stays
    in the batch. world_lights with such alphas cannot go view by view: a one-line error."""
    from shadow_scenes import BLOCK, CARD, GROUND, LIGHTS, rect_scene
    from shadow_scenes import CAMERA as CARD_CAMERA

    from vkpbr.render.renderer import Renderer

    lights = [LIGHTS["spot"], LIGHTS["point"]]
    opts = {"world_shadow_resolution": 256, "shadow_resolution": 256, "env": "none",
            "pipeline": "compute"}
    alphas = np.array([[[1.0, 1.0, 1.0, 1.0]], [[1.0, 1.0, 1.0, 0.2]]])
    with Renderer(rect_scene((GROUND, BLOCK, CARD)), validation=True) as rr:
        rr.world_slots([1], materials=["m2"])
        poses = np.stack([rr.state.local[[1]].copy()] * 2)
        for worlds in (None, poses):
            got = rr.render_batch([CARD_CAMERA] * 2, (W, H), lights, worlds=worlds,
                                  world_materials={"base_color": alphas}, **opts)
            for w in range(2):
                rr.set_material("m2", base_color=tuple(alphas[w, 0]))
                want = rr.render(CARD_CAMERA, lights, size=(W, H), **opts)
                assert np.array_equal(got[w], want), (w, worlds is None)
            rr.set_material("m2", base_color=(1.0, 1.0, 1.0, 1.0))
            assert np.count_nonzero(np.any(got[0] != got[1], axis=-1)) > 50  # the alpha shows
        with pytest.raises(UsageError, match="alpha differs between worlds"):
            rr.render_batch([CARD_CAMERA] * 2, (W, H), lights, world_materials={"base_color": alphas},
                            world_lights={"intensity": np.ones((2, 2))}, **opts)
        rr.check_validation()
