"""UV sets and texture transforms without a GPU: the glTF loader keeps every texture's own
texCoord and KHR_texture_transform, and the bake keeps them (and TEXCOORD_1) through a file,
generates tangents from the normal texture's set, and counts TEXCOORD_1's bytes."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import numpy as np
import pytest

from vkpbr.bake.bake import bake_report, bake_scene
from vkpbr.bake.tangents import tangent_uv_set
from vkpbr.errors import SceneError
from vkpbr.scene.baked_file import load_baked_scene, write_baked
from vkpbr.scene.gltf import load_gltf
from vkpbr.scene.types import Image, Material, Mesh, Node, Scene, TextureRef

XF = "KHR_texture_transform"


def write_gltf(path: Path, material: dict, texcoord1: bool = True) -> Path:
    """One triangle with TEXCOORD_0 (and TEXCOORD_1), five textures over one image, `material`."""
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    uv0 = np.array([[0, 0], [1, 0], [0, 1]], np.float32)
    uv1 = np.array([[0.5, 0.5], [0.25, 0.5], [0.5, 0.75]], np.float32)
    blob = pos.tobytes() + uv0.tobytes() + (uv1.tobytes() if texcoord1 else b"")
    views = [{"buffer": 0, "byteOffset": o, "byteLength": n} for o, n in ((0, 36), (36, 24), (60, 24))]
    accessors = [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]},
                 {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
                 {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}]
    attributes = {"POSITION": 0, "TEXCOORD_0": 1, **({"TEXCOORD_1": 2} if texcoord1 else {})}
    doc = {
        "asset": {"version": "2.0"}, "extensionsUsed": [XF],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": views if texcoord1 else views[:2],
        "accessors": accessors if texcoord1 else accessors[:2],
        "images": [{"uri": "data:image/png;base64,iVBORw0KGgo="}],
        "textures": [{"source": 0}],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": attributes, "material": 0}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}],
    }
    path.write_text(json.dumps(doc))
    return path


def info(texcoord: int | None = None, **transform: object) -> dict:
    out: dict = {"index": 0}
    if texcoord is not None:
        out["texCoord"] = texcoord
    if transform:
        out["extensions"] = {XF: transform}
    return out


def test_each_texture_info_keeps_its_own_texcoord_and_transform(tmp_path: Path) -> None:
    material = {
        "pbrMetallicRoughness": {
            "baseColorTexture": info(1, offset=[0.1, 0.2], rotation=0.3, scale=[1.5, 0.75]),
            "metallicRoughnessTexture": info(0, scale=[2, 2]),
        },
        "normalTexture": info(1),
        "occlusionTexture": info(offset=[0.3, 0.6]),  # texCoord absent: 0
        # The extension's texCoord overrides the textureInfo's (KHR_texture_transform).
        "emissiveTexture": info(0, rotation=1.0, texCoord=1),
    }
    scene = load_gltf(write_gltf(tmp_path / "sets.gltf", material))
    m = scene.meshes[0]
    assert m.texcoords1 is not None
    np.testing.assert_array_equal(m.texcoords1, [[0.5, 0.5], [0.25, 0.5], [0.5, 0.75]])
    mat = scene.materials[0]

    def ref(slot: str) -> tuple:
        r = getattr(mat, f"{slot}_texture")
        return r.texcoord, r.offset, r.rotation, r.scale

    assert ref("base_color") == (1, (0.1, 0.2), 0.3, (1.5, 0.75))
    assert ref("metallic") == ref("roughness") == (0, (0.0, 0.0), 0.0, (2.0, 2.0))
    assert ref("normal") == (1, (0.0, 0.0), 0.0, (1.0, 1.0))
    assert ref("occlusion") == (0, (0.3, 0.6), 0.0, (1.0, 1.0))
    assert ref("emissive") == (1, (0.0, 0.0), 1.0, (1.0, 1.0))
    assert (mat.metallic_texture.channel, mat.roughness_texture.channel) == (2, 1)


def test_mesh_without_texcoord1_has_none(tmp_path: Path) -> None:
    scene = load_gltf(write_gltf(tmp_path / "one.gltf", {}, texcoord1=False))
    assert scene.meshes[0].texcoords1 is None and scene.meshes[0].texcoords is not None


@pytest.mark.parametrize("where", ["info", "extension"])
def test_texcoord_beyond_1_is_refused(tmp_path: Path, where: str) -> None:
    tex = info(2) if where == "info" else info(0, texCoord=2)
    with pytest.raises(SceneError, match="texCoord 2"):
        load_gltf(write_gltf(tmp_path / "bad.gltf", {"normalTexture": tex}))


@pytest.mark.parametrize("value", [[0.5], "x", [0, "a"]])
def test_malformed_transform_is_refused(tmp_path: Path, value: object) -> None:
    with pytest.raises(SceneError):
        load_gltf(write_gltf(tmp_path / "bad.gltf", {"occlusionTexture": info(offset=value)}))


# --- the bake -------------------------------------------------------------------------------
def quad(uv1: bool, material: int = 0) -> Mesh:
    """A unit quad facing +Z, no tangents; TEXCOORD_1 is TEXCOORD_0 turned a quarter."""
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    uv0 = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
    return Mesh("quad", pos, np.array([0, 1, 2, 0, 2, 3], np.uint32),
                normals=np.tile(np.float32([0, 0, 1]), (4, 1)), texcoords=uv0,
                texcoords1=np.stack([1 - uv0[:, 1], uv0[:, 0]], 1) if uv1 else None, material=material)


def two_quad_scene(normal_set: int) -> Scene:
    refs = {"base_color_texture": TextureRef(0, texcoord=1, offset=(0.5, 0.25), rotation=0.7, scale=(2, 3)),
            "normal_texture": TextureRef(0, texcoord=normal_set, rotation=-0.2),
            "occlusion_texture": TextureRef(0, texcoord=0, scale=(4, 4))}
    return Scene("quads", meshes=[quad(True), quad(False)], materials=[Material(**refs)],
                 images=[Image("grid", pixels=np.full((2, 2, 4), 200, np.uint8))],
                 nodes=[Node(0), Node(1)])


def test_bake_round_trip_keeps_sets_transforms_and_texcoord1(tmp_path: Path) -> None:
    source = two_quad_scene(normal_set=1)
    path = tmp_path / "q.vkpbr"
    write_baked(path, bake_scene(source))
    back = load_baked_scene(path)
    for slot in ("base_color", "normal", "occlusion"):
        a, b = getattr(back.materials[0], f"{slot}_texture"), getattr(source.materials[0], f"{slot}_texture")
        assert (a.texcoord, a.offset, a.rotation, a.scale) == (b.texcoord, b.offset, b.rotation, b.scale), slot
    with_uv1, without = back.meshes
    assert without.texcoords1 is None  # zeros in the file's stream, but flagged as absent
    # The bake reorders vertices: match TEXCOORD_1 to TEXCOORD_0 per vertex.
    np.testing.assert_array_equal(with_uv1.texcoords1, np.stack([1 - with_uv1.texcoords[:, 1],
                                                                 with_uv1.texcoords[:, 0]], 1))


@pytest.mark.parametrize("normal_set", [0, 1])
def test_bake_generates_tangents_from_the_normal_textures_set(normal_set: int) -> None:
    """TEXCOORD_0's u grows along +X, TEXCOORD_1's along +Y; the mesh without TEXCOORD_1
    falls back to TEXCOORD_0 (+X) as the renderer's fill does."""
    baked = bake_scene(two_quad_scene(normal_set))
    t = baked.streams["tangents"]
    first = baked.mesh_table["first_vertex"]
    along = np.float32([0, 1, 0]) if normal_set == 1 else np.float32([1, 0, 0])
    np.testing.assert_allclose(t[first[0]:first[1], :3], np.tile(along, (4, 1)), atol=1e-6)
    np.testing.assert_allclose(t[first[1]:, :3], np.tile(np.float32([1, 0, 0]), (4, 1)), atol=1e-6)


def test_tangent_uv_set() -> None:
    assert tangent_uv_set(None) == 0 and tangent_uv_set(Material()) == 0
    assert tangent_uv_set(Material(normal_texture=TextureRef(0, texcoord=1))) == 1
    assert tangent_uv_set(Material(base_color_texture=TextureRef(0, texcoord=1))) == 0


def test_report_counts_texcoord1_only_when_baked() -> None:
    with_uv1 = two_quad_scene(0)
    without = Scene("plain", meshes=[quad(False)], materials=[Material()], nodes=[Node(0)])
    r1 = bake_report(with_uv1, bake_scene(with_uv1))["bytes_per_vertex"]
    r0 = bake_report(without, bake_scene(without))["bytes_per_vertex"]
    assert r0 == {"vectors": 48, "quat": 36, "packed": 24}
    assert r1 == {"vectors": 56, "quat": 44, "packed": 32}
