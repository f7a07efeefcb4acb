"""Batches of worlds (Renderer.render_batch(worlds=...), docs/batch.md "Worlds"): each view
equals `render` of its world alone, set through the public API (set_poses(space="world")):
bit for bit on the layered batch, and on the compute batch within its documented bound
(mean 1/255, p99 3/255) of the plain compute batch of that world and of `render`; instance ids and
depth against the NumPy ray cast of the moved triangles; visibility per world; a new step's
poses re-record nothing; the renderer's own state is untouched; one-line errors.

Shadows are off in the comparisons with `render` (the layered batch's bit-for-bit guarantee
holds without them); each world's own shadow maps are tests/gpu/test_world_shadows.py's.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_living_scene import POSES_WXYZ, assert_outputs_match, moved_scene, pose_matrix
from test_outputs import CAMERA, H, W, analytic_scene, ray_cast

from vkpbr.errors import UsageError
from vkpbr.scene.types import Camera

MOVED = ["box", "small sphere"]
NO_SHADOWS = {"shadows": False, "ao": "off"}


def world_poses(worlds: int, seed: int = 1) -> np.ndarray:
    """(W, 2, 7) position + w,x,y,z quaternion rows around the test poses."""
    rng = np.random.default_rng(seed)
    poses = np.repeat(POSES_WXYZ[None], worlds, 0).copy()
    poses[:, :, :3] += rng.normal(0.0, 0.3, (worlds, 2, 3))
    q = poses[:, :, 3:] + rng.normal(0.0, 0.3, (worlds, 2, 4))
    poses[:, :, 3:] = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return poses


def cameras(n: int) -> list[Camera]:
    """`n` cameras around the test camera (each world seen from its own place)."""
    out = []
    for i in range(n):
        a = 0.35 * i
        eye = np.asarray(CAMERA.eye) + np.array([np.sin(a), 0.1 * i, 1 - np.cos(a)])
        out.append(Camera(eye=tuple(eye), target=CAMERA.target, up=CAMERA.up, yfov_deg=CAMERA.yfov_deg))
    return out


def alone(r, camera: Camera, poses: np.ndarray, **kw) -> np.ndarray:  # noqa: ANN001
    """`render` of one world: its poses set on the renderer, then put back."""
    r.set_poses(MOVED, poses, space="world", quaternion="wxyz")
    try:
        return r.render(camera, size=(W, H), **kw)
    finally:
        r.reset_pose()


def test_layered_batch_views_equal_their_worlds_alone(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    r.world_slots(MOVED)
    poses = world_poses(4)
    cams = cameras(6)
    which = np.array([0, 1, 2, 3, 2, 0])  # more views than worlds: two see world 2 and 0
    got = r.render_batch(cams, (W, H), worlds=poses, world_of_view=which, quaternion="wxyz",
                         pipeline="forward", **NO_SHADOWS)
    for b, cam in enumerate(cams):
        want = alone(r, cam, poses[which[b]], pipeline="forward", **NO_SHADOWS)
        assert np.array_equal(got[b], want), f"view {b} (world {which[b]}) differs"


def test_compute_batch_of_worlds_equals_the_plain_batch_of_each(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    why = r.compute_batch_unavailable()
    if why is not None:
        pytest.skip(f"no compute batch here: {why}")
    r.world_slots(MOVED)
    poses = world_poses(3, seed=2)
    got = r.render_batch([CAMERA] * 3, (W, H), worlds=poses, quaternion="wxyz",
                         pipeline="compute", **NO_SHADOWS)
    for w in range(3):
        r.set_poses(MOVED, poses[w], space="world", quaternion="wxyz")
        plain = r.render_batch([CAMERA], (W, H), pipeline="compute", **NO_SHADOWS)[0]
        single = r.render(CAMERA, size=(W, H), pipeline="compute", raster="compute",
                          **NO_SHADOWS)
        r.reset_pose()
        # docs/batch.md's bound of a compute batch's view (a view's edge pixels depend on
        # the batch it is drawn in): mean 1/255, p99 3/255, against either
        for other in (plain, single):
            diff = np.abs(got[w].astype(int) - other)
            print(w, diff.mean(), np.percentile(diff, 99), diff.max())
            assert diff.mean() <= 1.0 and np.percentile(diff, 99) <= 3, f"world {w}"


def test_ids_and_depth_of_each_world_match_the_ray_cast(make_renderer) -> None:  # noqa: ANN001
    scene = analytic_scene()
    r = make_renderer(scene)
    r.world_slots(MOVED)
    poses = world_poses(2, seed=5)
    got = r.render_batch([CAMERA] * 2, (W, H), worlds=poses, quaternion="wxyz",
                         outputs=["color", "instance", "depth"])
    for w in range(2):
        mats = [pose_matrix(row) for row in poses[w]]
        cast = ray_cast(moved_scene(scene, MOVED, mats))
        assert_outputs_match({k: v[w] for k, v in got.items()}, cast, scene)


def test_world_visibility_hides_a_node_in_that_world_only(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    r.world_slots(MOVED)
    poses = world_poses(2, seed=7)
    shown = np.array([[True, True], [False, True]])  # world 1 hides the box
    got = r.render_batch([CAMERA] * 2, (W, H), worlds=poses, quaternion="wxyz",
                         world_visible=shown, pipeline="forward", **NO_SHADOWS)
    r.set_poses(MOVED, poses[1], space="world", quaternion="wxyz")
    r.set_visible("box", False)
    want = r.render(CAMERA, size=(W, H), pipeline="forward", **NO_SHADOWS)
    assert np.array_equal(got[1], want)
    assert not np.array_equal(got[0], want)


def test_new_poses_rerecord_nothing_and_leave_the_state(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    r.world_slots(MOVED)
    before = r.render(CAMERA, size=(W, H), pipeline="forward")
    for seed in range(len(r.slots) + 1):  # each slot records once (the first, shadows too)
        r.render_batch([CAMERA] * 3, (W, H), worlds=world_poses(3, seed), quaternion="wxyz",
                       pipeline="forward")
    recorded = dict(r.recorder._recorded)
    second = r.render_batch([CAMERA] * 3, (W, H), worlds=world_poses(3, 9), quaternion="wxyz",
                            pipeline="forward")
    assert r.recorder._recorded == recorded, "a new step's poses re-recorded"
    assert second.shape == (3, H, W, 4)
    assert np.array_equal(r.render(CAMERA, size=(W, H), pipeline="forward"), before)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"worlds": np.zeros((3, 2, 7))}, "world_slots"),
    ({"world_of_view": np.zeros(3, int)}, "need worlds"),
    # (found by hand: a ValueError, a TypeError from deep inside, or world_of_view ignored)
    ({"times": ["a", "b", "c"]}, "finite animation times"),
    ({"times": [1j] * 3}, "finite animation times"),
    ({"times": [0.0] * 3, "world_of_view": np.zeros(3, int)}, "without worlds="),
    ({"nope": 1}, "unknown render option 'nope'"),
    ({"options": "fast"}, "options: expected a RenderOptions, got str"),
    ({"lights": 5}, "lights: expected a Light or a list of them, got int"),
])
def test_errors_before_any_gpu_work(make_renderer, kwargs: dict, message: str) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    with pytest.raises(UsageError, match=message) as err:
        r.render_batch([CAMERA] * 3, (W, H), **kwargs)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(("size", "message"), [
    ((0, 0), "must be positive integers"), ((-1, 6), "must be positive integers"),
    ((8.5, 6), "must be positive integers"), ((float("nan"), 6), "must be positive integers"),
    ((8,), r"tuple of length 1: expected \(width, height\)"), ("8x6", "'8x6': expected"),
    (None, "None: expected"), ((8, 6, 1), "expected"), ((100000, 8), "exceeds this device's limit"),
])
def test_bad_sizes_are_one_line_in_every_call(make_renderer, size: object, message: str) -> None:  # noqa: ANN001
    """render, render_batch (which had taken (8.5, 6) and raised ZeroDivisionError, IndexError,
    ValueError or a Vulkan OverflowError for the others) and batch_step: the same check."""
    r = make_renderer(analytic_scene())
    for call in (lambda: r.render(CAMERA, size=size),
                 lambda: r.render_batch([CAMERA] * 2, size),
                 lambda: r.batch_step([CAMERA] * 2, size)()):
        with pytest.raises(UsageError, match=message) as err:
            call()
        assert "\n" not in str(err.value) and str(err.value).startswith("image size")
    assert r.render_batch([CAMERA] * 2, (W, H)).shape == (2, H, W, 4)  # (and it renders on)


@pytest.mark.parametrize(("which", "message"), [
    (np.array([0, 1, 5]), "out of range"),
    (np.array([0, 1]), r"expected \(3,\)"),
    (np.array([0.0, 1.0, 1.0]), "integers"),
])
def test_bad_world_of_view(make_renderer, which: np.ndarray, message: str) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    r.world_slots(MOVED)
    rows = np.tile([0, 0, 0, 1.0, 0, 0, 0], (2, 2, 1))
    with pytest.raises(UsageError, match=message):
        r.render_batch([CAMERA] * 3, (W, H), worlds=rows, world_of_view=which, quaternion="wxyz")
    with pytest.raises(UsageError, match="world_of_view"):
        r.render_batch([CAMERA] * 3, (W, H), worlds=rows, quaternion="wxyz")


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_gpu_expanded_worlds_match_the_host_ones(make_renderer, pipeline: str) -> None:  # noqa: ANN001
    """world_expand="gpu" (worlds.comp in float32, the CUDA route's kernel) against the host's
    exact records: the same pixels within 1 level (float32 matrices and normal matrices),
    with per-world visibility."""
    r = make_renderer(analytic_scene())
    if pipeline == "compute" and r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    r.world_slots(MOVED)
    poses = world_poses(4, seed=11)
    shown = np.array([[True, True], [False, True], [True, False], [False, False]])
    kw = dict(worlds=poses, quaternion="wxyz", world_visible=shown, pipeline=pipeline, **NO_SHADOWS)
    host = r.render_batch(cameras(4), (W, H), **kw)
    for given in (poses, np.stack([[pose_matrix(p) for p in world] for world in poses])):
        # (W, N, 7) rows (the kernel makes the rotations) and (W, N, 4, 4) matrices
        gpu = r.render_batch(cameras(4), (W, H), world_expand="gpu", **{**kw, "worlds": given})
        diff = np.abs(host.astype(int) - gpu)
        assert diff.max() <= 1 or np.mean(diff > 1) <= 0.001, diff.max()
        assert np.mean(diff) <= 0.05


def world_factors(worlds: int, seed: int = 3) -> dict:
    rng = np.random.default_rng(seed)
    return {"base_color": rng.uniform(0.1, 1.0, (worlds, 2, 4)),
            "metallic": rng.uniform(0.0, 1.0, (worlds, 2)),
            "roughness": rng.uniform(0.2, 1.0, (worlds, 2)),
            "emissive": rng.uniform(0.0, 0.3, (worlds, 2, 3))}


def alone_with(r, camera: Camera, factors: dict, w: int, poses=None, **kw) -> np.ndarray:  # noqa: ANN001
    """`render` of world `w`: its factors set with set_material (and its poses), then put back."""
    before = {k: dict(v) for k, v in r.state.materials.items()}
    for k, name in enumerate(["m2", "m1"]):
        r.set_material(name, base_color=factors["base_color"][w, k],
                       metallic=float(factors["metallic"][w, k]),
                       roughness=float(factors["roughness"][w, k]),
                       emissive=factors["emissive"][w, k])
    if poses is not None:
        r.set_poses(MOVED, poses[w], space="world", quaternion="wxyz")
    try:
        return r.render(camera, size=(W, H), **kw)
    finally:
        r.state.materials = before
        r.state.material_version += 1
        r.state.version += 1
        r.reset_pose()


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_world_material_factors(make_renderer, pipeline: str) -> None:  # noqa: ANN001
    """world_materials: each world's base colour, metallic, roughness and emissive of the
    named materials (the box's m2, the small sphere's m1), with and without poses, equal
    `render` with set_material of that world (the fragment path view by view: bit for bit;
    the compute batch within its bound)."""
    r = make_renderer(analytic_scene())
    if pipeline == "compute" and r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    r.world_slots(MOVED, materials=["m2", "m1"])
    factors, poses = world_factors(3), world_poses(3, seed=4)
    single = {"pipeline": pipeline, **NO_SHADOWS}
    if pipeline == "compute":
        single["raster"] = "compute"
    for given in (None, poses):
        kw = {} if given is None else {"worlds": given, "quaternion": "wxyz"}
        got = r.render_batch(cameras(3), (W, H), world_materials=factors, pipeline=pipeline,
                             **kw, **NO_SHADOWS)
        for w, cam in enumerate(cameras(3)):
            want = alone_with(r, cam, factors, w, given, **single)
            diff = np.abs(got[w].astype(int) - want)
            if pipeline == "forward":
                assert np.array_equal(got[w], want), f"world {w}"
            else:
                assert diff.mean() <= 1.0 and np.percentile(diff, 99) <= 3, (w, diff.mean())
    plain = r.render(cameras(1)[0], size=(W, H), pipeline=pipeline, **NO_SHADOWS)
    assert not np.array_equal(plain, got[0])  # the factors did change the image


def test_bad_world_materials(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    with pytest.raises(UsageError, match="name the materials"):
        r.render_batch([CAMERA] * 2, (W, H), world_materials={"metallic": np.zeros((2, 1))})
    with pytest.raises(UsageError, match="no material is named"):
        r.world_slots(materials=["paint"])
    r.world_slots(materials=["m2"])
    for given, message in (({"metallic": np.full((2, 1), 2.0)}, r"within \[0, 1\]"),
                           ({"shine": np.zeros((2, 1))}, "unknown factor"),
                           ({"base_color": np.zeros((2, 2, 4))}, "shape"),
                           ({"emissive": np.full((2, 1, 3), -1.0)}, ">= 0")):
        with pytest.raises(UsageError, match=message):
            r.render_batch([CAMERA] * 2, (W, H), world_materials=given)


@pytest.mark.parametrize("expand", ["host", "gpu"])
def test_local_poses_below_a_turned_root(make_renderer, tmp_path, expand: str) -> None:  # noqa: ANN001
    """space="local" on the tabletop worlds (benchmarks/tabletop.py: a simulator's z-up rows
    below a glTF root that turns them y-up, 17 moving bodies): each view equals
    set_poses(..., space="local") of its world (bit for bit on the host path, within 1 level
    on the GPU's)."""
    import importlib.util
    import sys
    from pathlib import Path

    from vkpbr.scene.loader import load_scene

    bench = Path(__file__).resolve().parents[2] / "benchmarks" / "tabletop.py"
    spec = importlib.util.spec_from_file_location("tabletop", bench)
    tt = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("tabletop", tt)
    spec.loader.exec_module(tt)
    world = tt.make_tabletop(models=())
    r = make_renderer(load_scene(tt.write_gltf(world, tmp_path)))
    moving = list(tt.MOVING)
    r.world_slots(moving)
    rows = tt.Motion(world, 3).poses(20, quaternion="xyzw").astype(np.float64)
    cam = Camera(eye=(2.2, 2.0, 2.2), target=(0.0, 0.8, 0.0))
    got = r.render_batch([cam] * 3, (W, H), worlds=rows, space="local", world_expand=expand,
                         pipeline="forward", **NO_SHADOWS)
    for w in range(3):
        r.set_poses(moving, rows[w], space="local")
        want = r.render(cam, size=(W, H), pipeline="forward", **NO_SHADOWS)
        r.reset_pose()
        diff = np.abs(got[w].astype(int) - want)
        if expand == "host":
            assert np.array_equal(got[w], want), f"world {w}"
        else:
            assert np.mean(diff) <= 0.05 and np.mean(diff > 1) <= 0.001, (w, diff.max())
    assert not np.array_equal(got[0], got[1])


@pytest.mark.parametrize("pipeline", ["forward", "compute"])
def test_world_lights_and_environment(make_renderer, pipeline: str) -> None:  # noqa: ANN001
    """world_lights (the frame's lights' intensity and colour) and world_environment
    (intensity, rotation about +Y) per world in the layered batch and the compute batch,
    against `render` with those lights and options (bit for bit on the layered batch, within
    the compute batch's bound), with and without poses."""
    import dataclasses

    from vkpbr.scene.types import Light

    r = make_renderer(analytic_scene())
    if pipeline == "compute" and r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    r.world_slots(MOVED)
    lamp = Light(kind="point", position=(1.0, 3.0, 2.0), color=(1.0, 1.0, 1.0), intensity=20.0)
    rng = np.random.default_rng(12)
    intensity = rng.uniform(5.0, 60.0, (3, 1))
    color = rng.uniform(0.2, 1.0, (3, 1, 3))
    env = {"intensity": np.array([0.3, 1.0, 2.0]), "rotation": np.array([0.0, 90.0, 200.0])}
    single = {"pipeline": pipeline, **NO_SHADOWS}
    if pipeline == "compute":
        single["raster"] = "compute"
    for poses in (None, world_poses(3, seed=13)):
        kw = {} if poses is None else {"worlds": poses, "quaternion": "wxyz"}
        got = r.render_batch(cameras(3), (W, H), [lamp], pipeline=pipeline, **kw,
                             world_lights={"intensity": intensity, "color": color},
                             world_environment=env, **NO_SHADOWS)
        for w, cam in enumerate(cameras(3)):
            light = dataclasses.replace(lamp, intensity=float(intensity[w, 0]),
                                        color=tuple(color[w, 0]))
            if poses is not None:
                r.set_poses(MOVED, poses[w], space="world", quaternion="wxyz")
            want = r.render(cam, size=(W, H), lights=[light], env_intensity=float(env["intensity"][w]),
                            env_rotation=float(env["rotation"][w]), **single)
            r.reset_pose()
            diff = np.abs(got[w].astype(int) - want)
            if pipeline == "forward":
                assert np.array_equal(got[w], want), f"world {w}"
            assert diff.mean() <= 1.0 and np.percentile(diff, 99) <= 3, (w, diff.mean(), diff.max())
    assert not np.array_equal(got[0], got[2])
    with pytest.raises(UsageError, match="frame's 1 light"):
        r.render_batch(cameras(3), (W, H), [lamp], pipeline=pipeline,
                       world_lights={"intensity": np.ones((3, 2))})
    if pipeline == "forward":  # (the layered batch takes no post step: view by view)
        with pytest.raises(UsageError, match="in a batch only"):
            r.render_batch(cameras(3), (W, H), [lamp], pipeline=pipeline, world_environment=env,
                           bloom=0.5)


@pytest.mark.parametrize("model", ["InterpolationTest", "CesiumMilkTruck", "CesiumMan"])
def test_per_view_times_equal_render_at_each_time(make_renderer, model: str) -> None:  # noqa: ANN001
    """render_batch(times=): each view the scene's animations at its own time, bit for bit
    `render(time=)` on the fragment path: node animations as a batch of worlds (the distinct
    times sampled at once), skins (CesiumMan) view by view."""
    from assets_path import ASSETS

    from vkpbr.scene.loader import load_scene

    path = ASSETS / model / "glTF" / f"{model}.gltf"
    if not path.exists():
        pytest.skip(f"{path} is not there (the sample models: tests/assets_path.py)")
    r = make_renderer(load_scene(path))
    cam = r.default_camera()
    times = np.array([0.0, 0.4, 1.1, 0.4, 2.0])
    kw = {"pipeline": "forward", "ao": "off", **NO_SHADOWS}
    got = r.render_batch([cam] * len(times), (48, 36), times=times, **kw)
    for i, t in enumerate(times):
        assert np.array_equal(got[i], r.render(cam, size=(48, 36), time=float(t), **kw)), t
    assert len({g.tobytes() for g in got}) > 1  # the times differ on screen
    with pytest.raises(UsageError, match="finite animation times"):
        r.render_batch([cam] * 2, (48, 36), times=[0.0, float("nan")], **kw)
    with pytest.raises(UsageError, match="without worlds"):
        r.render_batch([cam] * 2, (48, 36), times=[0.0, 1.0], worlds=np.zeros((2, 1, 7)), **kw)


def test_growing_world_factors_drops_the_frames_recordings(make_renderer) -> None:  # noqa: ANN001
    """A batch whose worlds' factors outgrow their buffer rewrites the compute path's sets:
    `render`'s recorded frames, which bind them too, are recorded again (they had been
    submitted with the old buffer destroyed: a validation error), and draw as before."""
    r = make_renderer(analytic_scene())
    if r.compute_batch_unavailable() is not None:
        pytest.skip(f"no compute batch here: {r.compute_batch_unavailable()}")
    r.world_slots(MOVED, materials=["m2"])
    first = r.render(CAMERA, size=(W, H), pipeline="compute", **NO_SHADOWS)
    for worlds in (1, 8):  # (the second outgrows the first's buffer)
        for _ in range(r.ring.count):  # every frame slot's recording made (then replayed)
            r.render(CAMERA, size=(W, H), pipeline="compute", **NO_SHADOWS)
        r.render_batch(cameras(worlds), (W, H), pipeline="compute", **NO_SHADOWS,
                       world_materials={"base_color": np.full((worlds, 1, 3), 0.5)})
        for _ in range(r.ring.count):
            got = r.render(CAMERA, size=(W, H), pipeline="compute", **NO_SHADOWS)
            r.check_validation()
            assert np.array_equal(got, first)
