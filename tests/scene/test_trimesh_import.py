# trimesh interop (vkpbr.scene.trimesh_import): small meshes trimesh builds (boxes, spheres),
# converted in memory and through PLY/STL/OFF files on disk, checked against NumPy evaluated
# here (face normals by cross products, the sRGB curve by its formula, world positions by the
# node matrices). The missing-trimesh messages are checked with trimesh hidden, so they run
# whether or not it is installed.

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import vkpbr
from vkpbr.errors import SceneError, UsageError
from vkpbr.scene.loader import load_scene
from vkpbr.scene.validate import validate_scene

NEEDS_TRIMESH = "trimesh is not installed (pip install 'vkpbr[trimesh]')"


@pytest.fixture
def trimesh():  # noqa: ANN201
    return pytest.importorskip("trimesh", reason=NEEDS_TRIMESH)


def srgb_decode(c8: np.ndarray) -> np.ndarray:
    c = c8 / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def triangle_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    p = positions[indices.reshape(-1, 3)].astype(np.float64)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def world_triangles(scene: vkpbr.Scene) -> np.ndarray:
    """(T, 3, 3) world-space triangles of every node, sorted for order-free comparison."""
    tris = []
    for node in scene.nodes:
        mesh = scene.meshes[node.mesh]
        m = np.asarray(node.matrix, np.float64)
        p = mesh.positions.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
        tris.append(p[mesh.indices.reshape(-1, 3)])
    return canonical(np.concatenate(tris))


def canonical(tris: np.ndarray) -> np.ndarray:
    """Triangles as sorted rows of rounded corners: equal sets compare equal."""
    t = np.round(tris, 5)
    t = np.sort(t.view([("", t.dtype)] * 3).reshape(len(t), 3), axis=1).view(t.dtype).reshape(-1, 3, 3)
    return t[np.lexsort(t.reshape(len(t), -1).T[::-1])]


def test_box_gets_flat_normals_and_its_triangles(trimesh) -> None:  # noqa: ANN001
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    scene = vkpbr.Scene.from_trimesh(box, name="box")
    validate_scene(scene, "box")
    assert scene.name == "box" and len(scene.meshes) == len(scene.nodes) == 1
    mesh = scene.meshes[0]
    assert mesh.triangle_count == 12 and mesh.positions.dtype == np.float32
    np.testing.assert_allclose(scene.bounds()[0], (-0.5, -1.0, -1.5))
    np.testing.assert_allclose(scene.bounds()[1], (0.5, 1.0, 1.5))
    # Flat: every corner's normal is its triangle's (no smoothing across the box's edges).
    tri_n = triangle_normals(mesh.positions, mesh.indices)
    np.testing.assert_allclose(mesh.normals[mesh.indices.reshape(-1, 3)],
                               np.repeat(tri_n[:, None], 3, axis=1), atol=1e-6)
    np.testing.assert_allclose(world_triangles(scene), canonical(box.triangles))


def test_given_normals_are_kept(trimesh) -> None:  # noqa: ANN001
    sphere = trimesh.creation.icosphere(subdivisions=1)
    normals = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    sphere = trimesh.Trimesh(sphere.vertices, sphere.faces, vertex_normals=normals, process=False)
    mesh = vkpbr.Scene.from_trimesh(sphere).meshes[0]
    assert mesh.vertex_count == len(normals)  # not unwelded
    np.testing.assert_allclose(mesh.normals, normals, atol=1e-6)


def test_vertex_and_face_colours_are_decoded_to_linear(trimesh, rng) -> None:  # noqa: ANN001
    box = trimesh.creation.box()
    vc = rng.integers(0, 256, (len(box.vertices), 4), dtype=np.uint8)
    box.visual = trimesh.visual.ColorVisuals(box, vertex_colors=vc)
    mesh = vkpbr.Scene.from_trimesh(box).meshes[0]
    # Flat normals unweld the corners; each corner keeps its source vertex's colour.
    src = box.faces.reshape(-1)
    np.testing.assert_allclose(mesh.colors[:, :3], srgb_decode(vc[src, :3]), atol=1e-6)
    np.testing.assert_allclose(mesh.colors[:, 3], vc[src, 3] / 255.0, atol=1e-6)

    box = trimesh.creation.box()
    fc = rng.integers(0, 256, (len(box.faces), 4), dtype=np.uint8)
    box.visual = trimesh.visual.ColorVisuals(box, face_colors=fc)
    mesh = vkpbr.Scene.from_trimesh(box).meshes[0]
    per_corner = mesh.colors[mesh.indices].reshape(-1, 3, 4)
    np.testing.assert_allclose(per_corner[:, :, :3], np.repeat(srgb_decode(fc[:, None, :3]), 3, 1),
                               atol=1e-6)


def test_pbr_material_and_uvs(trimesh, rng) -> None:  # noqa: ANN001
    from PIL import Image
    from trimesh.visual.material import PBRMaterial

    base = Image.fromarray(rng.integers(0, 256, (4, 8, 3), dtype=np.uint8))
    mr = Image.fromarray(rng.integers(0, 256, (2, 2, 3), dtype=np.uint8))
    normal = Image.fromarray(rng.integers(0, 256, (2, 2, 3), dtype=np.uint8))
    mat = PBRMaterial(name="metal", baseColorFactor=[1.0, 0.5, 0.0, 0.8], metallicFactor=0.25,
                      roughnessFactor=0.75, emissiveFactor=[0.1, 0.2, 0.3], alphaMode="MASK",
                      alphaCutoff=0.3, doubleSided=True, baseColorTexture=base,
                      metallicRoughnessTexture=mr, normalTexture=normal)
    sphere = trimesh.creation.uv_sphere(count=[8, 8])
    uv = rng.random((len(sphere.vertices), 2))
    sphere.visual = trimesh.visual.TextureVisuals(uv=uv, material=mat)
    scene = vkpbr.Scene.from_trimesh(sphere)
    validate_scene(scene, "sphere")
    (m,) = scene.materials
    assert m.name == "metal" and scene.meshes[0].material == 0
    np.testing.assert_allclose(m.base_color_factor, (1.0, 128 / 255, 0.0, 204 / 255))  # trimesh keeps 8 bits
    assert (m.metallic_factor, m.roughness_factor) == (0.25, 0.75)
    np.testing.assert_allclose(m.emissive_factor, (0.1, 0.2, 0.3))
    assert (m.alpha_mode, m.alpha_cutoff, m.double_sided) == ("mask", 0.3, True)
    assert (m.metallic_texture.channel, m.roughness_texture.channel) == (2, 1)  # glTF: B, G
    assert m.metallic_texture.image == m.roughness_texture.image != m.base_color_texture.image
    assert m.occlusion_texture is None and m.emissive_texture is None
    assert len(scene.images) == 3
    px = scene.images[m.base_color_texture.image].pixels
    assert px.shape == (4, 8, 4)
    np.testing.assert_array_equal(px[..., :3], np.asarray(base))
    assert (px[..., 3] == 255).all()
    # UVs: v flipped to the top-left origin; flat normals unwelded the corners.
    mesh = scene.meshes[0]
    src = sphere.faces.reshape(-1)
    np.testing.assert_allclose(mesh.texcoords[:, 0], uv[src, 0], atol=1e-6)
    np.testing.assert_allclose(mesh.texcoords[:, 1], 1.0 - uv[src, 1], atol=1e-6)


def test_simple_material_goes_through_to_pbr(trimesh) -> None:  # noqa: ANN001
    from PIL import Image
    from trimesh.visual.material import SimpleMaterial

    img = Image.fromarray(np.full((2, 2, 3), 200, np.uint8))
    simple = SimpleMaterial(image=img, diffuse=[255, 128, 0, 255], glossiness=10.0)
    box = trimesh.creation.box()
    box.visual = trimesh.visual.TextureVisuals(uv=np.zeros((8, 2)), material=simple)
    (m,) = vkpbr.Scene.from_trimesh(box).materials
    pbr = simple.to_pbr()
    np.testing.assert_allclose(m.base_color_factor, np.asarray(pbr.baseColorFactor) / 255.0)
    assert m.roughness_factor == pytest.approx(pbr.roughnessFactor)
    assert m.base_color_texture is not None


def test_scene_nodes_share_a_mesh(trimesh) -> None:  # noqa: ANN001
    box = trimesh.creation.box()
    tscene = trimesh.Scene()
    shift = trimesh.transformations.translation_matrix([1.0, 2.0, 3.0])
    turn = trimesh.transformations.rotation_matrix(0.7, [0.0, 1.0, 0.0])
    tscene.add_geometry(box, node_name="a", geom_name="box", transform=shift)
    tscene.graph.update(frame_to="b", geometry="box", matrix=turn)  # a second instance
    tscene.add_geometry(trimesh.PointCloud(np.zeros((3, 3))), node_name="cloud")
    with pytest.warns(UserWarning, match="skipped 1 geometries without triangles"):
        scene = vkpbr.Scene.from_trimesh(tscene)
    assert len(scene.meshes) == 1 and [n.name for n in scene.nodes] == ["a", "b"]
    np.testing.assert_allclose(scene.nodes[0].matrix, shift, atol=1e-7)
    np.testing.assert_allclose(scene.nodes[1].matrix, turn, atol=1e-7)
    np.testing.assert_allclose(world_triangles(scene), canonical(tscene.triangles), atol=1e-5)


def test_scene_camera(trimesh) -> None:  # noqa: ANN001
    tscene = trimesh.Scene(trimesh.creation.box())
    tscene.camera.fov = (60.0, 45.0)
    pose = np.eye(4)
    pose[:3, 3] = (0.0, 0.0, 5.0)
    tscene.camera_transform = pose
    (cam,) = vkpbr.Scene.from_trimesh(tscene).cameras
    np.testing.assert_allclose(cam.eye, (0.0, 0.0, 5.0))
    np.testing.assert_allclose(np.subtract(cam.target, cam.eye), (0.0, 0.0, -1.0), atol=1e-12)
    assert cam.yfov_deg == pytest.approx(45.0)


@pytest.mark.parametrize("suffix", [".ply", ".stl", ".off"])
def test_load_scene_reads_mesh_files_through_trimesh(trimesh, tmp_path: Path, suffix: str) -> None:  # noqa: ANN001
    box = trimesh.creation.box(extents=(2.0, 1.0, 0.5))
    path = tmp_path / f"box{suffix}"
    data = box.export(file_type=suffix[1:])
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    scene = load_scene(path)
    assert scene.source == path and scene.name == "box"
    np.testing.assert_allclose(world_triangles(scene), canonical(box.triangles), atol=1e-6)
    mesh = scene.meshes[0]
    tri_n = triangle_normals(mesh.positions, mesh.indices)
    np.testing.assert_allclose(mesh.normals[mesh.indices.reshape(-1, 3)][:, 0], tri_n, atol=1e-6)


def test_ply_colours_and_normals_from_the_file(trimesh, tmp_path: Path, rng) -> None:  # noqa: ANN001
    sphere = trimesh.creation.icosphere(subdivisions=1)
    normals = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    vc = rng.integers(0, 256, (len(sphere.vertices), 4), dtype=np.uint8)
    sphere = trimesh.Trimesh(sphere.vertices, sphere.faces, vertex_normals=normals,
                             vertex_colors=vc, process=False)
    (tmp_path / "s.ply").write_bytes(sphere.export(file_type="ply", vertex_normal=True))
    mesh = load_scene(tmp_path / "s.ply").meshes[0]
    np.testing.assert_allclose(mesh.normals, normals, atol=1e-6)
    np.testing.assert_allclose(mesh.colors[:, :3], srgb_decode(vc[:, :3]), atol=1e-6)


def test_malformed_file_is_one_line(trimesh, tmp_path: Path) -> None:  # noqa: ANN001
    path = tmp_path / "bad.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99\nend_header\n\x00")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_unknown_suffix_with_trimesh(trimesh, tmp_path: Path) -> None:  # noqa: ANN001
    path = tmp_path / "a.xyzw"
    path.write_bytes(b"x")
    with pytest.raises(SceneError, match=r"unknown scene format '.xyzw' \(known: .gltf.*through trimesh .*\.ply"):
        load_scene(path)


def test_without_trimesh_the_error_names_the_file_and_the_install(tmp_path: Path,
                                                                  monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setitem(sys.modules, "trimesh", None)  # `import trimesh` raises ImportError
    path = tmp_path / "box.ply"
    path.write_bytes(b"ply\n")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    text = str(info.value)
    assert text == (f"{path}: .ply files load through trimesh, which is not installed: "
                    "pip install 'vkpbr[trimesh]'")
    with pytest.raises(SceneError, match=r"unknown scene format '.foo' \(known: .gltf, .glb, .obj, "
                                         r"\.comp5822mesh, \.vkpbr\)$"):
        (tmp_path / "a.foo").write_bytes(b"x")
        load_scene(tmp_path / "a.foo")
    with pytest.raises(UsageError, match=r"from_trimesh needs trimesh: pip install 'vkpbr\[trimesh\]'"):
        vkpbr.Scene.from_trimesh(object())


def test_not_a_trimesh_object(trimesh) -> None:  # noqa: ANN001
    with pytest.raises(UsageError, match="expected a trimesh.Trimesh or trimesh.Scene, got list"):
        vkpbr.Scene.from_trimesh([1, 2])
    with pytest.raises(UsageError, match="nothing with triangles"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        vkpbr.Scene.from_trimesh(trimesh.Scene())


def test_ply_texture_goes_through_the_path_policy(trimesh, tmp_path: Path, rng) -> None:  # noqa: ANN001
    from PIL import Image

    texel = rng.integers(0, 256, (2, 2, 3), dtype=np.uint8)
    box = trimesh.creation.box()
    box.visual = trimesh.visual.TextureVisuals(uv=rng.random((8, 2)), image=Image.fromarray(texel))
    data = box.export(file_type="ply")
    (tmp_path / "sub").mkdir()
    Image.fromarray(texel).save(tmp_path / "sub" / "inside.png")
    Image.fromarray(texel).save(tmp_path / "outside.png")
    for name in ("inside.png", "../outside.png"):
        text = data.replace(b"end_header", f"comment TextureFile {name}\nend_header".encode(), 1)
        (tmp_path / "sub" / "box.ply").write_bytes(text)
        if name == "inside.png":
            scene = load_scene(tmp_path / "sub" / "box.ply")
            (m,) = scene.materials
            np.testing.assert_array_equal(scene.images[m.base_color_texture.image].pixels[..., :3],
                                          texel)
        else:
            with pytest.warns(UserWarning, match=r"1 texture file\(s\) not read: \.\./outside\.png "
                                                 r"\(outside the scene's folder\)"):
                scene = load_scene(tmp_path / "sub" / "box.ply")
            assert not any(np.array_equal(img.pixels[..., :3], texel) for img in scene.images)


def test_nested_nodes_get_world_transforms(trimesh) -> None:  # noqa: ANN001
    tscene = trimesh.Scene()
    parent = trimesh.transformations.rotation_matrix(0.5, [0.0, 0.0, 1.0])
    parent[:3, 3] = (3.0, 0.0, 0.0)
    child = trimesh.transformations.scale_and_translate(2.0, (0.0, 1.0, 0.0))
    tscene.graph.update(frame_from=tscene.graph.base_frame, frame_to="parent", matrix=parent)
    tscene.add_geometry(trimesh.creation.box(), node_name="child", geom_name="box",
                        parent_node_name="parent", transform=child)
    scene = vkpbr.Scene.from_trimesh(tscene)
    (node,) = scene.nodes
    np.testing.assert_allclose(node.matrix, parent @ child, atol=1e-6)
    np.testing.assert_allclose(world_triangles(scene), canonical(tscene.triangles), atol=1e-5)
