"""New instances of a loaded mesh (Renderer.add_instances / move_instances / remove_instances,
render/instances.py) and per-node materials (set_material(node=)) against a NumPy ray cast
(test_outputs.ray_cast: pinhole rays, Moller-Trumbore in float64) of a scene that holds the
same instances as ordinary nodes; the ids of the file's draws unchanged; moving re-records
nothing; the one-line errors.

Bounds as test_outputs: instance ids exact away from silhouettes, depth within 1e-4 relative.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from test_living_scene import assert_outputs_match
from test_outputs import CAMERA, H, W, analytic_scene, ray_cast

from vkpbr.errors import UsageError
from vkpbr.scene.types import Node


def translations(points: list[tuple[float, float, float]], scale: float = 1.0) -> np.ndarray:
    m = np.tile(np.eye(4), (len(points), 1, 1))
    m[:, :3, :3] *= scale
    m[:, :3, 3] = points
    return m


def with_nodes(scene, mesh: int, matrices: np.ndarray):  # noqa: ANN001, ANN201
    """`scene` with the instances as nodes after its own (what the ray cast draws)."""
    out = copy.deepcopy(scene)
    out.nodes += [Node(mesh, m.astype(np.float32), f"extra {k}") for k, m in enumerate(matrices)]
    return out


@pytest.mark.parametrize(("pipeline", "raster"), [("forward", "hardware"), ("compute", "compute")],
                         ids=["forward", "compute-raster"])
def test_instances_match_the_ray_cast(make_renderer, pipeline: str, raster: str) -> None:  # noqa: ANN001
    scene = analytic_scene()
    r = make_renderer(scene)
    if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
        pytest.skip("this device has no compute path")
    opts = {"pipeline": pipeline, "raster": raster}
    before = r.render(CAMERA, size=(W, H), outputs=["instance"], **opts)["instance"]
    mats = translations([(1.6, 0.4, 1.2), (-0.6, 0.3, 2.0), (0.6, 1.9, 0.0)], 0.6)
    ids = r.add_instances("mesh2", mats)  # the box, three times
    assert ids.tolist() == [5, 6, 7]  # after the file's four draws
    got = r.render(CAMERA, size=(W, H), outputs=["instance", "depth"], **opts)
    assert_outputs_match(got, ray_cast(with_nodes(scene, 2, mats)), scene)
    # The file's draws keep their ids where no instance covers them.
    free = got["instance"] <= 4
    assert np.array_equal(got["instance"][free], before[free])
    # Moving them is a pose: once each frame slot has drawn a moving scene, nothing more
    # is recorded (test_living_scene's rule).
    recorded: dict = {}
    for step in range(4 * r.ring.count):
        if step == 2 * r.ring.count:
            recorded = dict(r.recorder._recorded)
        moved = translations([(1.2, 0.4, 1.6 - 0.1 * step), (-1.6, 0.3, 1.8), (0.2, 2.2, 0.5)], 0.5)
        r.move_instances(ids, moved)
        got = r.render(CAMERA, size=(W, H), outputs=["instance", "depth"], **opts)
    assert r.recorder._recorded == recorded
    assert_outputs_match(got, ray_cast(with_nodes(scene, 2, moved)), scene)
    # Removed: gone from the frame; the freed records come back to the next add, no growth.
    r.remove_instances(ids[1:])
    got = r.render(CAMERA, size=(W, H), outputs=["instance", "depth"], **opts)
    assert_outputs_match(got, ray_cast(with_nodes(scene, 2, moved[:1])), scene)
    draws = len(r.gpu_scene.draws)
    again = r.add_instances(2, moved[1:2])
    assert again.tolist() == [6] and len(r.gpu_scene.draws) == draws


def test_instance_errors(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    with pytest.raises(UsageError, match="no mesh is named 'wheel'"):
        r.add_instances("wheel", np.eye(4)[None])
    with pytest.raises(UsageError, match="out of range"):
        r.add_instances(9, np.eye(4)[None])
    bad = np.eye(4)[None].copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(UsageError, match="NaN"):
        r.add_instances(0, bad)
    with pytest.raises(UsageError, match="last row"):
        r.add_instances(0, np.ones((1, 4, 4)))
    with pytest.raises(UsageError, match="shape"):
        r.add_instances(0, np.eye(3)[None])
    ids = r.add_instances(0, translations([(0, 3, 0), (1, 3, 0)]))
    r.remove_instances(ids[:1])
    with pytest.raises(UsageError, match="removed already"):
        r.remove_instances(ids[:1])
    with pytest.raises(UsageError, match="not made by add_instances"):
        r.remove_instances([1])
    with pytest.raises(UsageError, match="removed already"):
        r.move_instances(ids, translations([(0, 3, 0), (1, 3, 0)]))


def test_a_node_material_of_its_own(make_renderer) -> None:  # noqa: ANN001
    """set_material(node=) changes that node's factors only, also when another node shares
    its material; the material's own factors still reach the nodes that keep it."""
    scene = analytic_scene()
    scene.nodes[1].mesh = 0  # the small sphere's node draws the big sphere's mesh (material 0)
    r = make_renderer(scene)
    kw = {"size": (W, H), "lights": [], "env": "none", "ao": "off", "view": "base-color"}
    ids = r.render(CAMERA, size=(W, H), outputs=["instance"])["instance"]
    a = r.render(CAMERA, **kw)
    r.set_material(node="big sphere", base_color=(1.0, 0.0, 0.0))
    b = r.render(CAMERA, **kw)
    big, small = ids == 1, ids == 2
    assert big.sum() > 50 and small.sum() > 50
    assert np.array_equal(a[small], b[small])  # the other node keeps material 0's factors
    assert np.all(b[big][:, 1:3] == 0) and np.all(b[big][:, 0] > 200)  # red, as asked
    for _ in range(r.ring.count):  # every frame slot records the new material sets once
        r.render(CAMERA, **kw)
    recorded = dict(r.recorder._recorded)
    r.set_material(node="big sphere", base_color=(0.0, 0.0, 1.0))  # its own copy: no re-record
    for _ in range(r.ring.count):
        c = r.render(CAMERA, **kw)
    # (every recording made before is the one kept; a slot the frames before did not take,
    # where the GPU finished a frame before the next began, may record its first)
    after = r.recorder._recorded
    assert all(after.get(key) is rec for key, rec in recorded.items())
    assert np.all(c[big][:, 2] > 200) and np.all(c[big][:, :2] == 0)
    r.set_material("m0", base_color=(0.0, 1.0, 0.0))  # the shared material: the other node
    d = r.render(CAMERA, **kw)
    assert np.all(d[small][:, 1] > 200) and np.array_equal(d[big], c[big])
