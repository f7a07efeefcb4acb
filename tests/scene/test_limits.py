"""Issue 11, class 4: memory bombs are refused where they enter, with one line naming the
limit, before anything large is allocated."""

from __future__ import annotations

import resource
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene
from vkpbr.scene.textures import decode_image
from vkpbr.scene.types import Image


def _png_header_only(width: int, height: int) -> bytes:
    """A PNG that declares width x height RGBA pixels and holds almost nothing."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")


def test_a_declared_12000x12000_texture_is_refused_before_decoding() -> None:
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    pixels, notes = decode_image(Image("bomb.png", data=_png_header_only(12000, 12000)))
    grown_mib = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    assert pixels is None
    assert notes and notes[0][0] == "undecodable" and "texture limit" in notes[0][1], notes
    assert grown_mib < 100  # 12000 x 12000 RGBA would be 549 MiB


def test_the_texture_limit_can_be_raised_and_lowered(monkeypatch) -> None:  # noqa: ANN001
    img = Image("small", pixels=np.zeros((20, 20, 4), np.uint8))
    import io

    from PIL import Image as PILImage
    buf = io.BytesIO()
    PILImage.fromarray(img.pixels, "RGBA").save(buf, format="PNG")
    encoded = Image("small.png", data=buf.getvalue())
    assert decode_image(encoded)[0].shape == (20, 20, 4)
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_PIXELS", "399")
    assert decode_image(encoded)[0] is None
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_PIXELS", "400")
    assert decode_image(encoded)[0] is not None


def test_triangle_and_vertex_limits(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    from vkpbr.scene.validate import validate_scene

    obj = tmp_path / "m.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    scene = load_scene(obj)
    assert scene.triangle_count == 2
    monkeypatch.setenv("VKPBR_MAX_TRIANGLES", "1")
    with pytest.raises(SceneError, match=r"2 faces are over the limit of 1 triangles; raise it "
                                         "with VKPBR_MAX_TRIANGLES"):
        load_scene(obj)  # the OBJ reader's early count
    with pytest.raises(SceneError, match=r"2 triangles are over the limit of 1 \(VKPBR_MAX_TRIANGLES\)"):
        validate_scene(scene, obj)  # every format's check of the loaded scene
    monkeypatch.delenv("VKPBR_MAX_TRIANGLES")
    monkeypatch.setenv("VKPBR_MAX_VERTICES", "3")
    with pytest.raises(SceneError, match="VKPBR_MAX_VERTICES"):
        load_scene(obj)
    with pytest.raises(SceneError, match=r"6 vertices are over the limit of 3 \(VKPBR_MAX_VERTICES\)"):
        validate_scene(scene, obj)  # 6: flat normals give each triangle its own corners

_PEAK = """
import resource, sys
from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
try:
    load_scene(sys.argv[1])
    print("loaded")
except SceneError as exc:
    print(exc)
print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024)
"""


@pytest.mark.timeout(120)
def test_an_obj_over_the_face_limit_fails_before_its_arrays_are_built(tmp_path: Path) -> None:
    """Issue 11: a 1,000,000-face OBJ took 1.2 GiB (0.68 GiB here) before the triangle limit
    refused it; the OBJ reader now counts statements first. Run in a fresh process, so that
    its peak RSS is this load's and not an earlier test's."""
    import os
    import subprocess
    import sys

    obj = tmp_path / "million.obj"
    obj.write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3\n" * 1_000_000)  # 8 MB
    env = dict(os.environ, VKPBR_MAX_TRIANGLES="999999")
    out = subprocess.run([sys.executable, "-c", _PEAK, str(obj)], env=env, capture_output=True,
                         text=True, check=True).stdout.splitlines()
    assert out[0] == (f"{obj}: 1,000,000 faces are over the limit of 999,999 triangles; "
                      "raise it with VKPBR_MAX_TRIANGLES")
    assert float(out[1]) < 64, out  # MiB of peak growth: the file, a copy, the statement list


def test_obj_corner_and_statement_counts_are_checked_early(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    """One 1,000-corner face is 998 triangles (a fan): refused over a limit of 997 by the
    corner count, loaded at 998; v/vt/vn statements are held to the vertex limit."""
    obj = tmp_path / "fan.obj"
    angles = np.linspace(0, 2 * np.pi, 1000, endpoint=False)
    obj.write_text("".join(f"v {np.cos(a):.6f} {np.sin(a):.6f} 0\n" for a in angles)
                   + "vn 0 0 1\nf" + "".join(f" \t{i}//1" for i in range(1, 1001)) + "\n")
    monkeypatch.setenv("VKPBR_MAX_TRIANGLES", "997")
    with pytest.raises(SceneError, match=r"fan\.obj: 1 faces of 1,000 corners make 998 "
                                         r"triangles, over the limit of 997; raise it with "
                                         "VKPBR_MAX_TRIANGLES"):
        load_scene(obj)
    monkeypatch.setenv("VKPBR_MAX_TRIANGLES", "998")
    assert load_scene(obj).triangle_count == 998
    monkeypatch.setenv("VKPBR_MAX_VERTICES", "999")
    with pytest.raises(SceneError, match=r"fan\.obj: 1,000 vertex positions \(v statements\) "
                                         "are over the limit of 999 vertices; raise it with "
                                         "VKPBR_MAX_VERTICES"):
        load_scene(obj)


# --- the total decoded texture bytes of one scene (VKPBR_MAX_TEXTURE_BYTES) -------------------
def _png20(value: int) -> bytes:
    import io

    from PIL import Image as PILImage

    buf = io.BytesIO()
    PILImage.new("RGBA", (20, 20), (value, 0, 0, 255)).save(buf, format="PNG")
    return buf.getvalue()  # decodes to 20 * 20 * 4 = 1,600 bytes


def _scene_of_three(tmp_path: Path):  # noqa: ANN202
    from vkpbr.scene.types import Scene

    return Scene("three", source=tmp_path / "three.gltf",
                 images=[Image(f"t{i}.png", data=_png20(10 * i)) for i in range(3)])


def test_total_texture_bytes_limit_names_the_scene_texture_and_option(tmp_path: Path,
                                                                      monkeypatch) -> None:  # noqa: ANN001
    from vkpbr.scene.textures import decode_images

    scene = _scene_of_three(tmp_path)
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", "4799")  # 3 x 1,600 = 4,800 needed
    with pytest.raises(SceneError) as info:
        decode_images(scene, workers=1)
    assert str(info.value) == (
        f"{tmp_path / 'three.gltf'}: its textures decode to more than 4,799 bytes of RGBA8 (at "
        "t2.png (20x20, 1,600 bytes) after 3,200 bytes of earlier textures); raise the limit "
        "with VKPBR_MAX_TEXTURE_BYTES")
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", "4800")
    out = decode_images(scene, workers=3)
    assert [int(p[0, 0, 0]) for p in out] == [0, 10, 20]
    # Threads: which texture goes over depends on timing, the error does not.
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", "3000")
    with pytest.raises(SceneError, match=r"three\.gltf: its textures decode to more than 3,000 "
                                         r"bytes of RGBA8 \(at t\d\.png .*VKPBR_MAX_TEXTURE_BYTES"):
        decode_images(scene, workers=3)


def test_total_texture_bytes_are_charged_before_decoding(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    """Over the budget at the first header: no texture's pixels are decoded at all, and a
    downscaled texture is charged its downscaled size."""
    from PIL import ImageFile

    from vkpbr.scene.textures import decode_images

    loads = []
    real_load = ImageFile.ImageFile.load
    monkeypatch.setattr(ImageFile.ImageFile, "load",
                        lambda self: loads.append(self.size) or real_load(self))
    scene = _scene_of_three(tmp_path)
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", "1599")
    with pytest.raises(SceneError, match=r"at t0\.png \(20x20, 1,600 bytes\) after 0 bytes"):
        decode_images(scene, workers=1)
    assert loads == []
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", str(3 * 10 * 10 * 4))  # 10x10 each
    out = decode_images(scene, max_size=10, workers=1)
    assert [p.shape for p in out] == [(10, 10, 4)] * 3 and loads  # decoded this time


def test_bake_embedding_textures_honours_the_total_texture_bytes_limit(tmp_path: Path,
                                                                       monkeypatch) -> None:  # noqa: ANN001
    """`vkpbr bake --embed-textures` decodes every texture: the same limit, naming the source."""
    from fuzzing import Corpus

    from vkpbr.bake.bake import bake_file

    Corpus(tmp_path)  # s.gltf: one 8x8 texture (256 bytes decoded)
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", "255")
    with pytest.raises(SceneError, match=r"s\.gltf: its textures decode to more than 255 bytes"):
        bake_file(tmp_path / "s.gltf", tmp_path / "e.vkpbr", embed_textures=True, progress=False)
    monkeypatch.setenv("VKPBR_MAX_TEXTURE_BYTES", "256")
    bake_file(tmp_path / "s.gltf", tmp_path / "e.vkpbr", embed_textures=True, progress=False)


# --- issue 35: large inputs within the limits load in bounded time ---------------------------
def _materials_gltf(tmp_path: Path, count: int) -> Path:
    """The fuzz suite's textured quad with `count` distinct materials (about 105 bytes of JSON
    each: 29,000 of them are 3 MB), of which the mesh uses material 0."""
    import json
    import sys

    sys.path.insert(0, str(Path(__file__).parents[1]))
    from fuzzing import _gltf_buffer, _gltf_doc, _png

    (tmp_path / "t.png").write_bytes(_png())
    (tmp_path / "b.bin").write_bytes(_gltf_buffer())
    doc = _gltf_doc("b.bin", "t.png")
    base = doc["materials"][0]
    doc["materials"] = [dict(base, pbrMetallicRoughness=dict(
        base["pbrMetallicRoughness"], metallicFactor=(i % 1000) / 1000)) for i in range(count)]
    path = tmp_path / "many-materials.gltf"
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.timeout(120)
@pytest.mark.timeout(120)  # a hang guard, not a measurement (tests assert no timing)
def test_a_3mb_materials_array_loads(tmp_path: Path) -> None:
    """A glTF whose materials array is 3 MB of JSON (29,000 materials) loaded in 10-19 s
    (pygltflib built a dataclass per JSON object); the arrays are read as checked dicts now:
    2-3 s of CPU on the 2-core machine (measured, BENCHMARKS.md's table; not asserted)."""
    path = _materials_gltf(tmp_path, 29_000)
    assert path.stat().st_size > 3_000_000
    scene = load_scene(path)
    assert len(scene.materials) == 29_000
    assert scene.materials[999].metallic_factor == pytest.approx(0.999)


def test_the_material_count_is_limited(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = _materials_gltf(tmp_path, 12)
    monkeypatch.setenv("VKPBR_MAX_MATERIALS", "11")
    with pytest.raises(SceneError, match=r"many-materials.gltf: 12 materials are over the limit "
                                         r"of 11 \(VKPBR_MAX_MATERIALS\)$"):
        load_scene(path)
    monkeypatch.setenv("VKPBR_MAX_MATERIALS", "12")
    assert len(load_scene(path).materials) == 12


@pytest.mark.timeout(120)  # a hang guard, not a measurement (tests assert no timing)
def test_a_million_face_crlf_obj_loads(tmp_path: Path) -> None:
    """1,000,000 faces over 500,000 vertices with CRLF line endings (the issue measured 10 s
    for such a file): about 3 s of CPU now (vectorised checks, tinyobjloader for the parse;
    measured, BENCHMARKS.md's table; not asserted). Every face present."""
    rng = np.random.default_rng(35)
    n_v, n_f = 500_000, 1_000_000
    xyz = rng.random((n_v, 3)).round(4).tolist()
    faces = rng.integers(1, n_v + 1, (n_f, 3)).tolist()
    data = (b"".join(b"v %g %g %g\r\n" % tuple(p) for p in xyz)
            + b"".join(b"f %d %d %d\r\n" % tuple(f) for f in faces))
    obj = tmp_path / "million-crlf.obj"
    obj.write_bytes(data)
    scene = load_scene(obj)
    assert scene.triangle_count == n_f
