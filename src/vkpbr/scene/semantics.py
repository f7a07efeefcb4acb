"""Semantic ids of the dataset outputs: which class each drawn node-primitive belongs to.

`semantic_ids(scene, draws, source)` gives every draw (a node's mesh primitive, in the order
Renderer.instances lists them) a uint32 class id, 0 meaning "no class" (the background's id
too), and the table id -> label. The source of the classes:

- "mesh" (default): each mesh primitive its own class, id = mesh index + 1, label its name;
- "material": id = material index + 1, label the material's name;
- "extras": what the file says: glTF `extras: {"semantic": ...}` on the node, else on its
  mesh (scene.types.Node.semantic); an integer is the id itself, a label gets the next free
  id (labels sorted, after the integers); nodes without one get 0;
- a mapping {name: id or label} (or the path of a JSON file of one): each draw looked up by
  its node's name, else its mesh's, else its material's; a draw matching none gets 0, and a
  name matching nothing in the scene is an error (a typo would silently label nothing).

NumPy only, no Vulkan.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.errors import JsonError, UsageError
from vkpbr.json_input import read_json

__all__ = ["SEMANTIC_SOURCES", "semantic_ids", "load_semantic_mapping", "checked_mapping"]

SEMANTIC_SOURCES = ("mesh", "material", "extras")
Label = int | str


def load_semantic_mapping(path: str | Path) -> dict[str, Label]:
    """A JSON object {name: id or label} from `path` (one-line UsageError naming it)."""
    p = Path(path)
    try:
        doc = read_json(p)
    except OSError as e:
        raise UsageError(f"semantic mapping {p}: {e.strerror or e}") from None
    except JsonError as e:
        raise UsageError(f"semantic mapping {p}: not JSON ({e.problem})") from None
    return checked_mapping(doc, str(p))


def checked_mapping(doc: object, where: str) -> dict[str, Label]:
    """`doc` as a {name: id or label} mapping (one-line UsageError naming `where`)."""
    if not isinstance(doc, Mapping) or not doc:
        raise UsageError(f"semantic mapping {where}: expected a JSON object "
                         '{"node, mesh or material name": id or label}')
    out: dict[str, Label] = {}
    for name, value in doc.items():
        ok_int = isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 2**32
        ok_str = isinstance(value, str) and bool(value.strip())
        if not isinstance(name, str) or not (ok_int or ok_str):
            raise UsageError(f"semantic mapping {where}: {name!r}: the value must be an id "
                             f"(0 to 2^32 - 1) or a non-empty label, got {value!r}")
        out[name] = value if ok_int else value.strip()  # type: ignore[union-attr]
    return out


def _number(labels: Sequence[Label | None]) -> tuple[np.ndarray, dict[int, str]]:
    """Integers as given, labels numbered after the largest integer (sorted), None -> 0."""
    ints = [v for v in labels if isinstance(v, int)]
    names = sorted({v for v in labels if isinstance(v, str)})
    first = max(ints, default=0) + 1
    ids = {name: first + k for k, name in enumerate(names)}
    if first + len(names) - 1 >= 2**32:
        raise UsageError("semantic ids: the labels do not fit in uint32 after the largest id")
    out = np.array([0 if v is None else (v if isinstance(v, int) else ids[v]) for v in labels],
                   dtype=np.uint32)
    table = {int(v): str(v) for v in ints}
    table.update({i: name for name, i in ids.items()})
    return out, table


def semantic_ids(scene: Any, draws: Sequence[Any], source: str | Mapping[str, Label] | Path
                 ) -> tuple[np.ndarray, dict[int, str]]:
    """((D,) uint32 class id per draw, {id: label}) for `draws` (render.gpu_scene.Draw:
    .node, .mesh, .material) of `scene` from `source` (see the module docstring)."""
    if isinstance(source, Path) or (isinstance(source, str) and source not in SEMANTIC_SOURCES):
        if isinstance(source, str) and not source.lower().endswith(".json"):
            raise UsageError(f"semantics {source!r}: choose {', '.join(SEMANTIC_SOURCES)} or a "
                             "JSON file of {name: id or label}")
        mapping, where = load_semantic_mapping(source), str(source)
    elif isinstance(source, Mapping):
        mapping, where = checked_mapping(source, "(given)"), "(given)"
    elif isinstance(source, str):  # (one of SEMANTIC_SOURCES)
        mapping, where = None, ""
    else:
        raise UsageError(f"semantics: expected {', '.join(SEMANTIC_SOURCES)}, a mapping or a "
                         f"JSON file of {{name: id or label}}, got {type(source).__name__}")
    nodes, meshes, materials = scene.nodes, scene.meshes, scene.materials

    def node_name(d: Any) -> str:
        return nodes[d.node].name if 0 <= d.node < len(nodes) else ""

    def material_name(d: Any) -> str:
        return materials[d.material].name if 0 <= d.material < len(materials) else ""

    if source == "mesh":
        ids = np.array([d.mesh + 1 for d in draws], dtype=np.uint32)
        return ids, {int(i): meshes[i - 1].name for i in np.unique(ids)}
    if source == "material":
        ids = np.array([d.material + 1 for d in draws], dtype=np.uint32)
        return ids, {int(d.material + 1): material_name(d) for d in draws}
    if source == "extras":
        return _number([nodes[d.node].semantic if 0 <= d.node < len(nodes) else None
                        for d in draws])
    assert mapping is not None
    known = {n.name for n in nodes} | {m.name for m in meshes} | {m.name for m in materials}
    unknown = [name for name in mapping if name not in known]
    if unknown:
        raise UsageError(f"semantic mapping {where}: no node, mesh or material is named "
                         f"{unknown[0]!r}" + (f" (and {len(unknown) - 1} more)" if len(unknown) > 1 else ""))
    labels: list[Label | None] = []
    for d in draws:
        keys = (node_name(d), meshes[d.mesh].name, material_name(d))
        labels.append(next((mapping[k] for k in keys if k in mapping), None))
    return _number(labels)
