# Tests of missing textures: one summary log line per scene (never one per texture), for every
# format, strict mode (SceneError, one line), baked files that refer to external textures (said
# when baked, and the same line when they are gone at load), and Sponza without its textures.

from __future__ import annotations

import base64
import json
import logging
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage

from vkpbr.bake.bake import bake_file
from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene
from vkpbr.scene.textures import decode_images

TAIL = "rendering with default values (pass strict=True / --strict to make this an error)"


def triangle_gltf(path: Path, image_uris: list[str]) -> Path:
    """A one-triangle glTF whose material uses every image in `image_uris` (as base colour,
    normal, emissive... in turn); the triangle's bytes are a data: URI."""
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    slots = ["baseColorTexture", "normalTexture", "emissiveTexture", "occlusionTexture"]
    material: dict = {"pbrMetallicRoughness": {}}
    for k in range(len(image_uris)):
        if slots[k] == "baseColorTexture":
            material["pbrMetallicRoughness"]["baseColorTexture"] = {"index": k}
        else:
            material[slots[k]] = {"index": k}
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(pos),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(pos).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": len(pos)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "images": [{"uri": u} for u in image_uris],
        "textures": [{"source": k} for k in range(len(image_uris))],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}],
    }
    path.write_text(json.dumps(doc))
    return path


def messages(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name.startswith("vkpbr")]


def test_gltf_missing_textures_one_line(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    PILImage.new("RGB", (2, 2)).save(tmp_path / "here.png")
    path = triangle_gltf(tmp_path / "t.gltf", ["tex/gone%20a.png", "here.png", "gone_b.png"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # never a UserWarning per texture
        scene = load_scene(path)
    assert messages(caplog) == [
        f"2 of 3 textures not found next to {path} (first: tex/gone a.png); {TAIL}"]
    assert caplog.records[0].name == "vkpbr.scene.textures"
    assert caplog.records[0].levelno == logging.WARNING
    assert len(scene.images) == 3  # still referenced: the renderer binds defaults for them
    caplog.clear()
    load_scene(triangle_gltf(tmp_path / "ok.gltf", ["here.png"]))
    assert messages(caplog) == []  # nothing missing: nothing said


def test_strict_raises_one_line(tmp_path: Path) -> None:
    path = triangle_gltf(tmp_path / "t.gltf", ["gone.png", "gone2.png"])
    with pytest.raises(SceneError) as info:
        load_scene(path, strict=True)
    assert str(info.value) == f"{path}: 2 of 2 textures not found (first: gone.png)"
    assert "\n" not in str(info.value)


def test_obj_and_mtl_missing_textures(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    (tmp_path / "m.mtl").write_text("newmtl a\nmap_Kd maps/a.png\nmap_Bump maps/n.png\n"
                                    "newmtl b\nmap_Kd maps/a.png\n")
    path = tmp_path / "m.obj"
    path.write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n"
                    "usemtl b\nf 1 2 3\n")
    load_scene(path)
    assert messages(caplog) == [f"2 of 2 textures not found next to {path} (first: maps/a.png); {TAIL}"]
    with pytest.raises(SceneError, match="2 of 2 textures not found"):
        load_scene(path, strict=True)


def test_baked_file_with_external_textures(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    src_dir, out_dir = tmp_path / "src", tmp_path / "out"
    (src_dir / "maps").mkdir(parents=True)
    out_dir.mkdir()
    for name in ("a.png", "b.png"):
        PILImage.new("RGB", (4, 4), (9, 99, 199)).save(src_dir / "maps" / name)
    src = triangle_gltf(src_dir / "t.gltf", ["maps/a.png", "maps/b.png"])
    out = out_dir / "t.vkpbr"
    caplog.set_level(logging.INFO, logger="vkpbr.bake")
    report = bake_file(src, out, progress=False, textures="external", allow_outside_paths=True)
    assert report["external_textures"] == 2 and report["embedded_textures"] == 0
    # Said when baked: how many stay external and where they must be.
    assert messages(caplog) == [
        f"t.vkpbr: 2 of 2 textures stay external files; they must stay in "
        f"{(src_dir / 'maps').resolve()} (../src/maps from the baked file), or bake with "
        "--textures source to store them inside; they lie outside the baked file's folder, so "
        "loading it needs --allow-outside-paths"]
    caplog.clear()
    # They lie outside the baked file's folder: the path policy refuses them by default
    # (one line, like missing ones) and reads them with allow_outside_paths.
    load_scene(out)
    assert messages(caplog) == [
        f"2 of 2 textures of {out} outside the scene's folder (first: "
        "../src/maps/a.png; pass --allow-outside-paths "
        f"(allow_outside_paths=True) to read them); {TAIL}"]
    caplog.clear()
    load_scene(out, allow_outside_paths=True)
    assert messages(caplog) == []  # found next to the baked file's recorded paths
    (src_dir / "maps" / "b.png").unlink()
    load_scene(out, allow_outside_paths=True)  # the same one line when they are gone
    # Named as the baked file records it: relative to the baked file's folder.
    assert messages(caplog) == [
        f"1 of 2 textures not found next to {out} (first: ../src/maps/b.png); {TAIL}"]
    with pytest.raises(SceneError, match=r"t.vkpbr: 1 of 2 textures not found \(first: \.\./src/maps/b.png\)$"):
        load_scene(out, strict=True, allow_outside_paths=True)
    # An embedded bake says nothing about external files and needs none at load.
    caplog.clear()
    embedded = out_dir / "e.vkpbr"
    (src_dir / "maps" / "b.png").write_bytes((src_dir / "maps" / "a.png").read_bytes())
    assert bake_file(src, embedded, embed_textures=True, progress=False)["embedded_textures"] == 2
    shutil.rmtree(src_dir)
    scene = load_scene(embedded, strict=True)
    assert messages(caplog) == [] and all(img.pixels is not None for img in scene.images)


def test_a_plain_bake_elsewhere_is_self_contained(tmp_path: Path) -> None:
    """README's two lines in a row (`vkpbr bake scene.gltf --out elsewhere/scene.vkpbr`, then
    load that): the texture files' bytes are inside, as they are (PNG and JPEG), so the
    baked file loads with every texture after the sources are gone, and it is about as large
    as its sources, not their decoded pixels. A bake that cannot store a texture fails,
    naming it, instead of writing a file that renders untextured."""
    src_dir, out_dir = tmp_path / "src", tmp_path / "elsewhere"
    (src_dir / "maps").mkdir(parents=True)
    out_dir.mkdir()
    rng = np.random.default_rng(3)
    noise = rng.integers(0, 256, (256, 256, 3), dtype=np.uint8)
    PILImage.fromarray(noise).save(src_dir / "maps" / "a.png")
    PILImage.fromarray(noise).save(src_dir / "maps" / "b.jpg", quality=90)
    src = triangle_gltf(src_dir / "t.gltf", ["maps/a.png", "maps/b.jpg"])
    sources = sum((src_dir / "maps" / n).stat().st_size for n in ("a.png", "b.jpg"))
    out = out_dir / "t.vkpbr"
    report = bake_file(src, out, progress=False)
    assert report["embedded_textures"] == 2 and report["external_textures"] == 0
    assert sources < out.stat().st_size < sources + 64 * 1024  # the bytes, not 2 x 256 KiB RGBA
    originals = [(src_dir / "maps" / n).read_bytes() for n in ("a.png", "b.jpg")]
    shutil.rmtree(src_dir)
    scene = load_scene(out, strict=True)
    assert [img.data for img in scene.images] == originals  # stored as they were
    assert [img.mime_type for img in scene.images] == ["image/png", "image/jpeg"]
    pixels = decode_images(scene)
    assert np.array_equal(pixels[0][..., :3], noise)
    # A texture that is gone: the bake fails in one line naming it, and writes nothing.
    src_dir.mkdir()
    src = triangle_gltf(src_dir / "t.gltf", ["maps/gone.png"])
    with pytest.raises(SceneError, match=r"texture maps/gone.png: cannot embed it .*untextured"):
        bake_file(src, out_dir / "g.vkpbr", progress=False)
    assert not (out_dir / "g.vkpbr").exists()


def test_strict_bake_fails_before_writing(tmp_path: Path) -> None:
    src = triangle_gltf(tmp_path / "t.gltf", ["gone.png"])
    with pytest.raises(SceneError, match="1 of 1 textures not found"):
        bake_file(src, tmp_path / "t.vkpbr", progress=False, strict=True)
    assert not (tmp_path / "t.vkpbr").exists()


def test_textureless_sponza_prints_one_line(assets: Path, tmp_path: Path,
                                            caplog: pytest.LogCaptureFixture) -> None:
    """Sponza's .gltf and .bin without its 69 textures: one line in all, load and decode."""
    sponza = assets / "Sponza" / "glTF"
    path = tmp_path / "Sponza.gltf"
    shutil.copy(sponza / "Sponza.gltf", path)
    (tmp_path / "Sponza.bin").symlink_to(sponza / "Sponza.bin")
    # The .bin is a symlink out of tmp_path, which the path policy refuses by default.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = load_scene(path, allow_outside_paths=True)
        decode_images(scene)  # what the renderer does next: INFO only, below the default level
    assert len(scene.images) == 69
    (line,) = [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert line.getMessage().startswith(f"69 of 69 textures not found next to {path} (first: ")
    with pytest.raises(SceneError, match=r"Sponza.gltf: 69 of 69 textures not found \(first: "):
        load_scene(path, strict=True, allow_outside_paths=True)
    with pytest.raises(SceneError, match=r"Sponza.gltf: buffer 0 refers to Sponza.bin, which resolves outside "):
        load_scene(path)


def test_undecodable_texture_names_the_file_and_what_it_holds(tmp_path: Path,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    """Not "cannot identify image file <_io.BytesIO object at 0x...>": the file's name and
    the format its first bytes show."""
    (tmp_path / "page.png").write_text("<html>404 Not Found</html>")
    (tmp_path / "cut.png").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR")
    (tmp_path / "odd.jpg").write_bytes(bytes(range(7, 40)))
    scene = load_scene(triangle_gltf(tmp_path / "t.gltf", ["page.png", "cut.png", "odd.jpg"]))
    caplog.clear()
    decode_images(scene)
    text = " ".join(messages(caplog))
    assert "BytesIO" not in text and " at 0x" not in text, text
    assert "page.png (not a decodable image: text (HTML, XML or JSON), not an image" in text, text
    from vkpbr.scene.textures import decode_image

    said = [decode_image(img)[1][0][1] for img in scene.images]  # each image's own note
    assert said[0].startswith("page.png (not a decodable image: text"), said
    assert said[1].startswith("cut.png (PNG data") and "BytesIO" not in said[1], said
    assert said[2].startswith("odd.jpg (not a decodable image: data of no known image format "
                              "(first bytes 07 08"), said
