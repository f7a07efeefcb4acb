"""Issue 11, classes 1 and 2: a scene whose contents are not what vkpbr's types say (a baked
file's JSON passes its checksums; a glTF's numbers are absurd) fails at load with one
SceneError naming the file and the field, never later with a traceback."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import SceneError
from vkpbr.scene.baked_file import HAS_TEXCOORDS1, read_baked, write_baked
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Camera, Light, Sampler, TextureRef


@pytest.fixture(scope="module")
def baked(tmp_path_factory) -> Path:  # noqa: ANN001
    """A small baked scene with a texture, a camera and a light (bake of an OBJ)."""
    from PIL import Image

    from vkpbr.bake.bake import bake_file

    d = tmp_path_factory.mktemp("baked")
    Image.new("RGBA", (4, 4), (200, 100, 50, 255)).save(d / "c.png")
    (d / "m.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd c.png\n")
    (d / "s.obj").write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                             "usemtl m\nf 1/1 2/2 3/3\n")
    bake_file(d / "s.obj", d / "s.vkpbr", progress=False)
    return d / "s.vkpbr"


def _mutated(baked: Path, tmp: Path, change) -> Path:  # noqa: ANN001
    b = read_baked(baked)
    b.images = [dataclasses.replace(img, path=baked.parent / img.path) if img.path else img
                for img in b.images]
    change(b)
    out = tmp / "m.vkpbr"
    write_baked(out, b)  # fresh checksums: the file is intact, its contents are not valid
    return out


def _texture(b):  # noqa: ANN001, ANN202
    return b.materials[0].base_color_texture


CASES = {
    "null scene name": (lambda b: setattr(b, "name", None), "name: expected a string"),
    "roughness string": (lambda b: setattr(b.materials[0], "roughness_factor", "rough"),
                         "materials[0].roughness_factor"),
    "texture offset one number": (lambda b: setattr(_texture(b), "offset", (0.5,)), "offset"),
    "texture rotation list": (lambda b: setattr(_texture(b), "rotation", [1, 2]), "rotation"),
    "texture image null": (lambda b: setattr(_texture(b), "image", None), "image"),
    "texture image dict": (lambda b: setattr(_texture(b), "image", {"a": 1}), "image"),
    "alpha texture null image": (lambda b: setattr(b.materials[0], "alpha_texture", TextureRef(None)),
                                 "alpha_texture.image"),
    "channel 2^32": (lambda b: setattr(_texture(b), "channel", 2**32), "channel"),
    "sampler mag filter 0.5": (lambda b: setattr(_texture(b), "sampler", Sampler(mag_filter=0.5)),
                               "mag_filter"),
    "camera target of two numbers": (lambda b: b.cameras.append(Camera(target=(1.0, 2.0))),
                                     "].target"),
    "string zfar": (lambda b: b.cameras.append(Camera(zfar="far")), "far"),
    "light at 1e308": (lambda b: b.lights.append(Light(position=(1e308, 0, 0))), "].position[0]"),
    "positions near 3e38": (lambda b: b.streams["positions"].__setitem__(0, (3e38, 0, 0)),
                            "positions"),
    "texcoords1 flag without the stream": (
        lambda b: b.mesh_table.__setitem__("flags", b.mesh_table["flags"] | HAS_TEXCOORDS1),
        "texcoords1"),
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_invalid_baked_contents_are_one_line_errors(baked: Path, tmp_path: Path, case: str) -> None:
    change, field = CASES[case]
    path = _mutated(baked, tmp_path, change)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message and field in message, message


def test_the_unmutated_bake_loads(baked: Path, tmp_path: Path) -> None:
    scene = load_scene(_mutated(baked, tmp_path, lambda b: None))
    assert scene.triangle_count == 1


def test_absurd_gltf_numbers_fail_at_load(tmp_path: Path) -> None:
    """A node scaled by 1e30 puts the geometry beyond any float32 uniform: refused at load."""
    import json

    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    (tmp_path / "b.bin").write_bytes(pos)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0, "scale": [1e30, 1e30, 1e30]}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "buffers": [{"uri": "b.bin", "byteLength": 36}],
           "bufferViews": [{"buffer": 0, "byteLength": 36}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 0]}]}
    (tmp_path / "s.gltf").write_text(json.dumps(doc))
    with pytest.raises(SceneError, match="beyond"):
        load_scene(tmp_path / "s.gltf")
