"""The tabletop worlds scene (benchmarks/tabletop.py, issue 32): the glTF loads in vkpbr with the
moving nodes where the generator put them, the per-world motion is what a simulator would
write (rigid, on the table, the arm's links chained), and the MJCF loads in MuJoCo with the
same bodies at the same poses (MuJoCo's own kinematics as the outside reference)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from assets_path import ASSETS

from vkpbr.scene.loader import load_scene

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


def _load_tabletop():  # noqa: ANN202
    spec = importlib.util.spec_from_file_location("tabletop", BENCH / "tabletop.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["tabletop"] = module
    spec.loader.exec_module(module)
    return module


tt = _load_tabletop()
HAVE_MODELS = all((ASSETS / path).exists() for path, _ in tt.MODELS.values())


def _rows_world(rows: np.ndarray) -> np.ndarray:
    """glTF (y-up) world matrices of z-up pose rows (x, y, z, qx, qy, qz, qw)."""
    return tt.zup_to_yup() @ tt.pose_matrix(rows)


@pytest.mark.parametrize("models", [(), "all"])
def test_gltf_loads_with_the_moving_nodes_where_the_generator_put_them(tmp_path: Path, models) -> None:
    if models == "all" and not HAVE_MODELS:
        pytest.skip(f"the sample models are not in {ASSETS} (DamagedHelmet, CesiumMilkTruck)")
    world = tt.make_tabletop(models=tuple(tt.MODELS) if models == "all" else ())
    scene = load_scene(tt.write_gltf(world, tmp_path))
    tree = scene.node_tree()
    idx = tree.indices(list(tt.MOVING))
    assert [tree.names[i] for i in idx] == list(tt.MOVING)
    rest = np.array([b.rest for b in world.moving])
    np.testing.assert_allclose(tree.world()[idx], _rows_world(rest), atol=1e-6)
    # a simulator's poses, set as local poses, are those nodes' world poses in the z-up frame
    rows = tt.Motion(world, 3).poses(40, quaternion="xyzw")[2]
    local = tree.local.copy()
    local[idx] = tt.pose_matrix(rows)
    np.testing.assert_allclose(tree.world(local)[idx], _rows_world(rows), atol=1e-6)
    # the table top (z-up z = 0.75) is y = 0.75 in the file; the floor spans +-3 m
    lo, hi = scene.bounds()
    np.testing.assert_allclose(lo[[0, 2]], -3.0, atol=1e-5)
    assert 0.75 < hi[1] < 2.0 and abs(lo[1]) < 1e-5
    assert len(scene.lights) == 1 and scene.lights[0].kind == "directional"
    assert len(scene.cameras) == 1
    np.testing.assert_allclose(scene.cameras[0].eye, tt.camera_gltf(world)[:3, 3], atol=1e-6)
    if models:  # the models' meshes and textures came along, inside the scene's folder
        assert len(scene.meshes) > len(world.bodies) and len(scene.images) >= 5


def test_motion_is_rigid_on_the_table_and_repeatable() -> None:
    world = tt.make_tabletop(models=())
    m = tt.Motion(world, 64)
    a = m.poses(7, quaternion="xyzw")
    assert a.shape == (64, 17, 7) and a.dtype == np.float32
    np.testing.assert_array_equal(a, tt.Motion(world, 64).poses(7, "xyzw"))  # same seed
    assert not np.allclose(a, tt.Motion(world, 64, seed=1).poses(7, "xyzw"))
    assert not np.allclose(a, m.poses(8, "xyzw"))  # it moves
    assert np.ptp(a[:, :, :3], axis=0).max() > 0.05  # the worlds differ
    np.testing.assert_allclose(np.linalg.norm(a[..., 3:], axis=-1), 1.0, atol=1e-6)
    wxyz = m.poses(7, quaternion="wxyz")
    np.testing.assert_array_equal(wxyz[..., 3], a[..., 6])
    np.testing.assert_array_equal(wxyz[..., 4:], a[..., 3:6])
    # each link starts where the previous one ends: LINK_LENGTH along the previous link's z
    mats = tt.pose_matrix(a.astype(np.float64))
    for i in range(1, tt.ARM_LINKS):
        end = mats[:, i - 1, :3, 3] + mats[:, i - 1, :3, 2] * tt.LINK_LENGTH[i - 1]
        np.testing.assert_allclose(mats[:, i, :3, 3], end, atol=1e-5)
    np.testing.assert_allclose(a[:, 0, :3], np.broadcast_to(tt.ARM_BASE, (64, 3)), atol=1e-6)
    # objects stay on the table top, at their resting height, upright (or lying) as at rest
    obj = a[:, tt.ARM_LINKS:]
    assert np.all(np.abs(obj[..., 0]) < tt.TABLE_HALF[0]) and np.all(np.abs(obj[..., 1]) < tt.TABLE_HALF[1])
    np.testing.assert_allclose(obj[..., 2], np.broadcast_to(world.object_rest[:, 0], (64, 10)), atol=1e-6)
    up = mats[:, tt.ARM_LINKS:, :3, :3] @ np.array([0.0, 0.0, 1.0])
    rest_up = tt.quat_matrix(world.object_rest[:, 1:]) @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(up[..., 2], np.broadcast_to(rest_up[:, 2], (64, 10)), atol=1e-5)


def test_motion_in_torch_is_numpys() -> None:
    torch = pytest.importorskip("torch", reason="torch is not installed: the device path of "
                                "Motion.poses is checked where it is")
    world = tt.make_tabletop(models=())
    m = tt.Motion(world, 16)
    t = m.poses(11, "wxyz", device="cpu")
    assert isinstance(t, torch.Tensor) and t.dtype == torch.float32
    np.testing.assert_allclose(t.numpy(), m.poses(11, "wxyz"), atol=1e-6)


def test_mjcf_loads_in_mujoco_with_the_same_poses(tmp_path: Path) -> None:
    mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco): "
                                 "the MJCF is checked where it is")
    world = tt.make_tabletop(models=())
    model = mujoco.MjModel.from_xml_path(str(tt.write_mjcf(world, tmp_path / "tabletop.xml")))
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, i) for i in range(model.nbody)]
    assert names == ["world", *tt.MOVING]
    assert model.ngeom == len(world.bodies) and model.nq == 7 * len(tt.MOVING)
    data = mujoco.MjData(model)
    rows = tt.Motion(world, 2).poses(25, quaternion="wxyz")[1].astype(np.float64)
    data.qpos[:] = rows.reshape(-1)  # a freejoint's qpos: position + quaternion w, x, y, z
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    np.testing.assert_allclose(data.xpos[1:], rows[:, :3], atol=1e-6)
    q = data.xquat[1:] * np.sign(data.xquat[1:, :1] * rows[:, 3:4] + 1e-12)
    np.testing.assert_allclose(q, rows[:, 3:], atol=1e-6)
    # the geoms: each at its body's pose times its offset, as the glTF's vertices are placed
    for k, body in enumerate(world.moving):
        g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, body.name)
        m = tt.pose_matrix(rows[k], "wxyz")
        np.testing.assert_allclose(data.geom_xpos[g], m[:3, :3] @ body.shape.pos + m[:3, 3], atol=1e-6)
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "view")
    np.testing.assert_allclose(data.cam_xpos[cam], world.camera[:3, 3], atol=1e-5)
    np.testing.assert_allclose(data.cam_xmat[cam].reshape(3, 3), world.camera[:3, :3], atol=1e-5)
    assert model.cam_fovy[cam] == pytest.approx(world.yfov_deg)


def test_mjcf_refuses_the_world_with_models(tmp_path: Path) -> None:
    world = tt.make_tabletop(models=("DamagedHelmet",))
    with pytest.raises(ValueError, match="primitives-only"):
        tt.write_mjcf(world, tmp_path / "x.xml")


def test_spin_turns_each_world_about_its_own_axis() -> None:
    rest = np.array([[0.1, 0.2, 0.3, *tt.matrix_quat(tt.quat_matrix(np.array([0.5, 0.5, 0.5, 0.5])))]])
    spin = tt.Spin(rest, 32)
    a = spin.poses(9, quaternion="xyzw")
    assert a.shape == (32, 1, 7) and a.dtype == np.float32
    np.testing.assert_array_equal(a, tt.Spin(rest, 32).poses(9, "xyzw"))
    np.testing.assert_allclose(np.linalg.norm(a[..., 3:], axis=-1), 1.0, atol=1e-6)
    assert np.all(np.abs(a[..., :2] - rest[0, :2]) <= 0.1 + 1e-6) and np.allclose(a[..., 2], 0.3)
    # rotation = turn about the world's axis, then the rest rotation: the turn keeps its axis
    turn = tt.quat_matrix(a[:, 0, 3:].astype(np.float64)) @ tt.quat_matrix(rest[0, 3:]).T
    axis = spin.params["axis"][:, 0]
    np.testing.assert_allclose(np.einsum("wij,wj->wi", turn, axis), axis, atol=1e-5)
    assert np.ptp(a[:, 0, 3:], axis=0).max() > 0.3  # the worlds differ
