"""Semantic ids (vkpbr.scene.semantics): every source, the numbering of labels, bad input."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from vkpbr.errors import UsageError
from vkpbr.scene.semantics import semantic_ids
from vkpbr.scene.types import Material, Mesh, Node, Scene


@dataclass
class Draw:  # what semantic_ids reads of render.gpu_scene.Draw
    node: int
    mesh: int
    material: int


def scene_and_draws() -> tuple[Scene, list[Draw]]:
    tri = np.zeros((3, 3), np.float32)
    meshes = [Mesh(f"mesh{i}", tri, np.arange(3, dtype=np.uint32), material=i % 2) for i in range(3)]
    materials = [Material(name="stone"), Material(name="wood")]
    nodes = [Node(0, name="lion", semantic="statue"), Node(1, name="vase", semantic=7),
             Node(2, name="floor"), Node(1, name="vase2", semantic="statue")]
    scene = Scene("s", meshes=meshes, materials=materials, nodes=nodes)
    draws = [Draw(i, n.mesh, meshes[n.mesh].material) for i, n in enumerate(nodes)]
    return scene, draws


def test_mesh_and_material_sources() -> None:
    scene, draws = scene_and_draws()
    ids, labels = semantic_ids(scene, draws, "mesh")
    assert ids.tolist() == [1, 2, 3, 2] and labels == {1: "mesh0", 2: "mesh1", 3: "mesh2"}
    ids, labels = semantic_ids(scene, draws, "material")
    assert ids.tolist() == [1, 2, 1, 2] and labels == {1: "stone", 2: "wood"}


def test_extras_integers_kept_labels_numbered_after_them() -> None:
    scene, draws = scene_and_draws()
    ids, labels = semantic_ids(scene, draws, "extras")
    assert ids.dtype == np.uint32
    assert ids.tolist() == [8, 7, 0, 8] and labels == {7: "7", 8: "statue"}


def test_mapping_by_node_then_mesh_then_material(tmp_path: Path) -> None:
    scene, draws = scene_and_draws()
    mapping = {"lion": "cat", "mesh1": 3, "wood": "timber", "stone": "rock"}
    ids, labels = semantic_ids(scene, draws, mapping)
    # lion: its node's name; vase, vase2: mesh1 (before the material); floor: its material.
    assert ids.tolist() == [4, 3, 5, 3] and labels == {3: "3", 4: "cat", 5: "rock"}
    path = tmp_path / "classes.json"
    path.write_text(json.dumps(mapping))
    assert semantic_ids(scene, draws, str(path))[0].tolist() == ids.tolist()
    assert semantic_ids(scene, draws, path)[0].tolist() == ids.tolist()


@pytest.mark.parametrize("mapping, message", [
    ({"lino": 1}, "no node, mesh or material is named 'lino'"),
    ({"lion": -1}, "the value must be an id"),
    ({"lion": True}, "the value must be an id"),
    ({"lion": ""}, "non-empty label"),
    ({}, "expected a JSON object"),
])
def test_bad_mappings_are_one_line(mapping: dict, message: str) -> None:
    scene, draws = scene_and_draws()
    with pytest.raises(UsageError, match=message):
        semantic_ids(scene, draws, mapping)


def test_bad_sources_and_files(tmp_path: Path) -> None:
    scene, draws = scene_and_draws()
    with pytest.raises(UsageError, match="semantics 'node': choose mesh, material, extras"):
        semantic_ids(scene, draws, "node")
    with pytest.raises(UsageError, match="missing.json"):
        semantic_ids(scene, draws, str(tmp_path / "missing.json"))
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(UsageError, match="bad.json: not JSON"):
        semantic_ids(scene, draws, str(bad))


def test_gltf_extras_are_read(tmp_path: Path) -> None:
    """A glTF's node extras (and, for a node without, its mesh's) become Node.semantic."""
    import base64

    from vkpbr.scene.loader import load_scene

    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0, "extras": {"semantic": "chair"}}, {"mesh": 1},
                  {"mesh": 0, "extras": {"semantic": 5, "other": 1}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]},
                   {"primitives": [{"attributes": {"POSITION": 0}}], "extras": {"semantic": "table"}}],
        "buffers": [{"byteLength": len(pos),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(pos).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": len(pos)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
    }
    path = tmp_path / "s.gltf"
    path.write_text(json.dumps(doc))
    scene = load_scene(path)
    assert [n.semantic for n in scene.nodes] == ["chair", "table", 5]
