"""Dataset outputs (Renderer.render(outputs=...)) against a NumPy ray cast of the same triangles.

Scene: two UV spheres, a box and a ground plane at known poses. For every pixel centre the
test casts its ray (tests/pinhole.py, an independent camera model) against every triangle
(Moller-Trumbore in float64) and takes the first hit: the node it belongs to, the distance,
the barycentric interpolation of the vertex normals. Bounds (issue 15): instance ids 0 wrong
away from silhouettes and <= 0.5% wrong on the 1-pixel band around them; normals within 1e-3;
depth and range within 1e-4 relative; background ids 0, distances inf, normals 0. Both frame
paths.
"""

from __future__ import annotations

import numpy as np
import pytest
from pinhole import basis, pixel_rays
from raycast import first_hits

from vkpbr.errors import UsageError
from vkpbr.scene.default import plane, uv_sphere
from vkpbr.scene.types import Camera, Material, Mesh, Node, Scene

W, H = 72, 54
CAMERA = Camera(eye=(0.5, 2.2, 6.0), target=(0.0, 0.6, 0.0), yfov_deg=50.0, znear=0.05)
ALL = ("color", "depth", "range", "instance", "semantic", "normal", "normal_camera",
       "normal_geometric")


def box(size: float) -> Mesh:
    """An axis-aligned cube of edge `size` with flat faces (4 vertices each)."""
    h = size / 2
    faces = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u, v = np.roll(np.eye(3), 1, axis=0)[axis], np.roll(np.eye(3), 2, axis=0)[axis]
            if np.dot(np.cross(u, v), n) < 0:
                u, v = v, u  # counter-clockwise seen from outside: the front faces
            c = n * h
            faces.append((np.array([c - u * h - v * h, c + u * h - v * h, c + u * h + v * h,
                                    c - u * h + v * h]), n))
    pos = np.concatenate([f for f, _ in faces]).astype(np.float32)
    nrm = np.concatenate([np.tile(n, (4, 1)) for _, n in faces]).astype(np.float32)
    quads = np.arange(6)[:, None] * 4 + np.array([0, 1, 2, 0, 2, 3])
    return Mesh("box", positions=pos, normals=nrm, indices=quads.reshape(-1).astype(np.uint32),
                texcoords=np.zeros((24, 2), np.float32))


def translate(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4, dtype=np.float32)
    m[:3, 3] = (x, y, z)
    return m


def analytic_scene() -> Scene:
    meshes = [uv_sphere(0.8, 16, 32), uv_sphere(0.5, 16, 32), box(1.0), plane(12.0, 12.0)]
    for i, m in enumerate(meshes):
        m.name, m.material = f"mesh{i}", i
    materials = [Material(name=f"m{i}", base_color_factor=(0.2 * i + 0.2, 0.5, 0.5, 1.0))
                 for i in range(4)]
    nodes = [Node(0, translate(-1.2, 0.8, 0.0), "big sphere"),
             Node(1, translate(0.9, 0.5, 1.0), "small sphere"),
             Node(2, translate(1.0, 0.5, -1.2), "box"),
             Node(3, translate(0.0, 0.0, 0.0), "ground")]
    return Scene("analytic", meshes=meshes, materials=materials, nodes=nodes, cameras=[CAMERA])


def ray_cast(scene: Scene, camera: Camera = CAMERA) -> dict[str, np.ndarray]:
    """First hits of `camera`'s pixel-centre rays (W x H): node index (-1 = none), t,
    interpolated normal."""
    tris, normals, owner = [], [], []
    for k, node in enumerate(scene.nodes):
        mesh = scene.meshes[node.mesh]
        m = np.asarray(node.matrix, np.float64)
        p = mesh.positions.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        idx = mesh.indices.reshape(-1, 3)
        tris.append(p[idx])
        normals.append(mesh.normals.astype(np.float64)[idx])
        owner.append(np.full(len(idx), k))
    tri, nrm, own = np.concatenate(tris), np.concatenate(normals), np.concatenate(owner)
    eye = np.asarray(camera.eye, np.float64)
    d = pixel_rays(camera, W, H).reshape(-1, 3)
    best, best_t, bary = first_hits(tri, eye, d, chunk=128)
    best_b = bary[:, 1:]
    hit = best >= 0
    best_b = np.where(hit[:, None], best_b, 0.0)  # no hit: no barycentrics (NaN)
    b0 = 1 - best_b.sum(-1)
    n = (b0[:, None] * nrm[best, 0] + best_b[:, :1] * nrm[best, 1] + best_b[:, 1:] * nrm[best, 2])
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-12)
    forward = basis(camera)[2]
    return {"node": np.where(hit, own[best], -1).reshape(H, W),
            "range": best_t.reshape(H, W), "depth": (best_t * (d @ forward)).reshape(H, W),
            "normal": np.where(hit[:, None], n, 0).reshape(H, W, 3),
            "triangle": best.reshape(H, W)}


@pytest.fixture(scope="module")
def scene_and_cast():
    scene = analytic_scene()
    return scene, ray_cast(scene)


def silhouette_band(node: np.ndarray) -> np.ndarray:
    """Pixels whose node differs from a 4-neighbour's (both sides of every silhouette)."""
    band = np.zeros(node.shape, bool)
    for axis in (0, 1):
        diff = np.diff(node, axis=axis) != 0
        if axis == 0:
            band[1:] |= diff
            band[:-1] |= diff
        else:
            band[:, 1:] |= diff
            band[:, :-1] |= diff
    return band


# The depth pre-pass both ways: GPUs take it by default (Renderer.prepass_for), lavapipe does
# not, and the visibility pass the outputs come from must write depth either way.
# And the compute rasteriser (raster.comp) making the compute path's visibility buffer.
@pytest.mark.parametrize(("pipeline", "prepass", "raster"),
                         [("forward", False, "hardware"), ("forward", True, "hardware"),
                          ("compute", False, "hardware"), ("compute", False, "compute")],
                         ids=["forward", "forward-prepass", "compute", "compute-raster"])
def test_outputs_match_the_ray_cast(make_renderer, scene_and_cast, pipeline: str,
                                    prepass: bool, raster: str) -> None:
    scene, cast = scene_and_cast
    r = make_renderer(scene, depth_prepass=prepass)
    if raster == "compute" and not r.device.compute_raster:
        pytest.skip("no 64-bit storage atomics on this device")
    out = r.render(size=(W, H), outputs=ALL, pipeline=pipeline, env="none", raster=raster)
    names = {inst["id"]: inst["node"] for inst in r.instances}
    node_of = {n.name: k for k, n in enumerate(scene.nodes)}
    got_node = np.vectorize(lambda i: node_of[names[i]] if i else -1)(out["instance"])
    band = silhouette_band(cast["node"])
    wrong = got_node != cast["node"]
    assert not wrong[~band].any(), f"{wrong[~band].sum()} ids wrong away from silhouettes"
    assert wrong[band].mean() <= 0.005 * band.size / max(band.sum(), 1) + 0.005
    inside = (cast["node"] >= 0) & ~band
    background = cast["node"] < 0
    assert inside.sum() > 1000 and background.sum() > 50
    # The semantic id is the mesh's index + 1, as Renderer.instances says.
    sem = {inst["id"]: inst["semantic"] for inst in r.instances}
    assert np.array_equal(out["semantic"][inside], np.vectorize(sem.get)(out["instance"][inside]))
    for name in ("depth", "range"):
        np.testing.assert_allclose(out[name][inside], cast[name][inside], rtol=1e-4, err_msg=name)
        assert np.all(np.isinf(out[name][background])), name
    for name in ("normal", "normal_geometric"):  # no normal maps: the same normal
        err = np.linalg.norm(out[name][inside] - cast["normal"][inside], axis=-1)
        assert err.max() < 1e-3, (name, err.max())
        assert np.all(out[name][background] == 0), name
    right, up, forward = basis(CAMERA)
    rot = np.stack([right, up, -forward], axis=1)  # OpenGL camera axes as columns
    np.testing.assert_allclose(out["normal_camera"][inside], cast["normal"][inside] @ rot,
                               atol=1e-3)
    assert np.array_equal(out["color"], r.render(size=(W, H), pipeline=pipeline, env="none",
                                                 raster=raster))
    assert out["instance"][background].max() == 0 and out["instance"].dtype == np.uint32


def test_bad_output_names_and_devices(make_renderer) -> None:  # noqa: ANN001
    r = make_renderer(analytic_scene())
    with pytest.raises(UsageError, match="unknown output 'albedo'") as info:
        r.render(size=(W, H), outputs=("color", "albedo"))
    assert "\n" not in str(info.value)
    msaa = make_renderer(analytic_scene(), msaa=4)
    with pytest.raises(UsageError, match="single-sample"):
        msaa.render(size=(W, H), outputs=("instance",))


def test_semantic_ids_from_a_mapping_match_the_ray_cast(make_renderer, scene_and_cast) -> None:  # noqa: ANN001
    """Renderer(semantics={name: label}): every pixel the ray cast gives to a node carries that
    node's class away from silhouettes; the nodes the mapping leaves out are 0."""
    scene, cast = scene_and_cast
    mapping = {"big sphere": "ball", "small sphere": "ball", "m2": 9}  # m2: the box's material
    r = make_renderer(scene, semantics=mapping)
    out = r.render(size=(W, H), outputs=("semantic",), env="none")
    labels = r.semantic_labels
    want_of_node = {0: "ball", 1: "ball", 2: "9", 3: None}
    band = silhouette_band(cast["node"])
    for node, want in want_of_node.items():
        px = (cast["node"] == node) & ~band
        assert px.sum() > 10  # every node is seen (the small sphere covers the fewest pixels)
        got = {labels.get(int(i)) for i in np.unique(out["semantic"][px])}
        assert got == {want}, (scene.nodes[node].name, got)
    assert out["semantic"][cast["node"] < 0].max() == 0
    assert {i["node"]: i["label"] for i in r.instances}["box"] == "9"
    with pytest.raises(UsageError, match="no node, mesh or material is named 'boxx'"):
        make_renderer(scene, semantics={"boxx": 1})


def test_cli_semantics_file(tmp_path, capsys) -> None:  # noqa: ANN001
    """`render --outputs semantic --semantics classes.json`: the floor's class where the
    floor is, 0 elsewhere; a mapping naming nothing in the scene is one line, nothing written."""
    import json

    from PIL import Image

    from vkpbr.app.cli import main

    classes = tmp_path / "classes.json"
    classes.write_text(json.dumps({"floor": 4}))
    out = tmp_path / "f.png"
    args = ["render", "--outputs", "semantic,instance", "--size", "48x36", "--validation",
            "--out", str(out)]
    assert main([*args, "--semantics", str(classes)]) == 0
    sem = np.asarray(Image.open(tmp_path / "f.semantic.png"))
    assert set(np.unique(sem).tolist()) == {0, 4} and (sem == 4).mean() > 0.1
    classes.write_text(json.dumps({"flor": 4}))
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "g.png"), "--semantics", str(classes)]) != 0
    err = capsys.readouterr().err.strip()
    assert "no node, mesh or material is named 'flor'" in err and "\n" not in err
    assert not list(tmp_path.glob("g*"))
