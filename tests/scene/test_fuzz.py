# Deterministic fuzzing of every scene loader: seeded byte mutations (flips, truncations,
# insertions) of small .glb/.gltf/.obj/.comp5822mesh files and value mutations of glTF JSON
# (numbers made huge/negative/NaN/strings, keys deleted). Each case must load or raise
# SceneError - any other exception is a bug - within the test's timeout, which also shows
# that absurd counts are rejected before anything large is allocated.

from __future__ import annotations

import importlib.util
import json
import random
import shutil
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from assets_path import ASSETS  # the sample models, if present (optional here)
from fuzzing import mutate_bytes as _mutate_bytes
from fuzzing import mutate_json as _mutate_json

from vkpbr.errors import SceneError
from vkpbr.scene.comp5822 import write_comp5822mesh
from vkpbr.scene.loader import load_scene
from vkpbr.scene.types import Image, Material, Mesh, Node, Scene, TextureRef

HERE = Path(__file__).resolve().parent
SEED = 5822
_EVIL = [1e30, -1, 2**31, 2**64, -(2**40), 0, 7, float("nan"), float("inf"), "x", None, [], {},
         True, 3.5, [1, 2], {"a": 1}]  # fmt: skip


def _builder() -> type:
    """GltfBuilder from test_gltf.py, imported by path (test folders have no __init__.py)."""
    spec = importlib.util.spec_from_file_location("_vkpbr_scene_test_gltf", HERE / "test_gltf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.GltfBuilder


def _synthetic_gltf() -> object:
    """A small document that exercises most code paths: sparse, stride, strip, materials..."""
    b = _builder()()
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32)
    inter = np.concatenate([tri, tri[:, :2]], axis=1)
    view = b.view(inter.tobytes(), stride=20)
    sparse = {"count": 1,
              "indices": {"bufferView": b.view(np.array([1], np.uint16).tobytes()), "componentType": 5123},
              "values": {"bufferView": b.view(np.array([0.5, 0.5], np.float32).tobytes())}}  # fmt: skip
    b.doc["accessors"] += [
        {"bufferView": view, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": view, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC2",
         "sparse": sparse},
    ]  # fmt: skip
    col = b.accessor(np.full((4, 4), 200, np.uint8), 5121, "VEC4", normalized=True)
    idx = b.accessor(np.array([0, 1, 2, 3], np.uint8), 5121, "SCALAR")
    b.doc["meshes"].append({"primitives": [
        {"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "COLOR_0": col}, "indices": idx, "mode": 5,
         "material": 0},
        {"attributes": {"POSITION": 0}, "material": 0}]})  # fmt: skip
    b.doc["images"] = [{"bufferView": b.view(b"\x89PNG...."), "mimeType": "image/png"}]
    b.doc["samplers"] = [{"wrapS": 33071, "minFilter": 9987}]
    b.doc["textures"] = [{"source": 0, "sampler": 0}]
    b.doc["materials"] = [{"pbrMetallicRoughness": {
        "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}},
        "metallicRoughnessTexture": {"index": 0}}, "normalTexture": {"index": 0, "scale": 2},
        "alphaMode": "MASK", "alphaCutoff": 0.4}]  # fmt: skip
    b.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]
    b.doc["extensions"] = {
        "KHR_lights_punctual": {"lights": [{"type": "point"}, {"type": "directional"}]}
    }
    child = b.node(root=False, mesh=0, rotation=[0, 0, 0.7071, 0.7071], scale=[1, 2, 1])
    b.node(matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1], children=[child], camera=0)
    b.node(translation=[0, 3, 0], extensions={"KHR_lights_punctual": {"light": 0}})
    b.node(extensions={"KHR_lights_punctual": {"light": 1}})
    return b


_OBJ = b"""mtllib f.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vn 0 0 1
g a
usemtl m
f 1/1/1 2/2/1 3/3/1 4/1/1
f -1//1 -2//1 -3//1
usemtl n
f 1 2 4
"""
_MTL = b"newmtl m\nKd 1 0 0\nPm 0.5\nmap_Kd -s 2 2 t.png\nmap_d mask.png\nnewmtl n\nPr 0.2\nnorm n.png\n"


def _corpus(tmp: Path) -> list[tuple[str, Callable[[random.Random], None], Path]]:
    """(label, mutate-and-write callable, file to load)."""
    b = _synthetic_gltf()
    glb = b.save(tmp / "f.glb").read_bytes()
    gltf_doc = json.loads(b.save(tmp / "f.gltf", "datauri").read_text())
    (tmp / "f.mtl").write_bytes(_MTL)
    (tmp / "f.obj").write_bytes(_OBJ)
    rng = np.random.default_rng(1)
    (tmp / "t.png").write_bytes(b"")
    mesh = Mesh("m", rng.random((6, 3)).astype(np.float32), np.array([0, 1, 2, 3, 4, 5, 0, 2, 4], np.uint32),
                rng.random((6, 3)).astype(np.float32), rng.random((6, 2)).astype(np.float32), material=0)  # fmt: skip
    scene = Scene("c", meshes=[mesh, mesh], nodes=[Node(0), Node(1)], images=[Image("t", path=tmp / "t.png")],
                  materials=[Material(base_color_texture=TextureRef(0), alpha_texture=TextureRef(0))])  # fmt: skip
    write_comp5822mesh(scene, tmp / "f.comp5822mesh")
    comp = (tmp / "f.comp5822mesh").read_bytes()

    def write_bytes(target: Path, data: bytes) -> Callable[[random.Random], None]:
        return lambda r: target.write_bytes(_mutate_bytes(data, r))

    def write_json(target: Path, doc: dict) -> Callable[[random.Random], None]:
        return lambda r: target.write_text(json.dumps(_mutate_json(doc, r)))

    cases = [
        ("glb bytes", write_bytes(tmp / "m.glb", glb), tmp / "m.glb", 90),
        ("gltf json", write_json(tmp / "m.gltf", gltf_doc), tmp / "m.gltf", 90),
        (
            "gltf bytes",
            write_bytes(tmp / "mb.gltf", (tmp / "f.gltf").read_bytes()),
            tmp / "mb.gltf",
            20,
        ),
        ("obj bytes", write_bytes(tmp / "m.obj", _OBJ), tmp / "m.obj", 50),
        ("mtl bytes", write_bytes(tmp / "f.mtl", _MTL), tmp / "f.obj", 20),
        ("comp5822 bytes", write_bytes(tmp / "m.comp5822mesh", comp), tmp / "m.comp5822mesh", 50),
    ]
    if ASSETS.is_dir():
        for model in ("TextureCoordinateTest", "OrientationTest"):
            src = ASSETS / model / "glTF"
            for f in src.iterdir():
                if f.suffix == ".bin":
                    shutil.copy(f, tmp / f.name)
            doc = json.loads((src / f"{model}.gltf").read_text())
            cases.append(
                (f"{model} json", write_json(tmp / f"{model}.gltf", doc), tmp / f"{model}.gltf", 25)
            )
    out = []
    for label, mutate, target, n in cases:
        out += [(label, mutate, target)] * n
    return out


@pytest.mark.timeout(120)  # a hang (an absurd count allocated or looped over) fails here
def test_fuzz_loaders(tmp_path: Path) -> None:
    corpus = _corpus(tmp_path)
    assert len(corpus) >= 300
    rng = random.Random(SEED)
    outcomes = {"loaded": 0, "rejected": 0}
    old = np.seterr(all="raise")  # as strict as the project's conftest may make it
    try:
        for case, (label, mutate, target) in enumerate(corpus):
            mutate(rng)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    load_scene(target)
                    outcomes["loaded"] += 1
                except SceneError as exc:
                    named = "f.mtl" if label == "mtl bytes" else target.name  # the bad file
                    assert named in str(exc), (case, label, exc)
                    outcomes["rejected"] += 1
                except Exception as exc:  # noqa: BLE001 - the point of the test
                    pytest.fail(f"case {case} ({label}): {type(exc).__name__}: {exc}")
    finally:
        np.seterr(**old)
    assert outcomes["loaded"] > 20 and outcomes["rejected"] > 100, outcomes
