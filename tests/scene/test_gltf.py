# Tests of the glTF loader: every sample asset, then small synthetic files (written here) whose
# exact expected arrays are known: GLB, data URIs, byteStride, sparse, normalized, strip/fan,
# matrix + TRS hierarchies, materials, cameras, lights, and bad inputs that must raise SceneError.

from __future__ import annotations

import base64
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.geometry import auto_camera
from vkpbr.scene.gltf import load_gltf
from vkpbr.scene.loader import load_scene

TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)


class GltfBuilder:
    """Builds a glTF document and its binary buffer for tests (no pygltflib involved)."""

    def __init__(self) -> None:
        self.bin = bytearray()
        self.doc: dict = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [],
                          "accessors": [], "meshes": [], "nodes": [], "scenes": [{"nodes": []}]}  # fmt: skip

    def view(self, data: bytes, stride: int | None = None) -> int:
        self.bin += b"\0" * (-len(self.bin) % 4)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            view["byteStride"] = stride
        self.bin += data
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, arr: np.ndarray, ctype: int, atype: str, **extra: object) -> int:
        arr = np.asarray(arr)
        acc = {"bufferView": self.view(arr.tobytes()), "componentType": ctype,
               "count": len(arr), "type": atype, **extra}  # fmt: skip
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def mesh(self, attributes: dict, indices: int | None = None, **prim: object) -> int:
        p = {"attributes": attributes, **prim}
        if indices is not None:
            p["indices"] = indices
        self.doc["meshes"].append({"primitives": [p]})
        return len(self.doc["meshes"]) - 1

    def node(self, root: bool = True, **fields: object) -> int:
        self.doc["nodes"].append(fields)
        if root:
            self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def triangle(self) -> int:
        pos = self.accessor(TRI, 5126, "VEC3")
        idx = self.accessor(np.array([0, 1, 2], np.uint16), 5123, "SCALAR")
        return self.mesh({"POSITION": pos}, idx)

    def save(self, path: Path, kind: str = "glb") -> Path:
        """kind: 'glb', 'datauri' (.gltf with embedded buffer) or 'bin' (.gltf + .bin file)."""
        doc = json.loads(json.dumps(self.doc))
        doc["buffers"] = [{"byteLength": len(self.bin)}]
        if kind == "datauri":
            uri = "data:application/octet-stream;base64," + base64.b64encode(self.bin).decode()
            doc["buffers"][0]["uri"] = uri
        elif kind == "bin":
            (path.parent / (path.stem + ".bin")).write_bytes(bytes(self.bin))
            doc["buffers"][0]["uri"] = path.stem + ".bin"
        text = json.dumps(doc).encode()
        if kind == "glb":
            text += b" " * (-len(text) % 4)
            data = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
            body = struct.pack("<II", len(text), 0x4E4F534A) + text
            body += struct.pack("<II", len(data), 0x004E4942) + data
            path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
        else:
            path.write_bytes(text)
        return path


# -- sample assets ----------------------------------------------------------------------------


def test_every_sample_model_loads(assets: Path) -> None:
    files = sorted(assets.glob("*/glTF*/*.gltf"))
    assert len(files) >= 9
    for f in files:
        scene = load_scene(f)
        assert scene.triangle_count > 0, f
        for m in scene.meshes:
            assert m.normals is not None and m.normals.dtype == np.float32
            assert m.indices.dtype == np.uint32 and int(m.indices.max()) < m.vertex_count


def test_boombox_specgloss_folder_reads_the_extension(assets: Path) -> None:
    """KHR_materials_pbrSpecularGlossiness wins over the metallic-roughness fallback: the
    diffuse texture is the base colour, the specular-glossiness texture's RGB the specular
    colour and its A the glossiness (roughness = 1 - glossiness), metallic 0."""
    scene = load_gltf(assets / "BoomBox/glTF-pbrSpecularGlossiness/BoomBox.gltf")
    mat = scene.materials[0]
    names = [Path(scene.images[t.image].name).name
             for t in (mat.base_color_texture, mat.roughness_texture, mat.specular_color_texture)]
    assert names == ["BoomBox_diffuse.png", "BoomBox_specularGlossiness.png",
                     "BoomBox_specularGlossiness.png"]
    assert mat.glossiness and mat.roughness_texture.channel == 3
    assert mat.metallic_factor == 0.0 and mat.metallic_texture is None
    assert mat.specular_color_factor == (25.0, 25.0, 25.0)  # F0 = 0.04 x 25 x texel
    assert mat.occlusion_texture is not None and mat.emissive_texture is not None


def test_orientation_test_transforms(assets: Path) -> None:
    scene = load_gltf(assets / "OrientationTest/glTF/OrientationTest.gltf")
    doc = json.loads((assets / "OrientationTest/glTF/OrientationTest.gltf").read_text())
    by_name = {n.name: n.matrix for n in scene.nodes}
    for node in doc["nodes"]:
        m = by_name[node["name"]]
        assert m.dtype == np.float32 and m.shape == (4, 4)
        if "matrix" in node:
            np.testing.assert_allclose(m, np.array(node["matrix"]).reshape(4, 4).T, atol=1e-6)
        else:
            assert np.allclose(m[:3, 3], node.get("translation", [0, 0, 0]), atol=1e-6)
            r = m[:3, :3].astype(np.float64)  # rotation (no scale in this model)
            np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-5)


def test_alpha_blend_mode_test_modes_and_cutoffs(assets: Path) -> None:
    scene = load_gltf(assets / "AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf")
    modes = sorted((m.alpha_mode, round(m.alpha_cutoff, 3)) for m in scene.materials)
    assert modes == [("blend", 0.5), ("mask", 0.25), ("mask", 0.5), ("mask", 0.75),
                     ("opaque", 0.5), ("opaque", 0.5)]  # fmt: skip
    assert sum(m.double_sided for m in scene.materials) == 5


def test_normal_tangent_mirror_tangents_are_read(assets: Path) -> None:
    scene = load_gltf(assets / "NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf")
    t = scene.meshes[0].tangents
    assert t is not None and t.shape == (scene.meshes[0].vertex_count, 4)
    assert set(np.unique(t[:, 3]).tolist()) == {-1.0, 1.0}  # mirrored UVs present


def test_normal_tangent_test_has_no_tangents(assets: Path) -> None:
    scene = load_gltf(assets / "NormalTangentTest/glTF/NormalTangentTest.gltf")
    assert all(m.tangents is None for m in scene.meshes)


def test_sponza(assets: Path) -> None:
    scene = load_scene(assets / "Sponza/glTF/Sponza.gltf")
    assert scene.triangle_count == 262_267
    masked = [m for m in scene.materials if m.alpha_mode == "mask"]
    assert len(masked) == 3 and all(m.double_sided and m.alpha_cutoff == 0.5 for m in masked)
    assert len(scene.images) == 69 and all(img.path.is_file() for img in scene.images)
    lo, hi = scene.bounds()
    np.testing.assert_allclose(lo, [-15.37, -1.01, -9.46], atol=0.01)
    np.testing.assert_allclose(hi, [14.40, 11.44, 8.84], atol=0.01)
    cam = auto_camera(scene)
    assert cam.znear is None and cam.zfar is None  # chosen per render (reversed-Z)


# -- synthetic files --------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["glb", "datauri", "bin"])
def test_triangle_all_containers(tmp_path: Path, kind: str) -> None:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    scene = load_gltf(b.save(tmp_path / ("t.glb" if kind == "glb" else "t.gltf"), kind))
    (mesh,) = scene.meshes
    np.testing.assert_array_equal(mesh.positions, TRI)
    np.testing.assert_array_equal(mesh.indices, [0, 1, 2])  # flat normals: already unwelded
    np.testing.assert_array_equal(mesh.normals, np.tile([0, 0, 1], (3, 1)))
    assert mesh.material == -1 and scene.nodes[0].mesh == 0


def test_flat_normals_unweld_shared_vertices(tmp_path: Path) -> None:
    b = GltfBuilder()
    quad = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1]], np.float32)
    pos = b.accessor(quad, 5126, "VEC3")
    idx = b.accessor(np.array([0, 1, 2, 0, 2, 3], np.uint8), 5121, "SCALAR")
    b.node(mesh=b.mesh({"POSITION": pos}, idx))
    mesh = load_gltf(b.save(tmp_path / "q.glb")).meshes[0]
    np.testing.assert_array_equal(mesh.positions, quad[[0, 1, 2, 0, 2, 3]])
    np.testing.assert_array_equal(mesh.indices, np.arange(6))
    second = np.cross(quad[2] - quad[0], quad[3] - quad[0])
    np.testing.assert_allclose(mesh.normals[3:], np.tile(second / np.linalg.norm(second), (3, 1)))


def test_interleaved_byte_stride(tmp_path: Path) -> None:
    b = GltfBuilder()
    uv = np.array([[0, 0], [1, 0], [0, 1]], np.float32)
    inter = np.concatenate([TRI, uv], axis=1).astype(np.float32)  # 20-byte records
    view = b.view(inter.tobytes(), stride=20)
    b.doc["accessors"] += [
        {"bufferView": view, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": view, "byteOffset": 12, "componentType": 5126, "count": 3, "type": "VEC2"},
    ]
    b.node(mesh=b.mesh({"POSITION": 0, "TEXCOORD_0": 1}))
    mesh = load_gltf(b.save(tmp_path / "s.gltf", "datauri")).meshes[0]
    np.testing.assert_array_equal(mesh.positions, TRI)
    np.testing.assert_array_equal(mesh.texcoords, uv)


def test_sparse_accessor(tmp_path: Path) -> None:
    b = GltfBuilder()
    sparse = {"count": 1,
              "indices": {"bufferView": b.view(np.array([2], np.uint8).tobytes()), "componentType": 5121},
              "values": {"bufferView": b.view(np.array([5, 6, 7], np.float32).tobytes())}}  # fmt: skip
    pos = b.accessor(TRI, 5126, "VEC3", sparse=sparse)
    zero = {"componentType": 5126, "count": 3, "type": "VEC3", "sparse": sparse}
    b.doc["accessors"].append(zero)  # sparse on zeros, no bufferView
    b.node(mesh=b.mesh({"POSITION": pos, "NORMAL": 1}))
    mesh = load_gltf(b.save(tmp_path / "sp.glb")).meshes[0]
    np.testing.assert_array_equal(mesh.positions, [[0, 0, 0], [1, 0, 0], [5, 6, 7]])
    np.testing.assert_array_equal(mesh.normals, [[0, 0, 0], [0, 0, 0], [5, 6, 7]])


def test_normalized_components(tmp_path: Path) -> None:
    b = GltfBuilder()
    pos = b.accessor(TRI, 5126, "VEC3")
    uv = b.accessor(
        np.array([[0, 255], [128, 51], [255, 0]], np.uint8), 5121, "VEC2", normalized=True
    )
    uv1 = b.accessor(
        np.array([[0, 65535], [1, 2], [3, 4]], np.uint16), 5123, "VEC2", normalized=True
    )
    col = b.accessor(np.array([[-128, 127, 0], [-127, 64, 1], [0, 0, 0]], np.int8), 5120, "VEC3",
                     normalized=True)  # fmt: skip
    b.node(mesh=b.mesh({"POSITION": pos, "TEXCOORD_0": uv, "TEXCOORD_1": uv1, "COLOR_0": col}))
    mesh = load_gltf(b.save(tmp_path / "n.glb")).meshes[0]
    np.testing.assert_allclose(mesh.texcoords, np.array([[0, 255], [128, 51], [255, 0]]) / 255)
    np.testing.assert_allclose(mesh.texcoords1, np.array([[0, 65535], [1, 2], [3, 4]]) / 65535)
    np.testing.assert_allclose(mesh.colors[:, :3], [[-1, 1, 0], [-1, 64 / 127, 1 / 127], [0, 0, 0]])
    np.testing.assert_array_equal(mesh.colors[:, 3], 1.0)


@pytest.mark.parametrize(("mode", "expected"), [(5, [0, 1, 2, 1, 3, 2, 2, 3, 4]),
                                                (6, [1, 2, 0, 2, 3, 0, 3, 4, 0])])  # fmt: skip
def test_strip_and_fan(tmp_path: Path, mode: int, expected: list[int]) -> None:
    b = GltfBuilder()
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], np.float32)
    pos = b.accessor(pts, 5126, "VEC3")
    nrm = b.accessor(np.tile(np.float32([0, 0, 1]), (5, 1)), 5126, "VEC3")
    idx = b.accessor(np.arange(5, dtype=np.uint32), 5125, "SCALAR")
    b.node(mesh=b.mesh({"POSITION": pos, "NORMAL": nrm}, idx, mode=mode))
    np.testing.assert_array_equal(
        load_gltf(b.save(tmp_path / "st.glb")).meshes[0].indices, expected
    )


def test_matrix_and_trs_hierarchy(tmp_path: Path) -> None:
    b = GltfBuilder()
    mesh = b.triangle()
    parent_m = np.eye(4)
    parent_m[:3, 3] = [1, 2, 3]
    child = b.node(
        root=False,
        mesh=mesh,
        translation=[0, 0, 1],
        scale=[2, 2, 2],
        rotation=[0, math.sin(math.pi / 4), 0, math.cos(math.pi / 4)],
    )  # 90 deg about Y
    b.node(matrix=parent_m.T.reshape(-1).tolist(), children=[child])
    scene = load_gltf(b.save(tmp_path / "h.glb"))
    expected = np.array([[0, 0, 2, 1], [0, 2, 0, 2], [-2, 0, 0, 4], [0, 0, 0, 1]], np.float32)
    np.testing.assert_allclose(scene.nodes[0].matrix, expected, atol=1e-6)
    assert scene.nodes[0].matrix.dtype == np.float32


def test_materials_samplers_texture_transform(tmp_path: Path) -> None:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    b.doc["images"] = [
        {"uri": "missing.png"},
        {"bufferView": b.view(b"\x89PNG fake"), "mimeType": "image/png"},
    ]
    b.doc["samplers"] = [{"wrapS": 33071, "wrapT": 33648, "magFilter": 9728, "minFilter": 9729}]
    b.doc["textures"] = [{"source": 0, "sampler": 0}, {"source": 1}]
    xf = {
        "KHR_texture_transform": {
            "offset": [0.5, 0.25],
            "rotation": 1.5,
            "scale": [2, 3],
            "texCoord": 1,
        }
    }
    b.doc["extensionsUsed"] = b.doc["extensionsRequired"] = [
        "KHR_texture_transform",
        "KHR_materials_emissive_strength",
    ]
    b.doc["materials"] = [{
        "pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0.25, 0.75], "metallicFactor": 0.3,
                                 "roughnessFactor": 0.6, "baseColorTexture": {"index": 0, "extensions": xf},
                                 "metallicRoughnessTexture": {"index": 1}},
        "normalTexture": {"index": 1, "scale": 0.5}, "occlusionTexture": {"index": 1, "strength": 0.8},
        "emissiveTexture": {"index": 1}, "emissiveFactor": [1, 0.5, 0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
        "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True}]  # fmt: skip
    scene = load_gltf(b.save(tmp_path / "m.gltf", "bin"))  # missing.png: see test_missing_textures
    m = scene.materials[0]
    assert (
        scene.images[0].path == tmp_path / "missing.png" and scene.images[1].data == b"\x89PNG fake"
    )
    assert m.base_color_factor == (1, 0.5, 0.25, 0.75) and (
        m.metallic_factor,
        m.roughness_factor,
    ) == (0.3, 0.6)
    bc = m.base_color_texture
    assert (bc.offset, bc.rotation, bc.scale, bc.texcoord) == ((0.5, 0.25), 1.5, (2, 3), 1)
    s = bc.sampler
    assert (s.wrap_s, s.wrap_t, s.mag_filter, s.min_filter, s.mipmaps) == (
        "clamp",
        "mirror",
        "nearest",
        "linear",
        False,
    )
    assert (m.metallic_texture.channel, m.roughness_texture.channel, m.metallic_texture.image) == (
        2,
        1,
        1,
    )
    assert (
        m.normal_scale == 0.5
        and m.occlusion_strength == pytest.approx(0.8)
        and m.occlusion_texture.channel == 0
    )
    assert (
        m.emissive_factor == (4, 2, 0)
        and m.alpha_mode == "mask"
        and m.alpha_cutoff == pytest.approx(0.3)
    )
    assert m.double_sided and m.alpha_texture is None


def test_camera_and_lights(tmp_path: Path) -> None:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["cameras"] = [
        {"type": "perspective", "perspective": {"yfov": math.radians(50), "znear": 0.05}},
        {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.2, "zfar": 80}},
        {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 2, "zfar": 1}},  # invalid
        {"type": "perspective", "perspective": {"yfov": 0.5}},  # znear missing (required)
    ]
    b.node(camera=0, translation=[0, 1, 5])
    for k in (1, 2, 3):
        b.node(camera=k)
    b.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    b.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 0.5, 0.5], "intensity": 20, "range": 9},
        {"type": "directional", "intensity": 3},
        {"type": "spot", "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.4}}]}}  # fmt: skip
    b.node(translation=[1, 2, 3], extensions={"KHR_lights_punctual": {"light": 0}})
    b.node(extensions={"KHR_lights_punctual": {"light": 1}})
    # A spot at (0, 4, 0) turned to look down: rotation -90 degrees about +X maps -Z to -Y.
    half = math.sqrt(0.5)
    b.node(translation=[0, 4, 0], rotation=[-half, 0, 0, half],
           extensions={"KHR_lights_punctual": {"light": 2}})
    scene = load_gltf(b.save(tmp_path / "c.glb"))
    cam, finite, invalid, no_near = scene.cameras
    assert cam.eye == (0, 1, 5) and cam.target == (0, 1, 4) and cam.up == (0, 1, 0)
    # The file's znear is kept; no zfar means glTF's infinite projection: None, not a marker.
    assert cam.yfov_deg == pytest.approx(50) and cam.znear == 0.05 and cam.zfar is None
    assert (finite.znear, finite.zfar) == (0.2, 80.0)
    assert (invalid.znear, invalid.zfar) == (2.0, None)  # zfar <= znear: dropped, not fatal
    assert (no_near.znear, no_near.zfar) == (None, None)  # the renderer derives it
    point, sun, spot = scene.lights
    assert point.position == (1, 2, 3) and point.falloff == "inverse_square" and point.range == 9
    assert point.color == (1, 0.5, 0.5) and point.intensity == 20 and point.kind == "point"
    # KHR_lights_punctual: the light shines along its node's -Z; lux for directional lights.
    assert sun.kind == "directional" and sun.direction == (0, 0, -1) and sun.intensity == 3
    assert spot.kind == "spot" and spot.position == (0, 4, 0)
    assert spot.direction == pytest.approx((0, -1, 0), abs=1e-6)
    assert (spot.inner_cone, spot.outer_cone) == (0.1, 0.4)


def test_nan_positions_dropped_with_warning(tmp_path: Path) -> None:
    b = GltfBuilder()
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 0]], np.float32)
    pos = b.accessor(pts, 5126, "VEC3")
    idx = b.accessor(np.array([0, 1, 2, 0, 1, 3], np.uint16), 5123, "SCALAR")
    b.node(mesh=b.mesh({"POSITION": pos}, idx))
    with pytest.warns(UserWarning, match="non-finite"):
        scene = load_gltf(b.save(tmp_path / "nan.glb"))
    assert scene.triangle_count == 1 and np.isfinite(scene.bounds()[0]).all()


# -- bad input --------------------------------------------------------------------------------


def _bad(b: GltfBuilder, tmp_path: Path, match: str, kind: str = "glb") -> None:
    path = b.save(tmp_path / ("bad.glb" if kind == "glb" else "bad.gltf"), kind)
    with pytest.raises(SceneError, match=match) as info:
        load_scene(path)
    assert path.name in str(info.value)


def test_points_mode_rejected(tmp_path: Path) -> None:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["meshes"][0]["primitives"][0]["mode"] = 0
    _bad(b, tmp_path, "POINTS")


def test_unsupported_required_extension(tmp_path: Path) -> None:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    b.doc["extensionsRequired"] = ["KHR_lights_punctual", "EXT_lights_image_based"]
    _bad(b, tmp_path, "unsupported extension.*EXT_lights_image_based")


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda d: d["accessors"][1].update(count=3000), "count"),
        (lambda d: d["bufferViews"][0].update(byteLength=10_000), "exceeds its buffer"),
        (lambda d: d["accessors"][0].update(componentType=5130), "componentType"),
        (lambda d: d["meshes"][0]["primitives"][0].update(indices=9), "accessor 9"),
        (lambda d: d["nodes"][0].update(children=[0]), "reached twice"),
        (lambda d: d["nodes"][0].update(matrix=[1, 2, "x"]), "matrix"),
        (lambda d: d.update(materials=[None]), r"materials\[0\] is not an object"),
        (lambda d: d.update(nodes={"a": 1}), "nodes is not a list"),
        (lambda d: d["nodes"][0].update(matrix=[1, 2, 3]), "matrix"),
        (lambda d: d["asset"].update(version="1.0"), "version"),
        (lambda d: d["meshes"][0]["primitives"][0].update(material=4), "material"),
    ],
)
def test_bad_documents(tmp_path: Path, edit, match: str) -> None:  # noqa: ANN001
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    edit(b.doc)
    _bad(b, tmp_path, match)


def test_index_out_of_range(tmp_path: Path) -> None:
    b = GltfBuilder()
    pos = b.accessor(TRI, 5126, "VEC3")
    idx = b.accessor(np.array([0, 1, 3], np.uint16), 5123, "SCALAR")
    b.node(mesh=b.mesh({"POSITION": pos}, idx))
    _bad(b, tmp_path, "index 3 >= vertex count 3")


def test_truncated_and_malformed_files(tmp_path: Path) -> None:
    b = GltfBuilder()
    b.node(mesh=b.triangle())
    glb = b.save(tmp_path / "ok.glb").read_bytes()
    for cut in range(0, len(glb), 7):
        (tmp_path / "cut.glb").write_bytes(glb[:cut])
        with pytest.raises(SceneError, match="cut.glb"):
            load_gltf(tmp_path / "cut.glb")
    path = b.save(tmp_path / "t.gltf", "bin")
    (tmp_path / "t.bin").write_bytes(b.bin[:-2])
    with pytest.raises(SceneError, match="truncated"):
        load_gltf(path)
    (tmp_path / "t.bin").unlink()
    with pytest.raises(SceneError, match="t.bin"):
        load_gltf(path)
    (tmp_path / "j.gltf").write_text('{"asset": {"version": "2.0"}, "nodes": [')
    with pytest.raises(SceneError, match="j.gltf.*JSON"):
        load_gltf(tmp_path / "j.gltf")


def test_loader_rejects_missing_dir_and_unknown(tmp_path: Path) -> None:
    for path, match in [(tmp_path / "none.glb", "no such file"), (tmp_path, "directory")]:
        with pytest.raises(SceneError, match=match):
            load_scene(path)
    (tmp_path / "x.fbx").write_bytes(b"")
    with pytest.raises(SceneError, match="x.fbx.*unknown"):
        load_scene(tmp_path / "x.fbx")
