# Tests of the OBJ/MTL loader: a small OBJ + MTL written here with the course's PBR extensions,
# face forms (v, v/vt, v//vn, v/vt/vn), negative indices, polygon fans, texcoord flipping,
# material runs, and malformed files that must raise SceneError naming the file.

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene
from vkpbr.scene.obj import load_obj

OBJ = """# test file
mtllib test.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0 1.0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl stone
f 1/1/1 2/2/1 3/3/1 4/4/1
usemtl leaf
f -4/-4 -2/-2 -1/-1
g loose
f 1//1 2//1 3//1
usemtl undefined_one
f 1 2 3
"""

MTL = """newmtl stone
Kd 0.5 0.25 1
Pm 0.25
Pr 0.75
Ke 1 2 3
map_Kd -s 2 3 -o 0.5 0.5 stone.png
map_Pm stone_metal.png
map_Pr -clamp on stone_rough.png
norm -bm 0.5 stone_normal.png

newmtl leaf   # the course's masked foliage
Kd 1 1 1
map_Kd leaf.png
map_d leaf_mask.png
bump leaf_normal.png
d 1.0
"""


def write(tmp_path: Path, obj: str = OBJ, mtl: str = MTL) -> Path:
    (tmp_path / "test.mtl").write_text(mtl)
    for name in ("stone", "stone_metal", "stone_rough", "stone_normal", "leaf", "leaf_mask",
                 "leaf_normal"):  # fmt: skip
        (tmp_path / f"{name}.png").write_bytes(b"not decoded here")
    path = tmp_path / "test.obj"
    path.write_text(obj)
    return path


def test_geometry_and_runs(tmp_path: Path) -> None:
    with pytest.warns(UserWarning, match="undefined_one"):
        scene = load_obj(write(tmp_path))
    quad, leaf, loose, undefined = scene.meshes
    np.testing.assert_array_equal(quad.positions, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    np.testing.assert_array_equal(quad.indices, [0, 1, 2, 0, 2, 3])  # fan of the quad
    np.testing.assert_array_equal(quad.texcoords, [[0, 1], [1, 1], [1, 0], [0, 0]])  # v' = 1 - v
    np.testing.assert_array_equal(quad.normals, np.tile([0, 0, 1], (4, 1)))
    # -4/-2/-1 relative to 4 vertices defined so far = 1, 3, 4; no vn -> flat normals
    np.testing.assert_array_equal(leaf.positions, [[0, 0, 0], [1, 1, 0], [0, 1, 0]])
    np.testing.assert_array_equal(leaf.texcoords, [[0, 1], [1, 0], [0, 0]])
    np.testing.assert_allclose(leaf.normals, np.tile([0, 0, 1], (3, 1)))
    assert loose.texcoords is None and loose.normals is not None
    assert [m.material for m in scene.meshes] == [0, 1, 1, -1]
    assert [n.mesh for n in scene.nodes] == [0, 1, 2, 3]
    for m in scene.meshes:
        assert m.positions.dtype == np.float32 and m.indices.dtype == np.uint32
        assert m.positions.flags.c_contiguous


def test_materials(tmp_path: Path) -> None:
    with pytest.warns(UserWarning):
        scene = load_obj(write(tmp_path))
    stone, leaf = scene.materials
    names = [img.name for img in scene.images]
    assert stone.base_color_factor == (0.5, 0.25, 1, 1) and stone.emissive_factor == (1, 2, 3)
    assert (stone.metallic_factor, stone.roughness_factor) == (0.25, 0.75)
    bc = stone.base_color_texture
    assert names[bc.image] == "stone.png" and bc.scale == (2, 3) and bc.offset == (0.5, 0.5)
    assert names[stone.metallic_texture.image] == "stone_metal.png"
    assert stone.metallic_texture.channel == 0 and stone.roughness_texture.channel == 0
    assert stone.roughness_texture.sampler.wrap_s == "clamp"
    assert names[stone.normal_texture.image] == "stone_normal.png" and stone.normal_scale == 0.5
    assert stone.alpha_mode == "opaque" and stone.alpha_texture is None
    assert leaf.alpha_mode == "mask" and leaf.alpha_cutoff == 0.5 and leaf.double_sided
    assert names[leaf.alpha_texture.image] == "leaf_mask.png" and leaf.alpha_texture.channel == 0
    assert names[leaf.normal_texture.image] == "leaf_normal.png"
    assert leaf.metallic_factor == 0.0  # OBJ materials without Pm are dielectrics
    assert scene.images[0].path == tmp_path / "stone.png"


def test_missing_mtl_and_textures_warn(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    path = tmp_path / "a.obj"
    path.write_text("mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.warns(UserWarning, match="nowhere.mtl"):
        scene = load_scene(path)
    assert scene.triangle_count == 1 and scene.materials == []
    (tmp_path / "b.mtl").write_text("newmtl m\nmap_Kd gone.png\n")
    path.write_text("mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n")
    scene = load_scene(path)
    assert scene.images[0].path == tmp_path / "gone.png"
    # One line for all missing textures, whichever format (tests/scene/test_missing_textures.py)
    assert [r.getMessage() for r in caplog.records] == [
        f"1 of 1 textures not found next to {path} (first: gone.png); rendering with default "
        "values (pass strict=True / --strict to make this an error)"]


def test_large_obj_is_vectorised(tmp_path: Path) -> None:
    n = 200
    g = np.stack(np.meshgrid(np.arange(n), np.arange(n), indexing="ij"), -1).reshape(-1, 2)
    verts = "".join(f"v {x} {y} 0\n" for x, y in g)
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).reshape(-1) + 1
    faces = "".join(f"f {a} {a + n} {a + n + 1} {a + 1}\n" for a in i)
    path = tmp_path / "grid.obj"
    path.write_text(verts + faces)
    scene = load_obj(path)
    assert scene.triangle_count == 2 * (n - 1) ** 2
    assert scene.meshes[0].vertex_count == 6 * (n - 1) ** 2  # no vn: unwelded flat normals


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "vertex 3"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "vertex -4"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/5 2 3\n", "texcoord 5"),
        ("v 0 0 zero\nf 1 1 1\n", "bad number"),
        ("v 0 0\nf 1 1 1\n", "too few"),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", "fewer than 3"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n", "'/'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "bad face index"),
        ("v 0 0 0\n", "no faces"),
    ],
)
def test_bad_obj(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(SceneError, match=match) as info:
        load_obj(path)
    assert "bad.obj" in str(info.value)


def test_bad_mtl(tmp_path: Path) -> None:
    (tmp_path / "m.mtl").write_text("newmtl x\nKd red green blue\n")
    path = tmp_path / "o.obj"
    path.write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match="m.mtl"):
        load_obj(path)


# --- the reader on tinyobjloader: its fast path and the exact parse give the same scene -------

PLAIN = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n" \
        "o a\nf 1/1/1 2/2/1 3/3/1 4/3/1\no b\nf -4 -2 -1\n"


def _arrays(scene: object) -> list[tuple]:
    return [(m.name, m.material, m.positions.tolist(), m.indices.tolist(), m.normals.tolist(),
             None if m.texcoords is None else m.texcoords.tolist()) for m in scene.meshes]


@pytest.mark.parametrize("variant", [
    lambda t: t.replace("v 1 0 0\n", "v 1 0 0 # a comment\n"),  # '#' on a v line
    lambda t: t.replace("vt 1 0\n", "  vt 1 0\n"),  # leading blanks
    lambda t: t.replace("\n", "\r\n"),  # CRLF
    lambda t: t.replace("v 1 1 0\n", "v 1.0e0 +1 -0.0\n"),
])
def test_exact_parse_and_fast_path_agree(tmp_path: Path, variant) -> None:  # noqa: ANN001
    (tmp_path / "a.obj").write_text(PLAIN)
    (tmp_path / "b.obj").write_text(variant(PLAIN))
    a, b = load_obj(tmp_path / "a.obj"), load_obj(tmp_path / "b.obj")
    assert _arrays(a) == _arrays(b)
    assert [n.name for n in a.nodes] == [n.name for n in b.nodes] == ["a", "b"]


def test_nonfinite_vertices_drop_their_faces(tmp_path: Path) -> None:
    path = tmp_path / "n.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nv 1e999 0 0\nf 1 2 3\nf 1 2 4\nf 1 5 3\n")
    with pytest.warns(UserWarning, match="2 non-finite positions; dropped 2 triangles"):
        (mesh,) = load_obj(path).meshes
    assert mesh.triangle_count == 1
    np.testing.assert_array_equal(mesh.positions[mesh.indices], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


@pytest.mark.parametrize(("text", "match"), [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "line 4: face index 0"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1/1/1/1 2 3\n", "line 5: face corner with more"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nvn 0 0 1\nf 1//1 2//1 3//-2\n", "normal -2, only 1"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n", "normal 2, only 1 defined"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0\nf 1 2 3\n", "vn line 1 has too few numbers"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt u v\nf 1 2 3\n", "bad number in vt data"),
])
def test_more_bad_obj(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(SceneError, match=match) as info:
        load_obj(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_materials_from_two_libraries_map_by_name(tmp_path: Path) -> None:
    (tmp_path / "a.mtl").write_text("newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\n")
    (tmp_path / "b.mtl").write_text("newmtl blue\nKd 0 0 1\n")
    path = tmp_path / "m.obj"
    path.write_text("mtllib a.mtl\n  mtllib b.mtl # two\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                    "usemtl blue\nf 1 2 3\nusemtl red\nf 1 2 3\nusemtl green\nf 1 2 3\n"
                    "# mtllib not-a-statement.mtl\n")
    scene = load_obj(path)
    kd = [scene.materials[m.material].base_color_factor[:3] for m in scene.meshes]
    assert kd == [(0, 0, 1), (1, 0, 0), (0, 1, 0)]


def test_without_tinyobjloader_the_error_says_what_to_install(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    import sys

    monkeypatch.setitem(sys.modules, "tinyobjloader", None)
    path = tmp_path / "a.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match=r"a\.obj: reading OBJ files needs tinyobjloader: pip "
                                         r"install tinyobjloader==2\.0\.0rc13$"):
        load_obj(path)


def test_tinyobjloader_numbers_match_the_exact_parse(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    """tinyobjloader's float parse against NumPy's on numbers as tools write them (fixed,
    exponent, signs, many digits): positions and texcoords equal after the float32 cast."""
    import vkpbr.scene.obj as obj

    rng = np.random.default_rng(7)
    values = np.concatenate([rng.normal(0, 1e3, 300), rng.normal(0, 1e-3, 300), rng.random(300)])
    forms = ["{:.8f}", "{:.6e}", "{:+.3f}", "{!r}", "{:.17g}", "{:.0f}."]
    text = "".join(f"v {forms[i % 6].format(a)} {forms[(i + 1) % 6].format(b)} "
                   f"{forms[(i + 2) % 6].format(c)}\nvt {values[i]:.7f} {values[-i]:.5e}\n"
                   for i, (a, b, c) in enumerate(values.reshape(-1, 3).tolist()))
    n = len(values) // 3
    text += "".join(f"f {i}/{i} {i + 1}/{i + 1} {i + 2}/{i + 2}\n" for i in range(1, n - 1))
    path = tmp_path / "numbers.obj"
    path.write_text(text)
    assert obj._plain_vertex_lines(path.read_bytes())  # the fast path reads this file
    fast = load_obj(path)
    monkeypatch.setattr(obj, "_plain_vertex_lines", lambda data: False)
    exact = load_obj(path)
    assert _arrays(fast) == _arrays(exact)
