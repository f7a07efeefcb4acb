# glTF primitives -> Mesh: attributes through the document's accessor decoder, indices
# resolved (strips and fans turned into lists), flat normals where NORMAL is absent, triangles
# touching non-finite positions dropped with a warning (geometry.drop_nonfinite).
# Reference: glTF 2.0 spec 3.7.2 (meshes), 3.7.2.1 (attributes).

from __future__ import annotations

import numpy as np

from vkpbr.errors import SceneError
from vkpbr.scene.geometry import (
    drop_nonfinite,
    ensure_normals,
    fan_triangles,
    normalize_mesh_arrays,
    strip_triangles,
)
from vkpbr.scene.gltf_document import GltfDocument, check_index, get
from vkpbr.scene.types import Mesh

__all__ = ["primitive"]

_MODES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP"}


def primitive(ld: GltfDocument, mesh_index: int, prim_index: int, prim: object) -> Mesh:
    """One triangle primitive -> Mesh (indices resolved, flat normals if NORMAL is absent)."""
    name = f"{get(ld.gltf.meshes[mesh_index], 'name', f'mesh {mesh_index}')}/{prim_index}"
    mode = get(prim, "mode", 4)
    if mode in _MODES:
        raise SceneError(
            ld.path, f"mesh {name}: primitive mode {_MODES[mode]} is not triangles"
        )
    if mode not in (4, 5, 6):
        raise SceneError(ld.path, f"mesh {name}: unknown primitive mode {mode!r}")
    attrs = get(prim, "attributes", {})
    attrs = attrs if isinstance(attrs, dict) else getattr(attrs, "__dict__", None)
    if not isinstance(attrs, dict):
        raise SceneError(ld.path, f"mesh {name}: attributes is not an object")
    if attrs.get("POSITION") is None:
        raise SceneError(ld.path, f"mesh {name}: primitive has no POSITION")
    positions = ld.attribute(attrs["POSITION"], (3,), f"mesh {name} POSITION")
    n = len(positions)

    def optional(key: str, ncomps: tuple[int, ...]) -> np.ndarray | None:
        if attrs.get(key) is None:
            return None
        arr = ld.attribute(attrs[key], ncomps, f"mesh {name} {key}")
        if len(arr) != n:
            raise SceneError(ld.path, f"mesh {name}: {key} has {len(arr)} items, not {n}")
        return arr

    colors = optional("COLOR_0", (3, 4))
    if colors is not None and colors.shape[1] == 3:
        colors = np.concatenate([colors, np.ones((n, 1), np.float32)], axis=1)
    index_acc = get(prim, "indices")
    if index_acc is None:
        indices = np.arange(n, dtype=np.uint32)
    else:
        arr, _ = ld.accessor(index_acc)
        if arr.dtype.kind != "u" or arr.shape[1] != 1:
            raise SceneError(ld.path, f"mesh {name}: indices must be unsigned scalars")
        indices = arr.reshape(-1).astype(np.uint32)
        if len(indices) and int(indices.max()) >= n:
            raise SceneError(
                ld.path, f"mesh {name}: index {int(indices.max())} >= vertex count {n}"
            )
    if mode == 5:
        indices = strip_triangles(indices)
    elif mode == 6:
        indices = fan_triangles(indices)
    elif len(indices) % 3:
        raise SceneError(
            ld.path, f"mesh {name}: {len(indices)} indices is not a multiple of 3"
        )
    material = get(prim, "material", -1)
    if material != -1:
        material = check_index(ld.path, material, len(ld.gltf.materials or []), "material")
    mesh = Mesh(
        name=name,
        positions=positions,
        indices=indices,
        normals=optional("NORMAL", (3,)),
        texcoords=optional("TEXCOORD_0", (2,)),
        texcoords1=optional("TEXCOORD_1", (2,)),
        tangents=optional("TANGENT", (4,)),
        colors=colors,
        material=material,
    )
    return normalize_mesh_arrays(ensure_normals(drop_nonfinite(mesh, ld.path)))
