# Tests of the .vkpbr container: exact round trip, and rejection of truncated, corrupt,
# foreign, other-version and inconsistent files with BakeFormatError.
from __future__ import annotations

import dataclasses
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from vkpbr.bake.bake import bake_scene
from vkpbr.errors import BakeFormatError
from vkpbr.scene.baked_file import (
    ALIGN,
    BakedImage,
    BakedScene,
    load_baked_scene,
    read_baked,
    write_baked,
)
from vkpbr.scene.types import (
    Camera,
    Image,
    Light,
    Material,
    Mesh,
    Node,
    Sampler,
    Scene,
    TextureRef,
)


def small_scene(tmp_path: Path) -> Scene:
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32)
    n = np.tile(np.float32([0, 0, 1]), (4, 1))
    uv = np.array([[0, 1], [1, 1], [0, 0], [1, 0]], np.float32)
    quad = Mesh("quad", p, np.array([0, 1, 2, 2, 1, 3], np.uint32), n, uv, material=0,
                colors=np.ones((4, 4), np.float32))
    tri = Mesh("tri", p[:3] + 2, np.array([0, 1, 2], np.uint32), n[:3], None)
    tex = (tmp_path / "tex" / "albedo.png")
    mat = Material("m", base_color_factor=(1.0, 0.5, 0.25, 1.0), roughness_factor=0.3,
                   base_color_texture=TextureRef(0, Sampler(wrap_s="clamp"), offset=(0.5, 0.0)),
                   normal_texture=TextureRef(1, texcoord=0, rotation=0.25, scale=(2.0, 2.0)),
                   alpha_mode="mask")
    return Scene("small", meshes=[quad, tri], materials=[mat],
                 images=[Image("albedo.png", path=tex), Image("n.png", data=b"\x89PNG...")],
                 nodes=[Node(0, np.eye(4, dtype=np.float32), "a"),
                        Node(1, np.diag([2, 2, 2, 1]).astype(np.float32), "b")],
                 lights=[Light((1.0, 2.0, 3.0), intensity=5.0, falloff="inverse_square")],
                 cameras=[Camera(eye=(0.0, 1.0, 5.0), yfov_deg=45.0, name="cam")])


@pytest.fixture
def baked_path(tmp_path: Path) -> tuple[Path, BakedScene]:
    baked = bake_scene(small_scene(tmp_path))
    baked.source_key = "ab" * 32
    baked.images.append(BakedImage("raw", levels=[np.full((2, 2, 4), 7, np.uint8),
                                                  np.full((1, 1, 4), 9, np.uint8)], srgb=True))
    path = tmp_path / "small.vkpbr"
    write_baked(path, baked)
    return path, baked


def test_round_trip_is_exact(baked_path: tuple[Path, BakedScene], tmp_path: Path) -> None:
    path, baked = baked_path
    back = read_baked(path)
    assert back.streams.keys() == baked.streams.keys()
    for name, arr in baked.streams.items():
        np.testing.assert_array_equal(back.streams[name], arr, err_msg=name)
    np.testing.assert_array_equal(back.mesh_table, baked.mesh_table)
    assert back.mesh_names == baked.mesh_names and back.name == baked.name
    assert back.materials == baked.materials
    assert back.lights == baked.lights and back.cameras == baked.cameras
    assert [(n.mesh, n.name) for n in back.nodes] == [(n.mesh, n.name) for n in baked.nodes]
    for a, b in zip(back.nodes, baked.nodes, strict=True):
        np.testing.assert_array_equal(a.matrix, b.matrix)
    assert back.source_key == baked.source_key
    assert back.images[0].path == (tmp_path / "tex" / "albedo.png").resolve()
    assert back.images[1].data == b"\x89PNG..."
    assert [lv.tolist() for lv in back.images[2].levels] == \
        [lv.tolist() for lv in baked.images[2].levels]
    assert back.images[2].srgb and not back.images[0].srgb
    mapped = read_baked(path, mmap=True)
    np.testing.assert_array_equal(mapped.streams["positions"], baked.streams["positions"])


def test_sections_are_aligned(baked_path: tuple[Path, BakedScene]) -> None:
    data = baked_path[0].read_bytes()
    count = struct.unpack_from("<I", data, 16)[0]
    table = np.frombuffer(data, np.dtype([("name", "S16"), ("offset", "<u8"), ("size", "<u8"),
                                          ("crc32", "<u4"), ("reserved", "<u4")]), count, 64)
    assert (table["offset"] % ALIGN == 0).all()
    assert len(data) % ALIGN == 0


def test_load_baked_scene(baked_path: tuple[Path, BakedScene]) -> None:
    path, baked = baked_path
    scene = load_baked_scene(path)
    assert [m.name for m in scene.meshes] == ["quad", "tri"]
    quad = scene.meshes[0]
    assert quad.qtangents.shape == (4, 4) and quad.packed_frames.shape == (4,)
    assert quad.tangents.shape == (4, 4) and quad.texcoords.shape == (4, 2)
    assert quad.colors is not None and scene.meshes[1].colors is None
    assert scene.meshes[1].indices.max() < scene.meshes[1].vertex_count
    raw = scene.images[2]  # level 0 as pixels, the rest of the chain as mips, colour space kept
    assert raw.pixels.shape == (2, 2, 4) and (raw.pixels == 7).all() and raw.mips_srgb
    assert [m.tolist() for m in raw.mips] == [[[[9, 9, 9, 9]]]]
    assert scene.images[0].mips == () and scene.images[0].pixels is None
    with pytest.raises(BakeFormatError, match="stale"):
        load_baked_scene(path, expected_source_key="cd" * 32)
    load_baked_scene(path, expected_source_key="ab" * 32)


def test_every_truncation_is_rejected(baked_path: tuple[Path, BakedScene], tmp_path: Path) -> None:
    data = baked_path[0].read_bytes()
    cut = tmp_path / "cut.vkpbr"
    # Grown a byte at a time through one unbuffered handle: before each write the file holds
    # data[:size]. (Rewriting the file each time truncates it, ~2 ms a time on this disk.)
    with cut.open("wb", buffering=0) as f:
        for size in range(len(data)):
            assert cut.stat().st_size == size
            with pytest.raises(BakeFormatError):
                read_baked(cut)
            f.write(data[size:size + 1])
    cut.write_bytes(data + b"\0")
    with pytest.raises(BakeFormatError, match="unexpected bytes"):
        read_baked(cut)


def test_flipped_bytes_are_rejected(baked_path: tuple[Path, BakedScene], tmp_path: Path) -> None:
    data = baked_path[0].read_bytes()
    bad = tmp_path / "bad.vkpbr"
    # Every byte of header and table, and a byte every 7 in the sections (padding excluded:
    # it is not covered by a checksum and carries no data).
    count = struct.unpack_from("<I", data, 16)[0]
    table = np.frombuffer(data, np.dtype([("name", "S16"), ("offset", "<u8"), ("size", "<u8"),
                                          ("crc32", "<u4"), ("reserved", "<u4")]), count, 64)
    spots = list(range(40)) + list(range(64, 64 + 40 * count))
    for off, size in zip(table["offset"], table["size"], strict=True):
        spots += list(range(int(off), int(off + size), 7))
    bad.write_bytes(data)
    with bad.open("r+b", buffering=0) as f:  # one byte flipped, then put back: no rewrites
        for pos in spots:
            f.seek(pos)
            f.write(bytes([data[pos] ^ 0x10]))
            with pytest.raises(BakeFormatError):
                read_baked(bad)
            f.seek(pos)
            f.write(data[pos:pos + 1])
    assert bad.read_bytes() == data


def _rewrite_header(data: bytes, **fields: int) -> bytes:
    out = bytearray(data)
    offsets = {"version": 8, "header_size": 12, "sections": 16}
    for key, value in fields.items():
        struct.pack_into("<I", out, offsets[key], value)
    struct.pack_into("<I", out, 36, zlib.crc32(bytes(out[:36])))
    return bytes(out)


def test_wrong_magic_and_version(baked_path: tuple[Path, BakedScene], tmp_path: Path) -> None:
    data = baked_path[0].read_bytes()
    bad = tmp_path / "bad.vkpbr"
    bad.write_bytes(b"glTF" + data[4:])
    with pytest.raises(BakeFormatError, match="magic"):
        read_baked(bad)
    for version in (1, 3):  # 1: made before mip chains were stored; 3: by a newer vkpbr
        bad.write_bytes(_rewrite_header(data, version=version))
        with pytest.raises(BakeFormatError, match=f"version {version}, .* reads version 2 only; "
                                                  "bake the scene again"):
            read_baked(bad)
    bad.write_bytes(_rewrite_header(data, sections=10**6))
    with pytest.raises(BakeFormatError, match="section count"):
        read_baked(bad)


def test_inconsistent_counts_are_rejected(tmp_path: Path) -> None:
    good = bake_scene(small_scene(tmp_path))
    bad = tmp_path / "bad.vkpbr"
    for case in ("index", "range", "material", "node", "image"):
        baked = dataclasses.replace(good, streams={k: v.copy() for k, v in good.streams.items()},
                                    mesh_table=good.mesh_table.copy())
        if case == "index":  # the triangle mesh has 3 vertices: index 3 is out of range
            baked.streams["indices"][int(baked.mesh_table[1]["first_index"])] = 3
        elif case == "range":
            baked.mesh_table["vertex_count"][1] = 99
        elif case == "material":
            baked.mesh_table["material"][0] = 5
        elif case == "node":
            baked.nodes = [Node(7)]
        else:
            baked.images = []
        write_baked(bad, baked)
        with pytest.raises(BakeFormatError):
            read_baked(bad)


def test_write_is_atomic_and_leaves_no_temp_files(tmp_path: Path) -> None:
    baked = bake_scene(small_scene(tmp_path))
    path = tmp_path / "out.vkpbr"
    write_baked(path, baked)
    del baked.streams["positions"]
    with pytest.raises(KeyError):
        write_baked(path, baked)
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_file()) == ["out.vkpbr"]
    read_baked(path)


def test_levels_must_be_a_full_mip_chain(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    baked = bake_scene(small_scene(tmp_path))
    path = tmp_path / "m.vkpbr"
    for levels in ([np.zeros((4, 4, 4), np.uint8)],  # level 0 alone: not a chain
                   [np.zeros((4, 4, 4), np.uint8), np.zeros((2, 2, 4), np.uint8)],  # no 1x1
                   [np.zeros((4, 2, 4), np.uint8), np.zeros((2, 2, 4), np.uint8),
                    np.zeros((1, 1, 4), np.uint8)]):  # 4x2 halves to 2x1, not 2x2
        baked.images = [BakedImage("x", levels=levels)] * 2
        with pytest.raises(ValueError, match="full mip chain"):
            write_baked(path, baked)
        # A writer without the check (an older or foreign one): the reader rejects the file.
        monkeypatch.setattr("vkpbr.scene.baked_file.is_mip_chain", lambda levels: True)
        write_baked(path, baked)
        monkeypatch.undo()
        with pytest.raises(BakeFormatError, match="not a full mip chain|out of bounds"):
            read_baked(path)
    baked.images = [BakedImage("x", levels=[np.zeros((2, 2, 3), np.uint8),
                                            np.zeros((1, 1, 3), np.uint8)])] * 2  # RGB, no A
    with pytest.raises(ValueError, match="full mip chain"):
        write_baked(path, baked)
