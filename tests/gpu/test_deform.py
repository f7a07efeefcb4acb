"""Skins and morph targets posed on the GPU (render/deform.py) against NumPy, from outside.

The reference is written here from the glTF 2.0 specification alone (3.7.2.2 morph targets:
p + sum_i w_i d_i; 3.7.3 skins: sum_k w_k J_k p with J = world(joint) x inverseBind, the
skinned node's own transform ignored) on the arrays the loader gives, at poses the scene's
animations give at sampled times. Each rendered frame's instance ids and depth are compared
with a NumPy ray cast of the posed triangles (pinhole rays from tests/pinhole.py,
Moller-Trumbore in float64): ids exact away from silhouettes, depth within 1e-4 relative on
99% of the covered pixels and 1e-3 on all (a ray on a crease of the posed mesh may take the
other triangle). Every frame path and a batch.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from pinhole import basis, pixel_rays
from raycast import first_hits
from test_outputs import silhouette_band

from vkpbr.errors import UsageError
from vkpbr.scene.animation import sample
from vkpbr.scene.types import Camera

W, H = 64, 64


def posed_triangles(scene, time: float) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
    """(T, 3, 3) world triangles of every node's mesh at `time`, and each one's draw node."""
    pose = sample(scene, time)
    tree = scene.node_tree()
    world = tree.world(pose.local)
    tris, owner = [], []
    for k, node in enumerate(scene.nodes):
        mesh = scene.meshes[node.mesh]
        p = mesh.positions.astype(np.float64)
        targets = mesh.morph_targets.get("POSITION")
        if targets is not None:
            w = pose.weights.get(node.tree, mesh.morph_weights)
            p = p + np.einsum("t,tvc->vc", np.asarray(w, np.float64), targets.astype(np.float64))
        skin_index = tree.skin.get(node.tree) if mesh.joints is not None else None
        if skin_index is not None:
            skin = scene.skins[skin_index]
            joint = world[skin.joints] @ skin.inverse_bind  # (J, 4, 4)
            blend = np.einsum("vk,vkij->vij", mesh.weights.astype(np.float64),
                              joint[mesh.joints.astype(np.int64)])
            p = np.einsum("vij,vj->vi", blend, np.c_[p, np.ones(len(p))])[:, :3]
        else:
            m = world[node.tree]
            p = p @ m[:3, :3].T + m[:3, 3]
        tris.append(p[mesh.indices.reshape(-1, 3)])
        owner.append(np.full(len(mesh.indices) // 3, k))
    return np.concatenate(tris), np.concatenate(owner)


def ray_cast(tri: np.ndarray, owner: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) node hit (-1 none) and depth along the view axis of the pixel-centre rays."""
    d = pixel_rays(camera, W, H)
    best, t = _first_hits_by_rows(tri, camera, d)
    node = np.where(best >= 0, owner[np.maximum(best, 0)], -1)
    return node.reshape(H, W), (t * (d.reshape(-1, 3) @ basis(camera)[2])).reshape(H, W)


def _first_hits_by_rows(tri: np.ndarray, camera: Camera, d: np.ndarray, rows: int = 4
                        ) -> tuple[np.ndarray, np.ndarray]:
    """first_hits of the (H, W, 3) pixel rays `d`, a band of `rows` image rows at a time
    against the triangles whose rows (their corners projected by the pinhole, one row of
    margin) meet the band; a triangle reaching behind the camera goes with every band. The
    same hits as one first_hits of every ray and triangle, several times sooner."""
    eye = np.asarray(camera.eye, np.float64)
    _, up, fwd = basis(camera)
    rel = tri - eye
    z, y = rel @ fwd, rel @ up
    tan = np.tan(np.radians(camera.yfov_deg) / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        row = (1 - y / z / tan) * H / 2 - 0.5
    behind = np.any(z <= 1e-9, axis=1)
    lo, hi = np.where(behind, -np.inf, row.min(axis=1)), np.where(behind, np.inf, row.max(axis=1))
    best, dist = np.full(H * W, -1), np.full(H * W, np.inf)
    for r0 in range(0, H, rows):
        keep = np.flatnonzero((lo <= r0 + rows) & (hi >= r0 - 1))
        if not len(keep):
            continue
        b, t, _ = first_hits(tri[keep], eye, d[r0:r0 + rows].reshape(-1, 3))
        at = slice(r0 * W, min(r0 + rows, H) * W)
        best[at], dist[at] = np.where(b >= 0, keep[np.maximum(b, 0)], -1), t
    return best, dist


def camera_for(tri: np.ndarray) -> Camera:
    lo, hi = tri.reshape(-1, 3).min(0), tri.reshape(-1, 3).max(0)
    c, r = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
    return Camera(eye=tuple(c + np.array([0.4, 0.3, 1.0]) * 2.2 * r), target=tuple(c),
                  yfov_deg=45.0, znear=0.01 * r)


def check(got: dict, node: np.ndarray, depth: np.ndarray) -> None:
    want = np.where(node >= 0, 1, 0)  # one draw: id 1 where the posed mesh covers
    band = silhouette_band(want)
    ids = (got["instance"] > 0).astype(int)
    wrong = ids != want
    assert not np.any(wrong & ~band), f"{int(np.sum(wrong & ~band))} pixels off silhouettes"
    hit = (want > 0) & ~band
    assert hit.sum() > 50
    rel = np.abs(got["depth"][hit] - depth[hit]) / depth[hit]
    # Pixels on a posed mesh's own creases (a limb over the body) may take the other
    # triangle at a tie: 1% of the covered pixels are allowed 1e-3.
    assert np.mean(rel > 1e-4) <= 0.01, f"{np.mean(rel > 1e-4):.2%} beyond 1e-4"
    assert rel.max() <= 1e-3, rel.max()


MODELS = [("CesiumMan", (0.45, 1.3)), ("RiggedFigure", (0.2, 0.9)),
          ("RiggedSimple", (0.5, 2.5)), ("AnimatedMorphCube", (0.3, 1.4)),
          ("SimpleMorph", (0.5, 2.0))]


# Every model on the fragment path; a skin and a morph on both compute rasterisers.
CASES = [(m, t, "forward", "hardware") for m, t in MODELS] + [
    (m, t[:1], "compute", raster) for m, t in MODELS[::3] for raster in ("hardware", "compute")]


@pytest.mark.parametrize(("model", "times", "pipeline", "raster"), CASES,
                         ids=[f"{m}-{p}-{r}" for m, _, p, r in CASES])
def test_posed_meshes_match_the_reference(make_renderer, sample_scene, model: str, times: tuple,
                                          pipeline: str, raster: str) -> None:  # noqa: ANN001
    scene = sample_scene(model)
    r = make_renderer(scene)
    if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
        pytest.skip("this device has no compute path")
    for t in times:
        tri, owner = posed_triangles(scene, t)
        cam = camera_for(tri)
        got = r.render(cam, size=(W, H), outputs=["instance", "depth"], time=t,
                       pipeline=pipeline, raster=raster)
        node, depth = ray_cast(tri, owner, cam)
        check(got, node, depth)


def test_a_batch_draws_the_posed_mesh(make_renderer, sample_scene) -> None:  # noqa: ANN001
    scene = sample_scene("CesiumMan")
    r = make_renderer(scene)
    r.set_time(0.7)
    tri, _ = posed_triangles(scene, 0.7)
    cams = [camera_for(tri), camera_for(tri[:, ::-1])]
    batch = r.render_batch(cams, size=(W, H), lights=[], pipeline="forward", ao="off")
    for i, cam in enumerate(cams):
        assert np.array_equal(batch[i], r.render(cam, size=(W, H), lights=[], pipeline="forward",
                                                 ao="off"))


def test_times_per_frame_of_a_sequence(make_renderer, sample_scene) -> None:  # noqa: ANN001
    """render_many(times=) poses each frame at its own time, frames in flight included."""
    scene = sample_scene("CesiumMan")
    r = make_renderer(scene)
    times = [0.1, 0.5, 0.9, 1.3, 1.7]
    cam = camera_for(posed_triangles(scene, 0.0)[0])
    seq = list(r.render_many([cam] * len(times), size=(W, H), times=times, lights=[]))
    for t, frame in zip(times, seq, strict=True):
        assert np.array_equal(frame, r.render(cam, size=(W, H), time=t, lights=[]))
    assert not np.array_equal(seq[0], seq[2])


@pytest.mark.parametrize("model", ["CesiumMan", "AnimatedMorphCube", "BoxAnimated"])
def test_a_batch_of_times_leaves_the_state_as_it_was(make_renderer, sample_scene, model: str) -> None:  # noqa: ANN001
    """render_batch(times=) poses its views, not the renderer: skins and morphs (view by view
    through render_many(times=)) leave the state's time and poses as before the call, as the
    node animations' worlds do; each view equals render(time=) of its time."""
    scene = sample_scene(model)
    r = make_renderer(scene)
    r.set_time(0.3)
    cam = r.default_camera()
    before = r.render(cam, size=(W, H), lights=[], pipeline="forward")
    times = [0.9, 1.6]
    batch = r.render_batch([cam, cam], (W, H), lights=[], pipeline="forward", times=times)
    assert r.state.time == 0.3
    assert np.array_equal(r.render(cam, size=(W, H), lights=[], pipeline="forward"), before)
    for t, view in zip(times, batch, strict=True):
        assert np.array_equal(view, r.render(cam, size=(W, H), lights=[], pipeline="forward", time=t))


@pytest.mark.parametrize("model", [m for m, _ in MODELS])
def test_the_culling_spheres_hold_every_posed_vertex(sample_scene, model: str) -> None:  # noqa: ANN001
    """DeformLayout.frames (each deformed record's culling sphere, the frame its vertices are
    written in) holds every vertex the NumPy reference poses (tests/gltf_animation_reference.py),
    at the animation's times and with random joint rotations, non-uniform scales and weights
    beyond the animation's: a posed vertex in its frame's space is within the unit sphere."""
    from gltf_animation_reference import posed_vertices

    from vkpbr.render.deform import DEFORMED_RADIUS, DeformLayout, deformed_records

    scene = sample_scene(model)
    layout = DeformLayout(scene, deformed_records(scene))
    tree = scene.node_tree()
    rng = np.random.default_rng(7)
    for t in np.linspace(0.0, 2.0, 5):
        pose = sample(scene, t)
        for shake in (0.0, 0.4):
            local = pose.local.copy()
            joints = np.unique(np.concatenate([s.joints for s in scene.skins] or [np.zeros(0, int)]))
            for j in joints:  # a random turn and stretch of each joint
                q = rng.normal(size=4) * shake + np.array([0, 0, 0, 1.0])
                x, y, z, w = q / np.linalg.norm(q)
                rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
                local[j, :3, :3] = local[j, :3, :3] @ (rot * rng.uniform(1 - shake, 1 + shake, 3))
            weights = {k: np.asarray(v) * (1 + shake * rng.uniform(-2, 2, np.shape(v)))
                       for k, v in pose.weights.items()}
            shaken = dataclasses.replace(pose, local=local, weights=weights)
            world = tree.world(local)
            frames = layout.frames(world, weights)
            for k, rec in enumerate(layout.records):
                p = posed_vertices(scene, rec.node, shaken)[0]
                m = frames[k] if rec.skin is not None else world[rec.tree] @ frames[k]
                inside = np.c_[p, np.ones(len(p))] @ np.linalg.inv(m).T
                assert np.linalg.norm(inside[:, :3], axis=1).max() <= DEFORMED_RADIUS, (t, shake, k)
            if shake == 0.0:  # and not much larger than the mesh: half its sphere at least
                r = np.array([f[0, 0] for f in frames])
                assert np.all(r < 10 * np.maximum(layout.rest_radius, 1e-3))


def test_skins_with_weights_that_are_not_convex_are_never_culled(sample_scene) -> None:  # noqa: ANN001
    """A skin whose weights are negative or do not sum to one has no bounding sphere: its
    draw keeps the unbounded one and an identity frame (posed in world space as before)."""
    from vkpbr.render.deform import DeformLayout, convex_weights, deformed_records

    scene = sample_scene("RiggedSimple")
    mesh = next(m for m in scene.meshes if m.joints is not None)
    assert convex_weights(mesh)
    w = mesh.weights.copy()
    w[0, :2] = (1.5, -0.5)  # sums to one, one negative
    mesh.weights = w
    assert not convex_weights(mesh)
    layout = DeformLayout(scene, deformed_records(scene))
    frames = layout.frames(scene.node_tree().world(), {})
    skinned = [k for k, r in enumerate(layout.records) if r.skin is not None]
    assert skinned and all(np.array_equal(frames[k], np.eye(4)) for k in skinned)


@pytest.mark.parametrize(("model", "pipeline"), [("CesiumMan", "forward"), ("AnimatedMorphCube", "forward")])
def test_instances_of_a_deformed_mesh_match_the_reference(make_renderer, sample_scene, model: str,
                                                          pipeline: str) -> None:  # noqa: ANN001
    """add_instances of a skinned (and of a morphed) mesh: each instance has its own posed
    vertices, at the state's time plus its offset, placed by its matrix after the file's
    pose; ids and depth at every 4th pixel of each axis (away from the image's own
    silhouettes) against the NumPy reference of each (the file's at t, instance k at
    t + offset k, moved by its matrix), ray cast as above."""
    scene = sample_scene(model)
    r = make_renderer(scene)
    if pipeline == "compute" and r.compute_unavailable(r.offscreen_target((W, H), False)):
        pytest.skip("this device has no compute path")
    tri, _ = posed_triangles(scene, 0.0)
    span = float(np.ptp(tri.reshape(-1, 3)[:, 0])) * 1.3
    place = np.tile(np.eye(4), (2, 1, 1))  # one beside, one turned about y on the other side
    place[0, 0, 3], place[1, :3, :3], place[1, 0, 3] = span, [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], -span
    t, offsets = 0.45, np.array([0.5, 0.9])
    with pytest.raises(UsageError, match="time_offsets must be one finite number or 2"):
        r.add_instances(scene.nodes[0].mesh, place, time_offsets=[0.1, 0.2, 0.3])
    ids = r.add_instances(scene.nodes[0].mesh, place, time_offsets=offsets)
    r.set_time(t)
    parts, owners = [posed_triangles(scene, t)[0]], [np.ones(len(tri), np.int64)]
    for k in range(2):
        p = posed_triangles(scene, t + offsets[k])[0]
        parts.append(p @ place[k, :3, :3].T + place[k, :3, 3])
        owners.append(np.full(len(p), ids[k]))
    tri, owner = np.concatenate(parts), np.concatenate(owners)
    cam = camera_for(tri)
    got = r.render(cam, size=(W, H), outputs=["instance", "depth"], pipeline=pipeline)
    node, depth = ray_cast(tri, owner, cam)
    want = np.maximum(node, 0)
    band = silhouette_band(want)
    wrong = got["instance"].astype(np.int64) != want
    assert not np.any(wrong & ~band), f"{int(np.sum(wrong & ~band))} pixels off silhouettes"
    for i in (1, *ids):  # every one of them seen
        assert np.sum((want == i) & ~band) > 10, i
    hit = (want > 0) & ~band
    rel = np.abs(got["depth"][hit] - depth[hit]) / depth[hit]
    assert np.mean(rel > 1e-4) <= 0.01 and rel.max() <= 1e-3, rel.max()


@pytest.mark.parametrize("model", ["AnimatedMorphCube", "CesiumMan"])
def test_a_moved_deformed_node_keeps_its_pose_when_instances_are_added(make_renderer, sample_scene,
                                                                       model: str) -> None:  # noqa: ANN001
    """The file's deformed node moved and drawn, then add_instances of its mesh: the next
    frame equals, bit for bit, that of a renderer that added them without drawing in
    between (the morphed cube's draw had gone back to its model as loaded: 38 pixels off)."""
    scene = sample_scene(model)
    place = np.eye(4)[None].copy()
    place[0, 0, 3] = 1.0
    frames = []
    for between in (True, False):
        r = make_renderer(scene)
        moved = r.state.tree.local[0].copy()
        moved[0, 3] += 0.1
        r.set_pose(0, moved)
        if between:
            r.render(r.default_camera(), size=(W, H))
        r.add_instances(scene.nodes[0].mesh, place)
        frames.append(r.render(r.default_camera(), size=(W, H), outputs=["color", "instance"]))
    assert np.array_equal(frames[0]["instance"], frames[1]["instance"])
    assert np.array_equal(frames[0]["color"], frames[1]["color"])
