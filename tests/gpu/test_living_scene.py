"""The living scene on the GPU: poses and visibility set between frames (Renderer.set_poses,
set_visible) against a NumPy ray cast of the moved triangles (test_outputs.ray_cast: pinhole
rays, Moller-Trumbore in float64), on every frame path and the batch; nothing re-recorded
for a pose change; shadow maps redrawn when a caster moves and only then.

Bounds as test_outputs (issue 15): instance ids exact away from silhouettes and <= 0.5% wrong
on the band around them; depth within 1e-4 relative.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
from test_outputs import CAMERA, H, W, analytic_scene, ray_cast, silhouette_band

from vkpbr.errors import UsageError
from vkpbr.scene.types import Light

# Poses as a simulator writes them: position + quaternion, here in SAPIEN's w, x, y, z order.
POSES_WXYZ = np.array([[0.2, 0.9, 0.6, np.cos(0.4), 0.0, np.sin(0.4), 0.0],      # the box
                       [-0.4, 0.7, 1.4, np.cos(1.0), np.sin(1.0), 0.0, 0.0]])     # small sphere
MOVED = ["box", "small sphere"]


def pose_matrix(row: np.ndarray) -> np.ndarray:
    """(4, 4) of a position + w,x,y,z quaternion row, from the rotation's axis-angle form
    (Rodrigues), not from the quaternion formula the renderer uses."""
    w, axis = row[3], row[4:]
    angle = 2 * np.arctan2(np.linalg.norm(axis), w)
    k = axis / max(np.linalg.norm(axis), 1e-300)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx
    m[:3, 3] = row[:3]
    return m


def moved_scene(scene, names, matrices):  # noqa: ANN001, ANN201
    out = copy.deepcopy(scene)
    for node in out.nodes:
        if node.name in names:
            node.matrix = matrices[names.index(node.name)].astype(np.float32)
    return out


def assert_outputs_match(got: dict, cast: dict, scene) -> None:  # noqa: ANN001
    want_ids = cast["node"] + 1  # instance id = draw index + 1 (one draw a node here)
    band = silhouette_band(want_ids)
    wrong = got["instance"] != want_ids
    assert not np.any(wrong & ~band), f"{int(np.sum(wrong & ~band))} ids wrong off silhouettes"
    assert np.mean(wrong[band]) <= 0.005 + 1e-9 or np.sum(wrong) <= 3
    hit = (want_ids > 0) & ~band
    np.testing.assert_allclose(got["depth"][hit], cast["depth"][hit], rtol=1e-4)


@pytest.mark.parametrize(("pipeline", "raster"), [("forward", "hardware"), ("compute", "hardware"),
                                                  ("compute", "compute")],
                         ids=["forward", "compute", "compute-raster"])
def test_posed_nodes_match_the_ray_cast(make_renderer, pipeline: str, raster: str) -> None:  # noqa: ANN001
    scene = analytic_scene()
    r = make_renderer(scene)
    if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
        pytest.skip("this device has no compute path")
    r.render(CAMERA, size=(W, H), outputs=["instance"], pipeline=pipeline, raster=raster)
    r.set_poses(MOVED, POSES_WXYZ, quaternion="wxyz")
    got = r.render(CAMERA, size=(W, H), outputs=["instance", "depth"], pipeline=pipeline,
                   raster=raster)
    mats = [pose_matrix(row) for row in POSES_WXYZ]
    assert_outputs_match(got, ray_cast(moved_scene(scene, MOVED, mats)), scene)


def test_xyzw_and_matrices_give_the_same_frame(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    xyzw = POSES_WXYZ[:, [0, 1, 2, 4, 5, 6, 3]]
    r.set_poses(MOVED, xyzw)  # glTF's order, the default
    a = r.render(CAMERA, size=(W, H))
    r.set_poses(MOVED, np.stack([pose_matrix(row) for row in POSES_WXYZ]))
    b = r.render(CAMERA, size=(W, H))
    assert np.abs(a.astype(int) - b.astype(int)).max() <= 1


def test_world_space_poses_under_a_parent(make_renderer) -> None:  # noqa: ANN001
    """A child posed in world space lands where asked although its parent moved first."""
    from vkpbr.scene.tree import NodeTree

    scene = analytic_scene()
    k = len(scene.nodes)
    tree = NodeTree.flat([n.matrix for n in scene.nodes], [n.name for n in scene.nodes])
    # A new root "rig" above the box (index k): the box's local = its old world matrix.
    tree = NodeTree(tree.names + ["rig"], np.append(tree.parents, -1), np.concatenate(
        [tree.local, np.eye(4)[None]]), *(np.concatenate([a, a[:1]]) for a in
                                          (tree.translation, tree.rotation, tree.scale)),
        np.append(tree.uses_matrix, True), np.arange(k + 1))
    order = [k, *range(k)]  # parents first: the rig becomes index 0
    remap = {old: new for new, old in enumerate(order)}
    parents = np.array([-1 if p < 0 else remap[p] for p in tree.parents[order]])
    parents[remap[2]] = 0  # the box (node 2) hangs from the rig
    scene.tree = NodeTree([tree.names[i] for i in order], parents, tree.local[order],
                          tree.translation[order], tree.rotation[order], tree.scale[order],
                          tree.uses_matrix[order], tree.source[order])
    for i, node in enumerate(scene.nodes):
        node.tree = remap[i]
    r = make_renderer(scene)
    rig = np.eye(4)
    rig[:3, 3] = (0.0, 1.5, 0.0)
    r.set_pose("rig", rig)  # lifts the box with it
    lifted = r.state.world()[remap[2]]
    np.testing.assert_allclose(lifted, rig @ np.asarray(analytic_scene().nodes[2].matrix))
    target = pose_matrix(POSES_WXYZ[0])
    r.set_pose("box", target, space="world")
    np.testing.assert_allclose(r.state.world()[remap[2]], target, atol=1e-12)
    got = r.render(CAMERA, size=(W, H), outputs=["instance", "depth"])
    assert_outputs_match(got, ray_cast(moved_scene(analytic_scene(), ["box"], [target])), scene)


def test_hidden_nodes_leave_the_frame(make_renderer) -> None:  # noqa: ANN001
    scene = analytic_scene()
    r = make_renderer(scene)
    r.set_visible(["box", "big sphere"], [False, True])
    got = r.render(CAMERA, size=(W, H), outputs=["instance", "depth"])
    without = copy.deepcopy(scene)
    without.nodes = [n for n in without.nodes if n.name != "box"]
    cast = ray_cast(without)
    cast["node"] = np.where(cast["node"] >= 2, cast["node"] + 1, cast["node"])  # ids as drawn
    assert not np.any(got["instance"] == 3)
    assert_outputs_match(got, cast, scene)
    r.set_visible("box", True)
    back = r.render(CAMERA, size=(W, H), outputs=["instance"])
    assert np.any(back["instance"] == 3)


def test_a_pose_change_records_nothing(make_renderer) -> None:  # noqa: ANN001
    """After a frame slot has drawn a moving scene once (its recording redraws the sun's
    shadow maps, a still one's does not), later poses re-record nothing."""
    r = make_renderer(analytic_scene())
    frames, recorded = [], {}
    for step in range(4 * r.ring.count):
        if step == 2 * r.ring.count:
            recorded = dict(r.recorder._recorded)
        r.set_poses("box", np.array([[0.3 * step, 0.5, -1.2, 0.0, 0.0, 0.0, 1.0]]))
        frames.append(r.render(CAMERA, size=(W, H)))
    assert r.recorder._recorded == recorded
    assert all(np.any(a != b) for a, b in zip(frames, frames[1:], strict=False))


def test_moves_that_change_the_scene_bounds_record_nothing(make_renderer) -> None:  # noqa: ANN001
    """A node moved far enough to change the scene's bounds every frame (an animated crowd's
    do) re-records nothing either: the automatic GTAO radius, recorded into the frame's
    commands, is the scene's as loaded (render/ao.py), not its moving bounds'."""
    r = make_renderer(analytic_scene())
    radii, recorded = [], {}
    for step in range(4 * r.ring.count):
        if step == 2 * r.ring.count:
            recorded = dict(r.recorder._recorded)
        r.set_poses("box", np.array([[4.0 + 3.0 * step, 0.5, -1.2, 0.0, 0.0, 0.0, 1.0]]))
        r.render(CAMERA, size=(W, H))
        radii.append(r.frame_path.parts.bounds.radius)
    assert len(set(radii)) == len(radii), "the bounds did not move (test is moot)"
    assert any(key[3].ao is not None for key in recorded), "no GTAO in the frames (test is moot)"
    assert r.recorder._recorded == recorded


def test_batches_see_the_posed_scene(make_renderer) -> None:  # noqa: ANN001
    scene = analytic_scene()
    r = make_renderer(scene)
    r.set_poses(MOVED, POSES_WXYZ, quaternion="wxyz")
    cams = [CAMERA, dataclasses.replace(CAMERA, eye=(-2.0, 2.5, 5.0))]
    # A point light: a batch's views share a directional light's map (docs/batch.md), so
    # bit-equality with single frames holds for the others.
    lights = [Light(position=(0.5, 4.0, 1.0), intensity=60.0, falloff="inverse_square")]
    # ao="off": the layered batch draws no GTAO (docs/ambient-occlusion.md).
    batch = r.render_batch(cams, size=(W, H), lights=lights, pipeline="forward", ao="off")
    for i, cam in enumerate(cams):
        single = r.render(cam, lights=lights, size=(W, H), pipeline="forward", ao="off")
        assert np.array_equal(batch[i], single)


def test_moving_a_caster_redraws_its_shadow_map(make_renderer) -> None:  # noqa: ANN001
    """A point light's cube map is cached while nothing moves and redrawn when a caster does:
    the frame after a move equals a new Renderer's of the moved scene."""
    scene = analytic_scene()
    lights = [Light(position=(0.5, 4.0, 1.0), intensity=60.0, falloff="inverse_square")]
    r = make_renderer(scene)
    r.render(CAMERA, lights=lights, size=(W, H))
    r.render(CAMERA, lights=lights, size=(W, H))
    assert r.shadows.last_redraw == (("point", False),)  # still: cached
    r.set_poses(MOVED, POSES_WXYZ, quaternion="wxyz")
    moved = r.render(CAMERA, lights=lights, size=(W, H))
    assert r.shadows.last_redraw == (("point", True),)
    fresh = make_renderer(moved_scene(scene, MOVED, [pose_matrix(p) for p in POSES_WXYZ]))
    want = fresh.render(CAMERA, lights=lights, size=(W, H))
    assert np.abs(moved.astype(int) - want.astype(int)).max() <= 1


@pytest.mark.parametrize(("nodes", "poses", "kw", "message"), [
    ("box", np.zeros((2, 7)), {}, "shape"),
    ("box", np.full((1, 4, 4), np.nan), {}, "NaN"),
    # (found by hand: accepted, overflowing in the frame's matrices)
    ("box", np.array([[1e308, 0, 0, 0, 0, 0, 1.0]]), {}, "beyond"),
    ("box", np.array([[0, 0, 0, 0, 0, 0, 1e200]]), {}, "beyond"),
    ("box", np.ones((1, 4, 4)), {}, "last row"),
    ("box", np.diag([1.0, 0.0, 1.0, 1.0])[None], {}, "singular"),
    ("box", np.array([[0, 0, 0, 0, 0, 0, 0.0]]), {}, "length 0"),
    ("no such node", np.eye(4)[None], {}, "no node is named"),
    (7, np.eye(4)[None], {}, "out of range"),
    ("box", np.zeros((1, 7)) + [0, 0, 0, 0, 0, 0, 1], {"quaternion": "zyxw"}, "quaternion"),
    ("box", np.eye(4)[None], {"space": "camera"}, "space"),
    # (found by hand: a RecursionError, a TypeError, ValueErrors of np.asarray)
    (2**63, np.eye(4)[None], {}, "node index 9223372036854775808 is out of range"),
    ([10**40], np.eye(4)[None], {}, "node index 1e20 or more is out of range"),
    (None, np.eye(4)[None], {}, "nodes: expected an index, a name"),
    ("box", "abc", {}, "set_poses: expected numbers, got str"),
    ("box", [[1, 2], [3]], {}, "set_poses: expected numbers, got list of length 2"),
])
def test_bad_poses_are_one_line_errors(make_renderer, nodes, poses, kw, message) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    with pytest.raises(UsageError, match=message):
        r.set_poses(nodes, poses, **kw)
    with pytest.raises(UsageError, match="mask"):
        r.set_visible(["box", "ground"], [True])


def test_material_overrides_match_a_scene_loaded_with_them(make_renderer) -> None:  # noqa: ANN001
    """set_material changes the next frame as a scene loaded with those factors renders, on
    both paths; frames in flight keep theirs (each slot has its copy); bad values are one
    line."""
    scene = analytic_scene()
    r = make_renderer(scene)
    before = r.render(CAMERA, size=(W, H))
    r.set_material("m2", base_color=(0.9, 0.1, 0.1), metallic=0.7, roughness=0.3,
                   emissive=(0.0, 0.2, 0.0))
    changed = copy.deepcopy(scene)
    changed.materials[2] = dataclasses.replace(
        changed.materials[2], base_color_factor=(0.9, 0.1, 0.1, 1.0), metallic_factor=0.7,
        roughness_factor=0.3, emissive_factor=(0.0, 0.2, 0.0))
    fresh = make_renderer(changed)
    for pipeline in ("forward", "compute"):
        if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
            continue
        got = r.render(CAMERA, size=(W, H), pipeline=pipeline)
        want = fresh.render(CAMERA, size=(W, H), pipeline=pipeline)
        assert np.array_equal(got, want)
    assert not np.array_equal(before, r.render(CAMERA, size=(W, H)))
    for bad, message in (({"metallic": 2.0}, "metallic"), ({"base_color": (1, 1)}, "base_color"),
                         ({"emissive": (-1, 0, 0)}, "emissive")):
        with pytest.raises(UsageError, match=message):
            r.set_material(0, **bad)
    with pytest.raises(UsageError, match="no material is named"):
        r.set_material("nope", metallic=0.5)
    r.reset_pose()
    assert np.array_equal(before, r.render(CAMERA, size=(W, H)))


def test_bad_arguments_of_the_living_scene_api_are_one_line(make_renderer) -> None:  # noqa: ANN001
    """The state's and instances' calls given strings, ragged lists, no rows, a scalar time or
    as many times as cameras not (found by hand: each had raised a ValueError or TypeError from
    NumPy, zip or float deep inside); what is well-formed but empty is taken."""
    r = make_renderer(analytic_scene())
    before = r.render(CAMERA, size=(W, H))
    bad = [
        (lambda: r.set_pose("box", "x"), "set_pose: expected numbers, got str"),
        (lambda: r.set_weights("box", "x"), "set_weights: expected numbers, got str"),
        (lambda: r.set_material(0, base_color="red"), "set_material: base_color: expected numbers"),
        (lambda: r.set_material(0, metallic="x"), "set_material: metallic: expected numbers"),
        (lambda: r.set_material(0, emissive=(1e308, 0, 0)), "emissive must be 3 finite"),
        (lambda: r.set_material(0, base_color=np.zeros((5, 4))),  # (its repr has 5 lines)
         r"base_color must be 3 or 4 finite number\(s\), got ndarray of shape \(5, 4\)"),
        (lambda: r.add_instances(0, "x"), "add_instances: expected numbers, got str"),
        (lambda: r.add_instances(0, [[1, 2], [3]]), "add_instances: expected numbers"),
        (lambda: r.set_time("x"), "animation time: expected a number of seconds, got str"),
        (lambda: r.set_time(None), "animation time: expected a number of seconds, got None"),
        (lambda: r.set_time(float("nan")), "animation time must be finite"),
        (lambda: r.set_time(0.5, 0.5), "no animation is named 0.5"),
        (lambda: r.render(CAMERA, size=(W, H), time="x"), "animation time: expected"),
        (lambda: r.render(CAMERA, size=(W, H), nope=1), "unknown render option 'nope'"),
        (lambda: list(r.render_many([CAMERA] * 2, size=(W, H), times=[0.0])), "times: 1 for 2"),
        (lambda: list(r.render_many(iter([CAMERA] * 2), size=(W, H), times=iter([0.0]))),
         "times: fewer than the cameras"),
        (lambda: list(r.render_many([CAMERA], size=(W, H), times=iter([0.0, 1.0]))),
         "times: more than the cameras"),
        (lambda: list(r.render_many([CAMERA], size=(W, H), times=0.5)), "times: expected one a frame"),
        (lambda: list(r.render_many(5, size=(W, H))), "cameras: expected one a frame"),
        (lambda: list(r.render_many([CAMERA], size=(W, H), times=[None])), "animation time"),
    ]
    for call, message in bad:
        with pytest.raises(UsageError, match=message) as err:
            call()
        assert "\n" not in str(err.value)
    r.set_poses([], np.zeros((0, 4, 4)))  # no nodes, no poses: nothing to do
    assert r.add_instances(0, np.zeros((0, 7))).shape == (0,)
    r.remove_instances([])  # (no ids: [] is float64 to NumPy, and had been refused so)
    r.move_instances([], np.zeros((0, 4, 4)))
    assert np.array_equal(r.render(CAMERA, size=(W, H)), before)
    ids = r.add_instances(0, np.eye(4))  # one (4, 4) matrix, as one (7,) row is taken
    assert ids.shape == (1,)
