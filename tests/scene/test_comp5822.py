# Tests of the .comp5822mesh reader/writer (renderer-spec section 5): exact byte layout of a
# tiny file, bit-exact round trips, atomic writes, and rejection of every truncation point,
# bad magic/variant and out-of-range ids with a SceneError naming the file.

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.comp5822 import MAGIC, read_comp5822mesh, write_comp5822mesh
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Image, Material, Mesh, Node, Scene, TextureRef


def make_scene(tmp_path: Path, rng: np.random.Generator | None = None) -> Scene:
    rng = rng or np.random.default_rng(5822)
    (tmp_path / "tex").mkdir(exist_ok=True)
    images = []
    for name in ("albedo.png", "rough.png", "metal.png", "mask.png", "normal.png"):
        (tmp_path / "tex" / name).write_bytes(b"")
        images.append(Image(name=name, path=tmp_path / "tex" / name))
    mats = [
        Material(base_color_texture=TextureRef(0), roughness_texture=TextureRef(1),
                 metallic_texture=TextureRef(2), alpha_texture=TextureRef(3),
                 normal_texture=TextureRef(4), alpha_mode="mask", double_sided=True),
        Material(base_color_texture=TextureRef(0)),
    ]  # fmt: skip
    meshes = []
    for k, (nv, ntri) in enumerate([(5, 4), (3, 1), (7, 9)]):
        meshes.append(Mesh(
            name=f"m{k}",
            positions=rng.standard_normal((nv, 3)).astype(np.float32),
            normals=rng.standard_normal((nv, 3)).astype(np.float32),
            texcoords=rng.random((nv, 2)).astype(np.float32),
            indices=rng.integers(0, nv, 3 * ntri).astype(np.uint32),
            material=[0, 1, -1][k],
        ))  # fmt: skip
    nodes = [Node(mesh=i) for i in range(len(meshes))]
    return Scene("t", meshes=meshes, materials=mats, images=images, nodes=nodes)


def test_round_trip_is_exact(tmp_path: Path) -> None:
    scene = make_scene(tmp_path)
    scene.meshes[0].positions[0, 0] = np.float32(-0.0)  # sign bits survive too
    path = tmp_path / "a.comp5822mesh"
    write_comp5822mesh(scene, path)
    back = read_comp5822mesh(path)
    assert len(back.meshes) == 3 and [m.material for m in back.meshes] == [0, 1, -1]
    for a, b in zip(scene.meshes, back.meshes, strict=True):
        for name in ("positions", "normals", "texcoords", "indices"):
            x, y = getattr(a, name), getattr(b, name)
            assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), name
    assert [img.path for img in back.images] == [img.path for img in scene.images]
    m0 = back.materials[0]
    assert m0.alpha_mode == "mask" and m0.double_sided and m0.alpha_texture.image == 3
    assert (m0.roughness_texture.image, m0.metallic_texture.image, m0.normal_texture.image) == (
        1,
        2,
        4,
    )
    assert back.materials[1].metallic_texture is None and back.materials[1].metallic_factor == 0
    write_comp5822mesh(back, tmp_path / "b.comp5822mesh")  # file-level round trip
    assert (tmp_path / "b.comp5822mesh").read_bytes() == path.read_bytes()
    assert not [p for p in tmp_path.iterdir() if p.suffix == ".tmp"]  # temp file renamed
    assert load_scene(path).triangle_count == 14


def test_layout(tmp_path: Path) -> None:
    (tmp_path / "t.png").write_bytes(b"")
    scene = Scene("x", images=[Image("t.png", path=tmp_path / "t.png")],
                  materials=[Material(base_color_texture=TextureRef(0))],
                  meshes=[Mesh("m", np.zeros((3, 3), np.float32), np.arange(3, dtype=np.uint32),
                               np.zeros((3, 3), np.float32), np.zeros((3, 2), np.float32), material=0)],
                  nodes=[Node(0)])  # fmt: skip
    write_comp5822mesh(scene, tmp_path / "l.comp5822mesh")
    data = (tmp_path / "l.comp5822mesh").read_bytes()
    assert data[:16] == b"\0\0COMP5822Mmesh\0" == MAGIC and data[16:32] == b"default" + b"\0" * 9
    assert data[32:36] == struct.pack("<I", 1) and data[36:40] == struct.pack("<I", 6)
    assert data[40:46] == b"t.png\0" and data[46] == 4  # unreadable file -> 4 channels
    ids = struct.unpack_from("<I5I", data, 47)
    assert ids == (1, 0, 0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF)
    assert struct.unpack_from("<4I", data, 71) == (1, 0, 3, 3)
    assert len(data) == 87 + 3 * 32 + 3 * 4


def test_every_truncation_rejected(tmp_path: Path) -> None:
    path = tmp_path / "a.comp5822mesh"
    write_comp5822mesh(make_scene(tmp_path), path)
    data = path.read_bytes()
    cut = tmp_path / "cut.comp5822mesh"
    with cut.open("wb", buffering=0) as f:  # grown a byte at a time: data[:n] before each write
        for n in range(len(data)):
            assert cut.stat().st_size == n
            with pytest.raises(SceneError, match="cut.comp5822mesh"):
                read_comp5822mesh(cut)
            f.write(data[n:n + 1])
    cut.write_bytes(data + b"\0")
    with pytest.raises(SceneError, match="trailing"):
        read_comp5822mesh(cut)


def _patched(tmp_path: Path, offset: int, value: bytes) -> Path:
    path = tmp_path / "a.comp5822mesh"
    write_comp5822mesh(make_scene(tmp_path), path)
    data = bytearray(path.read_bytes())
    data[offset : offset + len(value)] = value
    bad = tmp_path / "bad.comp5822mesh"
    bad.write_bytes(bytes(data))
    return bad


@pytest.mark.parametrize(
    ("offset", "value", "match"),
    [
        (2, b"X", "magic"),
        (16, b"v2\0", "variant 'v2'"),
        (32, struct.pack("<I", 0x7FFFFFFF), "texture count"),
    ],
)
def test_bad_header(tmp_path: Path, offset: int, value: bytes, match: str) -> None:
    with pytest.raises(SceneError, match=match) as info:
        read_comp5822mesh(_patched(tmp_path, offset, value))
    assert "bad.comp5822mesh" in str(info.value)


def test_out_of_range_ids(tmp_path: Path) -> None:
    scene = make_scene(tmp_path)
    path = tmp_path / "a.comp5822mesh"
    write_comp5822mesh(scene, path)
    data = path.read_bytes()
    mat_table = data.index(struct.pack("<I", 2) + struct.pack("<5I", 0, 1, 2, 3, 4))
    bad = bytearray(data)
    bad[mat_table + 4 : mat_table + 8] = struct.pack("<I", 5)  # texture id 5 of 5
    (tmp_path / "b.comp5822mesh").write_bytes(bytes(bad))
    with pytest.raises(SceneError, match="texture id out of range"):
        read_comp5822mesh(tmp_path / "b.comp5822mesh")
    mesh0 = mat_table + 4 + 2 * 20 + 4
    bad = bytearray(data)
    bad[mesh0 : mesh0 + 4] = struct.pack("<I", 2)  # material 2 of 2
    (tmp_path / "b.comp5822mesh").write_bytes(bytes(bad))
    with pytest.raises(SceneError, match="material 2 out of range"):
        read_comp5822mesh(tmp_path / "b.comp5822mesh")
    first_index = mesh0 + 12 + 5 * 32
    bad = bytearray(data)
    bad[first_index : first_index + 4] = struct.pack("<I", 5)  # vertex 5 of 5
    (tmp_path / "b.comp5822mesh").write_bytes(bytes(bad))
    with pytest.raises(SceneError, match="index 5 >= vertex count 5"):
        read_comp5822mesh(tmp_path / "b.comp5822mesh")


def test_writer_refuses_unrepresentable(tmp_path: Path) -> None:
    scene = make_scene(tmp_path)
    scene.materials[0].roughness_texture = TextureRef(1, channel=1)  # glTF packed G
    with pytest.raises(SceneError, match="channel 1"):
        write_comp5822mesh(scene, tmp_path / "x.comp5822mesh")
    scene = make_scene(tmp_path)
    scene.images[0] = Image("embedded", data=b"png")
    with pytest.raises(SceneError, match="no file path"):
        write_comp5822mesh(scene, tmp_path / "x.comp5822mesh")
    assert not (tmp_path / "x.comp5822mesh").exists()


def test_node_transform_is_baked(tmp_path: Path) -> None:
    scene = make_scene(tmp_path)
    scene.nodes[1].matrix = np.diag([2.0, 2.0, 2.0, 1.0]).astype(np.float32)
    write_comp5822mesh(scene, tmp_path / "n.comp5822mesh")
    back = read_comp5822mesh(tmp_path / "n.comp5822mesh")
    np.testing.assert_allclose(back.meshes[1].positions, 2 * scene.meshes[1].positions, rtol=1e-6)
